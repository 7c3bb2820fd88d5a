//! Scalpel cuts: closed pieces, conserved volume, tree = full scan, the
//! tree visits fewer nodes and triangles than exist (counts, never time).

mod common;

use std::collections::HashMap;

use chisel::cut::{
    CutOptions, CutResult, Knife, Located, SPHERE_CHORD_ERROR, Side, cut, cut_full_scan, cut_mesh,
    cut_sequence, locate, locate_full_scan,
};
use chisel::foundation::Forest;
use chisel::surface::{IsoSpec, McOptions, Surface, marching_cubes};
use chisel::volume::{Volume, VolumeData};
use chisel::{Backend, TriMesh};
use glam::DVec3;

const CAP: CutOptions = CutOptions { cap: true };

/// Signed volume by the divergence theorem (f64, about `r`).
fn volume(m: &TriMesh, r: DVec3) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3() - r);
            a.dot(b.cross(c))
        })
        .sum::<f64>()
        / 6.0
}

/// Every edge used exactly twice, in opposite directions.
fn assert_closed(m: &TriMesh, what: &str) {
    let mut d: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            *d.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    for (&(a, b), &n) in &d {
        assert_eq!(n, 1, "{what}: directed edge {a}->{b} used {n} times");
        assert!(d.contains_key(&(b, a)), "{what}: edge {a}-{b} open");
    }
}

/// Closed pieces whose volumes add up to the original within `rel`.
fn assert_conserved(orig: &TriMesh, r: &CutResult, rel: f64, what: &str) {
    let c = orig
        .bounds()
        .map_or(DVec3::ZERO, |(lo, hi)| ((lo + hi) * 0.5).as_dvec3());
    let v0 = volume(orig, c);
    let mut sum = 0.0;
    for (i, p) in r.pieces.iter().enumerate() {
        assert_closed(p, &format!("{what} piece {i}"));
        sum += volume(p, c);
    }
    assert!(
        (sum - v0).abs() <= rel * v0.abs(),
        "{what}: pieces {sum} vs original {v0} (rel {:e})",
        (sum - v0).abs() / v0.abs()
    );
}

fn same_result(a: &CutResult, b: &CutResult) {
    assert_eq!(a.pieces, b.pieces, "tree and full scan differ");
    assert_eq!(a.sides, b.sides);
    assert_eq!(a.stats.triangles_split, b.stats.triangles_split);
    assert_eq!(a.stats.cut_vertices, b.stats.cut_vertices);
}

/// An n³ f32 volume of `f(p − centre)` at the grid points (unit spacing).
fn sampled(n: usize, f: impl Fn(DVec3) -> f64) -> Volume {
    let c = (n as f64 - 1.0) / 2.0;
    let mut data = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                data.push(f(DVec3::new(x as f64 - c, y as f64 - c, z as f64 - c)) as f32);
            }
        }
    }
    Volume::new([n; 3], [1.0; 3], [0.0; 3], VolumeData::F32(data)).unwrap()
}

fn ball_volume(n: usize, r: f64) -> Volume {
    sampled(n, |d| r - d.length())
}

/// A hollow ball (shell between radii r0 < r1): cuts give annular caps.
fn shell_volume(n: usize, r0: f64, r1: f64) -> Volume {
    sampled(n, |d| (d.length() - r0).min(r1 - d.length()))
}

/// The plane z = `z`, normal +z.
fn z_plane(z: f32) -> Knife {
    plane([0.0, 0.0, f64::from(z)], [0.0, 0.0, 1.0])
}

fn mc(vol: &Volume) -> Surface {
    marching_cubes(
        vol,
        IsoSpec::Level(0.0),
        &McOptions { close_border: true },
        Backend::Cpu,
    )
    .unwrap()
}

fn plane(p: [f64; 3], n: [f64; 3]) -> Knife {
    Knife::Plane {
        point: DVec3::from_array(p),
        normal: DVec3::from_array(n),
    }
}

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
    same_result(&r, &cut_full_scan(&s.mesh, &k, &CAP).unwrap());
    // Sub-linear: the tree visits fewer nodes and tests fewer triangles.
    assert!(
        r.stats.triangles_tested * 4 < r.stats.triangles_total,
        "{:?}",
        r.stats
    );
    assert!(r.stats.nodes_visited < r.stats.nodes_total, "{:?}", r.stats);
    assert!(r.stats.classes.clear > 0 && r.stats.classes.intersected > 0);
}

