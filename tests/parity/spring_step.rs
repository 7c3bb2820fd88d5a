//! Parity of `kernels/spring_step.wgsl` with `tissue::cpu::spring_step`
//! (explicit solver), plus the shared tissue fixtures of the other tissue
//! parity modules.
//!
//! Tolerance ([`tolerance_on`]): `spring_step` is bit-exact on a software
//! adapter (lavapipe contracts no multiply-add and rounds division and
//! sqrt correctly, as the mirror does); elsewhere, and for
//! `spring_chebyshev`, `tissue::cpu::position_tolerance(N, diagonal)` =
//! N · 8 ε_f32 · diagonal on positions after N iterations (see its docs),
//! with N capped at [`BOUND_ITERATIONS`] over whole relaxations. Stop
//! statuses and iteration counts must match exactly.

use chisel::Backend;
use chisel::gpu::Gpu;
use chisel::parity::{Tolerance, compare_exact, compare_vec, find_sentinel};
use chisel::tissue::chebyshev::{Spectrum, estimate_spectrum};
use chisel::tissue::cpu::{self, SpringChebyshevParams, SpringStepParams};
use chisel::tissue::phantom::FRAN_CHIN_ADVANCE_TOML;
use chisel::tissue::{
    Fragments, Material, NetworkParams, Plan, RelaxOptions, Solver, SpringNetwork, Status,
    Stiffness, gpu as tissue_gpu, iterate, relax,
};
use glam::Vec3;

use crate::common;

/// Named network fixtures: synthetic (icosphere, grid patch) and fran_cut.
pub fn networks() -> Vec<(&'static str, SpringNetwork)> {
    let mut out = vec![
        (
            "icosphere(3)",
            SpringNetwork::build(&common::icosphere(3), None, &NetworkParams::default()).unwrap(),
        ),
        (
            "grid 30x20",
            SpringNetwork::build(&grid_patch(30, 20), None, &NetworkParams::default()).unwrap(),
        ),
    ];
    if let Some(face) = common::real_mesh("fran_cut.vtk") {
        out.push((
            "fran_cut",
            SpringNetwork::build(&face, None, &NetworkParams::default()).unwrap(),
        ));
        let bending = NetworkParams {
            stiffness: Stiffness {
                bending: Material::linear(1.0),
                ..Default::default()
            },
            ..Default::default()
        };
        out.push((
            "fran_cut with bend springs",
            SpringNetwork::build(&face, None, &bending).unwrap(),
        ));
    }
    out
}

/// A gently curved `nx × ny` patch (spacing 1).
pub fn grid_patch(nx: usize, ny: usize) -> chisel::TriMesh {
    common::grid_mesh(nx, ny, |i, j| {
        let (x, y) = (i as f32, j as f32);
        Vec3::new(x, y, 0.02 * (x - nx as f32 / 2.0).powi(2))
    })
}

/// The bone layer with its upper third moved by `share` of the network size
/// along +x+z: a surgical increment that sets the whole network moving.
pub fn moved_bone(net: &SpringNetwork, share: f32) -> Vec<[f32; 4]> {
    let d = share * net.diagonal();
    let bone = net.bone_rest();
    let ys: Vec<f32> = bone.iter().map(|b| b[1]).collect();
    let cut = ys.iter().copied().fold(f32::NEG_INFINITY, f32::max)
        - (ys.iter().copied().fold(f32::NEG_INFINITY, f32::max)
            - ys.iter().copied().fold(f32::INFINITY, f32::min))
            / 3.0;
    bone.iter()
        .map(|&b| {
            if b[1] >= cut {
                [b[0] + d, b[1], b[2] + d, 0.0]
            } else {
                b
            }
        })
        .collect()
}

/// The iteration count past which the position bound stops growing. The
/// bound adds up per-iteration differences linearly, as a transient does;
/// a relaxation run to convergence forgets them (the damped iteration
/// contracts towards the one equilibrium both backends settle in), so over
/// a whole relaxation of thousands of iterations the linear bound would
/// grow to a sizeable share of the bone move while the states agree far
/// more closely (printed by `check_stop_status`).
const BOUND_ITERATIONS: u32 = 500;

/// The tolerance of positions after `n` iterations of `solver` on `gpu`:
/// exact for `spring_step` on a software adapter, else the derived bound
/// for min(`n`, [`BOUND_ITERATIONS`]) iterations.
fn tolerance_on(gpu: &Gpu, solver: Solver, n: u32, diagonal: f32) -> Tolerance {
    if solver == Solver::Explicit && gpu.is_software() {
        Tolerance::EXACT
    } else {
        cpu::position_tolerance(n.min(BOUND_ITERATIONS), diagonal)
    }
}

/// `x` moved well past `tol` (ten times it; one ulp when `tol` is exact):
/// what a negative control must catch.
fn corrupt(x: f32, tol: Tolerance) -> f32 {
    if tol.abs > 0.0 {
        x + 10.0 * tol.abs
    } else {
        x.next_up()
    }
}

