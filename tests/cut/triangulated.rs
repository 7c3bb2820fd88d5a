//! Triangulated knives: cuts like the sampled plane, loops inside one knife
//! triangle, rings, open curves, closed knives, contacts and bad knives.

use super::*;

#[test]
fn triangulated_knife_cuts_like_the_plane_it_samples() {
    let s = mc(&ball_volume(30, 10.0));
    let z = 14.3f32;
    let knife = Knife::Mesh(sheet(z));
    let flat = z_plane(z);
    let c = DVec3::splat(14.5);
    for opts in [CutOptions::default(), CAP] {
        let r = cut(&s.mesh, &s.forest, &knife, &opts).unwrap();
        let p = cut(&s.mesh, &s.forest, &flat, &opts).unwrap();
        assert_eq!(r.pieces.len(), 2);
        assert_eq!(r.sides, p.sides);
        assert_eq!(r.stats.curves_open, 0);
        same_result(&r, &cut_brute_force(&s.mesh, &knife, &opts).unwrap());
        // The knife's diagonal adds cut points inside surface triangles, so
        // the triangles differ from the plane's; the halves do not.
        let (a, b) = (side_volumes(&r, c), side_volumes(&p, c));
        if opts.cap {
            assert_eq!(r.stats.loops_capped, 1);
            assert_conserved(&s.mesh, &r, 1e-6, "ball/sheet");
            assert!((a.0 - b.0).abs() < 1e-4 * b.0, "{a:?} vs {b:?}");
            assert!((a.1 - b.1).abs() < 1e-4 * b.1, "{a:?} vs {b:?}");
        }
    }
}

