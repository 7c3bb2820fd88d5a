//! Parity of `kernels/particle_update.wgsl` against `particles::wh::cpu`:
//! one step from identical inputs (start sets, relaxed sets, moving
//! skeletons, σ adaptation on and off, a cell list used after particles
//! moved), under `cpu::accepts`. Negative controls: a mirror step that
//! misses one neighbour cell's particles, one with the F_t term dropped.

use chisel::Backend;
use chisel::gpu::Gpu;
use chisel::implicit::Scene;
use chisel::implicit::field::FieldInput;
use chisel::implicit::field::gpu::FieldBuffers;
use chisel::implicit::scene::EXAMPLES;
use chisel::parity::{compare_by, find_sentinel};
use chisel::particles::wh::gpu::UpdateBuffers;
use chisel::particles::wh::{StepInput, UpdateParams, cpu, sigma_for_spacing};
use chisel::particles::{CellList, Particles, Sampler, WhOptions};

use crate::common;

use chisel::particles::StepOutput as Step;

fn gpu_step(gpu: &Gpu, what: &str, field: &FieldInput, input: &StepInput<'_>) -> Step {
    let fb = FieldBuffers::upload(gpu, field).unwrap();
    let b = UpdateBuffers::upload(gpu, input).unwrap();
    let mut encoder = gpu.encoder("particle_update");
    b.record(gpu, &mut encoder, &fb).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let pos = b.pos_out.read(gpu).unwrap();
    let state = b.state.read(gpu).unwrap();
    assert_eq!(
        find_sentinel(&pos, [f32::NAN; 4]),
        None,
        "{what}: sentinel survived"
    );
    assert_eq!(
        find_sentinel(&state, [f32::NAN; 4]),
        None,
        "{what}: sentinel survived"
    );
    (pos, state)
}

fn compare(what: &str, u: &UpdateParams, want: &Step, got: &Step) -> Result<(), String> {
    let a: Vec<([f32; 4], [f32; 4])> = want.0.iter().copied().zip(want.1.iter().copied()).collect();
    let b: Vec<([f32; 4], [f32; 4])> = got.0.iter().copied().zip(got.1.iter().copied()).collect();
    compare_by(
        &format!("particle_update/{what}"),
        &a,
        &b,
        |x, y| !cpu::accepts(u, *x, *y),
        |x| format!("{x:?}"),
    )
    .map_err(|m| m.to_string())
}

/// A scene's particles after `iters` CPU iterations from the start set,
/// with the step input of the next iteration (scene time advancing by
/// `delta`).
fn case(
    name: &str,
    t: f64,
    r: f64,
    iters: u32,
) -> (FieldInput, Vec<[f32; 4]>, Vec<u32>, UpdateParams) {
    let text = EXAMPLES.iter().find(|e| e.0 == name).unwrap().1;
    let pose = Scene::from_toml_str(text, name).unwrap().pose(t);
    let field = FieldInput::new(&pose).unwrap();
    let opts = WhOptions::default();
    let sh = sigma_for_spacing(r, &opts);
    let mut s = Sampler::new(
        Particles::on_surface(&pose, sh, Backend::Cpu).unwrap(),
        sh,
        opts,
        &field,
    )
    .unwrap();
    for _ in 0..iters {
        s.iterate(&field, 0.0, true, Backend::Cpu).unwrap();
    }
    let pos = s.particles.points.clone();
    let positions = s.particles.positions();
    let cutoff = 3.0 * pos.iter().fold(0.0f32, |m, p| m.max(p[3]));
    let cells = CellList::build(&positions, cutoff, 0.5 * s.sigma_hat).unwrap();
    let u = UpdateParams {
        nx: cells.dims.x,
        ny: cells.dims.y,
        nz: cells.dims.z,
        n_particles: pos.len() as u32,
        n_cells: (cells.starts.len() - 1) as u32,
        dt: s.dt(),
        delta: 0.01,
        kappa: 0.5,
        alpha: 6.0,
        e_hat: 4.8,
        rho_sigma: 15.0,
        beta_sigma: (6.0 / sh) as f32,
        sigma_lo: 0.1 * s.sigma_hat,
        sigma_hi: 2.0 * s.sigma_hat,
        g_min2: s.g_min * s.g_min,
        adapt: 1,
    };
    (field, pos, cells.flat(), u)
}

fn check(
    gpu: &Gpu,
    what: &str,
    field: &FieldInput,
    pos: &[[f32; 4]],
    cells: &[u32],
    u: UpdateParams,
) {
    let input = StepInput {
        params: u,
        cells,
        positions: pos,
    };
    let want = cpu::particle_update(field, &input);
    let got = gpu_step(gpu, what, field, &input);
    compare(what, &u, &want, &got).unwrap_or_else(|m| panic!("{m}"));
}

#[test]
fn example_scenes() {
    let Some(gpu) = common::gpu() else { return };
    for (name, t, r, iters) in [
        ("dumbbell", 0.0, 0.1, 0),
        ("dumbbell", 0.44, 0.08, 20),
        ("torus", 0.5, 0.08, 10),
        ("finger", 0.3, 0.1, 10),
        ("molecule", 0.5, 0.1, 5),
    ] {
        let (field, pos, cells, u) = case(name, t, r, iters);
        let what = format!("{name}@{t}/{iters}");
        check(gpu, &what, &field, &pos, &cells, u);
        check(
            gpu,
            &format!("{what}/fixed-sigma"),
            &field,
            &pos,
            &cells,
            UpdateParams {
                adapt: 0,
                delta: 0.0,
                ..u
            },
        );
        // The same list after every particle moved by up to skin/2.
        let moved: Vec<[f32; 4]> = pos
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let d = 0.24 * u.sigma_hi / 2.0 * ((i % 7) as f32 / 7.0);
                [p[0] + d, p[1] - d, p[2], p[3]]
            })
            .collect();
        check(gpu, &format!("{what}/moved"), &field, &moved, &cells, u);
    }
}

/// The comparison fails when the mirror misses one neighbour cell (its
/// cell start moved onto its end) or drops F_t.
#[test]
fn negative_controls() {
    let (field, pos, cells, u) = case("dumbbell", 0.44, 0.08, 20);
    let input = StepInput {
        params: u,
        cells: &cells,
        positions: &pos,
    };
    let want = cpu::particle_update(&field, &input);
    compare("control", &u, &want, &want).unwrap();
    // Empty the most populated cell.
    let n_cells = u.n_cells as usize;
    let busiest = (0..n_cells)
        .max_by_key(|&c| cells[c + 1] - cells[c])
        .unwrap();
    let mut holed = cells.clone();
    holed[busiest] = holed[busiest + 1];
    let wrong = cpu::particle_update(
        &field,
        &StepInput {
            cells: &holed,
            ..input
        },
    );
    assert!(compare("missing-cell", &u, &want, &wrong).is_err());
    let still = cpu::particle_update(
        &field,
        &StepInput {
            params: UpdateParams { delta: 0.0, ..u },
            ..input
        },
    );
    let err = compare("no-rate", &u, &want, &still).unwrap_err();
    assert!(err.contains("particle_update/no-rate"), "{err}");
}
