//! Marching cubes: the CT head (500, 1150) and generated head-like phantoms
//! (256³, 512³), CPU and GPU in the same run, voxels/s. The CPU path reads
//! every sample once in its native type; each case prints that read
//! volume (bytes per voxel) and the sample bandwidth it implies, the bound
//! a memory-bound pass would hit. On a software adapter (lavapipe, ~1 M
//! voxels/s) the GPU runs only the CT head.
//!
//! `gpu_kernels` (printed, median of 5 runs) is the three kernels' time on
//! the GPU clock (timestamp queries; samples resident, no uploads or
//! readbacks), in total and per kernel: the kernels themselves, next to
//! `gpu_end_to_end`.
//!
//! `forest/*` times [`Forest::build`] alone (the tree that
//! `marching_cubes` builds beside the group figures), and
//! `vertex_components/*` the grouping that finishes the GPU path on the
//! host (vertex-connected components of the triangles).
//!
//! `CHISEL_BENCH_QUICK=1`: few samples, phantoms of 64³/128³ (CI smoke run).

use std::time::{Duration, Instant};

use chisel::Backend;
use chisel::foundation::{Forest, vertex_components};
use chisel::gpu::Gpu;
use chisel::mc::{Field, IsoSpec, LEAF_BLOCK, McOptions, gpu, marching_cubes};
use criterion::{Criterion, Throughput};

#[path = "common/mod.rs"]
mod bench_common;
use bench_common::{head_phantom, quick};

fn main() {
    let mut c = Criterion::default().configure_from_args();
    if quick() {
        c = c
            .sample_size(10)
            .warm_up_time(Duration::from_millis(200))
            .measurement_time(Duration::from_secs(1));
    } else {
        c = c.sample_size(10).measurement_time(Duration::from_secs(10));
    }
    let gpu = Gpu::new().ok();
    match &gpu {
        Some(g) => eprintln!("adapter: {}", g.describe()),
        None => eprintln!("adapter: none (GPU benches skipped)"),
    }
    let software = gpu.as_ref().is_some_and(|g| g.is_software());
    let mut cases: Vec<(String, chisel::Volume, f32)> = Vec::new();
    let head =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/headsq/quarter.nhdr");
    if let Ok(v) = chisel::io::read_volume(&head) {
        cases.push(("headsq_500".into(), v.clone(), 500.0));
        cases.push(("headsq_1150".into(), v, 1150.0));
    }
    let sizes: &[usize] = if quick() { &[64, 128] } else { &[256, 512] };
    for &n in sizes {
        cases.push((format!("phantom_{n}_bone"), head_phantom(n), 1300.0));
    }
    let opts = McOptions {
        close_border: true,
        ..McOptions::default()
    };
    let mut group = c.benchmark_group("mc");
    for (name, vol, level) in &cases {
        let voxels = vol.len() as u64;
        group.throughput(Throughput::Elements(voxels));
        let iso = IsoSpec::Level(*level);
        let cpu_s = median(|| {
            marching_cubes(vol, iso, &opts, Backend::Cpu).map(|s| s.mesh.triangles.len())
        });
        let tris = marching_cubes(vol, iso, &opts, Backend::Cpu)
            .map(|s| s.mesh.triangles.len())
            .unwrap_or(0);
        let bytes = vol.data.scalar_type().size();
        eprintln!(
            "mc/{name}: {voxels} voxels, {tris} triangles; cpu {:.1} ms = {:.1} M voxels/s \
             (reads {bytes} B/voxel = {:.2} GB/s of samples; {} threads)",
            cpu_s * 1e3,
            voxels as f64 / cpu_s / 1e6,
            (voxels * bytes as u64) as f64 / cpu_s / 1e9,
            rayon::current_num_threads()
        );
        group.bench_function(format!("cpu/{name}"), |b| {
            b.iter(|| marching_cubes(vol, iso, &opts, Backend::Cpu))
        });
        if let Ok(s) = marching_cubes(vol, iso, &opts, Backend::Cpu) {
            let cells = s.grid.dims.map(|d| d - 1);
            let n_groups = s.groups.len();
            let build = || {
                Forest::build(
                    s.mesh.view(),
                    &s.triangle_cells,
                    cells,
                    LEAF_BLOCK,
                    &s.triangle_groups,
                    n_groups,
                )
            };
            // Only the marching-cubes entry knows the surface is closed and
            // wound outward; the rest of the forest must be the same.
            let same = |f: Forest| {
                Forest {
                    closed_outward: s.forest.closed_outward,
                    ..f
                } == s.forest
            };
            if same(build()) {
                group.bench_function(format!("forest/{name}"), |b| b.iter(build));
            } else {
                eprintln!("mc/{name}: forest skipped (differs from marching_cubes')");
            }
            group.bench_function(format!("vertex_components/{name}"), |b| {
                b.iter(|| vertex_components(s.mesh.n_vertices(), &s.mesh.triangles))
            });
        }
        if software && voxels > 1 << 22 {
            eprintln!("mc/{name}: gpu skipped on a software adapter");
            continue;
        }
        if let Some(g) = &gpu {
            let gpu_s = median(|| {
                marching_cubes(vol, iso, &opts, Backend::Gpu(g)).map(|s| s.mesh.triangles.len())
            });
            eprintln!(
                "mc/{name}: gpu_end_to_end {:.1} ms = {:.1} M voxels/s (cpu/gpu {:.2})",
                gpu_s * 1e3,
                voxels as f64 / gpu_s / 1e6,
                cpu_s / gpu_s
            );
            group.bench_function(format!("gpu_end_to_end/{name}"), |b| {
                b.iter(|| marching_cubes(vol, iso, &opts, Backend::Gpu(g)))
            });
            // The four kernels alone, on the GPU clock (median of runs; a
            // criterion loop over it would re-run the whole pipeline for
            // every few milliseconds of kernel time).
            if let Ok(field) = Field::new(vol, iso, opts.close_border) {
                let runs = if quick() { 3 } else { 5 };
                let mut k: Vec<[f64; 4]> = (0..runs)
                    .filter_map(|_| gpu::marching_cubes_raw(g, &field).ok()?.kernel_seconds)
                    .collect();
                k.sort_by(|a, b| a.iter().sum::<f64>().total_cmp(&b.iter().sum()));
                if let Some(&[i, c, v, t]) = k.get(k.len() / 2) {
                    let total = i + c + v + t;
                    eprintln!(
                        "mc/{name}: gpu_kernels {:.3} ms = {:.1} M voxels/s (GPU clock, median of \
                         {runs}): inside {:.3}, classify {:.3}, vertices {:.3}, triangles {:.3} ms",
                        total * 1e3,
                        voxels as f64 / total / 1e6,
                        i * 1e3,
                        c * 1e3,
                        v * 1e3,
                        t * 1e3
                    );
                }
            }
        }
    }
    group.finish();
    c.final_summary();
}

/// Median wall time of a few runs, for the ratio line printed next to criterion's figures.
fn median<T, E>(mut f: impl FnMut() -> Result<T, E>) -> f64 {
    let runs = if quick() { 3 } else { 5 };
    let mut t: Vec<f64> = (0..runs)
        .filter_map(|_| {
            let s = Instant::now();
            f().ok().map(|_| s.elapsed().as_secs_f64())
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t.get(t.len() / 2).copied().unwrap_or(f64::NAN)
}