/// No zero-area triangle and no two vertices at one position.
fn assert_clean(m: &TriMesh, what: &str) {
    let mut seen = std::collections::HashSet::new();
    for p in &m.positions {
        assert!(
            seen.insert(p.to_array().map(f32::to_bits)),
            "{what}: two vertices at {p}"
        );
    }
    for t in &m.triangles {
        let [a, b, c] = t.map(|v| m.positions[v as usize].as_dvec3());
        assert_ne!((b - a).cross(c - a), DVec3::ZERO, "{what}: zero-area {t:?}");
    }
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
        same_result(&r, &cut_full_scan(&s.mesh, k, &CAP).unwrap());
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
    same_result(&r, &cut_full_scan(&s.mesh, &k, &CAP).unwrap());
}

/// Connected components of a mesh's vertices joined by its triangles, and
/// whether every vertex is used.
fn components(m: &TriMesh) -> (usize, bool) {
    let mut parent: Vec<usize> = (0..m.positions.len()).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    let mut used = vec![false; m.positions.len()];
    for t in &m.triangles {
        let [a, b, c] = t.map(|v| v as usize);
        used[a] = true;
        used[b] = true;
        used[c] = true;
        for y in [b, c] {
            let (ra, ry) = (find(&mut parent, a), find(&mut parent, y));
            parent[ra.max(ry)] = ra.min(ry);
        }
    }
    let n = (0..parent.len())
        .filter(|&x| find(&mut parent, x) == x)
        .count();
    (n, used.iter().all(|&u| u))
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
    same_result(&r, &cut_full_scan(&s.mesh, &k, &CAP).unwrap());
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
    same_result(&r, &cut_full_scan(&s.mesh, &small, &CAP).unwrap());
}

