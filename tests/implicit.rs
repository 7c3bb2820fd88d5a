//! Skeletal implicit fields (SPEC §3.1): the mirror against an independent
//! f64 oracle (values, ∇F by central differences, F_t by differences in
//! time), culling against no culling, the dumbbell's topology change, the
//! example scenes, and marching-cubes surfaces of known topology.

use chisel::Backend;
use chisel::implicit::field::{FieldInput, cpu};
use chisel::implicit::scene::EXAMPLES;
use chisel::implicit::{Blend, Influence, Pose, Primitive, Scene, Skeleton, grid};
use glam::DVec3;

mod common;

/// e(d) straight from the definitions (distance, not squared distance).
fn e64(inf: &Influence, d: f64) -> f64 {
    match *inf {
        Influence::Blobby { a, b } => b * (-a * d * d).exp(),
        Influence::Wyvill { radius, strength } => {
            if d >= radius {
                return 0.0;
            }
            let t = (d / radius).powi(2);
            strength * (1.0 - 22.0 / 9.0 * t + 17.0 / 9.0 * t * t - 4.0 / 9.0 * t * t * t)
        }
        Influence::Metaball { radius, strength } => {
            if d <= radius / 3.0 {
                strength * (1.0 - 3.0 * (d / radius).powi(2))
            } else if d < radius {
                1.5 * strength * (1.0 - d / radius).powi(2)
            } else {
                0.0
            }
        }
    }
}

