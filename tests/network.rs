//! The particle spring network (SPEC §3.3): χ through every local
//! operation, the energy of the spring law on a still surface (with a
//! negative control), and the examples animated at a small size: a closed,
//! oriented manifold without self-intersections every frame, the field's
//! topology every frame, the dumbbell's break and merge within ±0.03 of the
//! analytic centre distance.

use chisel::Backend;
use chisel::implicit::field::FieldInput;
use chisel::implicit::scene::EXAMPLES;
use chisel::implicit::{Scene, grid};
use chisel::mesh::Topology;
use chisel::mesh::intersect::self_intersections;
use chisel::particles::animate::{self, start_network};
use chisel::particles::network::{NetworkInput, NetworkParams, cpu};
use chisel::particles::{Network, NetworkOptions};
use glam::Vec3;

mod common;

fn scene(name: &str) -> Scene {
    let text = EXAMPLES.iter().find(|e| e.0 == name).unwrap().1;
    Scene::from_toml_str(text, name).unwrap()
}

/// (V, E, F, χ) of a closed mesh.
fn counts(net: &Network) -> (i64, i64, i64) {
    let t = Topology::of(&net.mesh());
    (t.used_vertices as i64, t.edges as i64, t.triangles as i64)
}

#[test]
fn split_and_collapse_change_v_e_f_by_one_three_two() {
    let s = scene("torus");
    let field = FieldInput::new(&s.pose(0.0)).unwrap();
    let mut net = start_network(&s, 0.08, NetworkOptions::default(), Backend::Cpu).unwrap();
    let mut rng = common::xorshift(5);
    let (mut splits, mut collapses) = (0, 0);
    // Random splits, and collapses of one half of the edge the last split
    // made (half-length edges, as in a real run).
    let mut last: Option<(u32, u32)> = None;
    for _ in 0..400 {
        let before = counts(&net);
        let after = match last.filter(|_| !rng().is_multiple_of(3)) {
            Some((a, m)) => {
                last = None;
                if net.collapse(a, m) {
                    collapses += 1;
                    (before.0 - 1, before.1 - 3, before.2 - 2)
                } else {
                    before
                }
            }
            None => {
                let t = net.triangles[(rng() % net.triangles.len() as u64) as usize];
                let k = (rng() % 3) as usize;
                let m = net
                    .split(t[k], t[(k + 1) % 3])
                    .expect("every edge of a closed mesh has two triangles");
                last = Some((t[k], m));
                splits += 1;
                (before.0 + 1, before.1 + 3, before.2 + 2)
            }
        };
        assert_eq!(counts(&net), after);
        let topo = net.check().unwrap();
        assert_eq!(
            topo.components.iter().map(|c| c.genus).collect::<Vec<_>>(),
            [Some(1)]
        );
    }
    assert!(
        splits > 100 && collapses > 20,
        "{splits} splits, {collapses} collapses"
    );
    // The network still relaxes onto the surface afterwards.
    for _ in 0..30 {
        net.iterate(&field, 0.0, Backend::Cpu).unwrap();
    }
    assert!(self_intersections(&net.mesh()).pairs.is_empty());
}

/// On a still surface with κ = 0 and no remeshing, U = ρ Σ (l³/3R − l²/2)
/// falls at every step for ρΔt = 0.25 from a relaxed network (the
/// projected gradient flow of eq. 13; the rest lattice is stable below
/// 1/3); at ρΔt = 1.2 it does not.
#[test]
fn spring_energy_falls_under_the_step_bound_and_not_beyond() {
    let s = scene("torus");
    let field = FieldInput::new(&s.pose(0.0)).unwrap();
    let mut net = start_network(&s, 0.08, NetworkOptions::default(), Backend::Cpu).unwrap();
    // Near the rest lattice first (the bound is the lattice's).
    for _ in 0..40 {
        net.iterate(&field, 0.0, Backend::Cpu).unwrap();
    }
    let (offsets, springs) = net.springs();
    let run = |rho_dt: f32| {
        let mut pos: Vec<[f32; 4]> = net.positions.iter().map(|p| [p.x, p.y, p.z, 0.0]).collect();
        let mut energies = Vec::new();
        for _ in 0..40 {
            let input = NetworkInput {
                params: NetworkParams {
                    n_vertices: pos.len() as u32,
                    dt: rho_dt,
                    delta: 0.0,
                    kappa: 0.5,
                    rho: 1.0,
                    g_min2: net.g_min * net.g_min,
                    step_max: f32::MAX,
                },
                offsets: &offsets,
                springs: &springs,
                positions: &pos,
            };
            pos = cpu::network_update(&field, &input).0;
            let mut e = 0.0f64;
            for i in 0..pos.len() {
                for sp in &springs[offsets[i] as usize..offsets[i + 1] as usize] {
                    let j = sp[0] as usize;
                    if j > i {
                        let l = f64::from(
                            (Vec3::from_slice(&pos[i][..3]) - Vec3::from_slice(&pos[j][..3]))
                                .length(),
                        );
                        let r = f64::from(f32::from_bits(sp[1]));
                        e += l * l * l / (3.0 * r) - l * l / 2.0;
                    }
                }
            }
            energies.push(e);
        }
        energies
    };
    let stable = run(0.25);
    for w in stable.windows(2).skip(5) {
        assert!(w[1] <= w[0] + 1e-6 * w[0].abs(), "energy rose: {w:?}");
    }
    let unstable = run(1.2);
    assert!(
        unstable.windows(2).any(|w| w[1] > w[0] + 1e-6 * w[0].abs()),
        "the control must fail"
    );
}

