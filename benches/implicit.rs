//! Implicit-surface benches (issue "Skeletal implicit surfaces"): the
//! kernels `implicit_field`, `particle_update` and `network_update` on the
//! 100-primitive blobby molecule at 10⁴, 10⁵ and 10⁶ samples, CPU and GPU
//! in one run, and the animated network's frame rate (one frame = the
//! default 4 transport + 8 relaxation iterations with remeshing and
//! surgery, and the manifold check) at 10⁴ and 10⁵ triangles.
//!
//! Throughput: elements (points, particles, vertices) per second; the GPU
//! figures include the upload and the read-back (`gpu_end_to_end`).
//! `CHISEL_BENCH_QUICK=1` (and `cargo test`): 10³ samples, frames at 10³.

use chisel::gpu::Backend;
use chisel::implicit::field::{FieldInput, implicit_field};
use chisel::implicit::scene::EXAMPLES;
use chisel::implicit::{Scene, grid};
use chisel::particles::animate::start_network;
use chisel::particles::network::{NetworkInput, NetworkParams, network_update};
use chisel::particles::wh::{Sampler, StepInput, UpdateParams, particle_update, sigma_for_spacing};
use chisel::particles::{CellList, NetworkOptions, Particles, WhOptions};
use criterion::{BenchmarkId, Criterion, Throughput};

#[path = "common/mod.rs"]
mod bench_common;
use bench_common::{group, quick};

fn example(name: &str) -> Scene {
    Scene::from_toml_str(EXAMPLES.iter().find(|e| e.0 == name).unwrap().1, name).unwrap()
}

fn sizes() -> Vec<usize> {
    if quick() {
        vec![1_000]
    } else {
        vec![10_000, 100_000, 1_000_000]
    }
}

/// The hexagonal spacing of `n` particles on the surface at `t`, and the
/// marching-cubes lattice spacing whose mesh has about `n` vertices there.
fn spacings_for(scene: &Scene, t: f64, n: usize) -> (f64, f64) {
    let h0 = 0.05;
    let s = grid::marching_cubes(&scene.pose(t), h0, Backend::Cpu).unwrap();
    let area: f64 = s.groups.iter().map(|g| g.area).sum();
    let count = s.mesh.positions.len() as f64;
    (
        (2.0 * area / (3f64.sqrt() * n as f64)).sqrt(),
        h0 * (count / n as f64).sqrt(),
    )
}

