//! Stop criteria and fixed-iteration increments of the relaxation, and the
//! accelerated (Chebyshev) solver's equilibrium against the explicit one.

use super::*;

fn one_step_plan(
    net: &SpringNetwork,
    dx: f32,
    increments: u32,
    iterations: Iterations,
) -> chisel::tissue::ResolvedPlan {
    Plan {
        name: None,
        dynamics: Default::default(),
        cuts: Vec::new(),
        steps: vec![Step {
            name: Some("move".into()),
            select: Selector::Vertices((0..net.n_bone() as u32).step_by(3).collect()),
            translate: [dx, 0.0, 0.0],
            rotate: None,
            increments,
            iterations,
            reset_velocities: false,
        }],
        source: None,
    }
    .resolve(net, &Fragments::new())
    .unwrap()
}

#[test]
fn stop_criteria_converged_stalled_diverged_limit() {
    let mesh = common::icosphere(1);
    let net = SpringNetwork::build(&mesh, None, &NetworkParams::default()).unwrap();
    let plan = one_step_plan(&net, 0.05, 2, Iterations::Converge);
    let r = relax(&net, &plan, &RelaxOptions::default(), Backend::Cpu).unwrap();
    assert_eq!(r.status, Status::Converged);
    assert!(
        r.steps[0]
            .increments
            .iter()
            .all(|i| i.max_speed < r.epsilon)
    );
    assert!(r.iterations > 0 && r.iterations.is_multiple_of(25));
    assert!(r.max_displacement > 0.0);

    let limited = RelaxOptions {
        max_iterations: 30,
        epsilon: Some(1e-12),
        ..RelaxOptions::default()
    };
    let r = relax(&net, &plan, &limited, Backend::Cpu).unwrap();
    assert_eq!(r.steps[0].increments[0].status, Status::IterationLimit);
    assert_eq!(r.steps[0].increments[0].iterations, 30);

    // Undamped oscillation with a generous δ: stalled at the first window.
    let osc = SpringNetwork::from_parts(
        &[Vec3::new(1.0, 0.0, 0.0), Vec3::ZERO],
        1,
        &[(0, 1, 0)],
        &[Material::linear(1.0)],
        1.0,
        0.0,
    )
    .unwrap();
    let plan = Plan::from_toml_str(
        "[[step]]\nselect = { vertices = [0] }\ntranslate = [0.5, 0, 0]\n",
        "o",
    )
    .unwrap()
    .resolve(&osc, &Fragments::new())
    .unwrap();
    let stall = RelaxOptions {
        delta: Some(10.0),
        epsilon: Some(1e-9),
        ..RelaxOptions::default()
    };
    let r = relax(&osc, &plan, &stall, Backend::Cpu).unwrap();
    assert_eq!(r.status, Status::Stalled);
    assert_eq!(r.iterations, 100);
    assert!(r.steps[0].increments[0].window_change.unwrap() < 10.0);

    // Forced Δt far above the limit: diverged, and the plan stops there.
    let limit = explicit::stability_limit(&net);
    let wild = RelaxOptions {
        dt: Some(3.0 * limit),
        force_dt: true,
        ..RelaxOptions::default()
    };
    let plan = one_step_plan(&net, 0.05, 4, Iterations::Converge);
    let r = relax(&net, &plan, &wild, Backend::Cpu).unwrap();
    assert_eq!(r.status, Status::Diverged);
    assert_eq!(
        r.steps[0].increments.len(),
        1,
        "plan must stop at divergence"
    );
}

