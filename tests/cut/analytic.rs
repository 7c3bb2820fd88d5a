//! Plane, sphere and rectangle knives on marching-cubes balls and shells:
//! closed halves, reused vertices, caps, open pieces and thread independence.

use super::*;

#[test]
fn plane_cut_of_a_ball_gives_two_closed_halves() {
    let s = mc(&ball_volume(40, 14.0));
    let k = plane([19.5, 19.5, 19.3], [0.2, 0.1, 1.0]);
    let r = cut(&s.mesh, &s.forest, &k, &CAP).unwrap();
    assert_eq!(r.pieces.len(), 2);
    assert_eq!(r.sides, vec![Side::Negative, Side::Positive]);
    assert_eq!(r.stats.loops_capped, 1);
    assert_eq!(r.stats.curves_open, 0);
    assert_conserved(&s.mesh, &r, 1e-6, "ball/plane");
    same_result(&r, &cut_brute_force(&s.mesh, &k, &CAP).unwrap());
    // Sub-linear: the tree visits fewer nodes and tests fewer triangles.
    assert!(
        r.stats.triangles_tested * 4 < r.stats.triangles_total,
        "{:?}",
        r.stats
    );
    assert!(r.stats.nodes_visited < r.stats.nodes_total, "{:?}", r.stats);
    assert!(r.stats.classes.clear > 0 && r.stats.classes.intersected > 0);
}

#[test]
fn knives_through_mesh_vertices_reuse_them() {
    // Marching-cubes vertices on x and y grid edges lie exactly in the
    // plane z = 14: their crossings land on them, and each becomes one cut
    // vertex — no coincident copies, no zero-area slivers, closed pieces.
    let s = mc(&ball_volume(30, 10.0));
    let on_plane = s.mesh.positions.iter().filter(|p| p.z == 14.0).count();
    assert!(on_plane > 20, "{on_plane}");
    let knives = [
        plane([0.0, 0.0, 14.0], [0.0, 0.0, 1.0]),
        Knife::Rect {
            centre: DVec3::new(14.5, 14.5, 14.0),
            normal: DVec3::Z,
            u_axis: DVec3::X,
            half_extents: [30.0, 30.0],
        },
        // Through grid points diagonally: crossings on and off vertices.
        plane([14.0, 14.0, 14.0], [1.0, 1.0, 0.0]),
    ];
    for (i, k) in knives.iter().enumerate() {
        let r = cut(&s.mesh, &s.forest, k, &CAP).unwrap();
        assert_eq!(r.pieces.len(), 2, "knife {i}");
        assert_eq!(
            (r.stats.loops_capped, r.stats.curves_open),
            (1, 0),
            "knife {i}"
        );
        for (j, p) in r.pieces.iter().enumerate() {
            assert_clean(p, &format!("knife {i} piece {j}"));
        }
        assert_conserved(&s.mesh, &r, 1e-9, &format!("knife {i}"));
        same_result(&r, &cut_brute_force(&s.mesh, k, &CAP).unwrap());
    }
    // A mesh knife after such a cut finds no degenerate triangle to refuse.
    let mut ball = common::icosphere(3);
    for p in &mut ball.positions {
        *p = (p.as_dvec3() * 6.0 + DVec3::new(14.37, 14.61, 21.13)).as_vec3();
    }
    let seq = cut_sequence(&s.mesh, &[knives[0].clone(), Knife::Mesh(ball)], &CAP).unwrap();
    assert_conserved(&s.mesh, &seq, 1e-9, "plane then icosphere");
}

#[test]
fn sphere_caps_of_an_inward_wound_surface_are_its_outward_caps_turned() {
    let s = mc(&ball_volume(30, 10.0));
    let mut inward = s.mesh.clone();
    inward.flip_winding();
    let k = Knife::Sphere {
        centre: DVec3::new(14.3, 14.6, 22.1),
        radius: 6.2,
    };
    let out = cut(&s.mesh, &s.forest, &k, &CAP).unwrap();
    let r = cut_mesh(&inward, &k, &CAP).unwrap();
    assert_eq!(r.sides, out.sides);
    assert_conserved(&inward, &r, 1e-9, "inward ball/sphere");
    let c = DVec3::splat(14.5);
    let (a, b) = (side_volumes(&r, c), side_volumes(&out, c));
    assert!(a.0 < 0.0 && a.1 < 0.0, "{a:?}");
    assert!((a.0 + b.0).abs() < 1e-3 * b.0, "{a:?} vs {b:?}");
}