#[test]
fn a_cut_loop_inside_one_knife_triangle_is_capped() {
    // One knife triangle holds the whole cut curve: the polygon around the
    // loop has no cut edge on its border and takes its side from the loop.
    let s = mc(&ball_volume(30, 10.0));
    let z = 14.3f32;
    let knife = TriMesh::new(
        vec![
            glam::Vec3::new(-50.3, -40.1, z),
            glam::Vec3::new(80.7, -30.2, z),
            glam::Vec3::new(0.6, 90.9, z),
        ],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let r = cut(&s.mesh, &s.forest, &Knife::Mesh(knife), &CAP).unwrap();
    let p = cut(&s.mesh, &s.forest, &z_plane(z), &CAP).unwrap();
    assert_eq!(r.sides, p.sides);
    assert_eq!(r.stats.loops_capped, 1);
    assert_conserved(&s.mesh, &r, 1e-6, "ball/one-triangle knife");
    let c = DVec3::splat(14.5);
    let (a, b) = (side_volumes(&r, c), side_volumes(&p, c));
    assert!((a.0 - b.0).abs() < 1e-6 * b.0, "{a:?} vs {b:?}");
}

#[test]
fn triangulated_knife_caps_a_hollow_ball_with_a_ring() {
    // Outer sphere and cavity are two closed components; the cavity's
    // triangles face into the void, and the cap is the ring between them.
    let s = mc(&shell_volume(30, 5.0, 11.0));
    assert_eq!(s.groups.len(), 2);
    let z = 14.3f32;
    let r = cut(&s.mesh, &s.forest, &Knife::Mesh(sheet(z)), &CAP).unwrap();
    let p = cut(&s.mesh, &s.forest, &z_plane(z), &CAP).unwrap();
    assert_eq!(r.pieces.len(), 2);
    assert_eq!(r.sides, p.sides);
    assert_eq!(r.stats.curves_open, 0);
    assert_conserved(&s.mesh, &r, 1e-6, "hollow ball/sheet");
    let ctr = DVec3::splat(14.5);
    let (a, b) = (side_volumes(&r, ctr), side_volumes(&p, ctr));
    assert!((a.0 - b.0).abs() < 1e-4 * b.0, "{a:?} vs {b:?}");
}

#[test]
fn triangulated_knife_caps_loops_and_leaves_open_curves_of_an_open_surface_open() {
    // A ball (a closed loop under the knife) and a slab at x ≥ 25.5 whose
    // surface ends at the volume border (an open cut curve, ending inside
    // knife triangles where the surface's border crosses them).
    let c = 14.5;
    let vol = sampled(30, |d| (8.0 - d.length()).max(d.x + c - 25.5));
    let s = marching_cubes(
        &vol,
        IsoSpec::Level(0.0),
        &McOptions {
            close_border: false,
            ..McOptions::default()
        },
        Backend::Cpu,
    )
    .unwrap();
    assert!(
        !s.forest.closed_outward,
        "an open surface is not known to be closed"
    );
    let z = 14.3f32;
    let r = cut(&s.mesh, &s.forest, &Knife::Mesh(sheet(z)), &CAP).unwrap();
    let p = cut(&s.mesh, &s.forest, &z_plane(z), &CAP).unwrap();
    assert_eq!((r.stats.loops_capped, p.stats.loops_capped), (1, 1));
    assert!(
        r.stats.curves_open == 1 && p.stats.curves_open == 1,
        "{:?} {:?}",
        r.stats,
        p.stats
    );
    assert_eq!(r.sides, p.sides);
    // The ball's halves are closed and match the plane's; the slab's are not.
    let ctr = DVec3::splat(c);
    let mut balls = 0;
    for (a, b) in r.pieces.iter().zip(&p.pieces) {
        let Some((lo, _)) = a.bounds() else { continue };
        if lo.x < 20.0 {
            assert_closed(a, "ball half");
            let (va, vb) = (volume(a, ctr), volume(b, ctr));
            assert!((va - vb).abs() < 1e-6 * vb.abs(), "{va} vs {vb}");
            balls += 1;
        }
    }
    assert_eq!(balls, 2);
    same_result(
        &r,
        &cut_brute_force(&s.mesh, &Knife::Mesh(sheet(z)), &CAP).unwrap(),
    );
}

#[test]
fn closed_triangulated_knife_cuts_a_cube_into_inside_and_outside() {
    let cube = common::cube();
    // An icosphere of radius 0.4 through the face x = 1: the cut curve
    // crosses the face's diagonal, knife edges pierce the face triangles.
    let (ctr, rad) = (DVec3::new(0.93, 0.52, 0.47), 0.4);
    let mut ball = common::icosphere(3);
    for p in &mut ball.positions {
        *p = (p.as_dvec3() * rad + ctr).as_vec3();
    }
    let knife = Knife::Mesh(ball.clone());
    let r = cut_mesh(&cube, &knife, &CAP).unwrap();
    assert_eq!(r.pieces.len(), 2, "inside and outside");
    assert_eq!(r.sides, vec![Side::Positive, Side::Negative]);
    assert_eq!(r.stats.curves_open, 0);
    assert_eq!(r.stats.loops_capped, 1);
    assert_conserved(&cube, &r, 1e-6, "cube/icosphere");
    // The inside piece is the ball's part with x < 1 (spherical cap of
    // height r − 0.07 cut off); the icosphere is a little smaller.
    let h = rad - 0.07;
    let part = 4.0 / 3.0 * std::f64::consts::PI * rad.powi(3)
        - std::f64::consts::PI * h * h * (3.0 * rad - h) / 3.0;
    let (neg, pos) = side_volumes(&r, DVec3::splat(0.5));
    assert!((neg - part).abs() < 0.03 * part, "{neg} vs {part}");
    assert!((neg + pos - 1.0).abs() < 1e-6);
    // Every cap vertex is a knife vertex or a cut point on the knife: the
    // inside piece's vertices all lie in the closed ball.
    let inside = &r.pieces[r.sides.iter().position(|s| *s == Side::Negative).unwrap()];
    for q in &inside.positions {
        assert!((q.as_dvec3() - ctr).length() <= rad + 1e-5, "{q}");
    }
    // The sheet of a closed knife, reversed, swaps the sides.
    let mut flipped = ball;
    for t in &mut flipped.triangles {
        t.swap(1, 2);
    }
    let f = cut_mesh(&cube, &Knife::Mesh(flipped), &CAP).unwrap();
    assert_eq!(f.sides, vec![Side::Negative, Side::Positive]);
    assert_conserved(&cube, &f, 1e-6, "cube/flipped icosphere");
    // A closed surface wound inward gives the same pieces, wound inward:
    // its solid is in front of its triangles.
    let mut inward = cube.clone();
    inward.flip_winding();
    let w = cut_mesh(&inward, &knife, &CAP).unwrap();
    assert_eq!(w.sides, r.sides);
    assert_eq!(w.stats.loops_capped, 1);
    for (a, b) in w.pieces.iter().zip(&r.pieces) {
        let (va, vb) = (volume(a, DVec3::splat(0.5)), volume(b, DVec3::splat(0.5)));
        assert!((va + vb).abs() < 1e-9, "{va} vs {vb}");
    }
}

#[test]
fn closed_triangulated_knife_bites_a_marching_cubes_ball_like_the_sphere() {
    let s = mc(&ball_volume(40, 14.0));
    let (ctr, rad) = (DVec3::new(19.37, 19.61, 31.13), 8.0);
    let mut ball = common::icosphere(4);
    for p in &mut ball.positions {
        *p = (p.as_dvec3() * rad + ctr).as_vec3();
    }
    let knife = Knife::Mesh(ball);
    let r = cut(&s.mesh, &s.forest, &knife, &CAP).unwrap();
    assert_eq!(r.pieces.len(), 2);
    assert_conserved(&s.mesh, &r, 1e-6, "ball/icosphere");
    same_result(&r, &cut_brute_force(&s.mesh, &knife, &CAP).unwrap());
    assert!(r.stats.triangles_tested * 2 < r.stats.triangles_total);
    let sph = cut(
        &s.mesh,
        &s.forest,
        &Knife::Sphere {
            centre: ctr,
            radius: rad,
        },
        &CAP,
    )
    .unwrap();
    let c = DVec3::splat(19.5);
    let (a, b) = (side_volumes(&r, c), side_volumes(&sph, c));
    assert!((a.0 - b.0).abs() < 0.02 * b.0, "{a:?} vs {b:?}");
}

#[test]
fn triangulated_knife_contacts_and_bad_knives_are_errors() {
    let cube = common::cube();
    let tri = |a: [f32; 3], b: [f32; 3], c: [f32; 3]| {
        TriMesh::new(vec![a.into(), b.into(), c.into()], vec![[0, 1, 2]]).unwrap()
    };
    // A knife vertex exactly on the face x = 1.
    let touching = tri([1.0, 0.5, 0.4], [1.5, 0.2, 0.5], [1.5, 0.8, 0.55]);
    let e = cut_mesh(&cube, &Knife::Mesh(touching), &CAP).unwrap_err();
    assert!(e.to_string().contains("move or tilt the knife"), "{e}");
    // An open knife whose border lies inside the cube.
    let short = TriMesh::new(
        vec![
            glam::Vec3::new(0.31, -0.5, 0.47),
            glam::Vec3::new(1.5, -0.5, 0.52),
            glam::Vec3::new(1.5, 1.5, 0.53),
            glam::Vec3::new(0.33, 1.5, 0.49),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .unwrap();
    let e = cut_mesh(&cube, &Knife::Mesh(short), &CAP).unwrap_err();
    assert!(e.to_string().contains("border"), "{e}");
    // Inconsistent orientation.
    let twisted = TriMesh::new(
        vec![
            glam::Vec3::new(-1.0, -1.0, 0.5),
            glam::Vec3::new(2.0, -1.0, 0.5),
            glam::Vec3::new(2.0, 2.0, 0.5),
            glam::Vec3::new(-1.0, 2.0, 0.5),
        ],
        vec![[0, 1, 2], [0, 3, 2]],
    )
    .unwrap();
    assert!(matches!(
        cut_mesh(&cube, &Knife::Mesh(twisted), &CAP),
        Err(chisel::Error::Refused(
            chisel::Refusal::KnifeNotManifold { .. }
        ))
    ));
    // The same sheet, consistently oriented, halves the cube (control).
    let good = TriMesh::new(
        vec![
            glam::Vec3::new(-1.0, -1.1, 0.5),
            glam::Vec3::new(2.1, -1.0, 0.5),
            glam::Vec3::new(2.0, 2.1, 0.5),
            glam::Vec3::new(-1.1, 2.0, 0.5),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .unwrap();
    let r = cut_mesh(&cube, &Knife::Mesh(good), &CAP).unwrap();
    assert_eq!(r.pieces.len(), 2);
    assert_conserved(&cube, &r, 1e-6, "cube/sheet");
    let (neg, pos) = side_volumes(&r, DVec3::splat(0.5));
    assert!(
        (neg - 0.5).abs() < 1e-6 && (pos - 0.5).abs() < 1e-6,
        "{neg} {pos}"
    );
}
