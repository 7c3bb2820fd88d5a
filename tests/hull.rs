//! Exact convex hulls of digital objects: seed figures and guarantees.

mod common;

use std::collections::HashSet;

use chisel::hull::{
    CellList, Containment, ConvexHull, CoplanarPolicy, HalfSpace, HullOptions, Order,
};
use chisel::phantom::voxel::{cube, cylinder_tunnel, digital_ball, ellipsoid_dent, torus};
use chisel::volume::Volume;
use chisel::voxel::{CandidateKind, Component, DigitalObject, Selection, voxel_centre};

fn object(v: &Volume) -> DigitalObject {
    DigitalObject::from_volume(v, Selection::Threshold(1.0), Component::All).unwrap()
}

fn opts(coplanar: CoplanarPolicy, order: Order) -> HullOptions {
    HullOptions { coplanar, order }
}

fn sub(a: [i64; 3], b: [i64; 3]) -> [i64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [i64; 3], b: [i64; 3]) -> [i64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [i64; 3], b: [i64; 3]) -> i64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Checks every guarantee of a hull of `o` independently of the hull code.
fn check_hull(o: &DigitalObject, h: &ConvexHull, what: &str) {
    let vs = h.vertices();
    let hs = h.half_spaces();
    // Every object voxel lies on the inner side of every face plane.
    for v in o.voxels() {
        let c = voxel_centre(v);
        for s in &hs {
            assert!(
                dot(s.normal, c) <= s.offset,
                "{what}: voxel {v:?} outside {s:?}"
            );
        }
    }
    // Every vertex is a voxel of S, lies on its faces' planes, and the
    // planes are the (primitive) planes of the faces.
    for v in vs {
        let vox = v.map(|c| (c - 1) / 2);
        assert!(o.contains(vox), "{what}: vertex {v:?} not in S");
    }
    let mut edges = HashSet::new();
    for f in h.faces() {
        let k = f.vertices.len();
        assert!(k >= 3, "{what}");
        let p = |i: usize| vs[f.vertices[i % k] as usize];
        for i in 0..k {
            assert_eq!(
                dot(f.plane.normal, p(i)),
                f.plane.offset,
                "{what}: vertex off its face plane"
            );
            // Strictly convex corners, CCW about the outward normal.
            let turn = dot(
                cross(sub(p(i + 1), p(i)), sub(p(i + 2), p(i + 1))),
                f.plane.normal,
            );
            assert!(turn > 0, "{what}: face corner not strictly convex");
            assert!(
                edges.insert((f.vertices[i], f.vertices[(i + 1) % k])),
                "{what}: directed edge twice"
            );
        }
        let g = f.plane.normal.iter().fold(0i64, |g, &c| gcd(g, c));
        assert_eq!(g, 1, "{what}: normal not primitive");
        // All hull vertices on the inner side.
        assert!(
            vs.iter().all(|&v| dot(f.plane.normal, v) <= f.plane.offset),
            "{what}: not convex"
        );
    }
    for &(u, w) in &edges {
        assert!(edges.contains(&(w, u)), "{what}: edge without twin");
    }
    assert_eq!(
        h.n_vertices() as i64 - h.n_edges() as i64 + h.n_faces() as i64,
        2,
        "{what}: Euler"
    );
    assert_eq!(
        h.volume6(),
        h.volume6_from_faces(),
        "{what}: incremental volume"
    );
    let cl = h.cell_list();
    assert_eq!(cl.euler(), 2);
    assert!(cl.edges.iter().all(|e| e.right != u32::MAX), "{what}");
}

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 { a.abs() } else { gcd(b, a % b) }
}

/// Adjacent faces of a merged hull are never coplanar.
fn check_maximal(h: &ConvexHull, what: &str) {
    let mut by_edge = std::collections::HashMap::new();
    for (i, f) in h.faces().iter().enumerate() {
        let k = f.vertices.len();
        for j in 0..k {
            by_edge.insert((f.vertices[j], f.vertices[(j + 1) % k]), i);
        }
    }
    for (&(u, w), &i) in &by_edge {
        let j = by_edge[&(w, u)];
        assert_ne!(
            h.faces()[i].plane,
            h.faces()[j].plane,
            "{what}: coplanar neighbours"
        );
    }
}

