//! Sphere caps, plain meshes and cut sequences, knives that miss, bad
//! knives, the real headsq bone and the polyhedral sphere.

use super::*;

/// A box [5.5, 34.5]³ on a 40³ grid (flat faces on half-integer planes).
fn box_volume() -> Volume {
    let n = 40;
    let mut data = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let d = [x, y, z]
                    .iter()
                    .map(|&i| (i as f64 - 5.5).min(34.5 - i as f64))
                    .fold(f64::INFINITY, f64::min);
                data.push(d as f32);
            }
        }
    }
    Volume::new([n; 3], [1.0; 3], [0.0; 3], VolumeData::F32(data)).unwrap()
}

#[test]
fn sphere_caps_follow_the_sphere() {
    let s = mc(&box_volume());
    // Centred on the face z = 34.5: the bite is a half ball.
    let (ctr, rad) = (DVec3::new(20.2, 19.7, 34.5), 8.0);
    let k = Knife::Sphere {
        centre: ctr,
        radius: rad,
    };
    let r = cut(&s.mesh, &s.forest, &k, &CAP).unwrap();
    assert_eq!(r.pieces.len(), 2);
    assert_conserved(&s.mesh, &r, 1e-6, "box/sphere");
    same_result(&r, &cut_brute_force(&s.mesh, &k, &CAP).unwrap());
    let inside = &r.pieces[r.sides.iter().position(|s| *s == Side::Negative).unwrap()];
    // Off the face, every vertex of the bite is on the sphere (f32).
    let mut off_face = 0;
    for q in &inside.positions {
        if (q.z - 34.5).abs() > 1e-4 {
            off_face += 1;
            let d = (q.as_dvec3() - ctr).length();
            assert!((d - rad).abs() < 4e-6 * rad, "cap vertex {q} at {d}");
        }
    }
    assert!(
        off_face > 100,
        "the cap has {off_face} vertices off the face"
    );
    // Its volume is the half ball's, up to the chord error and the loop's
    // polygon (a flat cap would give almost nothing).
    let half = 2.0 / 3.0 * std::f64::consts::PI * rad.powi(3);
    let v = volume(inside, ctr);
    assert!((v - half).abs() < 0.01 * half, "{v} vs {half}");
}

#[test]
fn grazing_sphere_caps_do_not_cross_the_surface() {
    let s = mc(&box_volume());
    // Balls of radius 30 reaching `depth` below the face z = 34.5: the face
    // meets the sphere at a grazing angle (2.6–5.1°), and a chord of the
    // first cap sags below the face, through it.
    let mut rounds = 0;
    for depth in [0.03, 0.05, 0.08, 0.12] {
        let k = Knife::Sphere {
            centre: DVec3::new(20.2, 19.7, 34.5 + 30.0 - depth),
            radius: 30.0,
        };
        let r = cut(&s.mesh, &s.forest, &k, &CAP).unwrap();
        let what = format!("box/grazing sphere {depth}");
        assert_eq!(r.pieces.len(), 2, "{what}");
        assert_conserved(&s.mesh, &r, 1e-6, &what);
        same_result(&r, &cut_brute_force(&s.mesh, &k, &CAP).unwrap());
        for (i, piece) in r.pieces.iter().enumerate() {
            let x = chisel::mesh::self_intersections(piece);
            assert!(x.pairs.is_empty(), "{what} piece {i}: {:?}", x.pairs);
        }
        rounds += r.stats.cap_repair_rounds;
    }
    assert!(
        rounds > 0,
        "no first cap crossed the face: the test shows nothing"
    );
}

#[test]
fn cuts_of_plain_meshes_and_sequences() {
    let ico = common::icosphere(4);
    let r = cut_mesh(&ico, &plane([0.1, 0.0, 0.0], [1.0, 0.2, 0.0]), &CAP).unwrap();
    assert_eq!(r.pieces.len(), 2);
    assert_conserved(&ico, &r, 1e-6, "icosphere/plane");
    let knives = [
        plane([0.0, 0.0, 0.1], [0.0, 0.0, 1.0]),
        plane([0.05, 0.0, 0.0], [1.0, 0.0, 0.0]),
        Knife::Sphere {
            centre: DVec3::new(0.0, 0.9, 0.0),
            radius: 0.4,
        },
    ];
    let r = cut_sequence(&ico, &knives, &CAP).unwrap();
    assert_eq!(
        r.pieces.len(),
        8,
        "four quarters, each bitten once by the sphere at y = 0.9"
    );
    assert_conserved(&ico, &r, 1e-6, "icosphere/sequence");
}

