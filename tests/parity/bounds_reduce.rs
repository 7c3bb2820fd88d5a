//! Parity of `kernels/bounds_reduce.wgsl` against `reduce::cpu`: exact (order
//! keys), per pass and end to end, with a glam min/max fold as the
//! independent oracle and the data README's boxes as ground truth.

use chisel::foundation::Aabb as Bounds;
use chisel::gpu::Gpu;
use chisel::parity::{Tolerance, compare_exact, compare_vec, find_sentinel};
use chisel::reduce::gpu::BoundsBuffers;
use chisel::reduce::{self, cpu};
use chisel::{Backend, Error, TriMesh};

use crate::common;

fn positions(mesh: &TriMesh) -> Vec<[f32; 4]> {
    mesh.positions
        .iter()
        .map(|p| [p.x, p.y, p.z, 0.0])
        .collect()
}

/// Seeded positions in [-scale, scale]³ (xorshift), w = 0.
fn random_positions(seed: u64, n: usize, scale: f32) -> Vec<[f32; 4]> {
    let mut s = seed.max(1);
    let mut c = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        ((s >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0) * scale
    };
    (0..n).map(|_| [c(), c(), c(), 0.0]).collect()
}

/// Every pass's GPU output equals the mirror's (keys, exactly), no sentinel
/// survives, and the end-to-end result equals the mirror and the oracle.
fn check(gpu: &Gpu, what: &str, p: &[[f32; 4]]) {
    let buffers = BoundsBuffers::new(gpu, p).unwrap();
    let mut encoder = gpu.encoder("bounds_reduce");
    buffers.record(gpu, &mut encoder).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let got = buffers.pass_outputs(gpu).unwrap();
    let mut want = vec![cpu::bounds_pass_positions(p)];
    while want[want.len() - 1].len() > 1 {
        want.push(cpu::bounds_pass(&want[want.len() - 1]));
    }
    assert_eq!(got.len(), want.len(), "{what}: pass count");
    for (k, (g, w)) in got.iter().zip(&want).enumerate() {
        assert_eq!(
            find_sentinel(g, [u32::MAX; 4]),
            None,
            "{what}: pass {k} sentinel"
        );
        let w: Vec<[u32; 4]> = w.iter().flatten().copied().collect();
        compare_exact(&format!("bounds_reduce/{what}/pass{k}"), &w, g)
            .unwrap_or_else(|m| panic!("{m}"));
    }
    let cpu_b = reduce::bounds_reduce(p, Backend::Cpu).unwrap().unwrap();
    let gpu_b = reduce::bounds_reduce(p, Backend::Gpu(gpu))
        .unwrap()
        .unwrap();
    assert_bits_eq(what, cpu_b, gpu_b);
    let v = |q: &[f32; 4]| glam::Vec3::new(q[0], q[1], q[2]);
    let (lo, hi) = p.iter().fold((v(&p[0]), v(&p[0])), |(lo, hi), q| {
        (lo.min(v(q)), hi.max(v(q)))
    });
    compare_vec(
        &format!("bounds_reduce/{what}/oracle"),
        &[lo.to_array(), hi.to_array()],
        &[gpu_b.min.to_array(), gpu_b.max.to_array()],
        Tolerance::EXACT,
    )
    .unwrap_or_else(|m| panic!("{m}"));
}

fn assert_bits_eq(what: &str, a: Bounds, b: Bounds) {
    let bits = |x: Bounds| [x.min.to_array(), x.max.to_array()].map(|v| v.map(f32::to_bits));
    assert_eq!(bits(a), bits(b), "{what}: {a:?} vs {b:?}");
}

#[test]
fn synthetic() {
    let Some(gpu) = common::gpu() else { return };
    check(gpu, "tetra", &positions(&common::tetra()));
    check(gpu, "cube", &positions(&common::cube()));
    check(gpu, "icosphere4", &positions(&common::icosphere(4)));
    check(
        gpu,
        "random_mesh",
        &positions(&common::random_mesh(7, 3000, 10)),
    );
    // Lanes (256), blocks (4096 items per workgroup) and pass counts.
    let (wg, b) = (256, cpu::BLOCK);
    for n in [
        1,
        2,
        wg - 1,
        wg,
        wg + 1,
        b - 1,
        b,
        b + 1,
        b * wg,
        b * wg + 1,
        1_000_007,
    ] {
        check(gpu, &format!("n{n}"), &random_positions(n as u64, n, 1e3));
    }
}

#[test]
fn extremes_land_anywhere() {
    // The min and max of each axis placed first, last, at lane and block
    // boundaries, in a later per-invocation item and in the last partial
    // block.
    let Some(gpu) = common::gpu() else { return };
    let b = cpu::BLOCK;
    let n = 3 * b + 17;
    for at in [0, n - 1, 255, 256, 2 * 256 + 7, b - 1, b, 3 * b + 3] {
        let mut p = random_positions(at as u64 + 11, n, 1.0);
        p[at] = [-5.0, 6.0, -7.0, 0.0];
        p[(at + 1) % n] = [8.0, -9.0, 10.0, 0.0];
        check(gpu, &format!("extremes@{at}"), &p);
        let b = reduce::bounds_reduce(&p, Backend::Gpu(gpu))
            .unwrap()
            .unwrap();
        assert_eq!(b.min.to_array(), [-5.0, -9.0, -7.0]);
        assert_eq!(b.max.to_array(), [8.0, 6.0, 10.0]);
    }
}

