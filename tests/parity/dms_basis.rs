//! Parity of `kernels/dms_basis.wgsl` against `dms::basis::cpu` (the f32
//! mirror, itself checked against the f64 oracle in tests/dms_spline.rs)
//! on jittered grids at several accuracies and on fran_cut, the kernel's
//! constant tables against `dms::program`, and negative controls.

use chisel::TriMesh;
use chisel::dms::basis::gpu::BasisBuffers;
use chisel::dms::basis::{BasisInput, cpu};
use chisel::dms::program::Program;
use chisel::dms::spline::lattice_params;
use chisel::dms::{Domain, Projection, knot_clouds, lattice, parametrise};
use chisel::gpu::{Gpu, Kernel};
use chisel::parity::{compare_vec, find_sentinel};
use glam::{DVec2, Vec3};

use crate::common;

/// A jittered grid mesh with its parameter points.
pub fn jittered(cols: usize, rows: usize, seed: u64) -> (Vec<DVec2>, TriMesh) {
    let mut next = common::xorshift(seed);
    let mut r = move || (next() >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
    let mut uv = Vec::new();
    for j in 0..rows {
        for i in 0..cols {
            let inner = i > 0 && j > 0 && i < cols - 1 && j < rows - 1;
            let s = if inner { 0.3 } else { 0.0 };
            uv.push(DVec2::new(i as f64 + s * r(), j as f64 + s * r()));
        }
    }
    let uv2 = uv.clone();
    let mesh = common::grid_mesh(cols, rows, move |i, j| {
        let p = uv2[j * cols + i];
        Vec3::new(p.x as f32, p.y as f32, (0.3 * (p.x * 0.8).sin()) as f32)
    });
    (uv, mesh)
}

/// The basis inputs of `mesh` over `uv` at the lattice of accuracy `n`.
pub fn input_of(uv: &[DVec2], mesh: &TriMesh, n: u32) -> (Domain, BasisInput) {
    let clouds = knot_clouds(uv, &mesh.triangles).unwrap();
    let d = Domain::new(&mesh.triangles, &clouds);
    let l = lattice(&mesh.triangles, mesh.n_vertices(), n).unwrap();
    let pts = lattice_params(&l, uv, &mesh.triangles);
    let input = BasisInput::new(&d, &pts).unwrap();
    (d, input)
}

pub fn gpu_weights(gpu: &Gpu, what: &str, input: &BasisInput) -> Vec<[f32; 4]> {
    let buffers = BasisBuffers::upload(gpu, input).unwrap();
    let mut encoder = gpu.encoder("dms_basis");
    buffers.record(gpu, &mut encoder).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let out = buffers.weights.read(gpu).unwrap();
    assert_eq!(
        find_sentinel(&out, [f32::NAN; 4]),
        None,
        "{what}: NaN sentinel survived"
    );
    out
}

/// GPU vs mirror, each row scaled by its largest gradient (the weights are
/// ≤ 1; the gradients scale with 1/knot spacing).
fn check(gpu: &Gpu, what: &str, input: &BasisInput) {
    let want = cpu::dms_basis(input);
    let got = gpu_weights(gpu, what, input);
    let (a, b) = scaled(input, &want, &got);
    compare_vec(&format!("dms_basis/{what}"), &a, &b, cpu::TOL).unwrap_or_else(|m| panic!("{m}"));
}

/// Both sides with each row's gradients divided by the row's largest
/// mirror gradient.
fn scaled(
    input: &BasisInput,
    want: &[[f32; 4]],
    got: &[[f32; 4]],
) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let mut a = want.to_vec();
    let mut b = got.to_vec();
    for p in 0..input.rows.n_rows() {
        let (lo, hi) = (
            input.rows.offsets[p] as usize,
            input.rows.offsets[p + 1] as usize,
        );
        let g = want[lo..hi]
            .iter()
            .map(|w| w[1].abs().max(w[2].abs()))
            .fold(1e-30f32, f32::max);
        for k in lo..hi {
            for i in 1..3 {
                a[k][i] /= g;
                b[k][i] /= g;
            }
        }
    }
    (a, b)
}

