//! The inside-hull scan on the CPU (SPEC §4.3, seed 003 §4.2): the per-row
//! method and the brute-force mirror against the independent i128 oracle
//! (bit for bit, on random polytopes and degenerate cases), the emulated
//! 64-bit arithmetic of the GPU fallback against native i64, the range
//! checks, and the ZKH classification on hand-built objects.

mod common;
mod hscan_fixtures;

use chisel::Backend;
use chisel::hull_scan::cpu::{self, i32x2};
use chisel::hull_scan::zkh::{self, ZkhClass};
use chisel::hull_scan::{self, Classification, HalfSpace, Side, VoxelBox, brute};
use chisel::parity::compare_exact;
use hscan_fixtures::{Polytope, Rng, box_faces, dirs26, random_half_spaces, supporting};
use proptest::prelude::*;

/// Brute oracle = brute mirror = rows (division) = rows (binary search,
/// emulated); returns the oracle.
fn all_agree(what: &str, faces: &[HalfSpace], bbox: &VoxelBox) -> Classification {
    let truth = brute::classify(faces, bbox).unwrap();
    let mirror = hull_scan::classify_voxels(faces, bbox, Backend::Cpu).unwrap();
    compare_exact(
        &format!("{what}: brute mirror"),
        &truth.sides,
        &mirror.sides,
    )
    .unwrap_or_else(|m| panic!("{m}"));
    let rows = hull_scan::classify(faces, bbox, Backend::Cpu).unwrap();
    compare_exact(&format!("{what}: rows"), &truth.sides, &rows.sides)
        .unwrap_or_else(|m| panic!("{m}"));
    let rows_i32x2 = cpu::hull_rows_i32x2(faces, bbox);
    assert_eq!(
        rows_i32x2,
        cpu::hull_rows(faces, bbox),
        "{what}: i32x2 rows vs division rows"
    );
    truth
}

#[test]
fn box_counts_by_hand() {
    // Voxels 2..=5 per axis of an 8³ box: 4³ voxels not outside, of which
    // the 2³ interior ones are strictly inside.
    let bbox = VoxelBox {
        origin: [0; 3],
        dims: [8; 3],
    };
    let c = all_agree("box", &box_faces([2; 3], [5; 3]), &bbox);
    assert_eq!(c.counts(), [512 - 64, 64 - 8, 8]);
    // Shifted origin, non-cubic box, no faces at all: everything inside.
    let bbox = VoxelBox {
        origin: [-3, 7, -11],
        dims: [5, 1, 3],
    };
    assert_eq!(all_agree("no faces", &[], &bbox).counts(), [0, 0, 15]);
}

#[test]
fn random_polytopes_agree_bit_for_bit() {
    let mut rng = Rng::new(7);
    for case in 0..300 {
        let dims = [
            rng.range(1, 24) as usize,
            rng.range(1, 12) as usize,
            rng.range(1, 12) as usize,
        ];
        let bbox = VoxelBox {
            origin: [rng.range(-20, 20), rng.range(-20, 20), rng.range(-20, 20)],
            dims,
        };
        let n = rng.range(0, 24) as usize;
        let k = [1, 3, 50, 100_000][case % 4];
        let faces = random_half_spaces(&mut rng, n, &bbox, k);
        all_agree(&format!("case {case}"), &faces, &bbox);
    }
}

#[test]
fn coplanar_rows_and_faces_parallel_to_x() {
    // Planes through voxel centres and corners, parallel to rows and not:
    // every "on" situation (one end, both ends, a whole row, a whole layer).
    let bbox = VoxelBox {
        origin: [0; 3],
        dims: [10, 9, 8],
    };
    let faces = vec![
        HalfSpace {
            normal: [0, 1, 0],
            offset: 11,
        },
        HalfSpace {
            normal: [0, 0, -1],
            offset: -3,
        },
        HalfSpace {
            normal: [1, 1, 0],
            offset: 20,
        },
        HalfSpace {
            normal: [-2, 0, 1],
            offset: 3,
        },
        HalfSpace {
            normal: [0, 1, 1],
            offset: 16,
        },
    ];
    let c = all_agree("coplanar", &faces, &bbox);
    let [_, on, inside] = c.counts();
    assert!(on > 20 && inside > 0, "{:?}", c.counts());
    // A slab of zero thickness (two opposite faces on one plane): no inside.
    let flat = vec![
        HalfSpace {
            normal: [0, 0, 1],
            offset: 7,
        },
        HalfSpace {
            normal: [0, 0, -1],
            offset: -7,
        },
    ];
    assert_eq!(all_agree("flat", &flat, &bbox).counts(), [720 - 90, 90, 0]);
}

