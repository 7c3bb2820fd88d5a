//! Parity of `kernels/blobby_energy.wgsl` against `blobby::energy::cpu`:
//! per-workgroup rows (Σ e_j/M and the gradient per primitive) on points
//! of a sphere (a partial last workgroup, negative strengths) and on the
//! fran_cut scan, within `cpu::tolerances` (a linear error bound from
//! 256 ulp per term). Negative controls: the GPU given one primitive less,
//! and the GPU without the normal term.

use chisel::blobby::energy::{EnergyInput, cpu, gpu::EnergyBuffers};
use chisel::blobby::{Blob, Model, RangePoints, Weights};
use chisel::gpu::Gpu;
use chisel::parity::find_sentinel;
use glam::DVec3;

use crate::common;

fn gpu_rows(gpu: &Gpu, what: &str, input: &EnergyInput) -> Vec<f32> {
    let buffers = EnergyBuffers::upload(gpu, input).unwrap();
    let mut encoder = gpu.encoder("blobby_energy");
    buffers.record(gpu, &mut encoder).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let rows = buffers.partials.read(gpu).unwrap();
    assert_eq!(
        find_sentinel(&rows, f32::NAN),
        None,
        "{what}: NaN sentinel survived"
    );
    rows
}

/// Random primitives around `centre` within `size`.
fn random_model(seed: u64, n: usize, centre: DVec3, size: f64) -> Model {
    let mut rng = common::xorshift(seed);
    let mut u = move || (rng() >> 11) as f64 / (1u64 << 53) as f64;
    Model {
        iso: 0.5,
        blobs: (0..n)
            .map(|_| Blob {
                centre: centre + size * DVec3::new(u() - 0.5, u() - 0.5, u() - 0.5),
                a: (1.0 + 4.0 * u()) / (size * size),
                b: if u() < 0.2 { -0.3 * u() } else { 0.3 + u() },
            })
            .collect(),
    }
}

fn sphere(m: usize) -> RangePoints {
    let p = common::fibonacci_sphere(m);
    RangePoints::new(p.clone(), p).unwrap()
}

const WEIGHTS: Weights = Weights {
    alpha: 0.3,
    beta: 0.0,
};

fn cases() -> Vec<(String, Model, RangePoints)> {
    let mut out = vec![
        (
            "sphere, 3 primitives".to_string(),
            random_model(1, 3, DVec3::ZERO, 1.5),
            sphere(5000),
        ),
        (
            "sphere, 40 primitives".to_string(),
            random_model(2, 40, DVec3::ZERO, 2.0),
            sphere(1500),
        ),
    ];
    if let Some(mesh) = common::real_mesh("fran_cut.vtk") {
        let points = RangePoints::from_mesh(&mesh).unwrap();
        let (lo, hi) = (points.positions.iter())
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        let model = random_model(3, 24, 0.5 * (lo + hi), (hi - lo).max_element());
        out.push(("fran_cut, 24 primitives".to_string(), model, points));
    }
    out
}

#[test]
fn blobby_energy_matches_the_mirror() {
    let Some(gpu) = common::gpu() else {
        return;
    };
    for (what, model, points) in cases() {
        let input = EnergyInput::new(&model, &points, WEIGHTS).unwrap();
        let want = cpu::blobby_energy(&input);
        let tol = cpu::tolerances(&input);
        let got = gpu_rows(gpu, &what, &input);
        assert!(cpu::accepts(&tol, &want, &got), "{what}: rows differ");
        // The bound is far below the outputs' own size.
        let (t, v): (f64, f64) = (
            tol.iter().sum(),
            want.iter().map(|x| f64::from(x.abs())).sum(),
        );
        assert!(t < 1e-2 * v, "{what}: tolerance {t} vs outputs {v}");
    }
}

#[test]
fn blobby_energy_negative_controls_fail() {
    let Some(gpu) = common::gpu() else {
        return;
    };
    let (what, model, points) = cases().swap_remove(0);
    let input = EnergyInput::new(&model, &points, WEIGHTS).unwrap();
    let want = cpu::blobby_energy(&input);
    let tol = cpu::tolerances(&input);
    // One primitive less: the rows have another length and other values;
    // compare the energies and the shared primitives' gradients.
    let mut fewer = model.clone();
    fewer.blobs.pop();
    let less = EnergyInput::new(&fewer, &points, WEIGHTS).unwrap();
    let got = gpu_rows(gpu, &what, &less);
    let (len, short) = (input.row_len(), less.row_len());
    let padded: Vec<f32> = (got.chunks_exact(short))
        .flat_map(|r| {
            r.iter()
                .copied()
                .chain(std::iter::repeat_n(0.0, len - short))
        })
        .collect();
    assert!(
        !cpu::accepts(&tol, &want, &padded),
        "{what}: a missing primitive passed"
    );
    // Without the normal term.
    let mut no_normals = input.clone();
    no_normals.params.alpha = 0.0;
    let got = gpu_rows(gpu, &what, &no_normals);
    assert!(
        !cpu::accepts(&tol, &want, &got),
        "{what}: a dropped normal term passed"
    );
}
