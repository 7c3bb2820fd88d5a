//! DMS spline benches (issue "DMS spline surfaces"): the basis evaluation
//! (`dms_basis`) and the surface gather (`dms_surface`) at the sizes of the
//! seed's Table 3 (grid disks: A = 24 × 23 exactly, B–D the nearest grids)
//! and on fran_cut at n = 3, 5, 7, 17, 33, CPU and GPU in one run; and the
//! whole chain (`dms_spline/cpu_end_to_end`: parametrisation, knots, basis,
//! control net, surface) for the D-size disk at n = 5, whose seed time was
//! 25 740 s.
//!
//! Throughput: evaluation points, and for the gather the bytes it must
//! move at least once (per row entry a source id, a weight `vec4` and a
//! source `vec4`; per point two offsets and two output `vec4`): the
//! memory-traffic bound.
//!
//! `CHISEL_BENCH_QUICK=1` (and `cargo test`): A only, fran_cut at n = 3.

#[path = "../tests/common/mod.rs"]
mod common;

use chisel::TriMesh;
use chisel::dms::basis::{BasisInput, BasisRows, cpu as basis_cpu, gpu as basis_gpu};
use chisel::dms::fit::ControlMap;
use chisel::dms::spline::lattice_params;
use chisel::dms::surface::{SurfaceInput, cpu as surface_cpu, gpu as surface_gpu};
use chisel::dms::{
    Domain, Fit, Projection, SplineOptions, knot_clouds, lattice, parametrise, spline,
};
use chisel::gpu::{Backend, GpuArray};
use criterion::{BenchmarkId, Criterion, Throughput};
use glam::{DVec2, Vec3};

#[path = "common/mod.rs"]
mod bench_common;
use bench_common::{group, quick};

/// A `cols × rows` grid disk on a half cylinder of radius 1 (a face-like
/// open surface), vertices jittered inside.
fn disk(cols: usize, rows: usize) -> TriMesh {
    let mut next = common::xorshift(cols as u64 * 131 + rows as u64);
    let jitter: Vec<[f32; 2]> = (0..cols * rows)
        .map(|_| [0, 1].map(|_| (next() >> 11) as f32 / (1u64 << 53) as f32 - 0.5))
        .collect();
    common::grid_mesh(cols, rows, |i, j| {
        let inner = i > 0 && j > 0 && i < cols - 1 && j < rows - 1;
        let s = if inner { 0.25 } else { 0.0 };
        let [dx, dy] = jitter[j * cols + i];
        let a = -1.3 + 2.6 * (i as f32 + s * dx) / (cols - 1) as f32;
        let y = 2.0 * (j as f32 + s * dy) / (rows - 1) as f32;
        Vec3::new(a.sin(), y, a.cos())
    })
}

/// Named meshes and accuracies.
fn cases() -> Vec<(String, TriMesh, Vec<u32>)> {
    // Table 3: A 552/1012, B 1157/2273, C 1502/2976, D 8641/17001.
    let sizes: &[(&str, usize, usize)] = if quick() {
        &[("A", 24, 23)]
    } else {
        &[("A", 24, 23), ("B", 35, 33), ("C", 39, 39), ("D", 97, 89)]
    };
    let mut out: Vec<(String, TriMesh, Vec<u32>)> = sizes
        .iter()
        .map(|&(name, c, r)| (format!("{name}_{}x{}", c, r), disk(c, r), vec![5]))
        .collect();
    if let Some(fran) = common::real_mesh("fran_cut.vtk") {
        let ns = if quick() {
            vec![3]
        } else {
            vec![3, 5, 7, 17, 33]
        };
        out.push(("fran_cut".into(), fran, ns));
    }
    out
}

/// The basis inputs of `mesh` (cylinder parametrisation) at accuracy `n`.
fn prepare(mesh: &TriMesh, n: u32) -> (Domain, BasisInput) {
    let p = parametrise(mesh, &Projection::Cylinder).expect("parametrise");
    let k = knot_clouds(&p.uv, &mesh.triangles).expect("knots");
    let d = Domain::new(&mesh.triangles, &k);
    let l = lattice(&mesh.triangles, mesh.n_vertices(), n).expect("lattice");
    let pts: Vec<DVec2> = lattice_params(&l, &p.uv, &mesh.triangles);
    let input = BasisInput::new(&d, &pts).expect("basis input");
    (d, input)
}