#[test]
fn extreme_magnitudes_at_the_range_limit() {
    let mut rng = Rng::new(99);
    let m = hull_scan::MAX_NORMAL;
    for corner in [[-32768, -32768, -32768], [32768 - 12, 32768 - 9, 32768 - 7]] {
        let bbox = VoxelBox {
            origin: corner,
            dims: [12, 9, 7],
        };
        for _ in 0..20 {
            let faces: Vec<HalfSpace> = (0..6)
                .map(|_| {
                    let normal = [
                        rng.range(-m, m),
                        rng.range(-m, m),
                        rng.range(-m, m) / rng.range(1, 1 << 20),
                    ];
                    let p = bbox.centre([
                        rng.range(0, 11) as usize,
                        rng.range(0, 8) as usize,
                        rng.range(0, 6) as usize,
                    ]);
                    HalfSpace {
                        normal,
                        offset: normal[0] * p[0] + normal[1] * p[1] + normal[2] * p[2],
                    }
                })
                .collect();
            all_agree("extreme", &faces, &bbox);
        }
    }
}

#[test]
fn out_of_range_inputs_are_refused() {
    let bbox = VoxelBox {
        origin: [0; 3],
        dims: [4; 3],
    };
    let too_big = HalfSpace {
        normal: [i64::from(i32::MAX) + 1, 0, 0],
        offset: 0,
    };
    let err = hull_scan::classify(&[too_big], &bbox, Backend::Cpu).unwrap_err();
    assert!(err.to_string().contains("normal component"), "{err}");
    let far = HalfSpace {
        normal: [1, 0, 0],
        offset: (1 << 60) + 1,
    };
    assert!(matches!(
        hull_scan::classify_voxels(&[far], &bbox, Backend::Cpu),
        Err(chisel::Error::Limit { asked, .. }) if asked == (1 << 60) + 1
    ));
    for (origin, dims) in [([32765, 0, 0], [4, 1, 1]), ([0, -32769, 0], [1, 1, 1])] {
        let err = hull_scan::row_spans(&[], &VoxelBox { origin, dims }, Backend::Cpu).unwrap_err();
        assert!(err.to_string().contains("2^16"), "{err}");
    }
    // The limits themselves are accepted.
    let edge = VoxelBox {
        origin: [-32768, 32767, 0],
        dims: [1, 1, 1],
    };
    hull_scan::check_range(
        &[HalfSpace {
            normal: [i64::from(i32::MAX), -i64::from(i32::MAX), 0],
            offset: 1 << 60,
        }],
        &edge,
    )
    .unwrap();
}

proptest! {
    #[test]
    fn i32x2_matches_native(a in any::<i32>(), b in any::<i32>(), c in any::<i64>(), d in any::<i64>()) {
        let w = |v: i64| i32x2::from_i64(v);
        prop_assert_eq!(i32x2::to_i64(i32x2::mul(a, b)), i64::from(a) * i64::from(b));
        prop_assert_eq!(i32x2::to_i64(i32x2::from_i32(a)), i64::from(a));
        prop_assert_eq!(i32x2::to_i64(i32x2::add(w(c), w(d))), c.wrapping_add(d));
        prop_assert_eq!(i32x2::to_i64(i32x2::sub(w(c), w(d))), c.wrapping_sub(d));
        prop_assert_eq!(i32x2::lt(w(c), w(d)), c < d);
        prop_assert_eq!(i32x2::le(w(c), w(c)), true);
        let u = i32x2::mul_u32(a as u32, b as u32);
        prop_assert_eq!(u64::from(u[0]) | (u64::from(u[1]) << 32), u64::from(a as u32) * u64::from(b as u32));
    }

    #[test]
    fn rows_equal_brute_force(seed in any::<u64>(), n in 0usize..16, k in 1i64..1000,
                              nx in 1usize..20, ny in 1usize..8, nz in 1usize..8) {
        let mut rng = Rng::new(seed);
        let bbox = VoxelBox { origin: [rng.range(-9, 9), rng.range(-9, 9), rng.range(-9, 9)], dims: [nx, ny, nz] };
        let faces = random_half_spaces(&mut rng, n, &bbox, k);
        let truth = brute::classify(&faces, &bbox).unwrap();
        let rows = hull_scan::classify(&faces, &bbox, Backend::Cpu).unwrap();
        prop_assert_eq!(&truth.sides, &rows.sides);
        prop_assert_eq!(cpu::hull_rows_i32x2(&faces, &bbox), cpu::hull_rows(&faces, &bbox));
    }
}