#[test]
fn a_knife_missing_the_mesh_changes_nothing() {
    let s = mc(&ball_volume(24, 8.0));
    let r = cut(
        &s.mesh,
        &s.forest,
        &plane([0.0, 0.0, 100.0], [0.0, 0.0, 1.0]),
        &CAP,
    )
    .unwrap();
    assert_eq!(r.pieces.len(), 1);
    assert_eq!(r.pieces[0].triangles.len(), s.mesh.triangles.len());
    assert_eq!(r.stats.triangles_tested, 0);
    assert_eq!(r.stats.nodes_visited, s.forest.groups.len());
    // A closed mesh knife that misses the ball, or swallows it whole: the
    // piece's side is told by its winding number, for either knife winding.
    let icosphere = |centre: DVec3, r: f64, inward: bool| {
        let mut b = common::icosphere(2);
        for p in &mut b.positions {
            *p = (p.as_dvec3() * r + centre).as_vec3();
        }
        if inward {
            b.flip_winding();
        }
        Knife::Mesh(b)
    };
    for inward in [false, true] {
        for (centre, r, inside) in [
            (DVec3::splat(100.0), 5.0, false),
            (DVec3::splat(11.5), 40.0, true),
        ] {
            let k = icosphere(centre, r, inward);
            let got = cut(&s.mesh, &s.forest, &k, &CAP).unwrap();
            assert_eq!(got.pieces.len(), 1);
            let want = if inside != inward {
                Side::Negative
            } else {
                Side::Positive
            };
            assert_eq!(got.sides, vec![want], "inside {inside} inward {inward}");
        }
    }
}

#[test]
fn bad_knives_are_errors() {
    let s = mc(&ball_volume(16, 5.0));
    for k in [
        plane([0.0; 3], [0.0; 3]),
        plane([f64::NAN, 0.0, 0.0], [0.0, 0.0, 1.0]),
        Knife::Sphere {
            centre: DVec3::ZERO,
            radius: -1.0,
        },
        Knife::Mesh(TriMesh::default()),
    ] {
        let r = cut(&s.mesh, &s.forest, &k, &CAP);
        assert!(
            matches!(
                r,
                Err(chisel::Error::InvalidParameter { .. } | chisel::Error::Empty { .. })
            ),
            "{k:?}: {:?}",
            r.err()
        );
    }
    let along = Knife::Rect {
        centre: DVec3::splat(7.5),
        normal: DVec3::Z,
        u_axis: DVec3::new(0.0, 0.0, 2.0),
        half_extents: [3.0, 3.0],
    };
    let e = cut(&s.mesh, &s.forest, &along, &CAP)
        .unwrap_err()
        .to_string();
    assert!(e.contains("must not be parallel to the normal"), "{e}");
}