/// The Chebyshev runs of both backends share one spectrum estimate (the
/// same coefficients), as `chisel bench relax` does.
fn one_spectrum(net: &SpringNetwork, solver: Solver) -> Option<Spectrum> {
    (solver == Solver::Chebyshev).then(|| estimate_spectrum(net))
}

/// Positions after `n` iterations on both backends agree within the
/// derived bound; a corrupted GPU coordinate is caught (negative control);
/// the NaN-prefilled second position buffer leaves no sentinel behind.
///
/// The bone moves by 3 % of the network size for the explicit scheme (the
/// kernel is bit-exact with its mirror on lavapipe) and by 1.5 % (about one
/// fran_cut grid spacing) for Chebyshev. Its kernel differs from the mirror
/// by a few ulp per step on lavapipe (≤ 1e-6 of |v|; which operation
/// rounds differently is not identified), and after a 3 % jump springs at
/// the bone invert: the transient passes through unstable (buckling)
/// states, where such differences grow ~1.2× per iteration (fran_cut:
/// 1e-7 after 10 iterations, 6e-4 after 50) and no rounding bound can hold,
/// although both settle to the same equilibrium (`check_stop_status`). At
/// 1.5 % it stays below 3e-7 on fran_cut and 3e-5 on the grid (bound
/// 7e-3) throughout.
pub fn check_iterations(gpu: &Gpu, solver: Solver, n: u32) {
    let share = match solver {
        Solver::Explicit => 0.03,
        Solver::Chebyshev => 0.015,
    };
    for (name, net) in networks() {
        let bone = moved_bone(&net, share);
        let opts = RelaxOptions {
            solver,
            spectrum: one_spectrum(&net, solver),
            ..RelaxOptions::default()
        };
        let a = iterate(&net, &bone, &opts, n, Backend::Cpu).unwrap();
        let b = iterate(&net, &bone, &opts, n, Backend::Gpu(gpu)).unwrap();
        assert_eq!(
            find_sentinel(&b, [f32::NAN; 4]),
            None,
            "{name}: sentinel survived"
        );
        let tol = tolerance_on(gpu, solver, n, net.diagonal());
        let derived = cpu::position_tolerance(n, net.diagonal());
        let what = format!("{} {name} after {n} iterations", solver.name());
        compare_vec(&what, &a, &b, tol).unwrap_or_else(|m| panic!("{m}"));
        let worst = a
            .iter()
            .zip(&b)
            .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f32::max))
            .fold(0.0, f32::max);
        eprintln!("{what}: max |cpu − gpu| = {worst:e} (bound {:e})", tol.abs);
        // The comparison is not vacuous: the network moved far more than
        // the derived bound.
        let moved = (0..net.n_free)
            .map(|i| Vec3::from_slice(&a[i][..3]).distance(Vec3::from_slice(&net.rest[i][..3])))
            .fold(0.0, f32::max);
        assert!(
            moved > 100.0 * derived.abs,
            "{what}: moved {moved} vs bound {}",
            derived.abs
        );
        // Negative control: one coordinate off by 10 tolerances (1 ulp when
        // exact) must fail.
        let mut bad = b.clone();
        let k = net.n_free / 2;
        bad[k][1] = corrupt(bad[k][1], tol);
        let m = compare_vec(&what, &a, &bad, tol).expect_err("corrupted output must be caught");
        assert_eq!(m.index, k);
    }
}

/// Per-increment statuses and iteration counts of a converge plan are
/// identical on both backends, and the final positions agree.
pub fn check_stop_status(gpu: &Gpu, solver: Solver) {
    for (name, net) in networks() {
        let plan = if name == "fran_cut" {
            Plan::from_toml_str(FRAN_CHIN_ADVANCE_TOML, "chin").unwrap()
        } else {
            let b = net.bone_rest();
            Plan::from_toml_str(
                &format!(
                    "[[step]]\nselect = {{ sphere = {{ center = [{}, {}, {}], radius = {} }} }}\n\
                     translate = [{}, 0, 0]\nincrements = 2\n",
                    b[0][0],
                    b[0][1],
                    b[0][2],
                    0.3 * net.diagonal(),
                    0.02 * net.diagonal()
                ),
                "p",
            )
            .unwrap()
        }
        .resolve(&net, &Fragments::new())
        .unwrap();
        let opts = RelaxOptions {
            solver,
            spectrum: one_spectrum(&net, solver),
            ..RelaxOptions::default()
        };
        let a = relax(&net, &plan, &opts, Backend::Cpu).unwrap();
        let b = relax(&net, &plan, &opts, Backend::Gpu(gpu)).unwrap();
        let summary = |r: &chisel::tissue::RelaxReport| -> Vec<(String, u64)> {
            r.steps
                .iter()
                .flat_map(|s| s.increments.iter())
                .map(|i| (format!("{:?}", i.status), i.iterations))
                .collect()
        };
        let what = format!("{} {name} stop status", solver.name());
        eprintln!("{what}: {:?}", summary(&a));
        // Every increment settles (a solver that diverges on either
        // backend fails here, even if both diverge alike).
        assert_eq!(a.status, Status::Converged, "{what}");
        compare_exact(&what, &summary(&a), &summary(&b)).unwrap_or_else(|m| panic!("{m}"));
        let n = u32::try_from(a.iterations).unwrap_or(u32::MAX);
        let tol = tolerance_on(gpu, solver, n, net.diagonal());
        let worst = (a.positions.iter().zip(&b.positions))
            .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f32::max))
            .fold(0.0, f32::max);
        eprintln!(
            "{what}: {} iterations, max |cpu − gpu| = {worst:e} (bound {:e}; uncapped {:e})",
            a.iterations,
            tol.abs,
            cpu::position_tolerance(n, net.diagonal()).abs
        );
        compare_vec(&what, &a.positions, &b.positions, tol).unwrap_or_else(|m| panic!("{m}"));
    }
}