/// A `n³` box of voxels with `holes` (inclusive voxel ranges) removed.
fn carved_cube(n: usize, holes: &[([usize; 3], [usize; 3])]) -> (Vec<bool>, VoxelBox) {
    let bbox = VoxelBox {
        origin: [0; 3],
        dims: [n; 3],
    };
    let mut obj = vec![true; n * n * n];
    for (lo, hi) in holes {
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    obj[x + n * (y + n * z)] = false;
                }
            }
        }
    }
    (obj, bbox)
}

/// Face index of the voxel-centre box hull of an `n³` cube: axis `a`,
/// `high` side (as `box_faces` orders them).
fn box_face(a: usize, high: bool) -> usize {
    2 * a + usize::from(high)
}

/// ZKH analysis of `obj` in `bbox` against the polytope `p`.
fn analyse(obj: &[bool], bbox: &VoxelBox, p: &Polytope) -> zkh::ZkhAnalysis {
    let c = hull_scan::classify(&p.faces, bbox, Backend::Cpu).unwrap();
    // Every object voxel lies inside or on its hull.
    assert!(
        obj.iter()
            .zip(&c.sides)
            .all(|(o, s)| !o || *s != Side::Outside as u8)
    );
    zkh::analyse(obj, &c, &p.faces, &p.adjacency).unwrap()
}

/// The cube's own hull: 6 faces at the outer voxel centres, each adjacent
/// to the 4 faces that are not its opposite.
fn cube_hull(n: usize) -> Polytope {
    let p = Polytope::new(&box_faces([0; 3], [n as i64 - 1; 3]));
    assert_eq!(p.faces.len(), 6);
    assert!(p.adjacency.iter().all(|a| a.len() == 4));
    p
}

#[test]
fn cube_with_closed_cavity() {
    let (obj, bbox) = carved_cube(12, &[([4; 3], [7; 3])]);
    let a = analyse(&obj, &bbox, &cube_hull(12));
    assert_eq!(a.components.len(), 1);
    let z = &a.components[0];
    assert_eq!(
        (z.size, z.class, z.face_sets.len()),
        (64, ZkhClass::Cavity, 0)
    );
}

#[test]
fn cube_with_dent_is_a_concavity() {
    let (obj, bbox) = carved_cube(12, &[([4, 4, 9], [7, 7, 11])]);
    let a = analyse(&obj, &bbox, &cube_hull(12));
    assert_eq!(a.components.len(), 1);
    let z = &a.components[0];
    assert_eq!((z.size, z.class), (48, ZkhClass::Concavity));
    assert_eq!(z.face_sets, vec![vec![box_face(2, true)]]);
}

#[test]
fn cube_with_through_hole_is_an_unbranched_tunnel() {
    let (obj, bbox) = carved_cube(12, &[([4, 4, 0], [7, 7, 11])]);
    let a = analyse(&obj, &bbox, &cube_hull(12));
    let z = &a.components[0];
    assert_eq!((a.components.len(), z.size), (1, 192));
    assert_eq!(z.class, ZkhClass::UnbranchedTunnel);
    assert_eq!(
        z.face_sets,
        vec![vec![box_face(2, false)], vec![box_face(2, true)]]
    );
}

