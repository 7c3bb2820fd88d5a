//! Fusion benches (issue "Volume-preserving fusion … blobby models"): the
//! kernel `ray_cast` against icospheres of 82k and 1.3M triangles (10⁶ rays
//! from an off-centre interior point; 10⁵–10⁶-triangle meshes), CPU and
//! GPU in one run, throughput in rays per second, the GPU end to end
//! (direction upload, dispatch, read-back; the BVH stays resident); and
//! the fusion of two 82k-triangle spheres to a relative volume error of
//! about 10⁻⁴ (tolerance 8·10⁻⁵), end to end on each backend. Kernel
//! `ray_hits` (after `ray_cast`'s counts) lists every hit of 10⁶ rays
//! through three nested 82k-triangle spheres; the layered fusion of a
//! torus and a sphere on a 128-cell grid.
//!
//! `CHISEL_BENCH_QUICK=1` (and `cargo test`): a 1,280-triangle sphere,
//! 10³ rays, a coarse fusion.

use chisel::TriMesh;
use chisel::fusion::{FuseOptions, RefineOptions, fuse};
use chisel::gpu::Backend;
use chisel::ray_cast::{Bvh, RayCaster};
use criterion::{BenchmarkId, Criterion, Throughput};
use glam::Vec3;

#[path = "common/mod.rs"]
mod bench_common;
use bench_common::{group, quick};

#[path = "../tests/common/mod.rs"]
mod common;

fn sphere(level: u32, r: f32, at: Vec3) -> TriMesh {
    let mut m = common::icosphere(level);
    for p in &mut m.positions {
        *p = *p * r + at;
    }
    m
}

fn benches(c: &mut Criterion) {
    let gpu = bench_common::gpu();
    let mut backends: Vec<(&'static str, Backend<'_>)> = vec![("cpu", Backend::Cpu)];
    if let Some(g) = &gpu {
        backends.push(("gpu_end_to_end", Backend::Gpu(g)));
    }
    let (levels, n_rays): (&[u32], usize) = if quick() {
        (&[3], 1_000)
    } else {
        (&[6, 8], 1_000_000)
    };
    let dirs: Vec<[f32; 4]> = common::fibonacci_sphere(n_rays)
        .iter()
        .map(|d| {
            let d = d.as_vec3();
            [d.x, d.y, d.z, 0.0]
        })
        .collect();
    let origin = Vec3::new(0.21, -0.13, 0.07);
    for &level in levels {
        let mesh = sphere(level, 1.0, Vec3::ZERO);
        let bvh = Bvh::build(&mesh).unwrap();
        let mut g = group(c, "ray_cast");
        g.throughput(Throughput::Elements(n_rays as u64));
        for &(name, b) in &backends {
            let caster = RayCaster::new(&bvh, b).unwrap();
            g.bench_function(
                BenchmarkId::new(name, format!("{}tri", mesh.n_triangles())),
                |bench| bench.iter(|| caster.cast(origin, &dirs).unwrap()),
            );
        }
        g.finish();
    }
    // ray_hits: three nested spheres, three hits per ray, listed (the
    // counting walk of ray_cast, the host scan, the listing walk).
    let level = levels[0];
    let mut shells = TriMesh::default();
    for r in [1.0, 1.5, 2.0] {
        let s = sphere(level, r, Vec3::ZERO);
        let n = shells.positions.len() as u32;
        shells.positions.extend(&s.positions);
        shells
            .triangles
            .extend(s.triangles.iter().map(|t| t.map(|v| v + n)));
    }
    let bvh = Bvh::build(&shells).unwrap();
    let mut g = group(c, "ray_hits");
    g.throughput(Throughput::Elements(n_rays as u64));
    for &(name, b) in &backends {
        let caster = RayCaster::new(&bvh, b).unwrap();
        g.bench_function(
            BenchmarkId::new(name, format!("{}tri", shells.n_triangles())),
            |bench| bench.iter(|| caster.hits(origin, &dirs).unwrap()),
        );
    }
    g.finish();

    let (level, tolerance) = if quick() { (3, 2e-3) } else { (6, 8e-5) };
    let a = sphere(level, 1.0, Vec3::ZERO);
    let b = sphere(level, 0.7, Vec3::new(0.8, 0.1, 0.0));
    let options = FuseOptions {
        refine: RefineOptions {
            tolerance: Some(tolerance),
            ..RefineOptions::default()
        },
        ..FuseOptions::default()
    };
    let mut g = group(c, "fusion");
    for &(name, backend) in &backends {
        let id = BenchmarkId::new(name, format!("2x{}tri", a.n_triangles()));
        g.bench_function(id, |bench| {
            bench.iter(|| fuse(&a, &b, &options, backend, |_| {}).unwrap())
        });
    }
    g.finish();

    // The layered fusion (seed 001 §2.6.2): a torus (not star-shaped) and
    // a sphere, on a grid of 128 cells along C's longest side.
    let cells = if quick() { 24 } else { 128 };
    let torus = common::torus(1.0, 0.35, 96, 32);
    let ball = sphere(4, 0.5, Vec3::new(1.0, 0.0, 0.0));
    let options = FuseOptions {
        cells,
        ..FuseOptions::default()
    };
    let mut g = group(c, "fusion_layered");
    for &(name, backend) in &backends {
        let id = BenchmarkId::new(name, format!("torus_sphere_{cells}cells"));
        g.bench_function(id, |bench| {
            bench.iter(|| fuse(&torus, &ball, &options, backend, |_| {}).unwrap())
        });
    }
    g.finish();
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    benches(&mut c);
    c.final_summary();
}