fn segment_distance(x: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let u = if ab.length_squared() > 0.0 {
        ((x - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (x - (a + u * ab)).length()
}

fn distance(s: &Skeleton, x: DVec3) -> f64 {
    let p = s.points();
    s.pieces()
        .iter()
        .map(|[i, j]| segment_distance(x, p[*i], p[*j]))
        .fold(f64::INFINITY, f64::min)
}

/// F(x) − I in f64, every primitive, no culling.
fn oracle(pose: &Pose, x: DVec3) -> f64 {
    let terms = pose
        .primitives
        .iter()
        .map(|p| p.weight * e64(&p.influence, distance(&p.skeleton, x)));
    let f = match pose.blend {
        Blend::Max => terms.fold(0.0, f64::max),
        _ => terms.sum(),
    };
    f - pose.iso
}

/// A mixed, animated scene: a blobby point, a Wyvill segment, a metaball
/// polyline, a negative blobby segment; ends, parameters and weights move.
fn mixed(blend: Blend) -> Scene {
    let w = |v: f64| if blend == Blend::Weighted { v } else { 1.0 };
    let primitives = vec![
        Primitive {
            skeleton: Skeleton::Point(DVec3::new(0.1, 0.2, -0.1)),
            influence: Influence::Blobby { a: 2.0, b: 1.2 },
            weight: w(1.5),
        },
        Primitive {
            skeleton: Skeleton::Segment(DVec3::new(-1.0, 0.0, 0.0), DVec3::new(0.5, 0.8, 0.3)),
            influence: Influence::Wyvill {
                radius: 1.1,
                strength: 0.9,
            },
            weight: w(0.8),
        },
        Primitive {
            skeleton: Skeleton::Polyline {
                points: vec![
                    DVec3::new(0.0, -1.0, 0.0),
                    DVec3::new(0.8, -0.6, 0.2),
                    DVec3::new(1.2, 0.1, -0.3),
                ],
                closed: false,
            },
            influence: Influence::Metaball {
                radius: 0.9,
                strength: 1.1,
            },
            weight: w(1.0),
        },
        Primitive {
            skeleton: Skeleton::Segment(DVec3::new(0.3, 0.3, 0.6), DVec3::new(0.4, -0.2, 0.7)),
            influence: Influence::Blobby {
                a: 6.0,
                b: if blend == Blend::Max { 0.4 } else { -0.4 },
            },
            weight: w(1.2),
        },
    ];
    let keys = vec![
        chisel::implicit::Key {
            time: 1.0,
            primitive: 0,
            skeleton: Some(Skeleton::Point(DVec3::new(0.4, 0.0, 0.1))),
            influence: Some(Influence::Blobby { a: 2.6, b: 0.9 }),
            weight: (blend == Blend::Weighted).then_some(1.1),
        },
        chisel::implicit::Key {
            time: 1.0,
            primitive: 1,
            skeleton: Some(Skeleton::Segment(
                DVec3::new(-1.2, 0.1, 0.0),
                DVec3::new(0.6, 0.6, 0.5),
            )),
            influence: Some(Influence::Wyvill {
                radius: 1.3,
                strength: 1.0,
            }),
            weight: None,
        },
        chisel::implicit::Key {
            time: 1.0,
            primitive: 2,
            skeleton: Some(Skeleton::Polyline {
                points: vec![
                    DVec3::new(0.1, -1.1, 0.0),
                    DVec3::new(0.8, -0.5, 0.3),
                    DVec3::new(1.1, 0.2, -0.2),
                ],
                closed: false,
            }),
            influence: Some(Influence::Metaball {
                radius: 1.0,
                strength: 1.3,
            }),
            weight: (blend == Blend::Weighted).then_some(0.7),
        },
    ];
    Scene::new(0.5, blend, primitives, &keys).unwrap()
}

fn eval(input: &FieldInput, x: DVec3) -> (chisel::implicit::field::Sample, cpu::Scales) {
    cpu::skeletal_field(input, x.as_vec3().to_array())
}

/// Points in a box around the mixed scene.
fn probe_points(n: usize, seed: u64) -> Vec<DVec3> {
    let mut rng = common::xorshift(seed);
    let mut u = move || (rng() >> 11) as f64 / (1u64 << 53) as f64;
    (0..n)
        .map(|_| DVec3::new(3.6 * u() - 1.8, 3.6 * u() - 1.8, 2.4 * u() - 1.2))
        .collect()
}

/// Whether x is near a crease of a polyline's distance (two segments
/// almost equally near) or a C¹ seam of the influences, where central
/// differences are unreliable.
fn near_seam(pose: &Pose, x: DVec3) -> bool {
    pose.primitives.iter().any(|p| {
        let pts = p.skeleton.points();
        let mut ds: Vec<f64> = p
            .skeleton
            .pieces()
            .iter()
            .map(|[i, j]| segment_distance(x, pts[*i], pts[*j]))
            .collect();
        ds.sort_by(f64::total_cmp);
        let d = ds[0];
        let crease = ds.len() > 1 && ds[1] - ds[0] < 1e-3;
        let r = p.influence.params()[0];
        let seam = match p.influence {
            Influence::Blobby { .. } => false,
            Influence::Wyvill { .. } => (d - r).abs() < 1e-3,
            Influence::Metaball { .. } => (d - r).abs() < 1e-3 || (d - r / 3.0).abs() < 1e-3,
        };
        crease || seam
    })
}

#[test]
fn values_gradients_and_rates_match_the_f64_oracle() {
    for blend in [Blend::Sum, Blend::Weighted, Blend::Max] {
        let scene = mixed(blend);
        for t in [0.0, 0.37, 0.81] {
            let pose = scene.pose(t);
            let input = FieldInput::new(&pose).unwrap();
            let (before, after) = (scene.pose(t - 1e-6), scene.pose(t + 1e-6));
            let mut checked = 0;
            for x in probe_points(2000, 7) {
                if near_seam(&pose, x) || (blend == Blend::Max && near_tie(&pose, x)) {
                    continue;
                }
                checked += 1;
                let (s, scale) = eval(&input, x);
                let tol = 1e-5 * (1.0 + f64::from(scale[0]));
                let want = oracle(&pose, x);
                assert!(
                    (f64::from(s.value) - want).abs() < tol,
                    "{blend:?} t={t} {x}: F {} vs {want}",
                    s.value
                );
                let h = 1e-5;
                let g = DVec3::from_array(std::array::from_fn(|k| {
                    let e = DVec3::AXES[k] * h;
                    (oracle(&pose, x + e) - oracle(&pose, x - e)) / (2.0 * h)
                }));
                let got = DVec3::new(
                    f64::from(s.grad[0]),
                    f64::from(s.grad[1]),
                    f64::from(s.grad[2]),
                );
                let gtol = 1e-4 * (1.0 + f64::from(scale[1]));
                assert!(
                    (got - g).abs().max_element() < gtol,
                    "{blend:?} t={t} {x}: ∇F {got} vs {g}"
                );
                if t > 0.0 {
                    let rate = (oracle(&after, x) - oracle(&before, x)) / 2e-6;
                    assert!(
                        (f64::from(s.rate) - rate).abs() < 1e-3 * (1.0 + f64::from(scale[1])),
                        "{blend:?} t={t} {x}: F_t {} vs {rate}",
                        s.rate
                    );
                }
            }
            assert!(
                checked > 1500,
                "{blend:?}: only {checked} points away from seams"
            );
        }
    }
}

/// Whether two primitives' values are nearly equal at x (max blend kinks).
fn near_tie(pose: &Pose, x: DVec3) -> bool {
    let mut v: Vec<f64> = (pose.primitives.iter())
        .map(|p| p.weight * e64(&p.influence, distance(&p.skeleton, x)))
        .collect();
    v.sort_by(|a, b| b.total_cmp(a));
    v.len() > 1 && v[0] - v[1] < 1e-3 && v[0] > 1e-3
}

/// The rates are the slopes of the key interval being entered: a negative
/// control for F_t (differences across a key do not match one side).
#[test]
fn rates_are_one_sided_at_keys_and_zero_after_the_last() {
    let scene = Scene::from_toml_str(EXAMPLES[0].1, "dumbbell").unwrap();
    let end = scene.pose(1.0);
    assert!(end.rates.iter().all(|r| r.points[0] == DVec3::ZERO));
    let input = FieldInput::new(&end).unwrap();
    assert_eq!(eval(&input, DVec3::new(0.3, 0.2, 0.0)).0.rate, 0.0);
    let mid = scene.pose(0.5);
    let input = FieldInput::new(&mid).unwrap();
    let (s, _) = eval(&input, DVec3::new(0.3, 0.2, 0.0));
    assert!(s.rate < 0.0, "pulling the blobs apart lowers F at the neck");
}

/// Culling drops at most n·τ: the culled mirror equals the full f64 sum
/// within that plus f32 rounding, also far from the skeleton and outside
/// the cull grid (where the mirror gives F = 0).
#[test]
fn culling_changes_f_by_less_than_half_an_ulp_of_iso() {
    let scene = Scene::from_toml_str(EXAMPLES[4].1, "molecule").unwrap();
    let pose = scene.pose(0.5);
    let input = FieldInput::new(&pose).unwrap();
    let (lo, hi) = grid::surface_bounds(&pose).unwrap();
    let mean = input.mean_cell_primitives();
    assert!(
        mean < 40.0,
        "culling keeps {mean} of 100 primitives per cell"
    );
    let mut rng = common::xorshift(3);
    let mut u = move || (rng() >> 11) as f64 / (1u64 << 53) as f64;
    let pad = DVec3::splat(2.0);
    for _ in 0..5000 {
        let x = lo - pad + (hi - lo + 2.0 * pad) * DVec3::new(u(), u(), u());
        let (s, scale) = eval(&input, x);
        let want = oracle(&pose, x);
        let tol = 0.5 * f64::from(f32::EPSILON) * 0.5
            + 4.0 * f64::from(f32::EPSILON) * (0.5 + f64::from(scale[0]));
        assert!(
            (f64::from(s.value) - want).abs() <= tol,
            "{x}: {} vs {want}",
            s.value
        );
    }
}

/// The dumbbell's neck breaks at centre distance 2√(ln 4) = 2.35482,
/// t* = 0.44353 in the example (the saddle at the origin crosses I).
#[test]
fn dumbbell_breaks_at_the_analytic_distance() {
    let scene = Scene::from_toml_str(EXAMPLES[0].1, "dumbbell").unwrap();
    let at = |t: f64| {
        let input = FieldInput::new(&scene.pose(t)).unwrap();
        eval(&input, DVec3::ZERO).0.value
    };
    let t_star = ((4f64.ln()).sqrt() - 1.0) / 0.4;
    assert!((t_star - 0.44353).abs() < 1e-5);
    assert!(at(t_star - 0.002) > 0.0 && at(t_star + 0.002) < 0.0);
    // The merge example meets at the mirrored time.
    let merge = Scene::from_toml_str(EXAMPLES[1].1, "merge").unwrap();
    let input = |t: f64| FieldInput::new(&merge.pose(t)).unwrap();
    assert!(eval(&input(1.0 - t_star - 0.002), DVec3::ZERO).0.value < 0.0);
    assert!(eval(&input(1.0 - t_star + 0.002), DVec3::ZERO).0.value > 0.0);
}

/// Marching cubes of the field: components and genus of the examples.
#[test]
fn marching_cubes_of_the_examples_has_their_topology() {
    let topo = |name: &str, t: f64, h: f64| {
        let text = EXAMPLES.iter().find(|e| e.0 == name).unwrap().1;
        let pose = Scene::from_toml_str(text, name).unwrap().pose(t);
        let s = grid::marching_cubes(&pose, h, Backend::Cpu).unwrap();
        let mut g: Vec<(i64, Option<i64>)> = s.groups.iter().map(|g| (g.euler, g.genus)).collect();
        g.sort();
        g
    };
    assert_eq!(topo("dumbbell", 0.0, 0.05), vec![(2, Some(0))]);
    assert_eq!(
        topo("dumbbell", 1.0, 0.05),
        vec![(2, Some(0)), (2, Some(0))]
    );
    assert_eq!(topo("torus", 0.0, 0.05), vec![(0, Some(1))]);
    assert_eq!(topo("torus", 1.0, 0.05), vec![(0, Some(1))]);
    assert_eq!(topo("finger", 0.7, 0.05), vec![(2, Some(0))]);
}

/// F ≤ I all over the faces of the surface bounds (f64 oracle; equality
/// where a lone primitive's reach is the surface itself).
#[test]
fn surface_bounds_hold_the_surface() {
    for (name, text) in EXAMPLES {
        let scene = Scene::from_toml_str(text, name).unwrap();
        for t in [0.0, 0.5, 1.0] {
            let pose = scene.pose(t);
            let (lo, hi) = grid::surface_bounds(&pose).unwrap();
            for i in 0..=20 {
                for j in 0..=20 {
                    let (u, v) = (i as f64 / 20.0, j as f64 / 20.0);
                    for axis in 0..3 {
                        for side in [lo, hi] {
                            let mut x = lo + (hi - lo) * DVec3::new(u, v, u * v);
                            x[axis] = side[axis];
                            assert!(oracle(&pose, x) < 1e-12, "{name} t={t}: F > I at {x}");
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn every_example_scene_reads() {
    assert_eq!(EXAMPLES.len(), 5);
    for (name, text) in EXAMPLES {
        let s = Scene::from_toml_str(text, name).unwrap();
        assert_eq!(s.duration(), 1.0, "{name}");
    }
    let molecule = Scene::from_toml_str(EXAMPLES[4].1, "molecule").unwrap();
    assert_eq!(molecule.primitives.len(), 100);
}