#[test]
fn seed_table_4_2_ball_face_counts() {
    // Digital balls of combinatorial radius r: faces of CH(S) with the three
    // coplanar policies (seed Table 4.2; 6-neighbourhood local corners in
    // lexicographic order, the seed's basic algorithm).
    let rows = [
        (12, 236, 140, 74),
        (16, 492, 428, 218),
        (20, 636, 380, 170),
        (24, 668, 524, 290),
    ];
    for (r, invisible, visible, merged) in rows {
        let o = object(&digital_ball(r).unwrap());
        let c = o.candidates(CandidateKind::Local6);
        let lex = |p| ConvexHull::build(&c, opts(p, Order::Lexicographic)).unwrap();
        let h_inv = lex(CoplanarPolicy::Invisible);
        let h_vis = lex(CoplanarPolicy::Visible);
        let h_mrg = lex(CoplanarPolicy::Merge);
        assert_eq!(
            (h_inv.n_faces(), h_vis.n_faces(), h_mrg.n_faces()),
            (invisible, visible, merged),
            "ball r = {r}"
        );
        for (h, name) in [
            (&h_inv, "invisible"),
            (&h_vis, "visible"),
            (&h_mrg, "merge"),
        ] {
            check_hull(&o, h, &format!("ball {r} {name}"));
        }
        check_maximal(&h_mrg, &format!("ball {r}"));
        // Every policy spans the same solid.
        assert_eq!(h_inv.volume6(), h_mrg.volume6());
        assert_eq!(h_vis.volume6(), h_mrg.volume6());
        // The facet count does not depend on candidates or order.
        for kind in [CandidateKind::Local26, CandidateKind::ConvexVoxels] {
            for order in [Order::Lexicographic, Order::ExtremeFirst, Order::Furthest] {
                let h =
                    ConvexHull::of_object(&o, kind, opts(CoplanarPolicy::Merge, order)).unwrap();
                assert_eq!(h.n_faces(), merged, "ball {r} {kind:?} {order:?}");
                assert_eq!(h.vertices(), h_mrg.vertices());
                let t =
                    ConvexHull::of_object(&o, kind, opts(CoplanarPolicy::Visible, order)).unwrap();
                assert_eq!(t.n_faces(), visible, "ball {r} {kind:?} {order:?}");
            }
        }
    }
}

/// Background voxels whose centres lie inside or on the hull (brute force
/// over the hull's voxel bounding box with the exact half-spaces).
fn background_inside(o: &DigitalObject, hs: &[HalfSpace], bbox: ([i64; 3], [i64; 3])) -> u64 {
    let (lo, hi) = bbox;
    let mut n = 0;
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                let c = voxel_centre([x, y, z]);
                if !o.contains([x, y, z]) && hs.iter().all(|h| h.side(c) <= 0) {
                    n += 1;
                }
            }
        }
    }
    n
}

#[test]
fn seed_table_8_6_background_inside_cylinder_hulls() {
    // The seed prints 87 135 for 100/85, which this digitization (that
    // reproduces all voxel and facet counts) does not give: 85 215 = 15 ×
    // 5 681. Pinned here so a change is noticed; see the module docs of
    // `phantom::voxel`.
    let rows = [
        (25, 10, 1_200),
        (50, 35, 14_595),
        (75, 60, 42_420),
        (100, 85, 85_215),
    ];
    for (d_o, d_i, inside) in rows {
        let o = object(&cylinder_tunnel(d_o, d_i, 15).unwrap());
        let h = ConvexHull::of_object(&o, CandidateKind::Local26, HullOptions::default()).unwrap();
        check_hull(&o, &h, &format!("cylinder {d_o}/{d_i}"));
        check_maximal(&h, "cylinder");
        assert_eq!(
            background_inside(&o, &h.half_spaces(), h.voxel_bbox()),
            inside,
            "{d_o}/{d_i}"
        );
    }
}

