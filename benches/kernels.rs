//! Kernel benches: one criterion group per kernel, each with `<k>/cpu` (the
//! mirror), `<k>/gpu_end_to_end` (upload + dispatch + readback) and
//! `<k>/gpu_resident` (record + dispatch + wait on uploaded buffers).
//! Throughput is reported in elements and in the bytes each kernel must
//! move through memory at least once (the memory-traffic bound: bytes /
//! time = effective GB/s).
//!
//! `CHISEL_BENCH_QUICK=1`: tiny sizes and sample counts, for CI smoke runs.
//! The adapter comes from `CHISEL_ADAPTER` and is printed first; without
//! one only the CPU benches run.

#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Duration;

use chisel::gpu::Gpu;
use chisel::vertex_normals::{self, NormalsInput};
use chisel::{exclusive_scan, reduce};
use criterion::{BenchmarkGroup, BenchmarkId, Criterion, Throughput, measurement::WallTime};

#[path = "common/mod.rs"]
mod bench_common;
use bench_common::quick;

/// Bunny-sized and ~4 M (quick: tiny).
fn sizes() -> Vec<usize> {
    if quick() {
        vec![4_096]
    } else {
        vec![35_947, 1 << 22]
    }
}

fn group<'a>(c: &'a mut Criterion, name: &str) -> BenchmarkGroup<'a, WallTime> {
    let mut g = bench_common::group(c, name);
    if !quick() {
        g.sample_size(20)
            .warm_up_time(Duration::from_millis(500))
            .measurement_time(Duration::from_secs(3));
    }
    g
}