#[test]
fn t_hole_in_a_cube_is_a_concavity_as_in_seed_fig_4_16() {
    // Mouths on the top, left and right faces; the top face shares an edge
    // with both side faces, so the incident faces form one edge-connected
    // set: a concavity by Def. CO (seed 003 §4.3.2, Fig. 4.16).
    let (obj, bbox) = carved_cube(12, &[([0, 4, 4], [11, 7, 7]), ([4, 4, 4], [7, 7, 11])]);
    let a = analyse(&obj, &bbox, &cube_hull(12));
    let z = &a.components[0];
    assert_eq!(z.class, ZkhClass::Concavity);
    assert_eq!(
        z.face_sets,
        vec![vec![
            box_face(0, false),
            box_face(0, true),
            box_face(2, true)
        ]]
    );
}

/// A `n³` cube with all 12 edges chamfered by `c` voxels: voxel kept when
/// for every pair of axes the distances to the nearest sides sum to ≥ c.
fn chamfered_cube(n: usize, c: usize) -> (Vec<bool>, VoxelBox) {
    let bbox = VoxelBox {
        origin: [0; 3],
        dims: [n; 3],
    };
    let e = |v: usize| v.min(n - 1 - v);
    let mut obj = vec![false; n * n * n];
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let (ex, ey, ez) = (e(x), e(y), e(z));
                obj[x + n * (y + n * z)] = ex + ey >= c && ey + ez >= c && ex + ez >= c;
            }
        }
    }
    (obj, bbox)
}

/// The exact hull of a chamfered cube (26 directions suffice; certified).
fn chamfered_hull(obj: &[bool], bbox: &VoxelBox) -> Polytope {
    let pts = hscan_fixtures::extreme_centres(obj, bbox);
    let p = Polytope::new(&supporting(&pts, &dirs26()));
    assert!(p.is_hull_of(&pts), "26-direction polytope is not the hull");
    p
}

fn face_with_normal(p: &Polytope, n: [i64; 3]) -> usize {
    p.faces.iter().position(|f| f.normal == n).expect("face")
}

#[test]
fn y_hole_in_a_chamfered_cube_is_a_branched_tunnel() {
    let n = 16;
    let (mut obj, bbox) = chamfered_cube(n, 4);
    let p = chamfered_hull(&obj, &bbox);
    // Chamfers separate the square faces: top and the sides share no edge.
    let (top, left, right) = (
        face_with_normal(&p, [0, 0, 1]),
        face_with_normal(&p, [-1, 0, 0]),
        face_with_normal(&p, [1, 0, 0]),
    );
    assert!(!p.adjacency[top].contains(&left) && !p.adjacency[top].contains(&right));
    // A straight hole left ↔ right: unbranched tunnel.
    let mut straight = obj.clone();
    for z in 6..10 {
        for y in 6..10 {
            for x in 0..n {
                straight[x + n * (y + n * z)] = false;
            }
        }
    }
    let a = analyse(&straight, &bbox, &p);
    assert_eq!(a.components.len(), 1);
    assert_eq!(a.components[0].class, ZkhClass::UnbranchedTunnel);
    assert_eq!(a.components[0].face_sets, vec![vec![left], vec![right]]);
    // Plus a shaft from the middle to the top: branched tunnel.
    obj = straight;
    for z in 8..n {
        for y in 6..10 {
            for x in 6..10 {
                obj[x + n * (y + n * z)] = false;
            }
        }
    }
    let a = analyse(&obj, &bbox, &p);
    assert_eq!(a.components.len(), 1);
    let z = &a.components[0];
    assert_eq!(z.class, ZkhClass::BranchedTunnel);
    let mut sets = z.face_sets.clone();
    sets.sort();
    let mut want = vec![vec![left], vec![right], vec![top]];
    want.sort();
    assert_eq!(sets, want);
}