#[test]
fn guarantees_on_seed_objects() {
    let objects = [
        ("cube", cube(7).unwrap()),
        ("torus", torus(40, 12).unwrap()),
        ("ellipsoid-dent", ellipsoid_dent(10, 10, 7, 5).unwrap()),
        ("ball 31", digital_ball(31).unwrap()),
    ];
    for (name, v) in &objects {
        let o = object(v);
        for kind in [
            CandidateKind::Local6,
            CandidateKind::Local18,
            CandidateKind::Local26,
            CandidateKind::ConvexVoxels,
        ] {
            for coplanar in [
                CoplanarPolicy::Invisible,
                CoplanarPolicy::Visible,
                CoplanarPolicy::Merge,
            ] {
                for order in [Order::Lexicographic, Order::ExtremeFirst, Order::Furthest] {
                    let h = ConvexHull::of_object(&o, kind, opts(coplanar, order)).unwrap();
                    check_hull(&o, &h, &format!("{name} {kind:?} {coplanar:?} {order:?}"));
                }
            }
        }
    }
    // Theorem TRM: the hull of the (digitally convex) axis-parallel cube is
    // the 6-face box.
    let h = ConvexHull::of_object(
        &object(&objects[0].1),
        CandidateKind::Local26,
        HullOptions::default(),
    )
    .unwrap();
    assert_eq!((h.n_faces(), h.n_vertices(), h.n_edges()), (6, 8, 12));
    assert_eq!(h.volume_voxels(), 216.0);
    assert_eq!(h.area_voxels(), 216.0);
}

