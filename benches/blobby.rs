//! Blobby-fit benches (issue "Volume-preserving fusion … blobby models"):
//! the kernel `blobby_energy` at 10⁴, 10⁵ and 10⁶ range points × 16 and 256
//! primitives, CPU and GPU in one run, throughput in point–primitive
//! evaluations (energy and gradient) per second, the GPU end to end
//! (upload, dispatch, read-back); and the fit of fran_cut to 32 and 64
//! primitives on the CPU.
//!
//! `CHISEL_BENCH_QUICK=1` (and `cargo test`): 10³ points × 16 primitives,
//! the fit to 4.

use chisel::blobby::energy::{EnergyInput, blobby_energy};
use chisel::blobby::fit::{FitOptions, fit};
use chisel::blobby::{Blob, Model, RangePoints};
use chisel::gpu::Backend;
use criterion::{BenchmarkId, Criterion, Throughput};
use glam::DVec3;

#[path = "common/mod.rs"]
mod bench_common;
use bench_common::{group, quick};

#[path = "../tests/common/mod.rs"]
mod common;

/// `n` primitives spread over the unit ball's surroundings.
fn model(n: usize) -> Model {
    let mut rng = common::xorshift(7);
    let mut u = move || (rng() >> 11) as f64 / (1u64 << 53) as f64;
    Model {
        iso: 0.5,
        blobs: (0..n)
            .map(|_| Blob {
                centre: 1.6 * DVec3::new(u() - 0.5, u() - 0.5, u() - 0.5),
                a: 2.0 + 6.0 * u(),
                b: 0.2 + u(),
            })
            .collect(),
    }
}

fn benches(c: &mut Criterion) {
    let gpu = bench_common::gpu();
    let mut backends: Vec<(&'static str, Backend<'_>)> = vec![("cpu", Backend::Cpu)];
    if let Some(g) = &gpu {
        backends.push(("gpu_end_to_end", Backend::Gpu(g)));
    }
    let (sizes, prims): (&[usize], &[usize]) = if quick() {
        (&[1_000], &[16])
    } else {
        (&[10_000, 100_000, 1_000_000], &[16, 256])
    };
    let weights = FitOptions::default().weights;
    for &m in sizes {
        let p = common::fibonacci_sphere(m);
        let points = RangePoints::new(p.clone(), p).unwrap();
        for &n in prims {
            let input = EnergyInput::new(&model(n), &points, weights).unwrap();
            let mut g = group(c, "blobby_energy");
            g.throughput(Throughput::Elements((m * n) as u64));
            for &(name, b) in &backends {
                g.bench_function(BenchmarkId::new(name, format!("{m}x{n}")), |bench| {
                    bench.iter(|| blobby_energy(&input, b).unwrap())
                });
            }
            g.finish();
        }
    }
    // The fit of fran_cut on the CPU.
    let Some(mesh) = common::real_mesh("fran_cut.vtk") else {
        eprintln!("fran_cut missing: fit bench skipped");
        return;
    };
    let mut points = RangePoints::from_mesh(&mesh).unwrap();
    points.orient_outward();
    let counts: &[usize] = if quick() { &[4] } else { &[32, 64] };
    let mut g = group(c, "blobby_fit");
    for &n in counts {
        let opts = FitOptions {
            primitives: n,
            ..FitOptions::default()
        };
        g.bench_function(BenchmarkId::new("cpu", n), |bench| {
            bench.iter(|| fit(&points, &opts, Backend::Cpu, |_| {}).unwrap())
        });
    }
    g.finish();
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    benches(&mut c);
    c.final_summary();
}
