//! Parity of `kernels/exclusive_scan_blocks.wgsl` + `exclusive_scan_add.wgsl`
//! against `exclusive_scan::cpu` (exact, wrapping u32), with a sequential fold as the
//! independent oracle and CSR offsets as real-data ground truth.

use chisel::Backend;
use chisel::exclusive_scan::gpu::ScanBuffers;
use chisel::exclusive_scan::{self, Scan, cpu};
use chisel::gpu::Gpu;
use chisel::mesh::Csr;
use chisel::parity::{compare_exact, find_sentinel};

use crate::common;

/// Textbook exclusive scan (sequential, wrapping).
fn oracle(values: &[u32]) -> Scan {
    let mut total = 0u32;
    let offsets = values
        .iter()
        .map(|&v| {
            let o = total;
            total = total.wrapping_add(v);
            o
        })
        .collect();
    Scan { offsets, total }
}

fn random_values(seed: u64, n: usize, max: u32) -> Vec<u32> {
    let mut s = seed.max(1);
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 32) as u32 % max.max(1)
        })
        .collect()
}

/// GPU = mirror = oracle, exactly; `sentinel_free`: the inputs keep every
/// partial sum below `u32::MAX`, so a surviving sentinel is a missed write.
fn check(gpu: &Gpu, what: &str, values: &[u32], sentinel_free: bool) -> Scan {
    let want = cpu::exclusive_scan(values);
    let truth = oracle(values);
    assert_eq!(want, truth, "{what}: mirror vs oracle");
    let got = exclusive_scan::exclusive_scan(values, Backend::Gpu(gpu)).unwrap();
    if sentinel_free {
        assert_eq!(
            find_sentinel(&got.offsets, u32::MAX),
            None,
            "{what}: sentinel"
        );
    }
    compare_exact(
        &format!("exclusive_scan/{what}"),
        &want.offsets,
        &got.offsets,
    )
    .unwrap_or_else(|m| panic!("{m}"));
    assert_eq!(got.total, want.total, "{what}: total");
    got
}

#[test]
fn edge_sizes() {
    let Some(gpu) = common::gpu() else { return };
    let wg = cpu::WG_SIZE;
    for (n, levels) in [
        (1, 1),
        (wg - 1, 1),
        (wg, 1),
        (wg + 1, 2),
        (wg * wg, 2),
        (wg * wg + 1, 3),
        (1_000_007, 3),
    ] {
        let v = random_values(n as u64, n, 1000);
        check(gpu, &format!("n{n}"), &v, true);
        assert_eq!(
            ScanBuffers::upload(gpu, &v).unwrap().n_levels(),
            levels,
            "n{n}"
        );
    }
    let empty = check(gpu, "empty", &[], true);
    assert_eq!(empty.total, 0);
}

#[test]
fn random_sizes() {
    let Some(gpu) = common::gpu() else { return };
    for (seed, n) in random_values(41, 6, 200_000).into_iter().enumerate() {
        let v = random_values(seed as u64 + 100, n as usize + 1, 1 << 12);
        check(gpu, &format!("random{seed}"), &v, true);
    }
    // All ones: offsets are the indices.
    let ones = vec![1u32; 70_001];
    let s = check(gpu, "ones", &ones, true);
    assert!(s.offsets.iter().enumerate().all(|(i, &o)| o as usize == i));
    assert_eq!(s.total, 70_001);
}

#[test]
fn wraps_mod_2_32() {
    // Large values overflow many times; both sides wrap identically.
    let Some(gpu) = common::gpu() else { return };
    let v = random_values(8, 100_000, u32::MAX);
    let s = check(gpu, "wrapping", &v, false);
    let exact: u64 = v.iter().map(|&x| u64::from(x)).sum();
    assert_eq!(u64::from(s.total), exact % (1 << 32));
}

#[test]
fn grid_2d() {
    // 65_537 blocks: the first level dispatches a 2-D grid with surplus
    // workgroups, which must neither write offsets nor totals.
    let Some(gpu) = common::gpu() else { return };
    let blocks = gpu.device.limits().max_compute_workgroups_per_dimension as usize + 2;
    let n = blocks * cpu::WG_SIZE - 3;
    if n * 4 > gpu.max_binding_bytes() as usize {
        eprintln!("skipping grid_2d: {n} values exceed one binding");
        return;
    }
    check(gpu, "grid_2d", &random_values(77, n, 16), true);
}

#[test]
fn real_headsq_mask() {
    // 0/1 mask of headsq ≥ 500 (the skin iso-value): the total is the
    // number of voxels at or above it.
    let Some(v) = common::real_volume("headsq/quarter.nhdr") else {
        return;
    };
    let Some(gpu) = common::gpu() else { return };
    let mask: Vec<u32> = v
        .data
        .to_f32()
        .iter()
        .map(|&x| u32::from(x >= 500.0))
        .collect();
    let s = check(gpu, "headsq>=500", &mask, true);
    assert_eq!(s.total as usize, mask.iter().filter(|&&m| m == 1).count());
    assert!(s.total > 0 && (s.total as usize) < mask.len());
}

#[test]
fn real_bunny_counts() {
    let Some(mesh) = common::real_mesh("bunny.ply") else {
        return;
    };
    let Some(gpu) = common::gpu() else { return };
    // Per-triangle vertex counts (3 each): offsets 3·t, total 3·#F.
    let per_tri = vec![3u32; mesh.n_triangles()];
    let s = check(gpu, "bunny/tri_vertices", &per_tri, true);
    assert!(
        s.offsets
            .iter()
            .enumerate()
            .all(|(t, &o)| o as usize == 3 * t)
    );
    assert_eq!(s.total as usize, 3 * 69_451);
    // Per-vertex incident-triangle counts (0 for the 1,113 unused
    // vertices): the scan is the CSR offsets built by counting sort.
    let csr = Csr::vertex_triangles(mesh.n_vertices(), &mesh.triangles);
    let counts: Vec<u32> = csr.offsets.windows(2).map(|w| w[1] - w[0]).collect();
    let s = check(gpu, "bunny/valence", &counts, true);
    compare_exact("bunny/csr", &csr.offsets[..counts.len()], &s.offsets).unwrap();
    assert_eq!(Some(&s.total), csr.offsets.last());
}

#[test]
fn negative_control() {
    let Some(gpu) = common::gpu() else { return };
    let v = random_values(9, 3000, 100);
    let want = cpu::exclusive_scan(&v);
    let mut got = exclusive_scan::exclusive_scan(&v, Backend::Gpu(gpu)).unwrap();
    compare_exact("exclusive_scan/control", &want.offsets, &got.offsets).unwrap();
    let k = 2049;
    got.offsets[k] += 1;
    let m = compare_exact("exclusive_scan/control", &want.offsets, &got.offsets).unwrap_err();
    assert_eq!((m.index, m.count), (k, 1), "{m}");
}