#[test]
fn headsq_bone_plane_and_sphere_cuts_conserve_volume() {
    let Some(vol) = common::real_volume("headsq/quarter.nhdr") else {
        return;
    };
    let s = marching_cubes(
        &vol,
        IsoSpec::Level(1150.0),
        &McOptions {
            close_border: true,
            ..McOptions::default()
        },
        Backend::Cpu,
    )
    .unwrap();
    let (lo, hi) = s.mesh.bounds().unwrap();
    let mid = ((lo + hi) * 0.5).as_dvec3();
    // A jaw-like cut below the middle of the head, tilted.
    let p = Knife::Plane {
        point: mid + DVec3::new(0.0, 0.0, 25.0),
        normal: DVec3::new(0.0, 0.3, 1.0),
    };
    let r = cut(&s.mesh, &s.forest, &p, &CAP).unwrap();
    assert!(r.pieces.len() >= 2);
    assert_conserved(&s.mesh, &r, 1e-6, "headsq/plane");
    same_result(&r, &cut_brute_force(&s.mesh, &p, &CAP).unwrap());
    assert!(
        r.stats.triangles_tested * 3 < r.stats.triangles_total,
        "{:?}",
        r.stats
    );
    assert!(
        r.stats.nodes_visited * 2 < r.stats.nodes_total,
        "{:?}",
        r.stats
    );
    let sph = Knife::Sphere {
        centre: mid + DVec3::new(0.0, -40.0, -20.0),
        radius: 35.0,
    };
    let r = cut(&s.mesh, &s.forest, &sph, &CAP).unwrap();
    assert!(r.pieces.len() >= 2);
    assert_conserved(&s.mesh, &r, 1e-6, "headsq/sphere");
    same_result(&r, &cut_brute_force(&s.mesh, &sph, &CAP).unwrap());
    eprintln!("headsq sphere cut: {:?}", r.stats);
    // This sphere crosses two edges of a sliver (ends 0.0015 apart) near
    // their shared corner; both crossings round to one f32 point, which is
    // one cut vertex, not two vertices and zero-area triangles.
    let sph = Knife::Sphere {
        centre: DVec3::new(100.0, 100.0, 60.0),
        radius: 35.0,
    };
    let r = cut(&s.mesh, &s.forest, &sph, &CAP).unwrap();
    assert_conserved(&s.mesh, &r, 1e-6, "headsq/sphere 35");
    same_result(&r, &cut_brute_force(&s.mesh, &sph, &CAP).unwrap());
    for (i, piece) in r.pieces.iter().enumerate() {
        assert_clean(piece, &format!("headsq/sphere 35 piece {i}"));
        let x = chisel::mesh::self_intersections(piece);
        assert!(
            x.pairs.is_empty(),
            "headsq/sphere 35 piece {i}: {:?}",
            x.pairs
        );
    }
    // This sphere meets the bone at grazing angles: its first cap crosses
    // it, and two rounds of repair clear every crossing.
    let graze = Knife::Sphere {
        centre: DVec3::new(80.0, 80.0, 80.0),
        radius: 35.0,
    };
    let r = cut(&s.mesh, &s.forest, &graze, &CAP).unwrap();
    assert_conserved(&s.mesh, &r, 1e-6, "headsq/sphere graze");
    assert!(r.stats.cap_repair_rounds > 0, "{:?}", r.stats);
    assert_eq!(r.stats.cap_crossings, 0, "{:?}", r.stats);
    assert!(!r.stats.sphere_polyhedral, "the repair suffices");
    for (i, piece) in r.pieces.iter().enumerate() {
        let x = chisel::mesh::self_intersections(piece);
        assert!(
            x.pairs.is_empty(),
            "headsq/sphere graze piece {i}: {:?}",
            x.pairs
        );
    }
    // These two pass within f32 rounding of bone vertices, or leave a loop
    // edge's chord where the bone grazes them: the repaired analytic caps
    // still cross the bone (3 and 5 crossings), so the cuts run along the
    // polyhedral sphere, whose caps cannot cross it.
    for (centre, radius) in [([120.0, 80.0, 60.0], 25.0), ([120.0, 120.0, 80.0], 25.0)] {
        let k = Knife::Sphere {
            centre: DVec3::from_array(centre),
            radius,
        };
        let what = format!("headsq/sphere {centre:?} r {radius}");
        let r = cut(&s.mesh, &s.forest, &k, &CAP).unwrap();
        assert!(r.stats.sphere_polyhedral, "{what}: {:?}", r.stats);
        assert!(r.stats.cap_crossings > 0, "{what}: {:?}", r.stats);
        assert!(r.pieces.len() >= 2, "{what}");
        assert_conserved(&s.mesh, &r, 1e-6, &what);
        same_result(&r, &cut_brute_force(&s.mesh, &k, &CAP).unwrap());
        for (i, piece) in r.pieces.iter().enumerate() {
            let x = chisel::mesh::self_intersections(piece);
            assert!(x.pairs.is_empty(), "{what} piece {i}: {:?}", x.pairs);
        }
        // The cut follows the polyhedron: every vertex of a piece is a bone
        // vertex or lies within the chord bound of the sphere.
        let bone: std::collections::HashSet<[u32; 3]> = s
            .mesh
            .positions
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect();
        for p in r.pieces.iter().flat_map(|m| &m.positions) {
            let d = (p.as_dvec3() - DVec3::from_array(centre)).length();
            assert!(
                bone.contains(&p.to_array().map(f32::to_bits))
                    || (d - radius).abs() <= (SPHERE_CHORD_ERROR + 1e-6) * radius,
                "{what}: vertex {p} at {d}"
            );
        }
    }
}

#[test]
fn polyhedral_sphere_is_an_outward_closed_sphere_within_the_chord_bound() {
    let (c, r) = (DVec3::new(3.0, -2.0, 7.5), 12.5);
    let a = Knife::polyhedral_sphere(c, r, 0);
    let t = chisel::mesh::Topology::of(&a);
    assert!(t.closed && t.is_manifold() && t.consistently_oriented);
    assert_eq!(t.components.len(), 1);
    assert_eq!(t.components[0].euler, 2);
    // Outward: a positive volume just below the ball's.
    let ball = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    assert!(t.signed_volume < ball && t.signed_volume > (1.0 - 3.0 * SPHERE_CHORD_ERROR) * ball);
    for p in &a.positions {
        let d = (p.as_dvec3() - c).length();
        assert!((d - r).abs() < 1e-6 * r, "{p} at {d}");
    }
    for tri in &a.triangles {
        let [p, q, s] = tri.map(|v| a.positions[v as usize].as_dvec3() - c);
        let plane = (q - p).cross(s - p).normalize().dot(p);
        assert!(
            plane > 0.0 && r - plane <= (SPHERE_CHORD_ERROR + 1e-6) * r,
            "sag {}",
            r - plane
        );
    }
    // Another attempt turns it.
    let b = Knife::polyhedral_sphere(c, r, 1);
    assert_eq!(a.triangles, b.triangles);
    assert_ne!(a.positions, b.positions);
}
