//! Cutting a ≥ 1M-triangle surface: sequences of plane and sphere knives
//! through the B+ tree forest against a plain scan of every triangle, in
//! the same run (locate phase, and the whole cut with caps).
//!
//! `CHISEL_BENCH_QUICK=1`: a ~100k-triangle surface and few samples.

use std::time::{Duration, Instant};

use chisel::Backend;
use chisel::cut::{CutOptions, Knife, cut, cut_brute_force, locate, locate_brute_force};
use chisel::mc::{IsoSpec, McOptions, marching_cubes};
use chisel::volume::{Volume, VolumeData};
use criterion::{Criterion, Throughput};
use glam::DVec3;

#[path = "common/mod.rs"]
mod bench_common;
use bench_common::quick;

/// A hollow, slightly bumpy ball (bone-like shell) sampled on n³.
fn shell(n: usize) -> Volume {
    let c = (n as f32 - 1.0) / 2.0;
    let (r0, r1) = (0.38 * n as f32, 0.46 * n as f32);
    let mut data = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let (dx, dy, dz) = (x as f32 - c, y as f32 - c, z as f32 - c);
                let d = (dx * dx + dy * dy + dz * dz).sqrt()
                    + 1.5 * (dx * 0.2).sin() * (dy * 0.2).cos();
                data.push((d - r0).min(r1 - d));
            }
        }
    }
    Volume::new([n; 3], [1.0; 3], [0.0; 3], VolumeData::F32(data)).expect("shell dims")
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    c = if quick() {
        c.sample_size(10)
            .warm_up_time(Duration::from_millis(200))
            .measurement_time(Duration::from_secs(1))
    } else {
        c.sample_size(20).measurement_time(Duration::from_secs(5))
    };
    let n = if quick() { 110 } else { 340 };
    let surf = marching_cubes(
        &shell(n),
        IsoSpec::Level(0.0),
        &McOptions {
            close_border: true,
            ..McOptions::default()
        },
        Backend::Cpu,
    )
    .expect("marching cubes");
    let mesh = &surf.mesh;
    let m = mesh.triangles.len();
    let ctr = DVec3::splat((n as f64 - 1.0) / 2.0);
    let r = 0.42 * n as f64;
    let mut knives: Vec<Knife> = (0..8)
        .map(|i| Knife::Plane {
            point: ctr + DVec3::new(0.0, 0.0, (i as f64 - 3.5) * 0.1 * r),
            normal: DVec3::new(0.1 * i as f64, 0.2, 1.0),
        })
        .collect();
    knives.extend((0..4).map(|i| Knife::Sphere {
        centre: ctr
            + DVec3::new(
                r * (0.3 * i as f64).cos(),
                r * (0.3 * i as f64).sin(),
                0.3 * r,
            ),
        radius: 0.25 * r,
    }));
    // Shared machines: the load average says how much to trust the run.
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    eprintln!(
        "cut: surface of {m} triangles, {} groups, {} knives; {} cores, load {}",
        surf.groups.len(),
        knives.len(),
        rayon::current_num_threads(),
        load.split_whitespace()
            .take(3)
            .collect::<Vec<_>>()
            .join(" ")
    );
    // Ratio lines (median of runs), then criterion's own figures.
    let time = |f: &dyn Fn()| {
        let mut t: Vec<f64> = (0..5)
            .map(|_| {
                let s = Instant::now();
                f();
                s.elapsed().as_secs_f64()
            })
            .collect();
        t.sort_by(f64::total_cmp);
        t[2]
    };
    // Tree and scan in turns, so that a shared machine's drift shows in
    // both halves of each pair; each half is the best of 3 sweeps (the
    // first after the other half runs with its caches and idle threads).
    let sweep = |f: &dyn Fn(&Knife)| {
        (0..3)
            .map(|_| {
                let s = Instant::now();
                knives.iter().for_each(f);
                s.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let mut pairs: Vec<(f64, f64)> = (0..9)
        .map(|_| {
            let tree = sweep(&|k| std::mem::drop(locate(mesh, &surf.forest, k)));
            (
                tree,
                sweep(&|k| std::mem::drop(locate_brute_force(mesh, k))),
            )
        })
        .collect();
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let ratio = median(pairs.iter().map(|(t, s)| s / t).collect());
    let scan_locate = median(pairs.iter().map(|p| p.1).collect());
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let tree_locate = pairs[pairs.len() / 2].0;
    // The tree walk is single-threaded; the same scan on one thread too.
    let scan_locate_1t = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map(|pool| {
            pool.install(|| {
                time(&|| {
                    for k in &knives {
                        let _ = locate_brute_force(mesh, k);
                    }
                })
            })
        })
        .unwrap_or(f64::NAN);
    eprintln!(
        "cut/locate: one-thread scan {:.2} ms per knife ({:.1}x the tree)",
        scan_locate_1t * 1e3 / knives.len() as f64,
        scan_locate_1t / tree_locate
    );
    let cap = CutOptions { cap: true };
    let tree_cut = time(&|| {
        for k in &knives {
            let _ = cut(mesh, &surf.forest, k, &cap);
        }
    });
    let scan_cut = time(&|| {
        for k in &knives {
            let _ = cut_brute_force(mesh, k, &cap);
        }
    });
    let mut visited = (0, 0, 0, 0);
    for k in &knives {
        if let Ok(l) = locate(mesh, &surf.forest, k) {
            visited.0 += l.stats.nodes_visited;
            visited.1 += l.stats.nodes_total;
            visited.2 += l.stats.triangles_tested;
            visited.3 += l.stats.triangles_total;
        }
    }
    eprintln!(
        "cut/locate: tree {:.2} ms vs scan {:.2} ms per knife (medians of 9 turns, each the best of 3 sweeps; {:.1}x, median of the turns' ratios); nodes {}/{} triangles {}/{}",
        tree_locate * 1e3 / knives.len() as f64,
        scan_locate * 1e3 / knives.len() as f64,
        ratio,
        visited.0,
        visited.1,
        visited.2,
        visited.3
    );
    eprintln!(
        "cut/capped: tree {:.2} ms vs scan {:.2} ms per knife ({:.2}x; both assemble all pieces)",
        tree_cut * 1e3 / knives.len() as f64,
        scan_cut * 1e3 / knives.len() as f64,
        scan_cut / tree_cut
    );
    let mut group = c.benchmark_group("cut");
    group.throughput(Throughput::Elements((m * knives.len()) as u64));
    group.bench_function("locate_tree", |b| {
        b.iter(|| {
            for k in &knives {
                std::hint::black_box(locate(mesh, &surf.forest, k).ok());
            }
        })
    });
    group.bench_function("locate_brute_force", |b| {
        b.iter(|| {
            for k in &knives {
                std::hint::black_box(locate_brute_force(mesh, k).ok());
            }
        })
    });
    group.bench_function("capped_tree", |b| {
        b.iter(|| {
            for k in &knives {
                std::hint::black_box(cut(mesh, &surf.forest, k, &cap).ok());
            }
        })
    });
    group.bench_function("capped_brute_force", |b| {
        b.iter(|| {
            for k in &knives {
                std::hint::black_box(cut_brute_force(mesh, k, &cap).ok());
            }
        })
    });
    group.finish();
    c.final_summary();
}