#[test]
fn coplanar_contact_counts_as_concavity() {
    // Hull vertices at cell corners (planes at even coordinates): the dent's
    // corners only touch the top plane (s = 0), none lies outside — still a
    // concavity (seed 003 §4.2.3, last paragraph); the closed cavity stays
    // a cavity and the through-hole a tunnel.
    let n = 12;
    let corner_box: Vec<HalfSpace> = (0..3)
        .flat_map(|a| {
            let mut lo = [0i64; 3];
            lo[a] = -1;
            let mut hi = [0i64; 3];
            hi[a] = 1;
            [
                HalfSpace {
                    normal: lo,
                    offset: 0,
                },
                HalfSpace {
                    normal: hi,
                    offset: 2 * n as i64,
                },
            ]
        })
        .collect();
    let p = Polytope::new(&corner_box);
    let cases = [
        (vec![([4, 4, 9], [7, 7, 11])], ZkhClass::Concavity),
        (vec![([4; 3], [7; 3])], ZkhClass::Cavity),
        (vec![([4, 4, 0], [7, 7, 11])], ZkhClass::UnbranchedTunnel),
    ];
    for (holes, class) in cases {
        let (obj, bbox) = carved_cube(n, &holes);
        let c = hull_scan::classify(&p.faces, &bbox, Backend::Cpu).unwrap();
        assert_eq!(c.counts(), [0, 0, (n * n * n) as u64]);
        let a = zkh::analyse(&obj, &c, &p.faces, &p.adjacency).unwrap();
        assert_eq!(a.components.len(), 1);
        assert_eq!(a.components[0].class, class, "{holes:?}");
    }
}

#[test]
fn zkh_inputs_are_checked() {
    let (obj, bbox) = carved_cube(4, &[]);
    let p = cube_hull(4);
    let c = hull_scan::classify(&p.faces, &bbox, Backend::Cpu).unwrap();
    assert!(matches!(
        zkh::analyse(&obj[1..], &c, &p.faces, &p.adjacency),
        Err(chisel::Error::Mismatch { expected, found, .. }) if found + 1 == expected
    ));
    let mut bad = p.adjacency.clone();
    bad[0].push(99);
    assert!(matches!(
        zkh::analyse(&obj, &c, &p.faces, &bad),
        Err(chisel::Error::InvalidData {
            at: chisel::Position::Item {
                kind: "face",
                index: 0
            },
            ..
        })
    ));
    // A solid cube has no ZKH.
    let a = zkh::analyse(&obj, &c, &p.faces, &p.adjacency).unwrap();
    assert!(a.components.is_empty() && a.labels.iter().all(|&l| l == 0));
}

#[test]
fn digital_ball_inside_its_supporting_polytope() {
    let (obj, bbox) = hscan_fixtures::digital_ball(20, 17);
    let pts = hscan_fixtures::extreme_centres(&obj, &bbox);
    let faces = supporting(&pts, &hscan_fixtures::directions(3));
    let c = all_agree("ball", &faces, &bbox);
    assert!(obj.iter().zip(&c.sides).all(|(o, s)| !o || *s != 0));
    let [_, on, inside] = c.counts();
    assert!(on > 0 && inside > 0);
}

/// Incident faces by brute force: every corner of every ZKH voxel against
/// every face (`n·c ≥ d`), per label.
fn incident_by_brute_force(
    a: &zkh::ZkhAnalysis,
    bbox: &VoxelBox,
    faces: &[HalfSpace],
) -> Vec<Vec<usize>> {
    let [nx, ny, _] = bbox.dims;
    let mut sets = vec![std::collections::BTreeSet::new(); a.components.len()];
    for (i, &l) in a.labels.iter().enumerate() {
        if l == 0 {
            continue;
        }
        let v = [i % nx, (i / nx) % ny, i / (nx * ny)];
        for corner in 0..8 {
            let c: [i64; 3] =
                std::array::from_fn(|k| 2 * (bbox.origin[k] + (v[k] + ((corner >> k) & 1)) as i64));
            for (f, face) in faces.iter().enumerate() {
                if face.side(c) >= 0 {
                    sets[l as usize - 1].insert(f);
                }
            }
        }
    }
    sets.into_iter().map(|s| s.into_iter().collect()).collect()
}