/// One dispatch on perturbed inputs: positions and velocities of every
/// free node match, the sentinel-filled output is fully written.
pub fn check_single_step(gpu: &Gpu, solver: Solver) {
    for (name, net) in networks() {
        let opts = RelaxOptions {
            solver,
            external_forces: Some(
                (0..net.n_free)
                    .map(|i| Vec3::new(0.0, 0.01 * ((i % 7) as f32 - 3.0), 0.0))
                    .collect(),
            ),
            ..RelaxOptions::default()
        };
        let dt = chisel::tissue::explicit::choose_dt(&net, None, false).unwrap();
        // The kernels' state: displacements from rest.
        let mut pos: Vec<[f32; 4]> = iterate(&net, &moved_bone(&net, 0.03), &opts, 3, Backend::Cpu)
            .unwrap()
            .iter()
            .zip(&net.rest)
            .map(|(p, r)| [p[0] - r[0], p[1] - r[1], p[2] - r[2], p[3]])
            .collect();
        let diag = net.diagonal();
        for (i, p) in pos.iter_mut().enumerate().take(net.n_free) {
            p[0] += 1e-3 * diag * ((i * 31 % 17) as f32 / 17.0 - 0.5);
        }
        let vel: Vec<[f32; 4]> = (0..net.n_free)
            .map(|i| [1e-3 * diag * ((i % 5) as f32 - 2.0), 0.0, 1e-3 * diag, 0.0])
            .collect();
        let forces: Vec<[f32; 4]> = opts
            .external_forces
            .as_ref()
            .unwrap()
            .iter()
            .map(|f| [f.x, f.y, f.z, 0.0])
            .collect();
        let mut materials = [[0.0f32; 4]; 16];
        for (row, m) in materials.iter_mut().zip(&net.materials) {
            *row = m.table_row();
        }
        let mut cpu_pos = pos.clone();
        let mut cpu_vel = vel.clone();
        let (gpu_pos, gpu_vel) = match solver {
            Solver::Explicit => {
                let params = SpringStepParams {
                    n_free: net.n_free as u32,
                    use_forces: true,
                    dt,
                    damping: 0.5,
                    materials,
                };
                cpu::spring_step(
                    &params,
                    &net.csr,
                    &net.rest,
                    &forces,
                    &pos,
                    &mut cpu_pos,
                    &mut cpu_vel,
                );
                tissue_gpu::spring_step(gpu, &params, &net.csr, &net.rest, &forces, &pos, &vel)
            }
            Solver::Chebyshev => {
                let params = SpringChebyshevParams {
                    n_free: net.n_free as u32,
                    use_forces: true,
                    h: dt,
                    momentum: 0.95,
                    gain: 2.0 / dt,
                    isotropy: chisel::tissue::chebyshev::BLOCK_ISOTROPY,
                    materials,
                };
                cpu::spring_chebyshev(
                    &params,
                    &net.csr,
                    &net.rest,
                    &forces,
                    &pos,
                    &mut cpu_pos,
                    &mut cpu_vel,
                );
                tissue_gpu::spring_chebyshev(gpu, &params, &net.csr, &net.rest, &forces, &pos, &vel)
            }
        }
        .unwrap();
        assert_eq!(find_sentinel(&gpu_pos, [f32::NAN; 4]), None, "{name}");
        let what = format!("{} {name} one step", solver.name());
        let tol = tolerance_on(gpu, solver, 1, diag);
        compare_vec(&what, &cpu_pos[..net.n_free], &gpu_pos, tol).unwrap_or_else(|m| panic!("{m}"));
        // Velocities: position tolerance per unit step, relative to h.
        let vtol = Tolerance {
            abs: tol.abs / dt,
            rel: 0.0,
        };
        compare_vec(&what, &cpu_vel, &gpu_vel, vtol).unwrap_or_else(|m| panic!("{m}"));
    }
}

#[test]
fn spring_step_single_dispatch() {
    let Some(gpu) = common::gpu() else { return };
    check_single_step(gpu, Solver::Explicit);
}

#[test]
fn spring_step_after_n_iterations() {
    let Some(gpu) = common::gpu() else { return };
    check_iterations(gpu, Solver::Explicit, 201);
}

#[test]
fn spring_step_stop_status() {
    let Some(gpu) = common::gpu() else { return };
    check_stop_status(gpu, Solver::Explicit);
}
