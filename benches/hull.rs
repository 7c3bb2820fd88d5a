//! Hull benches: exact incremental hulls of the seed's digital balls
//! (combinatorial radius r = 12…400), the seed objects, smooth random blobs
//! in 256³ and 512³ grids (`chisel phantom blob`) and the CT head bone.
//!
//! `hull/<object>` times candidate extraction (26-neighbourhood local
//! corners) plus the hull with coplanar faces merged; `hull_points/ball_24`
//! times the hull of all boundary-voxel centres of the r = 24 ball (the
//! input the Qhull comparison in the README uses, ~2.4 ms via scipy).
//! `polyhedrize/<object>` times the whole lossless polyhedrization (nested
//! shells, §4.4) with `polyhedrize/<object>/verify` the exact voxelization
//! of the result over the object's box by the nested convex tests,
//! `polyhedrize/<object>/verify_ray_parity` the same by ray parity on the
//! merged surface (§4.4.3) with the stored labels, and prints shells, faces and
//! integers (eq. 8.2) against marching cubes (eq. 8.1).
//! `CHISEL_BENCH_QUICK=1`: small cases and sample counts, for CI smoke runs.

use std::hint::black_box;
use std::time::Duration;

use chisel::Backend;
use chisel::hull::{ConvexHull, HullOptions};
use chisel::phantom::voxel::{blob, cylinder_tunnel, digital_ball, ellipsoid_dent, torus};
use chisel::polyhedron::{PolyhedrizeOptions, polyhedrize};
use chisel::volume::Volume;
use chisel::voxel::{CandidateKind, Component, DigitalObject, Selection, voxel_centre};
use criterion::{BenchmarkGroup, BenchmarkId, Criterion, Throughput, measurement::WallTime};

#[path = "common/mod.rs"]
mod bench_common;
use bench_common::quick;

fn group<'a>(c: &'a mut Criterion, name: &str) -> BenchmarkGroup<'a, WallTime> {
    let mut g = bench_common::group(c, name);
    if quick() {
        g.measurement_time(Duration::from_millis(100));
    } else {
        g.sample_size(20);
    }
    g
}

fn object(v: &Volume, sel: Selection) -> DigitalObject {
    DigitalObject::from_volume(v, sel, Component::Largest).expect("object")
}

fn bench_object(g: &mut BenchmarkGroup<'_, WallTime>, name: &str, o: &DigitalObject) {
    let h = ConvexHull::of_object(o, CandidateKind::Local26, HullOptions::default()).expect("hull");
    eprintln!(
        "{name}: {} voxels, {} candidates, hull {} faces {} vertices, {} visibility tests",
        o.n_voxels(),
        h.stats().candidates,
        h.n_faces(),
        h.n_vertices(),
        h.stats().visibility_tests
    );
    g.throughput(Throughput::Elements(o.n_voxels()));
    g.bench_function(BenchmarkId::from_parameter(name), |b| {
        b.iter(|| {
            ConvexHull::of_object(black_box(o), CandidateKind::Local26, HullOptions::default())
                .expect("hull")
        })
    });
}

fn bench_polyhedrize(g: &mut BenchmarkGroup<'_, WallTime>, name: &str, o: &DigitalObject) {
    let run = || {
        polyhedrize(o, PolyhedrizeOptions::default(), Backend::Cpu, &|_| {}).expect("polyhedrize")
    };
    let (p, _) = run();
    let s = p.summary();
    eprintln!(
        "polyhedrize {name}: {} voxels, {} shells, {} faces, {} integers (eq. 8.2) vs {} (eq. 8.1), G_nc {}",
        o.n_voxels(),
        s.shells,
        s.faces,
        s.integers_eq_8_2,
        chisel::voxel::marching_cubes_integers(2 * o.n_boundary_facets()),
        s.g_nc
    );
    g.throughput(Throughput::Elements(o.n_voxels()));
    g.bench_function(BenchmarkId::from_parameter(name), |b| b.iter(run));
    g.bench_function(BenchmarkId::new(name, "verify"), |b| {
        b.iter(|| p.mismatches(black_box(o), Backend::Cpu, 1).expect("verify"))
    });
    let surface = p.merged_surface().expect("merged surface");
    g.bench_function(BenchmarkId::new(name, "verify_ray_parity"), |b| {
        b.iter(|| {
            p.mismatches_ray_parity(&surface, black_box(o), Backend::Cpu, 1)
                .expect("verify")
        })
    });
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    let thr = Selection::Threshold(1.0);
    {
        let mut g = group(&mut c, "hull");
        let radii: &[u32] = if quick() {
            &[12, 24]
        } else {
            &[12, 24, 50, 100, 200, 400]
        };
        for &r in radii {
            bench_object(
                &mut g,
                &format!("ball_{r}"),
                &object(&digital_ball(r).expect("ball"), thr),
            );
        }
        bench_object(
            &mut g,
            "cylinder_50_35",
            &object(&cylinder_tunnel(50, 35, 15).expect("cyl"), thr),
        );
        bench_object(
            &mut g,
            "ellipsoid_dent",
            &object(&ellipsoid_dent(13, 13, 8, 5).expect("ell"), thr),
        );
        bench_object(
            &mut g,
            "torus_60_20",
            &object(&torus(60, 20).expect("torus"), thr),
        );
        let blobs: &[u32] = if quick() { &[64] } else { &[256, 512] };
        for &n in blobs {
            bench_object(
                &mut g,
                &format!("blob_{n}"),
                &object(&blob(n, 1).expect("blob"), thr),
            );
        }
        let head = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../shared/data/headsq/quarter.nhdr");
        match chisel::io::read_volume(&head) {
            Ok(v) => bench_object(
                &mut g,
                "headsq_bone_1150",
                &object(&v, Selection::Threshold(1150.0)),
            ),
            Err(e) => eprintln!("CT head skipped: {e}"),
        }
        g.finish();
    }
    {
        let mut g = group(&mut c, "hull_points");
        let o = object(&digital_ball(24).expect("ball"), thr);
        let boundary: Vec<[i64; 3]> = o
            .voxels()
            .filter(|v| {
                (0..3).any(|a| {
                    [-1, 1].iter().any(|&d| {
                        let mut n = *v;
                        n[a] += d;
                        !o.contains(n)
                    })
                })
            })
            .map(voxel_centre)
            .collect();
        eprintln!("ball_24 boundary voxels: {}", boundary.len());
        g.throughput(Throughput::Elements(boundary.len() as u64));
        g.bench_function("ball_24_boundary", |b| {
            b.iter(|| {
                ConvexHull::build(black_box(&boundary), HullOptions::default()).expect("hull")
            })
        });
        g.finish();
    }
    {
        let mut g = group(&mut c, "polyhedrize");
        bench_polyhedrize(
            &mut g,
            "cylinder_50_35",
            &object(&cylinder_tunnel(50, 35, 15).expect("cyl"), thr),
        );
        bench_polyhedrize(
            &mut g,
            "torus_40_12",
            &object(&torus(40, 12).expect("torus"), thr),
        );
        let head = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../shared/data/headsq/quarter.nhdr");
        if !quick() {
            match chisel::io::read_volume(&head) {
                Ok(v) => bench_polyhedrize(
                    &mut g,
                    "headsq_bone_1150",
                    &object(&v, Selection::Threshold(1150.0)),
                ),
                Err(e) => eprintln!("CT head skipped: {e}"),
            }
        }
        g.finish();
    }
    c.final_summary();
}
