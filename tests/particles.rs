//! Witkin–Heckbert particles (SPEC §3.2) and the cell list: the cell list
//! equals a brute-force search (with negative controls), a relaxation on
//! the dumbbell converges onto the surface at the spacing asked for and
//! covers it, and runs are deterministic.

use chisel::Backend;
use chisel::implicit::field::FieldInput;
use chisel::implicit::field::cpu::skeletal_field;
use chisel::implicit::scene::EXAMPLES;
use chisel::implicit::{Scene, grid};
use chisel::particles::wh::{equilibrium_spacing, sigma_for_spacing};
use chisel::particles::{CellList, Particles, Sampler, WhOptions};
use glam::Vec3;

mod common;

/// Points on a unit sphere, a cluster, points on cell faces and far away.
fn cloud(seed: u64, n: usize) -> Vec<Vec3> {
    let mut rng = common::xorshift(seed);
    let mut u = move || (rng() >> 11) as f32 / (1u64 << 53) as f32;
    let mut out: Vec<Vec3> = (0..n)
        .map(|_| {
            let v = Vec3::new(2.0 * u() - 1.0, 2.0 * u() - 1.0, 2.0 * u() - 1.0);
            v.normalize_or(Vec3::X) * (1.0 + 0.05 * u())
        })
        .collect();
    out.extend((0..n / 10).map(|_| Vec3::new(0.3, 0.3, 0.3) + 0.02 * Vec3::new(u(), u(), u())));
    // Exactly on multiples of 0.25 (cell faces for cutoff + skin = 0.25).
    out.extend(
        (0..20).map(|k| Vec3::new(-1.0 + 0.25 * (k % 8) as f32, 0.25 * (k / 8) as f32, 0.5)),
    );
    out.push(Vec3::new(40.0, -3.0, 2.0));
    out
}

fn brute(pos: &[Vec3], cutoff: f32) -> Vec<Vec<usize>> {
    (0..pos.len())
        .map(|i| {
            (0..pos.len())
                .filter(|&j| j != i && pos[i].distance_squared(pos[j]) < cutoff * cutoff)
                .collect()
        })
        .collect()
}

fn listed(cells: &CellList, pos: &[Vec3], cutoff: f32) -> Vec<Vec<usize>> {
    (0..pos.len())
        .map(|i| {
            let mut v: Vec<usize> = cells
                .candidates(i)
                .filter(|&j| pos[i].distance_squared(pos[j]) < cutoff * cutoff)
                .collect();
            v.sort_unstable();
            v
        })
        .collect()
}

#[test]
fn cell_list_equals_brute_force_until_half_the_skin_is_used() {
    let (cutoff, skin) = (0.2, 0.05);
    for seed in [1, 2, 3] {
        let pos = cloud(seed, 3000);
        let cells = CellList::build(&pos, cutoff, skin).unwrap();
        assert!(cells.cell >= cutoff + skin);
        assert_eq!(
            listed(&cells, &pos, cutoff),
            brute(&pos, cutoff),
            "seed {seed}"
        );
        // Every particle moved by up to skin/2 in a random direction.
        let mut rng = common::xorshift(seed + 10);
        let mut u = move || (rng() >> 11) as f32 / (1u64 << 53) as f32;
        let moved: Vec<Vec3> = pos
            .iter()
            .map(|p| {
                *p + 0.5
                    * skin
                    * u()
                    * Vec3::new(2.0 * u() - 1.0, 2.0 * u() - 1.0, 2.0 * u() - 1.0)
                        .normalize_or(Vec3::X)
            })
            .collect();
        assert!(cells.still_valid(&moved, cutoff));
        assert_eq!(
            listed(&cells, &moved, cutoff),
            brute(&moved, cutoff),
            "seed {seed}, moved"
        );
        // Negative controls: a move beyond skin/2 asks for a rebuild, and a
        // list built for half the cutoff misses pairs.
        let mut far = moved.clone();
        far[7] += Vec3::new(0.5 * skin + 1e-3, 0.0, 0.0) + (pos[7] - moved[7]);
        assert!(!cells.still_valid(&far, cutoff));
        assert!(
            !cells.still_valid(&moved, cutoff * 1.01),
            "a larger cutoff needs a rebuild"
        );
        let near = &pos[..pos.len() - 1];
        let short = CellList::build(near, cutoff / 4.0, 0.0).unwrap();
        assert!(short.cell < cutoff);
        assert!(
            listed(&short, near, cutoff) != brute(near, cutoff),
            "a too-fine list must miss pairs"
        );
    }
    assert_eq!(CellList::build(&[], 0.2, 0.0).unwrap().items.len(), 0);
    assert!(CellList::build(&[Vec3::NAN], 0.2, 0.0).is_err());
}

