//! The demo's head phantom and jaw-advance plan, and the accelerated
//! solver's equilibrium on a ~10⁵-node network.

mod common;

use chisel::Backend;
use chisel::tissue::phantom::{self, FRAN_CHIN_ADVANCE_TOML, FRAN_GRID, HeadPhantom};
use chisel::tissue::{
    Fragments, Iterations, NetworkParams, Plan, RelaxOptions, Solver, SpringNetwork, Status, relax,
};
use glam::Vec3;

fn phantom_network(resolution: usize) -> (HeadPhantom, SpringNetwork) {
    let head = phantom::head_phantom(resolution).unwrap();
    let params = NetworkParams {
        origin: Some(head.origin.to_array()),
        ..NetworkParams::default()
    };
    let net = SpringNetwork::build(&head.skin, Some(&head.skull), &params).unwrap();
    (head, net)
}

#[test]
fn jaw_advance_moves_the_chin_not_the_forehead() {
    let (head, net) = phantom_network(24);
    let plan = HeadPhantom::demo_plan()
        .unwrap()
        .resolve(&net, &head.fragments())
        .unwrap();
    assert_eq!(plan.steps[0].bone_vertices.len(), head.jaw_vertices.len());
    let opts = RelaxOptions {
        solver: Solver::Chebyshev,
        ..RelaxOptions::default()
    };
    let r = relax(&net, &plan, &opts, Backend::Cpu).unwrap();
    assert_eq!(r.status, Status::Converged, "{:?}", r.steps);
    let disp_at = |dir: Vec3| {
        let (i, _) = head
            .skin
            .positions
            .iter()
            .enumerate()
            .max_by(|a, b| {
                a.1.normalize()
                    .dot(dir)
                    .total_cmp(&b.1.normalize().dot(dir))
            })
            .unwrap();
        r.displacement[i]
    };
    let chin = disp_at(Vec3::new(0.0, -0.75, 0.66).normalize());
    let forehead = disp_at(Vec3::new(0.0, 0.6, 0.8).normalize());
    let back = disp_at(Vec3::new(0.0, 0.0, -1.0));
    eprintln!(
        "chin {chin} mm, forehead {forehead} mm, back {back} mm, {} iterations",
        r.iterations
    );
    assert!(
        chin > 1.0 && chin < 9.0,
        "chin moved {chin} mm for a 6 mm jaw advance"
    );
    assert!(forehead < 0.2 * chin && back < 0.05 * chin);
    // The skin mesh carries the displacement for the caller to write.
    let skin = r.skin_mesh(&net);
    assert_eq!(skin.n_vertices(), head.skin.n_vertices());
}

#[test]
fn demo_relaxation_on_the_gpu_matches_the_cpu() {
    let Some(gpu) = common::gpu() else { return };
    let (head, net) = phantom_network(24);
    let plan = HeadPhantom::demo_plan()
        .unwrap()
        .resolve(&net, &head.fragments())
        .unwrap();
    let opts = RelaxOptions {
        solver: Solver::Chebyshev,
        ..RelaxOptions::default()
    };
    let a = relax(&net, &plan, &opts, Backend::Cpu).unwrap();
    let b = relax(&net, &plan, &opts, Backend::Gpu(&gpu)).unwrap();
    assert_eq!(a.iterations, b.iterations);
    assert_eq!(b.status, Status::Converged);
    let tol = chisel::tissue::cpu::position_tolerance(a.iterations as u32, net.diagonal());
    chisel::parity::compare_vec("phantom", &a.positions, &b.positions, tol)
        .unwrap_or_else(|m| panic!("{m}"));
}