#[test]
fn corner_hull_of_a_cube_is_the_cube() {
    let o = object(&cube(5).unwrap());
    let h =
        ConvexHull::of_object(&o, CandidateKind::ConvexCorners, HullOptions::default()).unwrap();
    assert_eq!((h.n_faces(), h.n_vertices()), (6, 8));
    assert_eq!(h.volume_voxels(), 125.0);
    assert_eq!(h.area_voxels(), 150.0);
    let frame = chisel::voxel::Frame {
        spacing: [1.0, 2.0, 3.0],
        origin: [5.0, 0.0, -1.0],
        ..Default::default()
    };
    let s = h.summary(&frame);
    assert_eq!((s.faces, s.vertices, s.edges, s.triangles), (6, 8, 12, 12));
    assert_eq!(s.integers_eq_8_2, 3 * 8 + 5 * 6);
    assert_eq!(s.integers_compact, 2 + 3 * 8 + 6 * 5);
    assert!((s.volume_world - 750.0).abs() < 1e-9);
    // Box 5 × 10 × 15: 2·(50 + 75 + 150).
    assert!((s.area_world - 550.0).abs() < 1e-9, "{}", s.area_world);
    assert_eq!(h.bbox(), ([2, 2, 2], [12, 12, 12]));
    assert_eq!(h.voxel_bbox(), ([1, 1, 1], [5, 5, 5]));
    assert_eq!(h.containment([7, 7, 7]), Containment::Inside);
    assert_eq!(h.containment([2, 7, 7]), Containment::On);
    assert_eq!(h.containment([1, 7, 7]), Containment::Outside);
    // Oblique and reflected frames: the mesh is the box moved into the
    // world, still wound outward, with the same volume and area.
    let m = h.to_mesh(&frame).unwrap();
    for axes in [
        [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
    ] {
        let turned = chisel::voxel::Frame { axes, ..frame };
        let t = h.to_mesh(&turned).unwrap();
        assert!(
            (t.signed_volume() - m.signed_volume()).abs() < 1e-6,
            "{axes:?}"
        );
        assert!(m.signed_volume() > 0.0);
        let st = h.summary(&turned);
        assert!((st.area_world - 550.0).abs() < 1e-9 && (st.volume_world - 750.0).abs() < 1e-9);
        assert_eq!(
            t.positions[0].to_array(),
            turned.world_f32(h.vertices()[0]).to_array()
        );
    }
}

#[test]
fn hull_is_deterministic_and_order_independent() {
    let o = object(&ellipsoid_dent(12, 9, 8, 5).unwrap());
    let c = o.candidates(CandidateKind::Local18);
    let a = ConvexHull::build(&c, HullOptions::default()).unwrap();
    let b = ConvexHull::build(&c, HullOptions::default()).unwrap();
    assert_eq!(a.faces(), b.faces());
    assert_eq!(a.vertices(), b.vertices());
    let mut rev = c.clone();
    rev.reverse();
    rev.extend_from_slice(&c[..10]);
    let r = ConvexHull::build(&rev, HullOptions::default()).unwrap();
    assert_eq!(r.faces(), a.faces());
    let planes = |h: &ConvexHull| -> HashSet<HalfSpace> { h.half_spaces().into_iter().collect() };
    let l = ConvexHull::build(&c, opts(CoplanarPolicy::Merge, Order::Lexicographic)).unwrap();
    assert_eq!(planes(&l), planes(&a));
}

#[test]
fn tetrahedron_cell_list_matches_appendix_c() {
    let pts = [[0, 0, 0], [6, 0, 0], [0, 6, 0], [0, 0, 6]];
    let h = ConvexHull::build(&pts, HullOptions::default()).unwrap();
    let cl = h.cell_list();
    assert_eq!(
        (cl.vertices.len(), cl.edges.len(), cl.faces.len()),
        (4, 6, 4)
    );
    for (v, vert) in cl.vertices.iter().enumerate() {
        assert_eq!(vert.edges.len(), 3);
        for &se in &vert.edges {
            let e = cl.edges[(se.unsigned_abs() - 1) as usize];
            // + : the edge ends here, − : it starts here (Table C.1).
            assert_eq!(if se > 0 { e.end } else { e.start }, v as u32);
        }
    }
    for (f, face) in cl.faces.iter().enumerate() {
        assert_eq!(face.boundary.len(), 3);
        for (k, &(v, se)) in face.boundary.iter().enumerate() {
            let e = cl.edges[(se.unsigned_abs() - 1) as usize];
            let (from, to, side) = if se > 0 {
                (e.start, e.end, e.left)
            } else {
                (e.end, e.start, e.right)
            };
            assert_eq!(from, v);
            assert_eq!(to, face.boundary[(k + 1) % 3].0);
            assert_eq!(
                side, f as u32,
                "face lies left of its positively used edges"
            );
        }
    }
    assert_eq!(h.volume6(), 216);
    assert_eq!(cl.integers_eq_8_2(), 3 * 4 + 5 * 4);
    let enc = cl.encode_compact();
    assert_eq!(enc.len(), 2 + 12 + 4 * 4);
    assert_eq!(CellList::decode_compact(&enc).unwrap(), cl);
    let at = |r: chisel::Result<CellList>| match r {
        Err(chisel::Error::InvalidData {
            at:
                chisel::Position::Item {
                    kind: "integer",
                    index,
                },
            ..
        }) => index,
        other => panic!("expected an error naming the integer, got {other:?}"),
    };
    assert_eq!(
        at(CellList::decode_compact(&enc[..enc.len() - 1])),
        enc.len() as u64 - 1
    );
    assert_eq!(
        at(CellList::decode_compact(&[1, 1, 0, 0, 0, 3, 0, 0, 7])),
        8
    );
}

#[test]
fn compact_encoding_round_trips_on_a_ball() {
    let o = object(&digital_ball(20).unwrap());
    let h = ConvexHull::of_object(&o, CandidateKind::Local26, HullOptions::default()).unwrap();
    let cl = h.cell_list();
    assert_eq!(CellList::decode_compact(&cl.encode_compact()).unwrap(), cl);
    assert_eq!(cl.integers_eq_8_2(), 3 * 192 + 5 * 170);
}

#[test]
fn mesh_export_is_closed_and_outward() {
    let o = object(&torus(30, 10).unwrap());
    let h = ConvexHull::of_object(&o, CandidateKind::Local26, HullOptions::default()).unwrap();
    let m = h.to_mesh(&o.frame()).unwrap();
    assert_eq!(m.n_triangles(), h.n_triangles());
    // Signed volume of the mesh equals the exact hull volume (voxel units).
    let vol: f64 = m
        .triangles
        .iter()
        .map(|t| {
            let p = t.map(|i| m.positions[i as usize].as_dvec3());
            p[0].dot(p[1].cross(p[2])) / 6.0
        })
        .sum();
    assert!(
        (vol - h.volume_voxels()).abs() < 1e-6 * vol,
        "{vol} vs {}",
        h.volume_voxels()
    );
}

#[test]
fn flat_and_degenerate_inputs() {
    // A one-voxel-thick square: a flat polygon, two opposite faces.
    let mut pts = Vec::new();
    for x in 0..4 {
        for y in 0..3 {
            pts.push([2 * x + 1, 2 * y + 1, 5]);
        }
    }
    let h = ConvexHull::build(&pts, HullOptions::default()).unwrap();
    assert!(h.is_planar());
    assert_eq!((h.n_faces(), h.n_vertices(), h.n_edges()), (2, 4, 4));
    assert_eq!(h.half_spaces().len(), 6);
    for p in &pts {
        assert!(h.half_spaces().iter().all(|s| s.side(*p) <= 0));
    }
    assert_eq!(h.containment([3, 3, 5]), Containment::On);
    assert_eq!(h.containment([3, 3, 7]), Containment::Outside);
    assert_eq!(h.containment([9, 3, 5]), Containment::Outside);
    assert!(matches!(
        ConvexHull::build(&[[1, 1, 1], [3, 3, 3], [5, 5, 5]], HullOptions::default()),
        Err(chisel::Error::Refused(chisel::Refusal::Collinear {
            points: 3
        }))
    ));
    assert!(matches!(
        ConvexHull::build(&[], HullOptions::default()),
        Err(chisel::Error::Refused(chisel::Refusal::Collinear {
            points: 0
        }))
    ));
    assert!(matches!(
        ConvexHull::build(&[[1 << 20, 0, 0]], HullOptions::default()),
        Err(chisel::Error::InvalidData {
            at: chisel::Position::Item {
                kind: "point",
                index: 0
            },
            ..
        })
    ));
}

#[test]
fn real_ct_bone_hull() {
    let Some(o) = common::ct_bone() else {
        return;
    };
    let h = ConvexHull::of_object(&o, CandidateKind::Local26, HullOptions::default()).unwrap();
    eprintln!(
        "headsq ≥ 1150 largest: {} voxels, {} candidates, hull {} faces {} vertices, {:?}",
        o.n_voxels(),
        h.stats().candidates,
        h.n_faces(),
        h.n_vertices(),
        h.stats()
    );
    check_hull(&o, &h, "headsq bone");
    check_maximal(&h, "headsq bone");
}

#[test]
fn corner_hulls_contain_the_voxel_cubes() {
    for v in [
        torus(40, 12).unwrap(),
        ellipsoid_dent(9, 7, 6, 4).unwrap(),
        digital_ball(21).unwrap(),
    ] {
        let o = object(&v);
        let h = ConvexHull::of_object(&o, CandidateKind::ConvexCorners, HullOptions::default())
            .unwrap();
        let hs = h.half_spaces();
        for vox in o.voxels() {
            for k in 0..8i64 {
                let c = chisel::voxel::voxel_corner([
                    vox[0] + (k & 1),
                    vox[1] + (k >> 1 & 1),
                    vox[2] + (k >> 2 & 1),
                ]);
                assert!(hs.iter().all(|s| s.side(c) <= 0), "corner {c:?} outside");
            }
        }
        // Vertices are even (0-cells) and the hull is a closed convex surface.
        assert!(h.vertices().iter().all(|v| v.iter().all(|c| c % 2 == 0)));
        assert_eq!(
            h.n_vertices() as i64 - h.n_edges() as i64 + h.n_faces() as i64,
            2
        );
        assert_eq!(h.volume6(), h.volume6_from_faces());
    }
}

#[test]
fn real_ct_skin_hull() {
    let Some(v) = common::real_volume("headsq/quarter.nhdr") else {
        return;
    };
    let o =
        DigitalObject::from_volume(&v, Selection::Threshold(500.0), Component::Largest).unwrap();
    let h = ConvexHull::of_object(&o, CandidateKind::Local26, HullOptions::default()).unwrap();
    eprintln!(
        "headsq ≥ 500 largest: {} voxels, {} candidates, hull {} faces {} vertices",
        o.n_voxels(),
        h.stats().candidates,
        h.n_faces(),
        h.n_vertices()
    );
    check_hull(&o, &h, "headsq skin");
    check_maximal(&h, "headsq skin");
}

#[test]
fn real_frog_tissue_hulls() {
    let Some(v) = common::real_volume("froggy/frogtissue.mhd") else {
        return;
    };
    for label in (1..=15).map(f64::from) {
        let o =
            DigitalObject::from_volume(&v, Selection::Label(label), Component::Largest).unwrap();
        let h = ConvexHull::of_object(&o, CandidateKind::Local26, HullOptions::default()).unwrap();
        eprintln!(
            "frog label {label}: {} voxels, hull {} faces {} vertices",
            o.n_voxels(),
            h.n_faces(),
            h.n_vertices()
        );
        check_hull(&o, &h, &format!("frog label {label}"));
        check_maximal(&h, "frog");
    }
}

/// Facets by brute force: distinct primitive planes through three points
/// with every point on one side (O(n⁴), small inputs only).
fn brute_force_facets(pts: &[[i64; 3]]) -> HashSet<HalfSpace> {
    let mut out = HashSet::new();
    for i in 0..pts.len() {
        for j in i + 1..pts.len() {
            for k in j + 1..pts.len() {
                let n = cross(sub(pts[j], pts[i]), sub(pts[k], pts[i]));
                if n == [0, 0, 0] {
                    continue;
                }
                let g = n.iter().fold(0i64, |g, &c| gcd(g, c));
                for sign in [1, -1] {
                    let n = n.map(|c| sign * c / g);
                    let d = dot(n, pts[i]);
                    if pts.iter().all(|&p| dot(n, p) <= d) {
                        out.insert(HalfSpace {
                            normal: n,
                            offset: d,
                        });
                    }
                }
            }
        }
    }
    out
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(128))]
    /// Points on a tiny grid are full of coplanar and collinear quadruples:
    /// the merged hull must be exactly the brute-force facet set, every
    /// policy must span the same solid, and V − E + F = 2.
    #[test]
    fn merged_hull_equals_brute_force_facets(
        raw in proptest::collection::vec((0i64..4, 0i64..4, 0i64..4), 4..24)
    ) {
        let pts: Vec<[i64; 3]> = raw.into_iter().map(|(x, y, z)| [x, y, z]).collect();
        let facets = brute_force_facets(&pts);
        let Ok(h) = ConvexHull::build(&pts, HullOptions::default()) else {
            // Collinear input: no facet exists, no two opposite planes either.
            proptest::prop_assert!(facets.is_empty());
            return Ok(());
        };
        if h.is_planar() {
            return Ok(());
        }
        let got: HashSet<HalfSpace> = h.half_spaces().into_iter().collect();
        proptest::prop_assert_eq!(&got, &facets);
        proptest::prop_assert_eq!(h.n_vertices() as i64 - h.n_edges() as i64 + h.n_faces() as i64, 2);
        proptest::prop_assert_eq!(h.volume6(), h.volume6_from_faces());
        for coplanar in [CoplanarPolicy::Invisible, CoplanarPolicy::Visible] {
            for order in [Order::Lexicographic, Order::ExtremeFirst, Order::Furthest] {
                let t = ConvexHull::build(&pts, opts(coplanar, order)).unwrap();
                proptest::prop_assert_eq!(t.volume6(), h.volume6());
                proptest::prop_assert_eq!(t.volume6_from_faces(), h.volume6());
                proptest::prop_assert_eq!(t.n_vertices() as i64 - t.n_edges() as i64 + t.n_faces() as i64, 2);
                for s in t.half_spaces() {
                    proptest::prop_assert!(pts.iter().all(|&p| s.side(p) <= 0));
                }
            }
        }
    }
}
