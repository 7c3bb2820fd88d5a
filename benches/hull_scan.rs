//! Inside-hull scan benchmarks (SPEC §4.3): a ball of radius r voxels in an
//! n³ box (r = 100 in 256³, r = 200 in 512³), enclosed by its 1154 tangent
//! planes in the primitive integer directions with components in −5..=5
//! (many faces, as hulls of big digital balls have), and the exact hull of
//! a smooth random blob in the same box (`blob_N`, `chisel phantom blob
//! --n N --seed 1`). Groups, in voxels/s:
//! `hull_scan/cpu_rows` (row spans), `hull_scan/cpu_classify` (spans + side
//! codes: the "512³ in under 1 s" target), `hull_scan/cpu_rows_culled`
//! (blobs: each layer scans only the faces meeting it), `hull_scan/cpu_brute` (every
//! voxel × every face; 128³ and below), `hull_scan/gpu_rows_{int64,i32x2}`,
//! `hull_scan/gpu_rows_culled_{int64,i32x2}` (blobs: per layer the list of
//! faces meeting it) and `hull_scan/gpu_brute_{int64,i32x2}` (upload +
//! dispatch + readback; brute force only up to 64³ on software adapters).
//! `CHISEL_BENCH_QUICK=1`: 64³ and 128³ boxes, few samples.

use std::hint::black_box;
use std::time::Duration;

use chisel::Backend;
use chisel::gpu::{Gpu, GpuOptions};
use chisel::hull::{ConvexHull, HullOptions};
use chisel::hull_scan::gpu::{Arithmetic, HullScanInput};
use chisel::hull_scan::{self, HalfSpace, VoxelBox};
use chisel::phantom::voxel::blob;
use chisel::voxel::{CandidateKind, Component, DigitalObject, Selection};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

#[path = "common/mod.rs"]
mod bench_common;
use bench_common::quick;

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 { a.abs() } else { gcd(b, a % b) }
}

/// Tangent planes of the ball of combinatorial centre `(n, n, n)` (a cell
/// corner at the box centre) and radius `2r`: `u·p ≤ u·c + ⌊2r·|u|⌋` for
/// every primitive `u` with components in −k..=k (exact integer sqrt).
fn ball_faces(n: usize, r: i64, k: i64) -> Vec<HalfSpace> {
    let c = n as i64;
    let mut out = Vec::new();
    for a in -k..=k {
        for b in -k..=k {
            for d in -k..=k {
                if (a, b, d) == (0, 0, 0) || gcd(gcd(a, b), d) != 1 {
                    continue;
                }
                let norm2 = (a * a + b * b + d * d) as u128;
                let reach = (4 * (r as u128) * (r as u128) * norm2).isqrt() as i64;
                out.push(HalfSpace {
                    normal: [a, b, d],
                    offset: (a + b + d) * c + reach,
                });
            }
        }
    }
    out
}

/// (label, n, half-spaces, face z ranges): the tangent-plane balls, then
/// the exact hull of a smooth random blob (`chisel phantom blob`) in the
/// same n³ box, with its faces' z ranges for the culled scan.
type Case = (String, usize, Vec<HalfSpace>, Option<Vec<[i64; 2]>>);