/// Animates `name` with the network at edge length `r` over `frames` on
/// the CPU and checks every frame; returns the topology events' (time,
/// components, reseed).
fn animate_checked(name: &str, r: f64, frames: u32, guard: bool) -> Vec<(f64, usize, bool)> {
    animate_on(name, r, frames, guard, Backend::Cpu).0
}

/// Topology events (time, components, reseed) and each frame's sorted
/// genus list (one entry per component).
type Animated = (Vec<(f64, usize, bool)>, Vec<Vec<i64>>);

/// [`animate_checked`] on `backend`, also returning each frame's genus
/// lists.
fn animate_on(name: &str, r: f64, frames: u32, guard: bool, backend: Backend<'_>) -> Animated {
    let s = scene(name);
    let times = animate::frame_times(&s, frames);
    let opts = NetworkOptions {
        guard,
        ..NetworkOptions::default()
    };
    let net = start_network(&s, r, opts, backend).unwrap();
    let mut events = Vec::new();
    let mut per_frame = Vec::new();
    animate::network(&s, &times, net, backend, |net, t, steps| {
        let mesh = net.mesh();
        let topo = net.check().unwrap_or_else(|e| panic!("{name} t={t}: {e}"));
        assert!(
            self_intersections(&mesh).pairs.is_empty(),
            "{name} t={t}: self-intersections"
        );
        let mut genus: Vec<i64> = topo.components.iter().filter_map(|c| c.genus).collect();
        genus.sort_unstable();
        let reference = grid::marching_cubes(&s.pose(t), r / 4.0, Backend::Cpu).unwrap();
        let mut want: Vec<i64> = reference.groups.iter().filter_map(|g| g.genus).collect();
        want.sort_unstable();
        assert_eq!(genus, want, "{name} t={t}: components/genus vs the field's");
        events.extend(
            steps
                .events
                .iter()
                .map(|e| (e.time, e.components, e.reseed)),
        );
        per_frame.push(genus);
        Ok(())
    })
    .unwrap();
    (events, per_frame)
}

#[test]
fn dumbbell_breaks_at_the_analytic_distance() {
    let events = animate_checked("dumbbell", 0.1, 5, false);
    let split = events.iter().find(|e| e.1 == 2).expect("a split event");
    let distance = 2.0 * (1.0 + 0.4 * split.0);
    assert!(
        (distance - 2.0 * 4f64.ln().sqrt()).abs() <= 0.03,
        "split at centre distance {distance}"
    );
}

#[test]
fn reverse_dumbbell_merges_at_the_analytic_distance() {
    let events = animate_checked("dumbbell_merge", 0.1, 5, false);
    let merge = events.iter().find(|e| e.1 == 1).expect("a merge event");
    let distance = 2.0 * (1.4 - 0.4 * merge.0);
    assert!(
        (distance - 2.0 * 4f64.ln().sqrt()).abs() <= 0.03,
        "merge at centre distance {distance}"
    );
}

#[test]
fn torus_and_finger_keep_their_topology() {
    assert!(animate_checked("torus", 0.1, 4, false).is_empty());
    assert!(animate_checked("finger", 0.1, 4, false).is_empty());
}

/// The molecule's tunnels open and close where the local surgery alone
/// does not follow them; with the guard every frame holds, and what the
/// guard did is reported as reseed events at frame times.
#[test]
fn molecule_frames_hold_with_the_guard() {
    let s = scene("molecule");
    let times = animate::frame_times(&s, 3);
    let events = animate_checked("molecule", 0.15, 3, true);
    for e in events.iter().filter(|e| e.2) {
        assert!(times.contains(&e.0), "a reseed between frames: {e:?}");
    }
}

/// The five examples on the GPU (lavapipe in CI) and the CPU: the same
/// components and genus every frame, each checked against the field as in
/// [`animate_checked`] (the local surgery alone except on the molecule).
#[test]
fn cpu_and_gpu_networks_have_the_same_topology_every_frame() {
    let Some(gpu) = common::gpu() else {
        return;
    };
    for name in ["dumbbell", "dumbbell_merge", "torus", "finger", "molecule"] {
        let guard = name == "molecule";
        let cpu = animate_on(name, 0.15, 3, guard, Backend::Cpu).1;
        let gpu = animate_on(name, 0.15, 3, guard, Backend::Gpu(gpu)).1;
        assert_eq!(cpu, gpu, "{name}: per-frame genus lists, CPU vs GPU");
    }
}