fn xorshift(seed: u64) -> impl FnMut() -> u64 {
    let mut s = seed.max(1);
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

fn random_f32(seed: u64, n: usize) -> Vec<f32> {
    let mut next = xorshift(seed);
    (0..n)
        .map(|_| (next() >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0)
        .collect()
}

fn run_resident(gpu: &Gpu, label: &str, record: impl Fn(&mut wgpu::CommandEncoder)) {
    let mut encoder = gpu.encoder(label);
    record(&mut encoder);
    gpu.submit_and_wait(encoder).expect("submit");
}

fn bench_vertex_normals(c: &mut Criterion, gpu: Option<&Gpu>) {
    let mut g = group(c, "vertex_normals");
    // icosphere(6): 40_962 vertices (bunny-sized); icosphere(8): 655_362
    // vertices, 1.31 M triangles.
    let levels: &[u32] = if quick() { &[3] } else { &[6, 8] };
    for &level in levels {
        let mesh = common::icosphere(level);
        let input = NormalsInput::new(&mesh);
        let (nv, nf) = (mesh.n_vertices() as u64, mesh.n_triangles() as u64);
        // positions 16 B + offsets 4 B + normals 16 B per vertex; indices
        // 12 B + three adjacency entries 12 B per triangle.
        g.throughput(Throughput::ElementsAndBytes {
            elements: nv,
            bytes: 36 * nv + 24 * nf,
        });
        g.bench_with_input(BenchmarkId::new("cpu", nv), &input, |b, i| {
            b.iter(|| vertex_normals::cpu::vertex_normals(i))
        });
        if let Some(gpu) = gpu {
            g.bench_with_input(BenchmarkId::new("gpu_end_to_end", nv), &input, |b, i| {
                b.iter(|| vertex_normals::gpu::vertex_normals(gpu, i).expect("gpu"))
            });
            let buffers = vertex_normals::gpu::NormalsBuffers::upload(gpu, &input).expect("upload");
            g.bench_function(BenchmarkId::new("gpu_resident", nv), |b| {
                b.iter(|| {
                    run_resident(gpu, "vertex_normals", |e| {
                        buffers.record(gpu, e).expect("record")
                    })
                })
            });
        }
    }
    g.finish();
}

fn bench_bounds_reduce(c: &mut Criterion, gpu: Option<&Gpu>) {
    let mut g = group(c, "bounds_reduce");
    for n in sizes() {
        let xs = random_f32(n as u64, 3 * n);
        let p: Vec<[f32; 4]> = xs.chunks(3).map(|c| [c[0], c[1], c[2], 0.0]).collect();
        g.throughput(Throughput::ElementsAndBytes {
            elements: n as u64,
            bytes: 16 * n as u64,
        });
        g.bench_with_input(BenchmarkId::new("cpu", n), &p, |b, p| {
            b.iter(|| reduce::cpu::bounds_reduce(p))
        });
        if let Some(gpu) = gpu {
            g.bench_with_input(BenchmarkId::new("gpu_end_to_end", n), &p, |b, p| {
                b.iter(|| reduce::gpu::bounds_reduce(gpu, p).expect("gpu"))
            });
            let buffers = reduce::gpu::BoundsBuffers::new(gpu, &p).expect("upload");
            g.bench_function(BenchmarkId::new("gpu_resident", n), |b| {
                b.iter(|| {
                    run_resident(gpu, "bounds_reduce", |e| {
                        buffers.record(gpu, e).expect("record")
                    })
                })
            });
        }
    }
    g.finish();
}

fn bench_range_reduce(c: &mut Criterion, gpu: Option<&Gpu>) {
    let mut g = group(c, "range_reduce");
    for n in sizes() {
        let s = random_f32(n as u64 + 7, n);
        g.throughput(Throughput::ElementsAndBytes {
            elements: n as u64,
            bytes: 4 * n as u64,
        });
        g.bench_with_input(BenchmarkId::new("cpu", n), &s, |b, s| {
            b.iter(|| reduce::cpu::range_reduce(s))
        });
        if let Some(gpu) = gpu {
            g.bench_with_input(BenchmarkId::new("gpu_end_to_end", n), &s, |b, s| {
                b.iter(|| reduce::gpu::range_reduce(gpu, s).expect("gpu"))
            });
            let buffers = reduce::gpu::RangeBuffers::new(gpu, &s).expect("upload");
            g.bench_function(BenchmarkId::new("gpu_resident", n), |b| {
                b.iter(|| {
                    run_resident(gpu, "range_reduce", |e| {
                        buffers.record(gpu, e).expect("record")
                    })
                })
            });
        }
    }
    g.finish();
}

fn bench_exclusive_scan(c: &mut Criterion, gpu: Option<&Gpu>) {
    let mut g = group(c, "exclusive_scan");
    for n in sizes() {
        let mut next = xorshift(n as u64 + 3);
        let v: Vec<u32> = (0..n).map(|_| (next() % 16) as u32).collect();
        // Blocks read and write 4 B per element, the add pass again.
        g.throughput(Throughput::ElementsAndBytes {
            elements: n as u64,
            bytes: 16 * n as u64,
        });
        g.bench_with_input(BenchmarkId::new("cpu", n), &v, |b, v| {
            b.iter(|| exclusive_scan::cpu::exclusive_scan(v))
        });
        if let Some(gpu) = gpu {
            g.bench_with_input(BenchmarkId::new("gpu_end_to_end", n), &v, |b, v| {
                b.iter(|| exclusive_scan::gpu::exclusive_scan(gpu, v).expect("gpu"))
            });
            let buffers = exclusive_scan::gpu::ScanBuffers::upload(gpu, &v).expect("upload");
            g.bench_function(BenchmarkId::new("gpu_resident", n), |b| {
                b.iter(|| {
                    run_resident(gpu, "exclusive_scan", |e| {
                        buffers.record(gpu, e).expect("record")
                    })
                })
            });
        }
    }
    g.finish();
}

fn main() {
    let gpu = bench_common::gpu();
    let mut c = Criterion::default().configure_from_args();
    bench_vertex_normals(&mut c, gpu.as_ref());
    bench_bounds_reduce(&mut c, gpu.as_ref());
    bench_range_reduce(&mut c, gpu.as_ref());
    bench_exclusive_scan(&mut c, gpu.as_ref());
    c.final_summary();
}