/// ~10⁵ nodes: fran_cut's grid refined 4× (102,483 nodes), on the CPU
/// mirror (the GPU case of this size and larger is in `benches/relax.rs`).
///
/// A 0.25 mm chin increment. The explicit scheme runs a fixed 16,000
/// iterations: at this size its softest (overdamped sliding) modes relax
/// at ~3·10⁻⁴ per iteration, so its |v| < ε criterion fires long before the
/// positions settle (max |v| ≈ λ e / γ is tiny for tiny λ). Chebyshev runs
/// to its own stop (ε = 5e-8, at the f32 floor of its pseudo-velocity).
///
/// Known limit, measured: the static problem is not unique here. A few
/// subcutis nodes next to the moved bone have two stable states (adjacent
/// nodes pass each other: measured 5 nodes differ by > 0.1 mm, max
/// 0.29 mm); the explicit dynamics and the momentum iteration land in
/// different ones, Chebyshev's with the lower energy. A single 1 mm
/// increment buckles the skin below the chin the same way (≈ 480 nodes,
/// 1.28 mm). That is non-uniqueness, not precision (both residuals at the
/// f32 floor). So the test asserts: all but 1 % of the nodes agree within
/// 1 % of the largest displacement, Chebyshev's equilibrium has no higher
/// spring energy than the explicit one, and Chebyshev needs ≥ 4× fewer
/// iterations. Takes ~1.5 min at the test profile, hence ignored.
#[test]
#[ignore = "~1.5 min on 2 busy cores at the test profile; run with --ignored"]
fn chebyshev_reaches_the_explicit_equilibrium_on_1e5_nodes() {
    let Some(face) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let fine = phantom::refine_grid(&face, FRAN_GRID.0, FRAN_GRID.1, 4).unwrap();
    let net = SpringNetwork::build(&fine, None, &NetworkParams::default()).unwrap();
    assert!(net.n_nodes() > 100_000);
    let plan = |iterations| {
        let mut plan = Plan::from_toml_str(FRAN_CHIN_ADVANCE_TOML, "chin").unwrap();
        plan.steps[0].translate = plan.steps[0].translate.map(|c| c / 16.0);
        plan.steps[0].increments = 1;
        plan.steps[0].iterations = iterations;
        plan.resolve(&net, &Fragments::new()).unwrap()
    };
    let opts = |solver| RelaxOptions {
        solver,
        epsilon: Some(5e-8),
        max_iterations: 20_000,
        ..RelaxOptions::default()
    };
    let a = relax(
        &net,
        &plan(Iterations::Fixed(16_000)),
        &opts(Solver::Explicit),
        Backend::Cpu,
    )
    .unwrap();
    let b = relax(
        &net,
        &plan(Iterations::Converge),
        &opts(Solver::Chebyshev),
        Backend::Cpu,
    )
    .unwrap();
    assert!(
        matches!(b.status, Status::Converged | Status::Stalled),
        "{:?}",
        b.status
    );
    let dist: Vec<f32> = (0..net.n_free)
        .map(|i| {
            Vec3::from_slice(&a.positions[i][..3]).distance(Vec3::from_slice(&b.positions[i][..3]))
        })
        .collect();
    let max_dist = dist.iter().copied().fold(0.0, f32::max);
    let disp = a.max_displacement;
    let off = dist.iter().filter(|&&d| d > 1e-2 * disp).count();
    let energy = |r: &chisel::tissue::RelaxReport| -> f64 {
        let x = |i: u32| Vec3::from_slice(&r.positions[i as usize][..3]).as_dvec3();
        net.springs
            .iter()
            .map(|s| {
                let m = &net.materials[s.material as usize];
                let l = s.rest as f64;
                let e = x(s.a).distance(x(s.b)) - l;
                let knee = (e - m.knee as f64 * l).max(0.0);
                0.5 * m.c1 as f64 * e * e + 0.5 * (m.c2 - m.c1) as f64 * knee * knee
            })
            .sum()
    };
    let (e_a, e_b) = (energy(&a), energy(&b));
    eprintln!(
        "1e5 nodes: max dist {max_dist:e}, {off} nodes off by > 1 % of the max displacement {disp:e}; \
         energy explicit {e_a:e}, chebyshev {e_b:e}; explicit {} it, chebyshev {} it ({:?})",
        a.iterations, b.iterations, b.status
    );
    assert!(disp > 1e-4);
    assert!(off * 100 < net.n_free, "{off} of {} nodes", net.n_free);
    assert!(e_b <= e_a * (1.0 + 1e-6), "{e_b} vs {e_a}");
    assert!(b.iterations * 4 < a.iterations);
}