#[test]
fn uncapped_cut_leaves_open_pieces_with_the_cut_as_boundary() {
    let s = mc(&ball_volume(30, 10.0));
    let k = plane([14.5, 14.5, 14.5], [0.0, 0.0, 1.0]);
    let r = cut(&s.mesh, &s.forest, &k, &CutOptions::default()).unwrap();
    assert_eq!(r.pieces.len(), 2);
    assert_eq!(r.stats.loops_capped, 0);
    for p in &r.pieces {
        let mut d: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &p.triangles {
            for k in 0..3 {
                *d.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        let open: Vec<_> = d
            .keys()
            .filter(|&&(a, b)| !d.contains_key(&(b, a)))
            .collect();
        assert!(!open.is_empty());
        for &&(a, b) in &open {
            for v in [a, b] {
                let z = p.positions[v as usize].z;
                assert!(
                    (z - 14.5).abs() < 1e-4,
                    "open edge off the plane at z = {z}"
                );
            }
        }
    }
}

#[test]
fn hollow_shell_cut_gets_annular_caps() {
    let s = mc(&shell_volume(44, 9.0, 16.0));
    assert_eq!(s.groups.len(), 2, "outer shell and cavity");
    let k = plane([21.5, 21.5, 22.0], [0.0, 1.0, 0.3]);
    let r = cut(&s.mesh, &s.forest, &k, &CAP).unwrap();
    assert_eq!(
        r.pieces.len(),
        2,
        "each half is one solid with its annular cap"
    );
    assert_eq!(r.stats.loops_capped, 2);
    assert_conserved(&s.mesh, &r, 1e-6, "shell/plane");
    same_result(&r, &cut_brute_force(&s.mesh, &k, &CAP).unwrap());
}

/// Regrouping runs in parallel chunks of 65,536 input triangles: on a
/// surface several chunks long the pieces are the same on one thread as on
/// four, each is connected, uses every vertex it has, and together they
/// hold every triangle.
#[test]
fn pieces_are_the_same_on_any_number_of_threads() {
    let s = mc(&shell_volume(128, 40.0, 58.0));
    let n = s.mesh.triangles.len();
    assert!(n > 2 * 65_536, "{n} triangles");
    let knives = [
        (plane([63.5, 63.5, 60.0], [0.1, 0.2, 1.0]), CAP),
        (
            plane([63.5, 63.5, 60.0], [0.1, 0.2, 1.0]),
            CutOptions { cap: false },
        ),
        (plane([63.5, 40.0, 63.5], [0.0, 1.0, 0.0]), CAP),
    ];
    for (k, opts) in &knives {
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| cut(&s.mesh, &s.forest, k, opts).unwrap())
        };
        let (one, four) = (on(1), on(4));
        same_result(&one, &four);
        assert_eq!(one.pieces.len(), if opts.cap { 2 } else { 4 }, "{k:?}");
        for p in &one.pieces {
            assert_eq!(components(p), (1, true), "{k:?}");
        }
        let held: usize = one.pieces.iter().map(|p| p.triangles.len()).sum();
        let split = one.stats.triangles_split;
        assert!(
            held >= n + split,
            "{held} triangles for {n} input, {split} split"
        );
    }
}

#[test]
fn sphere_cut_takes_a_bite() {
    let s = mc(&ball_volume(40, 14.0));
    // Closed at the border and wound outward: the tree's cut skips the
    // orientation analysis that the scan's makes, with the same pieces.
    assert!(s.forest.closed_outward);
    let k = Knife::Sphere {
        centre: DVec3::new(19.5, 19.5, 31.0),
        radius: 8.0,
    };
    let r = cut(&s.mesh, &s.forest, &k, &CAP).unwrap();
    assert_eq!(r.pieces.len(), 2);
    assert!(r.sides.contains(&Side::Negative) && r.sides.contains(&Side::Positive));
    assert_conserved(&s.mesh, &r, 1e-6, "ball/sphere");
    same_result(&r, &cut_brute_force(&s.mesh, &k, &CAP).unwrap());
    assert!(
        r.stats.triangles_tested * 2 < r.stats.triangles_total,
        "{:?}",
        r.stats
    );
}

#[test]
fn rectangle_that_cuts_through_equals_the_plane_and_partial_one_keeps_one_piece() {
    let s = mc(&ball_volume(30, 10.0));
    let n = [0.0, 0.3, 1.0];
    let p = [14.5, 14.5, 15.0];
    let big = Knife::Rect {
        centre: DVec3::from_array(p),
        normal: DVec3::from_array(n),
        u_axis: DVec3::X,
        half_extents: [50.0, 50.0],
    };
    let a = cut(&s.mesh, &s.forest, &big, &CAP).unwrap();
    let b = cut(&s.mesh, &s.forest, &plane(p, n), &CAP).unwrap();
    assert_eq!(a.pieces, b.pieces);
    // A small rectangle makes a slit: still one watertight piece.
    let small = Knife::Rect {
        centre: DVec3::new(14.5, 14.5, 14.5),
        normal: DVec3::Z,
        u_axis: DVec3::X,
        half_extents: [4.0, 30.0],
    };
    let r = cut(&s.mesh, &s.forest, &small, &CAP).unwrap();
    assert_eq!(r.pieces.len(), 1);
    assert_eq!(r.sides, vec![Side::Both]);
    assert!(r.stats.triangles_partial > 0 && r.stats.curves_open > 0);
    assert_eq!(r.stats.loops_capped, 0, "an open slit is not capped");
    // The slit opens the surface: its open edges lie in the plane z = 14.5
    // inside the rectangle; every other edge is used twice.
    let p = &r.pieces[0];
    let mut d: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &p.triangles {
        for k in 0..3 {
            *d.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    let mut open = 0;
    for &(a, b) in d.keys() {
        if !d.contains_key(&(b, a)) {
            open += 1;
            for v in [a, b] {
                let q = p.positions[v as usize];
                assert!(
                    (q.z - 14.5).abs() < 1e-4 && (q.x - 14.5).abs() <= 4.0 + 1e-4,
                    "{q}"
                );
            }
        }
    }
    assert!(open > 0);
    same_result(&r, &cut_brute_force(&s.mesh, &small, &CAP).unwrap());
}