#[test]
fn fixed_iteration_increments_and_velocity_reset() {
    let net = SpringNetwork::build(&common::icosphere(1), None, &NetworkParams::default()).unwrap();
    let plan = one_step_plan(&net, 0.05, 10, Iterations::Fixed(1));
    let carry = relax(&net, &plan, &RelaxOptions::default(), Backend::Cpu).unwrap();
    assert_eq!(carry.iterations, 10);
    assert_eq!(carry.steps[0].increments.len(), 10);
    let mut reset_plan = plan.clone();
    reset_plan.steps[0].reset_velocities = true;
    let reset = relax(&net, &reset_plan, &RelaxOptions::default(), Backend::Cpu).unwrap();
    // With one iteration per increment and zeroed velocities the network
    // can only creep: it moves strictly less than when momentum carries.
    assert!(reset.max_displacement < carry.max_displacement);
    assert!(reset.max_displacement > 0.0);
}

// ---------------------------------------------------------------- accelerated solver

/// Relaxes `plan` with both solvers to a tight ε and returns (max distance
/// between the equilibria, largest displacement, explicit iterations,
/// chebyshev iterations).
fn compare_solvers(
    net: &SpringNetwork,
    plan: &chisel::tissue::ResolvedPlan,
    eps: f32,
) -> (f32, f32, u64, u64) {
    let opts = |solver| RelaxOptions {
        solver,
        epsilon: Some(eps),
        max_iterations: 1_000_000,
        ..RelaxOptions::default()
    };
    let a = relax(net, plan, &opts(Solver::Explicit), Backend::Cpu).unwrap();
    let b = relax(net, plan, &opts(Solver::Chebyshev), Backend::Cpu).unwrap();
    let per_inc = |r: &chisel::tissue::RelaxReport| {
        r.steps[0]
            .increments
            .iter()
            .map(|i| i.iterations)
            .collect::<Vec<_>>()
    };
    eprintln!("explicit {:?}\nchebyshev {:?}", per_inc(&a), per_inc(&b));
    // Stalled = at rest within the f32 noise floor of the positions.
    for r in [&a, &b] {
        assert!(
            matches!(r.status, Status::Converged | Status::Stalled),
            "{:?}",
            r.status
        );
    }
    let dist = (0..net.n_free)
        .map(|i| {
            let (p, q) = (a.positions[i], b.positions[i]);
            Vec3::new(p[0] - q[0], p[1] - q[1], p[2] - q[2]).length()
        })
        .fold(0.0, f32::max);
    let disp = (0..net.n_free)
        .map(|i| {
            let (p, r) = (a.positions[i], net.rest[i]);
            Vec3::new(p[0] - r[0], p[1] - r[1], p[2] - r[2]).length()
        })
        .fold(0.0, f32::max);
    (dist, disp, a.iterations, b.iterations)
}

#[test]
fn chebyshev_reaches_the_explicit_equilibrium_on_a_sphere() {
    let net = SpringNetwork::build(&common::icosphere(3), None, &NetworkParams::default()).unwrap();
    let plan = one_step_plan(&net, 0.05, 1, Iterations::Converge);
    let (dist, disp, it_e, it_c) = compare_solvers(&net, &plan, 1e-6);
    eprintln!("icosphere(3): dist {dist:e}, disp {disp:e}, explicit {it_e}, chebyshev {it_c}");
    assert!(disp > 0.01);
    assert!(dist < 1e-3 * disp, "{dist} vs {disp}");
    assert!(it_c < it_e);
}

#[test]
fn chebyshev_reaches_the_explicit_equilibrium_on_fran_cut() {
    let Some(face) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let net = SpringNetwork::build(&face, None, &NetworkParams::default()).unwrap();
    let plan = Plan::from_toml_str(phantom::FRAN_CHIN_ADVANCE_TOML, "chin")
        .unwrap()
        .resolve(&net, &Fragments::new())
        .unwrap();
    // ε = 3e-7 m/s is just above the f32 noise floor of 0.1 m coordinates.
    let (dist, disp, it_e, it_c) = compare_solvers(&net, &plan, 3e-7);
    eprintln!("fran_cut: dist {dist:e}, disp {disp:e}, explicit {it_e}, chebyshev {it_c}");
    assert!(disp > 0.002, "{disp}");
    assert!(dist < 2.5e-3 * disp, "{dist} vs {disp}");
    assert!(it_c < it_e);
}