fn benches(c: &mut Criterion) {
    let scene = example("molecule");
    let pose = scene.pose(0.5);
    let field = FieldInput::new(&pose).unwrap();
    let gpu = bench_common::gpu();
    let mut backends: Vec<(&'static str, Backend<'_>)> = vec![("cpu", Backend::Cpu)];
    if let Some(g) = &gpu {
        // Upload, dispatch and read-back each time.
        backends.push(("gpu_end_to_end", Backend::Gpu(g)));
    }
    for n in sizes() {
        let (r, h) = spacings_for(&scene, 0.5, n);
        let opts = WhOptions::default();
        let sh = sigma_for_spacing(r, &opts);
        let mc = grid::marching_cubes(&pose, h, Backend::Cpu).unwrap();
        let particles = Particles::new(&mc.mesh.positions, sh as f32);
        let positions = particles.positions();
        let cells = CellList::build(&positions, 3.3 * sh as f32, 0.5 * sh as f32).unwrap();
        let flat = cells.flat();
        let points: Vec<[f32; 4]> = particles.points.clone();
        let count = points.len() as u64;
        {
            let mut g = group(c, "implicit_field");
            g.throughput(Throughput::Elements(count));
            for &(name, b) in &backends {
                g.bench_function(BenchmarkId::new(name, count), |bench| {
                    bench.iter(|| implicit_field(&field, &points, b).unwrap())
                });
            }
        }
        {
            let u = UpdateParams {
                nx: cells.dims.x,
                ny: cells.dims.y,
                nz: cells.dims.z,
                n_particles: points.len() as u32,
                n_cells: (cells.starts.len() - 1) as u32,
                dt: 0.25 / 6.0,
                delta: 0.0,
                kappa: 0.5,
                alpha: 6.0,
                e_hat: 4.8,
                rho_sigma: 15.0,
                beta_sigma: (6.0 / sh) as f32,
                sigma_lo: 0.1 * sh as f32,
                sigma_hi: 2.0 * sh as f32,
                g_min2: 1e-8,
                adapt: 1,
            };
            let input = StepInput {
                params: u,
                cells: &flat,
                positions: &points,
            };
            let mut g = group(c, "particle_update");
            g.throughput(Throughput::Elements(count));
            for &(name, b) in &backends {
                g.bench_function(BenchmarkId::new(name, count), |bench| {
                    bench.iter(|| particle_update(&field, &input, b).unwrap())
                });
            }
        }
        {
            let (_, h) = spacings_for(&scene, 0.0, n);
            let net = start_network(&scene, h, NetworkOptions::default(), Backend::Cpu).unwrap();
            let r = h;
            let (offsets, springs) = net.springs();
            let pos: Vec<[f32; 4]> = net.positions.iter().map(|p| [p.x, p.y, p.z, 0.0]).collect();
            let input = NetworkInput {
                params: NetworkParams {
                    n_vertices: pos.len() as u32,
                    dt: 0.2,
                    delta: 0.0,
                    kappa: 0.5,
                    rho: 1.0,
                    g_min2: 1e-8,
                    step_max: 0.5 * r as f32,
                },
                offsets: &offsets,
                springs: &springs,
                positions: &pos,
            };
            let mut g = group(c, "network_update");
            g.throughput(Throughput::Elements(pos.len() as u64));
            for &(name, b) in &backends {
                g.bench_function(BenchmarkId::new(name, pos.len()), |bench| {
                    bench.iter(|| network_update(&field, &input, b).unwrap())
                });
            }
        }
    }
    converge(c);
    // Frames of the animated network (moving scene, remeshing, surgery, check).
    let frame_sizes: &[usize] = if quick() {
        &[1_000]
    } else {
        &[10_000, 100_000]
    };
    let mut g = group(c, "network_frame");
    for &triangles in frame_sizes {
        let (_, h) = spacings_for(&scene, 0.0, triangles / 2);
        let net = start_network(&scene, h, NetworkOptions::default(), Backend::Cpu).unwrap();
        g.throughput(Throughput::Elements(1));
        g.bench_function(BenchmarkId::new("cpu", net.triangles.len()), |bench| {
            bench.iter_batched(
                || net.clone(),
                |mut net| {
                    let opts = net.opts;
                    for k in 0..opts.transport + opts.relax {
                        let t = 0.5
                            + 0.01 * f64::from(k.min(opts.transport)) / f64::from(opts.transport);
                        let f = FieldInput::new(&scene.pose(t)).unwrap();
                        let delta = if k < opts.transport {
                            0.01 / opts.transport as f32
                        } else {
                            0.0
                        };
                        net.iterate(&f, delta, Backend::Cpu).unwrap();
                        net.surgery(&f);
                    }
                    net.check().unwrap();
                    net
                },
                criterion::BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

/// Witkin–Heckbert relaxation to the stopping rule (residual ≤ 1e-4 of the
/// diagonal, energy change ≤ 1e-6 per step) of about 5,000 particles on the
/// dumbbell at t = 0, from its marching-cubes vertices; the iterations are
/// printed once.
fn converge(c: &mut Criterion) {
    let n = if quick() { 500 } else { 5_000 };
    let scene = example("dumbbell");
    let pose = scene.pose(0.0);
    let field = FieldInput::new(&pose).unwrap();
    let opts = WhOptions::default();
    let sh = sigma_for_spacing(spacings_for(&scene, 0.0, n).0, &opts);
    let start = Particles::on_surface(&pose, sh, Backend::Cpu).unwrap();
    let run = || {
        let mut s = Sampler::new(start.clone(), sh, opts, &field).unwrap();
        (
            s.relax(&field, 3000, Backend::Cpu).unwrap(),
            s.particles.len(),
        )
    };
    let (r, count) = run();
    eprintln!(
        "particles_converge: {} → {count} particles, {} + {} iterations, converged {}",
        start.len(),
        r.adapt_iterations,
        r.settle_iterations,
        r.converged
    );
    let mut g = group(c, "particles_converge");
    g.bench_function(BenchmarkId::new("cpu", count), |bench| bench.iter(run));
    g.finish();
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    benches(&mut c);
    c.final_summary();
}