fn main() {
    let gpu = bench_common::gpu();
    let mut c = Criterion::default().configure_from_args();
    for (name, mesh, ns) in cases() {
        for n in ns {
            let (d, input) = prepare(&mesh, n);
            let points = input.points.len() as u64;
            let id = format!("{name}/n{n}");
            eprintln!(
                "{id}: {points} points, {} candidates, {} row entries",
                input.candidates.targets.len(),
                input.rows.targets.len()
            );
            let mut g = group(&mut c, "dms_basis");
            g.throughput(Throughput::Elements(points));
            g.bench_function(BenchmarkId::new("cpu", &id), |b| {
                b.iter(|| basis_cpu::dms_basis(&input))
            });
            if let Some(gpu) = &gpu {
                // Resident when the rows fit one binding, else in ranges of
                // points (upload + dispatch + read-back each).
                match basis_gpu::BasisBuffers::upload(gpu, &input) {
                    Ok(buffers) => g.bench_function(BenchmarkId::new("gpu_resident", &id), |b| {
                        b.iter(|| {
                            let mut e = gpu.encoder("dms_basis");
                            buffers.record(gpu, &mut e).expect("record");
                            gpu.submit_and_wait(e).expect("submit");
                        })
                    }),
                    Err(_) => g.bench_function(BenchmarkId::new("gpu_end_to_end", &id), |b| {
                        b.iter(|| basis_gpu::dms_basis(gpu, &input).expect("gpu"))
                    }),
                };
            }
            g.finish();
            // The gather of a changed control net over the lattice rows.
            let basis = BasisRows {
                weights: basis_cpu::dms_basis(&input),
                rows: input.rows.clone(),
            };
            let rows = SurfaceInput::over_controls(&basis, d.n_controls());
            let src: Vec<[f32; 4]> = ControlMap::identify(&d)
                .apply(&mesh.positions)
                .iter()
                .map(|c| [c.x as f32, c.y as f32, c.z as f32, 0.0])
                .collect();
            let entries = rows.rows.targets.len() as u64;
            let mut g = group(&mut c, "dms_surface");
            g.throughput(Throughput::ElementsAndBytes {
                elements: points,
                bytes: 36 * entries + 40 * points,
            });
            g.bench_function(BenchmarkId::new("cpu", &id), |b| {
                b.iter(|| surface_cpu::dms_surface(&rows, &src))
            });
            if let Some(gpu) = &gpu {
                let sources = GpuArray::from_slice(gpu, "sources", &src).expect("sources");
                match surface_gpu::SurfaceBuffers::upload(gpu, &rows) {
                    Ok(buffers) => g.bench_function(BenchmarkId::new("gpu_resident", &id), |b| {
                        b.iter(|| {
                            let mut e = gpu.encoder("dms_surface");
                            buffers.record(gpu, &mut e, &sources).expect("record");
                            gpu.submit_and_wait(e).expect("submit");
                        })
                    }),
                    Err(_) => g.bench_function(BenchmarkId::new("gpu_end_to_end", &id), |b| {
                        b.iter(|| surface_gpu::dms_surface(gpu, &rows, &src).expect("gpu"))
                    }),
                };
            }
            g.finish();
        }
    }
    // The whole chain for the D-size disk (quick: A) at n = 5.
    let (name, mesh) = if quick() {
        ("A_24x23", disk(24, 23))
    } else {
        ("D_97x89", disk(97, 89))
    };
    let opts = SplineOptions {
        projection: Projection::Cylinder,
        fit: Fit::Identify,
        data: None,
        n: 5,
    };
    let mut g = group(&mut c, "dms_spline");
    g.throughput(Throughput::Elements(mesh.n_vertices() as u64));
    g.bench_function(
        BenchmarkId::new("cpu_end_to_end", format!("{name}/n5")),
        |b| b.iter(|| spline(&mesh, &opts, Backend::Cpu).expect("spline")),
    );
    g.finish();
    c.final_summary();
}