#[test]
fn signed_zero_infinity_and_subnormals() {
    // totalOrder: −0 < +0, so min is −0 and max is +0 whatever the order.
    let Some(gpu) = common::gpu() else { return };
    let tiny = f32::from_bits(1); // smallest subnormal
    let p = vec![
        [0.0, -0.0, tiny, 0.0],
        [-0.0, 0.0, -tiny, 0.0],
        [0.0, f32::INFINITY, 0.0, 0.0],
        [f32::NEG_INFINITY, 0.0, 0.0, 0.0],
    ];
    check(gpu, "zeros", &p);
    let b = reduce::bounds_reduce(&p, Backend::Gpu(gpu))
        .unwrap()
        .unwrap();
    assert_eq!(b.min.x, f32::NEG_INFINITY);
    assert_eq!(b.min.y.to_bits(), (-0.0f32).to_bits());
    assert_eq!(b.max.x.to_bits(), 0.0f32.to_bits());
    assert_eq!(b.max.y, f32::INFINITY);
    assert_eq!((b.min.z, b.max.z), (-tiny, tiny));
}

#[test]
fn nan_and_empty() {
    let Some(gpu) = common::gpu() else { return };
    for backend in [Backend::Cpu, Backend::Gpu(gpu)] {
        assert_eq!(reduce::bounds_reduce(&[], backend).unwrap(), None);
        let mut p = random_positions(3, 1000, 1.0);
        p[500][1] = f32::NAN;
        assert!(matches!(
            reduce::bounds_reduce(&p, backend),
            Err(Error::InvalidParameter { ref value, .. }) if value == "NaN"
        ));
        p[500][1] = -f32::NAN;
        assert!(matches!(
            reduce::bounds_reduce(&p, backend),
            Err(Error::InvalidParameter { ref value, .. }) if value == "NaN"
        ));
    }
}

#[test]
fn chunked_over_binding_limit() {
    // 4 KiB bindings: 256 positions per chunk, so 20_000 span 79 chunks.
    let Some(base) = common::gpu() else { return };
    // The test device seen with 4 KiB bindings (no second device).
    let gpu = base.view(Some(4096), false);
    let p = random_positions(99, 20_000, 50.0);
    assert!(chisel::gpu::chunk_ranges(p.len(), 16, gpu.max_binding_bytes()).len() > 1);
    let want = reduce::bounds_reduce(&p, Backend::Cpu).unwrap().unwrap();
    let got = reduce::bounds_reduce(&p, Backend::Gpu(&gpu))
        .unwrap()
        .unwrap();
    assert_bits_eq("chunked", want, got);
}

#[test]
fn real_meshes() {
    // Boxes from ../shared/data/README.md (6 significant digits there).
    let cases: [(&str, [f32; 3], [f32; 3]); 3] = [
        (
            "fran_cut.vtk",
            [0.0, -0.2048, -0.118986],
            [0.1056, -0.0512003, 0.00411239],
        ),
        (
            "bunny.ply",
            [-0.0946899, 0.0329874, -0.0618736],
            [0.0610091, 0.187321, 0.0587997],
        ),
        (
            "fsu/footbones.ply",
            [-5.63324, -1.86044, -2.12503],
            [5.63321, 1.86044, 2.12566],
        ),
    ];
    for (rel, lo, hi) in cases {
        let Some(mesh) = common::real_mesh(rel) else {
            return;
        };
        let Some(gpu) = common::gpu() else { return };
        let p = positions(&mesh);
        check(gpu, rel, &p);
        let b = reduce::mesh_bounds(&mesh, Backend::Gpu(gpu))
            .unwrap()
            .unwrap();
        let readme = Tolerance {
            abs: 0.0,
            rel: 1e-5,
        };
        compare_vec(
            &format!("bounds_reduce/{rel}/readme"),
            &[lo, hi],
            &[b.min.to_array(), b.max.to_array()],
            readme,
        )
        .unwrap_or_else(|m| panic!("{m}"));
    }
}

#[test]
fn negative_control() {
    let Some(gpu) = common::gpu() else { return };
    let p = random_positions(5, 50_000, 1.0);
    let buffers = BoundsBuffers::new(gpu, &p).unwrap();
    let mut encoder = gpu.encoder("bounds_reduce");
    buffers.record(gpu, &mut encoder).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let mut got = buffers.pass_outputs(gpu).unwrap().swap_remove(0);
    let want: Vec<[u32; 4]> = cpu::bounds_pass_positions(&p)
        .into_iter()
        .flatten()
        .collect();
    compare_exact("bounds_reduce/control", &want, &got).unwrap();
    let k = 7;
    got[k][2] ^= 1;
    let m = compare_exact("bounds_reduce/control", &want, &got).unwrap_err();
    assert_eq!((m.index, m.count), (k, 1), "{m}");
}