/// A square sheet knife in the plane z = `z` (two triangles, normal +z),
/// corners off the grid diagonals so no knife edge meets a surface edge.
fn sheet(z: f32) -> TriMesh {
    TriMesh::new(
        vec![
            glam::Vec3::new(-10.3, -9.1, z),
            glam::Vec3::new(40.7, -10.2, z),
            glam::Vec3::new(39.6, 40.9, z),
            glam::Vec3::new(-9.4, 39.8, z),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .unwrap()
}

/// Every edge used twice in opposite directions, and the volumes of the
/// pieces on each side.
fn side_volumes(r: &CutResult, c: DVec3) -> (f64, f64) {
    let mut v = (0.0, 0.0);
    for (p, s) in r.pieces.iter().zip(&r.sides) {
        match s {
            Side::Negative => v.0 += volume(p, c),
            Side::Positive => v.1 += volume(p, c),
            Side::Both => panic!("a piece on both sides"),
        }
    }
    v
}

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
        same_result(&r, &cut_full_scan(&s.mesh, &knife, &opts).unwrap());
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
        &cut_full_scan(&s.mesh, &Knife::Mesh(sheet(z)), &CAP).unwrap(),
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
    same_result(&r, &cut_full_scan(&s.mesh, &knife, &CAP).unwrap());
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
    assert!(cut_mesh(&cube, &Knife::Mesh(twisted), &CAP).is_err());
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
    same_result(&r, &cut_full_scan(&s.mesh, &k, &CAP).unwrap());
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
        same_result(&r, &cut_full_scan(&s.mesh, &k, &CAP).unwrap());
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
        assert!(cut(&s.mesh, &s.forest, &k, &CAP).is_err(), "{k:?}");
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
    assert!(e.contains("is parallel to its normal"), "{e}");
}

#[test]
fn headsq_bone_plane_and_sphere_cuts_conserve_volume() {
    let Some(vol) = common::real_volume("headsq/quarter.nhdr") else {
        return;
    };
    let s = marching_cubes(
        &vol,
        IsoSpec::Level(1150.0),
        &McOptions { close_border: true },
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
    same_result(&r, &cut_full_scan(&s.mesh, &p, &CAP).unwrap());
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
    same_result(&r, &cut_full_scan(&s.mesh, &sph, &CAP).unwrap());
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
    same_result(&r, &cut_full_scan(&s.mesh, &sph, &CAP).unwrap());
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
        same_result(&r, &cut_full_scan(&s.mesh, &k, &CAP).unwrap());
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

/// Everything but the counts: crossed triangles, cut vertex numbering,
/// points (bit for bit) and sides.
fn same_located(a: &Located, b: &Located, what: &str) {
    assert_eq!(a.triangles, b.triangles, "{what}: crossed triangles");
    assert_eq!(a.edge_cuts, b.edge_cuts, "{what}: edge cuts");
    assert_eq!(a.points, b.points, "{what}: points");
    assert_eq!(a.lower_negative, b.lower_negative, "{what}: sides");
    assert_eq!(a.edges, b.edges, "{what}: edges");
}

#[test]
fn tree_locate_equals_the_scan_on_every_analytic_knife() {
    let s = mc(&shell_volume(40, 11.0, 16.0));
    let c = DVec3::splat(19.5);
    let knives = [
        plane([19.5, 19.5, 21.3], [0.1, 0.2, 1.0]),
        plane([19.5, 19.5, 19.5], [0.0, 0.0, 1.0]),
        Knife::Sphere {
            centre: c + DVec3::new(13.0, 2.0, 1.0),
            radius: 6.3,
        },
        Knife::Rect {
            centre: c,
            normal: DVec3::new(0.3, -0.2, 1.0),
            u_axis: DVec3::X,
            half_extents: [14.0, 6.0],
        },
    ];
    let plain = Forest::from_triangles(s.mesh.view()).forest;
    // The same boxes taken as unsorted: every child box is tested instead
    // of the binary-searched slab.
    assert!(s.forest.axis_sorted);
    let unsorted = Forest {
        axis_sorted: false,
        ..s.forest.clone()
    };
    for k in &knives {
        let scan = locate_full_scan(&s.mesh, k).unwrap();
        assert!(!scan.triangles.is_empty(), "{k:?} misses the shell");
        let tree = locate(&s.mesh, &s.forest, k).unwrap();
        same_located(&tree, &scan, "marching-cubes forest");
        assert!(tree.stats.triangles_tested < tree.stats.triangles_total / 4);
        same_located(
            &locate(&s.mesh, &plain, k).unwrap(),
            &scan,
            "virtual-grid forest",
        );
        let all = locate(&s.mesh, &unsorted, k).unwrap();
        same_located(&all, &scan, "unsorted forest");
        assert!(all.stats.nodes_visited > tree.stats.nodes_visited, "{k:?}");
        assert!(all.stats.triangles_tested >= tree.stats.triangles_tested);
    }
    // Negative control: a knife moved by a tenth of a voxel differs.
    let moved = plane([19.5, 19.5, 21.4], [0.1, 0.2, 1.0]);
    let a = locate(&s.mesh, &s.forest, &knives[0]).unwrap();
    let b = locate(&s.mesh, &s.forest, &moved).unwrap();
    assert_ne!(a.points, b.points);
}

#[test]
fn leaf_tables_name_each_triangles_corners_and_positions() {
    let s = mc(&shell_volume(24, 6.0, 9.0));
    let f = &s.forest;
    assert_eq!(f.corners.len(), f.triangles.len());
    assert_eq!(f.leaf_positions.len(), f.leaf_vertices.len());
    for (&v, &q) in f.leaf_vertices.iter().zip(&f.leaf_positions) {
        assert_eq!(
            q, s.mesh.positions[v as usize],
            "leaf position of vertex {v}"
        );
    }
    for c in &f.cells {
        let vs = &f.leaf_vertices[c.vertices.range()];
        assert!(vs.windows(2).all(|w| w[0] < w[1]), "distinct, ascending");
        for i in c.triangles.range() {
            let want = s.mesh.triangles[f.triangles[i] as usize];
            let got = f.corners[i].map(|v| {
                assert!(c.vertices.range().contains(&(v as usize)));
                f.leaf_vertices[v as usize]
            });
            assert_eq!(got, want);
        }
    }
}

#[test]
fn a_forest_of_another_mesh_is_an_error() {
    let s = mc(&ball_volume(16, 5.0));
    let other = mc(&ball_volume(16, 6.0));
    let k = plane([7.5, 7.5, 7.5], [0.0, 0.0, 1.0]);
    let err = locate(&s.mesh, &other.forest, &k).unwrap_err();
    assert!(err.to_string().contains("forest was built for"), "{err}");
    assert!(cut(&s.mesh, &other.forest, &k, &CAP).is_err());
}