#[test]
fn the_kernel_tables_are_the_program() {
    let src = Kernel::DmsBasis.source();
    let table = |name: &str| -> Vec<[u32; 3]> {
        let start = src
            .find(&format!("const {name} = array<"))
            .unwrap_or_else(|| panic!("{name}"));
        let body = &src[start..];
        let body = &body[body.find("(\n").unwrap()..body.find(");").unwrap()];
        body.split("vec3<u32>(")
            .skip(1)
            .map(|v| {
                let nums: Vec<u32> = v
                    .split(')')
                    .next()
                    .unwrap()
                    .split(',')
                    .map(|x| x.trim().trim_end_matches('u').parse().unwrap())
                    .collect();
                [nums[0], nums[1], nums[2]]
            })
            .collect()
    };
    let p = Program::new();
    assert_eq!(table("DEGREE0"), chisel::dms::program::DEGREE0.to_vec());
    assert_eq!(
        table("DEGREE1_W"),
        p.degree1.iter().map(|e| e.0).collect::<Vec<_>>()
    );
    assert_eq!(
        table("DEGREE1_CHILD"),
        p.degree1.iter().map(|e| e.1).collect::<Vec<_>>()
    );
    assert_eq!(
        table("DEGREE2_W"),
        p.degree2.iter().map(|e| e.0).collect::<Vec<_>>()
    );
    assert_eq!(
        table("DEGREE2_CHILD"),
        p.degree2.iter().map(|e| e.1).collect::<Vec<_>>()
    );
}

#[test]
fn synthetic() {
    let Some(gpu) = common::gpu() else { return };
    for (cols, rows, seed, n) in [(3, 3, 1, 2), (6, 5, 2, 3), (9, 7, 3, 5), (5, 8, 4, 9)] {
        let (uv, mesh) = jittered(cols, rows, seed);
        let (_, input) = input_of(&uv, &mesh, n);
        check(gpu, &format!("grid{cols}x{rows}/n{n}"), &input);
    }
}

#[test]
fn fran_cut() {
    let Some(mesh) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let p = parametrise(&mesh, &Projection::Cylinder).unwrap();
    let (_, input) = input_of(&p.uv, &mesh, 5);
    let Some(gpu) = common::gpu() else { return };
    check(gpu, "fran_cut/n5", &input);
}

#[test]
fn negative_controls() {
    let Some(gpu) = common::gpu() else { return };
    let (uv, mesh) = jittered(6, 5, 9);
    let (_, input) = input_of(&uv, &mesh, 4);
    let want = cpu::dms_basis(&input);
    let got = gpu_weights(gpu, "control", &input);
    let (a, mut b) = scaled(&input, &want, &got);
    compare_vec("dms_basis/control", &a, &b, cpu::TOL).unwrap();
    let k = b.len() / 2;
    b[k][0] += 4.0 * cpu::TOL.abs + 4.0 * cpu::TOL.rel;
    let m = compare_vec("dms_basis/control", &a, &b, cpu::TOL).unwrap_err();
    assert_eq!((m.index, m.count), (k, 1), "{m}");
    // A dropped candidate (the kernel sees one triangle fewer at a point
    // with several) changes that point's row beyond the tolerance.
    let p = (0..input.rows.n_rows())
        .find(|&p| input.candidates.row(p).len() >= 3)
        .unwrap();
    let mut short = input.clone();
    let c = short.candidates.offsets[p + 1] as usize - 1;
    short.candidates.targets[c] = short.candidates.targets[c - 1];
    let got = gpu_weights(gpu, "dropped", &short);
    let (a, b) = scaled(&input, &want, &got);
    assert!(compare_vec("dms_basis/dropped", &a, &b, cpu::TOL).is_err());
}

/// Inputs larger than one storage binding run in ranges of points: with
/// bindings capped at 16 KiB the grid's rows take several dispatches, and
/// the weights equal one dispatch's.
#[test]
fn chunked_dispatches_equal_one() {
    let Some(base) = common::gpu() else { return };
    let (uv, mesh) = jittered(9, 8, 11);
    let (_, input) = input_of(&uv, &mesh, 5);
    let small = base.view(Some(16 << 10), false);
    let parts = chisel::gpu::row_chunks(
        &[(&input.rows.offsets, 16), (&input.candidates.offsets, 24)],
        small.max_binding_bytes(),
    );
    assert!(parts.len() > 3, "{} parts", parts.len());
    assert_eq!(parts.first().map(|r| r.start), Some(0));
    assert_eq!(parts.last().map(|r| r.end), Some(input.points.len()));
    let whole = gpu_weights(base, "whole", &input);
    let chunked = chisel::dms::basis::gpu::dms_basis(&small, &input).unwrap();
    assert_eq!(whole, chunked);
}