/// x* for the default energy, against the lattice sum by hand at x*.
#[test]
fn equilibrium_spacing_solves_the_lattice_sum() {
    let x = equilibrium_spacing(0.8);
    assert!((x - 1.6258).abs() < 1e-3, "{x}");
    // First ring alone: 6 exp(−x²/2)(1 − x²/9)² is the bulk of Ê.
    let ring = 6.0 * (-x * x / 2.0).exp() * (1.0 - x * x / 9.0f64).powi(2);
    assert!(ring > 0.6 && ring < 0.8, "{ring}");
}

/// Relaxed dumbbell (t = 0) at edge length 0.08: on the surface, at the
/// spacing asked for, covering the dense reference, deterministic.
fn relaxed(
    r: f64,
) -> (
    Sampler,
    chisel::particles::wh::Relaxation,
    chisel::implicit::Pose,
) {
    let scene = Scene::from_toml_str(EXAMPLES[0].1, "dumbbell").unwrap();
    let pose = scene.pose(0.0);
    let field = FieldInput::new(&pose).unwrap();
    let opts = WhOptions::default();
    let sh = sigma_for_spacing(r, &opts);
    let start = Particles::on_surface(&pose, sh, Backend::Cpu).unwrap();
    let mut s = Sampler::new(start, sh, opts, &field).unwrap();
    let relax = s.relax(&field, 3000, Backend::Cpu).unwrap();
    (s, relax, pose)
}

#[test]
fn relaxation_converges_on_the_surface_at_the_asked_spacing() {
    let r = 0.08;
    let (s, relax, pose) = relaxed(r);
    assert!(relax.converged, "{relax:?}");
    let field = FieldInput::new(&pose).unwrap();
    for p in &s.particles.points {
        let (f, _) = skeletal_field(&field, [p[0], p[1], p[2]]);
        let g = Vec3::from_array(f.grad).length();
        assert!(
            f.value.abs() / g <= relax.residual_bound,
            "{p:?}: {}",
            f.value / g
        );
    }
    // Hexagonal-equivalent spacing from the area of a dense reference.
    let reference = grid::marching_cubes(&pose, 0.02, Backend::Cpu).unwrap();
    let area: f64 = reference.groups.iter().map(|g| g.area).sum();
    let n = s.particles.len() as f64;
    let spacing = (2.0 * area / (3f64.sqrt() * n)).sqrt();
    assert!(
        (spacing / r - 1.0).abs() < 0.15,
        "spacing {spacing} for edge length {r} ({n} particles)"
    );
    // Every reference vertex within 2σ̂ of a particle (no holes).
    let pos = s.particles.positions();
    let cells = CellList::build(&pos, 2.0 * s.sigma_hat, 0.0).unwrap();
    let mut probe = pos.clone();
    let first = probe.len();
    probe.extend(reference.mesh.positions.iter().step_by(7));
    let near = CellList::build(&probe, 2.0 * s.sigma_hat, 0.0).unwrap();
    for v in first..probe.len() {
        let covered = near
            .candidates(v)
            .any(|j| j < first && probe[v].distance(probe[j]) < 2.0 * s.sigma_hat);
        assert!(
            covered,
            "reference vertex {} has no particle within 2σ̂",
            probe[v]
        );
    }
    drop(cells);
    // Deterministic: a second run gives the same particles, bit for bit.
    let (again, _, _) = relaxed(r);
    assert_eq!(again.particles, s.particles);
}