#[test]
fn zkh_incident_faces_match_brute_force_on_random_objects() {
    let mut rng = Rng::new(31);
    let mut classes = std::collections::BTreeSet::new();
    for case in 0..40 {
        let n = rng.range(6, 14) as usize;
        let bbox = VoxelBox {
            origin: [rng.range(-5, 5), rng.range(-5, 5), rng.range(-5, 5)],
            dims: [n, n + 1, n - 1],
        };
        // A random blob: a ball with random voxels removed.
        let len = bbox.n_voxels().unwrap();
        let density = rng.range(55, 90) as u64;
        let obj: Vec<bool> = (0..len)
            .map(|i| {
                let p = bbox.centre([i % n, (i / n) % (n + 1), i / (n * (n + 1))]);
                let c: [i64; 3] = std::array::from_fn(|k| 2 * bbox.origin[k] + bbox.dims[k] as i64);
                let d2: i64 = (0..3).map(|k| (p[k] - c[k]).pow(2)).sum();
                d2 <= (n as i64 * n as i64) && rng.next() % 100 < density
            })
            .collect();
        // Half the blobs get a straight 2 × 2 hole along a random axis.
        let mut obj = obj;
        if case % 2 == 0 {
            let axis = (rng.next() % 3) as usize;
            for (i, o) in obj.iter_mut().enumerate() {
                let v = [i % n, (i / n) % (n + 1), i / (n * (n + 1))];
                let near = (0..3)
                    .filter(|&k| k != axis)
                    .all(|k| v[k].abs_diff(bbox.dims[k] / 2) <= 1 && v[k] < bbox.dims[k] / 2 + 1);
                *o &= !near;
            }
        }
        if !obj.iter().any(|&o| o) {
            continue;
        }
        let pts = hscan_fixtures::centres(&obj, &bbox);
        let p = Polytope::new(&supporting(&pts, &dirs26()));
        let a = analyse(&obj, &bbox, &p);
        let want = incident_by_brute_force(&a, &bbox, &p.faces);
        for (z, w) in a.components.iter().zip(&want) {
            let mut got: Vec<usize> = z.face_sets.iter().flatten().copied().collect();
            got.sort_unstable();
            assert_eq!(&got, w, "case {case}, ZKH {}", z.label);
            classes.insert(z.class);
        }
    }
    assert!(classes.len() >= 3, "{classes:?}");
}

proptest! {
    /// Layer culling by face z ranges gives the spans of the full scan, on
    /// hulls of random lattice points (flat and degenerate ones included)
    /// in boxes that reach beyond the hull.
    #[test]
    fn culled_rows_equal_full_rows(seed in any::<u64>(), n in 1usize..40, spread in 1i64..12,
                                   flat in any::<bool>()) {
        let mut rng = Rng::new(seed);
        let points: Vec<[i64; 3]> = (0..n)
            .map(|_| {
                let z = if flat { 2 * spread } else { rng.range(0, 4 * spread) };
                [rng.range(0, 4 * spread), rng.range(0, 4 * spread), z]
            })
            .collect();
        let Ok(hull) = chisel::hull::ConvexHull::build(&points, Default::default()) else {
            return Ok(());
        };
        let faces: Vec<HalfSpace> = hull.half_spaces().into_iter().map(Into::into).collect();
        let extents = hull.face_z_extents();
        prop_assert_eq!(extents.len(), faces.len());
        let bbox = VoxelBox { origin: [-1, -1, -1], dims: [2 * spread as usize + 3; 3] };
        let full = cpu::hull_rows(&faces, &bbox);
        prop_assert_eq!(&cpu::hull_rows_culled(&faces, &extents, &bbox), &full);
        prop_assert_eq!(&hull.row_spans(&bbox, Backend::Cpu).unwrap(), &full);
    }
}

#[test]
fn culling_with_wrong_ranges_is_detected() {
    // Negative control: the cube's +x face said to span one layer only is
    // missing from the other layers, whose rows then run to the box's end.
    let (faces, mut extents, bbox) = hscan_fixtures::cube_hull();
    let full = cpu::hull_rows(&faces, &bbox);
    assert_eq!(cpu::hull_rows_culled(&faces, &extents, &bbox), full);
    let side = faces.iter().position(|f| f.normal == [1, 0, 0]).unwrap();
    extents[side] = [9, 9];
    assert_ne!(cpu::hull_rows_culled(&faces, &extents, &bbox), full);
    assert!(matches!(
        hull_scan::row_spans_culled(&faces, &extents[1..], &bbox, Backend::Cpu),
        Err(chisel::Error::Mismatch { .. })
    ));
}
