//! Parity of marching cubes (`mc_inside`, `mc_classify`, `mc_vertices`,
//! `mc_triangles`) end to end against the CPU path `mc::cpu`.
//!
//! Both sides compute `t = clamp((level − a) / (b − a), T_MIN, 1 − T_MIN)`
//! and `u[axis] = f32(p[axis]) + t` with the same f32 operations (one
//! division, an exact clamp, one addition — nothing to contract into an
//! FMA), and the world transform runs on the host for both. Vertex
//! positions, keyed by grid edge id, are compared within
//! [`position_tolerance`]: WGSL lets the division be off by 2.5 ulp (the
//! NVIDIA H200 is, by 1 ulp on ~1 % of the vertices); on a software adapter
//! (lavapipe divides correctly rounded) they must be bit-identical. The
//! topology is exact everywhere: the triangle set as sorted triples of grid
//! edge ids (rotated to start at the smallest), and also in output order,
//! with cells and groups.

use std::collections::BTreeMap;

use chisel::Backend;
use chisel::gpu::Gpu;
use chisel::mc::{self, Field, IsoSpec, McOptions, Surface};
use chisel::parity::{Mismatch, Tolerance, compare_exact, compare_vec, find_sentinel};
use chisel::volume::{Volume, VolumeData};

use super::mc_kernels::random_volume;
use crate::common;

/// Positions keyed by grid edge id, in edge order.
fn positions_by_edge(s: &Surface) -> Vec<[f32; 3]> {
    let by: BTreeMap<u64, [f32; 3]> = s
        .vertex_edges
        .iter()
        .zip(&s.mesh.positions)
        .map(|(&k, p)| (k, p.to_array()))
        .collect();
    by.into_values().collect()
}

/// Largest honest position difference for `vol` (world units): `t` within
/// 2.5 ulp (WGSL's division bound; ulp(t) ≤ 2⁻²⁴ for t < 1), the sum
/// `f32(p) + t` at most one ulp of a grid coordinate (≤ 2⁻²³·n for n
/// points along the longest axis, close-border padding included) further,
/// both scaled by the spacing; the host's transform, in f64 rounded once to
/// f32, adds one ulp of the world coordinate (rel 2⁻²³).
fn position_tolerance(vol: &Volume) -> Tolerance {
    let n = (vol.dims.iter().max().unwrap() + 2) as f32;
    let s = vol.spacing.iter().copied().fold(0.0, f64::max) as f32;
    let grid = 2.5 * 2f32.powi(-24) + 2f32.powi(-23) * n;
    Tolerance {
        abs: s * grid,
        rel: 2f32.powi(-23),
    }
}

/// The tolerance [`check`] applies on `gpu`: exact on a software adapter.
fn tolerance_on(gpu: &Gpu, vol: &Volume) -> Tolerance {
    if gpu.is_software() {
        Tolerance::EXACT
    } else {
        position_tolerance(vol)
    }
}

fn compare(what: &str, cpu: &Surface, gpu: &Surface, tol: Tolerance) -> Result<(), Mismatch> {
    let mut e_cpu = cpu.vertex_edges.clone();
    let mut e_gpu = gpu.vertex_edges.clone();
    e_cpu.sort_unstable();
    e_gpu.sort_unstable();
    compare_exact(&format!("{what}: vertex edge ids"), &e_cpu, &e_gpu)?;
    compare_vec(
        &format!("{what}: positions by edge"),
        &positions_by_edge(cpu),
        &positions_by_edge(gpu),
        tol,
    )?;
    compare_exact(
        &format!("{what}: triangle set"),
        &cpu.canonical_triangles(),
        &gpu.canonical_triangles(),
    )?;
    compare_exact(
        &format!("{what}: triangles in order"),
        &cpu.mesh.triangles,
        &gpu.mesh.triangles,
    )?;
    compare_exact(
        &format!("{what}: cells"),
        &cpu.triangle_cells,
        &gpu.triangle_cells,
    )?;
    compare_exact(
        &format!("{what}: groups"),
        &cpu.triangle_groups,
        &gpu.triangle_groups,
    )?;
    let euler = |s: &Surface| s.groups.iter().map(|g| g.euler).collect::<Vec<_>>();
    compare_exact(&format!("{what}: group χ"), &euler(cpu), &euler(gpu))?;
    Ok(())
}

fn check(gpu: &Gpu, what: &str, vol: &Volume, iso: IsoSpec, close: bool) {
    let opts = McOptions {
        close_border: close,
        ..McOptions::default()
    };
    let c = mc::marching_cubes(vol, iso, &opts, Backend::Cpu).unwrap();
    let g = mc::marching_cubes(vol, iso, &opts, Backend::Gpu(gpu)).unwrap();
    assert!(
        !c.mesh.triangles.is_empty(),
        "{what}: empty surface proves nothing"
    );
    compare(what, &c, &g, tolerance_on(gpu, vol)).unwrap_or_else(|m| panic!("{m}"));
}