fn cases() -> Vec<Case> {
    let sizes: &[(usize, i64)] = if quick() {
        &[(64, 25), (128, 50)]
    } else {
        &[(256, 100), (512, 200)]
    };
    let mut out: Vec<Case> = sizes
        .iter()
        .map(|&(n, r)| (n.to_string(), n, ball_faces(n, r, 5), None))
        .collect();
    for &(n, _) in sizes {
        let v = blob(n as u32, 1).expect("blob");
        let o = DigitalObject::from_volume(&v, Selection::Threshold(1.0), Component::Largest)
            .expect("blob object");
        let h = ConvexHull::of_object(&o, CandidateKind::Local26, HullOptions::default())
            .expect("blob hull");
        let faces = h.half_spaces().into_iter().map(HalfSpace::from).collect();
        out.push((format!("blob_{n}"), n, faces, Some(h.face_z_extents())));
    }
    out
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("hull_scan");
    if quick() {
        g.sample_size(10)
            .warm_up_time(Duration::from_millis(200))
            .measurement_time(Duration::from_secs(1));
    } else {
        g.sample_size(10).measurement_time(Duration::from_secs(5));
    }
    let gpus: Vec<(Gpu, &str)> = [(false, "int64"), (true, "i32x2")]
        .into_iter()
        .filter_map(|(portable, name)| {
            let gpu = Gpu::with_options(GpuOptions {
                portable,
                ..Default::default()
            })
            .ok()?;
            let want = if portable {
                Arithmetic::I32x2
            } else {
                Arithmetic::Int64
            };
            (Arithmetic::of(&gpu) == want).then_some((gpu, name))
        })
        .collect();
    match gpus.first() {
        Some((gpu, _)) => eprintln!("adapter: {}", gpu.describe()),
        None => eprintln!("no adapter: CPU only"),
    }
    let software = gpus.first().is_some_and(|(g, _)| g.is_software());
    for (label, n, faces, extents) in cases() {
        let bbox = VoxelBox {
            origin: [0; 3],
            dims: [n; 3],
        };
        let voxels = (n * n * n) as u64;
        eprintln!("box {n}³, {label}: {} faces", faces.len());
        g.throughput(Throughput::Elements(voxels));
        g.bench_with_input(BenchmarkId::new("cpu_rows", &label), &n, |b, _| {
            b.iter(|| hull_scan::row_spans(black_box(&faces), &bbox, Backend::Cpu).unwrap())
        });
        g.bench_with_input(BenchmarkId::new("cpu_classify", &label), &n, |b, _| {
            b.iter(|| hull_scan::classify(black_box(&faces), &bbox, Backend::Cpu).unwrap())
        });
        if let Some(extents) = &extents {
            g.bench_with_input(BenchmarkId::new("cpu_rows_culled", &label), &n, |b, _| {
                b.iter(|| {
                    hull_scan::row_spans_culled(black_box(&faces), extents, &bbox, Backend::Cpu)
                        .unwrap()
                })
            });
        }
        // Brute force is ~100× slower than rows: 256³ on 2 cores takes a minute.
        if n <= 128 {
            g.bench_with_input(BenchmarkId::new("cpu_brute", &label), &n, |b, _| {
                b.iter(|| {
                    hull_scan::classify_voxels(black_box(&faces), &bbox, Backend::Cpu).unwrap()
                })
            });
        }
        for (gpu, name) in &gpus {
            let arith = Arithmetic::of(gpu);
            g.bench_with_input(
                BenchmarkId::new(format!("gpu_rows_{name}"), &label),
                &n,
                |b, _| {
                    b.iter(|| {
                        HullScanInput::upload(gpu, black_box(&faces), &bbox)
                            .and_then(|i| i.rows(gpu, arith))
                            .unwrap()
                    })
                },
            );
            if let Some(extents) = &extents {
                g.bench_with_input(
                    BenchmarkId::new(format!("gpu_rows_culled_{name}"), &label),
                    &n,
                    |b, _| {
                        b.iter(|| {
                            HullScanInput::upload(gpu, black_box(&faces), &bbox)
                                .and_then(|i| i.culled(extents))
                                .and_then(|i| i.rows(gpu, arith))
                                .unwrap()
                        })
                    },
                );
            }
            if !software || n <= 64 {
                g.bench_with_input(
                    BenchmarkId::new(format!("gpu_brute_{name}"), &label),
                    &n,
                    |b, _| {
                        b.iter(|| {
                            HullScanInput::upload(gpu, black_box(&faces), &bbox)
                                .and_then(|i| i.scan(gpu, arith))
                                .unwrap()
                        })
                    },
                );
            }
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