#[test]
fn mc_random_volumes() {
    let Some(gpu) = common::gpu() else { return };
    for seed in 1..=4u64 {
        let vol = random_volume(seed, [23, 17, 11]);
        // 1000: samples exactly at the level (clamped interpolation).
        for (close, level) in [(false, 1000.5), (true, 1000.5), (true, 1000.0)] {
            check(
                gpu,
                &format!("random {seed} close {close} level {level}"),
                &vol,
                IsoSpec::Level(level),
                close,
            );
        }
    }
}

#[test]
fn mc_labels() {
    let Some(gpu) = common::gpu() else { return };
    let mut next = common::xorshift(9);
    let data: Vec<u8> = (0..30 * 20 * 10).map(|_| (next() % 4) as u8).collect();
    let vol = Volume::new([30, 20, 10], [1.0; 3], [0.0; 3], VolumeData::U8(data)).unwrap();
    check(gpu, "labels", &vol, IsoSpec::Label(2.0), true);
}

/// A binding cap of 64 KiB forces many classify slabs and one-or-two-layer
/// emission slabs (the triangles of one layer take most of a binding), each
/// making its own inside flags; a cap of 192 KiB keeps the samples and the
/// whole grid's flags resident while the emission still runs in slabs.
#[test]
fn mc_slabs_match_single_pass() {
    let Some(gpu) = common::gpu() else { return };
    let small = gpu.view(Some(64 << 10), false);
    let vol = random_volume(5, [40, 30, 60]);
    let field = Field::new(&vol, IsoSpec::Level(1000.5), true).unwrap();
    let layer_bytes = (field.dims[0] * field.dims[1] * 4) as u64;
    let total = layer_bytes * field.dims[2] as u64;
    assert!(
        total > 4 * small.max_binding_bytes(),
        "cap must force slabs"
    );
    check(&small, "slabs", &vol, IsoSpec::Level(1000.5), true);
    // Samples and inside flags resident (made once for both passes), the
    // emission still in slabs (`vert_base` takes 4 bytes a point).
    let resident = gpu.view(Some(192 << 10), false);
    let sample_bytes = total / 2;
    assert!(sample_bytes <= resident.max_binding_bytes() && total > resident.max_binding_bytes());
    check(
        &resident,
        "resident slabs",
        &vol,
        IsoSpec::Level(1000.5),
        true,
    );
}

#[test]
fn mc_headsq() {
    let Some(gpu) = common::gpu() else { return };
    let Some(vol) = common::real_volume("headsq/quarter.nhdr") else {
        return;
    };
    for level in [500.0, 1150.0] {
        check(
            gpu,
            &format!("headsq {level}"),
            &vol,
            IsoSpec::Level(level),
            true,
        );
    }
}

#[test]
fn mc_sentinels_and_negative_control() {
    let Some(gpu) = common::gpu() else { return };
    let vol = random_volume(3, [20, 18, 16]);
    let iso = IsoSpec::Level(1000.5);
    let field = Field::new(&vol, iso, true).unwrap();
    let raw = mc::gpu::marching_cubes_raw(gpu, &field).unwrap();
    assert!(!raw.triangles.is_empty());
    // Kernel time on the GPU clock exactly when the device has timestamps.
    match raw.kernel_seconds {
        Some(t) => assert!(
            gpu.features.timestamps && t.iter().all(|&t| t > 0.0 && t.is_finite()),
            "{t:?}"
        ),
        None => assert!(!gpu.features.timestamps),
    }
    assert_eq!(find_sentinel(&raw.triangles, [u32::MAX; 4]), None);
    assert!(
        raw.positions
            .iter()
            .all(|p| p[..3].iter().all(|c| c.is_finite()))
    );
    let cpu = mc::marching_cubes(
        &vol,
        iso,
        &McOptions {
            close_border: true,
            ..McOptions::default()
        },
        Backend::Cpu,
    )
    .unwrap();
    let ok = mc::finish(&field, mc::gpu::assemble(raw.clone(), true));
    let tol = position_tolerance(&vol);
    compare("unchanged", &cpu, &ok, tolerance_on(gpu, &vol)).unwrap();
    // One grid coordinate off by twice the tolerance (in grid units, so the
    // world difference is twice its absolute part plus the relative slack).
    let slack = (tol.abs + tol.rel * 64.0) / vol.spacing[1] as f32;
    let mut bad = raw.clone();
    bad.positions[7][1] += 2.0 * slack;
    let s = mc::finish(&field, mc::gpu::assemble(bad, true));
    assert!(
        compare("off by twice the bound", &cpu, &s, tol).is_err(),
        "comparator missed a position twice the tolerance away"
    );
    // On a software adapter one ulp is already a mismatch.
    let mut bad = raw.clone();
    bad.positions[7][1] = f32::from_bits(bad.positions[7][1].to_bits() + 1);
    let s = mc::finish(&field, mc::gpu::assemble(bad, true));
    assert!(
        compare("one ulp", &cpu, &s, Tolerance::EXACT).is_err(),
        "exact comparator missed a 1-ulp position"
    );
    // Two vertices of one triangle swapped (orientation flip).
    let mut bad = raw;
    let t = bad.triangles.len() / 2;
    bad.triangles[t].swap(0, 1);
    let s = mc::finish(&field, mc::gpu::assemble(bad, true));
    assert!(
        compare("flipped", &cpu, &s, tol).is_err(),
        "comparator missed a flipped triangle"
    );
}
