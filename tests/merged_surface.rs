//! The merged surface's convex faces (Theorem KE, seed 003 §4.5.6) and
//! point-in-polyhedron by ray parity (§4.4.3): exact convexity and tiling
//! of every convex face, and ray-parity voxelization equal to the nested
//! shell voxelization on the seed objects, random carvings and CT bone.

mod common;

use std::collections::HashMap;

use chisel::Backend;
use chisel::hull_scan::{Side, VoxelBox};
use chisel::phantom::voxel::{cylinder_tunnel, ellipsoid_dent, torus};
use chisel::polyhedron::{MergedSurface, PolyhedrizeOptions, Polyhedron, polyhedrize, theorem_ke};
use chisel::volume::Volume;
use chisel::voxel::{Component, DigitalObject, Selection};

fn object(v: &Volume) -> DigitalObject {
    DigitalObject::from_volume(v, Selection::Threshold(1.0), Component::All).unwrap()
}

fn run(o: &DigitalObject) -> Polyhedron {
    polyhedrize(o, PolyhedrizeOptions::default(), Backend::Cpu, &|_| {})
        .unwrap()
        .0
}

fn run_balls(o: &DigitalObject) -> Polyhedron {
    let options = PolyhedrizeOptions {
        balls: true,
        ..Default::default()
    };
    polyhedrize(o, options, Backend::Cpu, &|_| {}).unwrap().0
}

/// Planar coordinates of `p` on a plane with normal `n`, written here
/// independently of the library: the dominant axis dropped, the other two
/// ordered so that counter-clockwise about `n` stays counter-clockwise.
fn planar(p: [i64; 3], n: [i64; 3]) -> [i64; 2] {
    let k = (0..3).max_by_key(|&a| n[a].abs()).unwrap();
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    if n[k] > 0 { [p[i], p[j]] } else { [p[j], p[i]] }
}

fn orient(a: [i64; 2], b: [i64; 2], c: [i64; 2]) -> i128 {
    let (ab, ac) = (
        [(b[0] - a[0]) as i128, (b[1] - a[1]) as i128],
        [(c[0] - a[0]) as i128, (c[1] - a[1]) as i128],
    );
    ab[0] * ac[1] - ab[1] * ac[0]
}

/// Twice the signed area of a planar cycle.
fn area2(c: &[[i64; 2]]) -> i128 {
    (0..c.len())
        .map(|k| {
            let (a, b) = (c[k], c[(k + 1) % c.len()]);
            a[0] as i128 * b[1] as i128 - a[1] as i128 * b[0] as i128
        })
        .sum()
}

/// Exact convexity of a planar cycle: distinct points, positive area, and
/// every point on the left of or on every edge's line (which rules out
/// reflex corners, spikes and cycles winding twice).
fn is_convex(c: &[[i64; 2]]) -> bool {
    let mut sorted = c.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    sorted.len() == c.len()
        && c.len() >= 3
        && area2(c) > 0
        && (0..c.len()).all(|k| {
            let (a, b) = (c[k], c[(k + 1) % c.len()]);
            c.iter().all(|&q| orient(a, b, q) >= 0)
        })
}

/// Every convex face is convex, lies on its face's plane, and the convex
/// faces of each face tile it: their directed edges, with interior pairs
/// cancelled, are exactly the face's loop edges (so the sum of their
/// indicators has the face's boundary), and their areas add up to the
/// face's (so, all being positive, they do not overlap).
fn assert_convex_tiling(m: &MergedSurface, what: &str) {
    let mut by_face: Vec<Vec<&Vec<u32>>> = vec![Vec::new(); m.faces.len()];
    for c in &m.convex_faces {
        by_face[c.face as usize].push(&c.vertices);
    }
    for (fi, f) in m.faces.iter().enumerate() {
        let pos = |v: u32| planar(m.vertices[v as usize], f.normal);
        let mut edges: HashMap<(u32, u32), i64> = HashMap::new();
        let mut area = 0;
        for c in &by_face[fi] {
            let pts: Vec<[i64; 2]> = c.iter().map(|&v| pos(v)).collect();
            assert!(is_convex(&pts), "{what}: face {fi}: {pts:?} is not convex");
            for &v in c.iter() {
                let p = m.vertices[v as usize];
                let d: i64 = (0..3).map(|a| f.normal[a] * p[a]).sum();
                assert_eq!(d, f.offset, "{what}: face {fi}: off the plane");
            }
            area += area2(&pts);
            for k in 0..c.len() {
                let (a, b) = (c[k], c[(k + 1) % c.len()]);
                *edges.entry((a, b)).or_default() += 1;
                *edges.entry((b, a)).or_default() -= 1;
            }
        }
        let mut loop_edges: HashMap<(u32, u32), i64> = HashMap::new();
        let mut face_area = 0;
        for lp in &f.loops {
            face_area += area2(&lp.iter().map(|&v| pos(v)).collect::<Vec<_>>());
            for k in 0..lp.len() {
                let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
                *loop_edges.entry((a, b)).or_default() += 1;
                *loop_edges.entry((b, a)).or_default() -= 1;
            }
        }
        edges.retain(|_, c| *c != 0);
        loop_edges.retain(|_, c| *c != 0);
        assert_eq!(edges, loop_edges, "{what}: face {fi}: boundary");
        assert_eq!(area, face_area, "{what}: face {fi}: area");
    }
    assert!(m.n_convex_faces() >= m.n_faces_split(), "{what}");
    assert!(m.n_convex_faces() <= m.triangles.len(), "{what}");
}

/// The voxel box of the object plus a one-voxel margin.
fn margin_box(o: &DigitalObject) -> VoxelBox {
    let (lo, hi) = o.voxel_bbox();
    VoxelBox {
        origin: lo.map(|c| c - 1),
        dims: std::array::from_fn(|a| (hi[a] - lo[a] + 3) as usize),
    }
}

/// Ray parity with the stored labels equals the nested-shell voxelization
/// and S; every `stride`-th voxel also agrees with the single-point rays
/// along x and y. Returns the sides.
fn assert_ray_parity(p: &Polyhedron, o: &DigitalObject, stride: usize, what: &str) -> Vec<Side> {
    let m = p.merged_surface().unwrap();
    let b = margin_box(o);
    let sides = m.classify(&b).unwrap();
    let by_rays = p.voxelize_ray_parity(&m, &b, Backend::Cpu).unwrap();
    let nested = p.voxelize(&b, Backend::Cpu).unwrap();
    let differ = (0..nested.len())
        .filter(|&k| by_rays[k] != nested[k])
        .count();
    assert_eq!(differ, 0, "{what}: ray parity vs voxelize");
    let (n, first) = p.mismatches_ray_parity(&m, o, Backend::Cpu, 5).unwrap();
    assert_eq!(n, 0, "{what}: {first:?}");
    let [nx, ny, _] = b.dims;
    for k in (0..sides.len()).step_by(stride) {
        let c = b.centre([k % nx, k / nx % ny, k / (nx * ny)]);
        for axis in [0, 1] {
            assert_eq!(
                m.side_of(c, axis).unwrap(),
                sides[k],
                "{what}: centre {c:?}, ray along axis {axis}"
            );
        }
    }
    sides
}

#[test]
fn theorem_ke_refuses_reflex_merges_and_accepts_collinear_ones() {
    // Unit square split along its diagonal (0,0)–(2,2): convex union.
    let (p1, p2) = ([2, 2], [0, 0]);
    assert!(theorem_ke(p1, p2, [2, 0], [2, 0], [0, 2], [0, 2]));
    // F1 = (0,0) (2,0) (2,2), F2 = (0,0) (2,2) (-2,4): a convex
    // quadrilateral, accepted; F2 = (0,0) (2,2) (6,10): the corner at
    // (2,2) turns right in the union (reflex), refused.
    assert!(theorem_ke(p1, p2, [2, 0], [2, 0], [-2, 4], [-2, 4]));
    assert!(!theorem_ke(p1, p2, [2, 0], [2, 0], [6, 10], [6, 10]));
    // F2 = (0,0) (2,2) (2,4): (2,0), (2,2), (2,4) collinear — S1 = P1,
    // a straight corner: accepted.
    assert!(theorem_ke(p1, p2, [2, 0], [2, 0], [2, 4], [2, 4]));
    // Just past collinear, (3,4): reflex at P1, refused.
    assert!(!theorem_ke(p1, p2, [2, 0], [2, 0], [3, 4], [3, 4]));
    // Both faces on the line of E (a spike): refused.
    assert!(!theorem_ke(
        [2, 0],
        [0, 0],
        [4, 0],
        [-2, 0],
        [-2, 0],
        [4, 0]
    ));
    // The test's own convexity check catches the L it must refuse.
    assert!(!is_convex(&[[0, 0], [2, 0], [2, 2], [6, 10]]));
    assert!(is_convex(&[[0, 0], [2, 0], [2, 2], [-2, 4]]));
    assert!(is_convex(&[[0, 0], [2, 0], [2, 2], [2, 4], [0, 2]]));
}

#[test]
fn theorem_ke_is_convexity_of_both_corners() {
    // Seeded random convex pairs: triangle F1 = P1 P2 A (left of P1→P2)
    // and F2 = P2 P1 B (right of it); KE must say whether their union
    // P1 B P2 A is convex at P1 and at P2 (orientation tests).
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut rnd = |m: i64| {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s % (2 * m as u64 + 1)) as i64 - m
    };
    let (mut yes, mut no) = (0, 0);
    for _ in 0..20_000 {
        let (p1, p2) = ([rnd(4), rnd(4)], [rnd(4), rnd(4)]);
        let (a, b) = ([rnd(6), rnd(6)], [rnd(6), rnd(6)]);
        if p1 == p2 || orient(p1, p2, a) <= 0 || orient(p2, p1, b) <= 0 {
            continue;
        }
        // Union cycle: P1 → B → P2 → A; convex at P1: A → P1 → B,
        // at P2: B → P2 → A (collinear counts as convex).
        let convex = orient(a, p1, b) >= 0 && orient(b, p2, a) >= 0;
        assert_eq!(
            theorem_ke(p1, p2, a, a, b, b),
            convex,
            "P1 {p1:?} P2 {p2:?} A {a:?} B {b:?}"
        );
        if convex { yes += 1 } else { no += 1 }
    }
    assert!(yes > 1000 && no > 1000, "{yes} {no}");
}

fn print_counts(m: &chisel::polyhedron::MergedSurface, what: &str) {
    println!(
        "{what}: {} merged faces ({} split), {} convex, {} triangles",
        m.n_faces(),
        m.n_faces_split(),
        m.n_convex_faces(),
        m.triangles.len()
    );
}

#[test]
fn cylinders_torus_and_dent_split_into_convex_faces() {
    for (d_o, d_i) in [(25, 10), (50, 35), (75, 60), (100, 85)] {
        let o = object(&cylinder_tunnel(d_o, d_i, 15).unwrap());
        let m = run(&o).merged_surface().unwrap();
        let what = format!("cylinder {d_o}/{d_i}");
        assert_convex_tiling(&m, &what);
        print_counts(&m, &what);
        // The side faces are convex already; each cap (a ring around a
        // convex hole) needs at least three convex pieces: each lies in a
        // half-plane missing the hole, and two such half-planes leave part
        // of the ring next to the hole uncovered.
        assert!(m.n_convex_faces() >= m.n_faces_split() + 2 * 2, "{what}");
        assert!(
            m.n_convex_faces() < m.triangles.len(),
            "{what}: merges happen"
        );
    }
    for (what, v) in [
        ("torus", torus(40, 12).unwrap()),
        ("dented ellipsoid", ellipsoid_dent(13, 13, 8, 5).unwrap()),
    ] {
        let m = run(&object(&v)).merged_surface().unwrap();
        assert_convex_tiling(&m, what);
        print_counts(&m, what);
    }
}

/// Planes `(normal, offset)` with canonical sign: first non-zero normal
/// component positive.
type Planes = std::collections::HashSet<([i64; 3], i64)>;

/// The plane `normal · x = offset` with canonical sign.
fn canon(n: [i64; 3], d: i64) -> ([i64; 3], i64) {
    let s = if n.iter().find(|&&c| c != 0).is_some_and(|&c| c > 0) {
        1
    } else {
        -1
    };
    (n.map(|c| c * s), d * s)
}

/// Per 3-D shell, its depth and the unoriented planes of its hull's faces.
fn shell_planes(p: &Polyhedron) -> Vec<(u32, Planes)> {
    (p.shells.iter())
        .filter_map(|s| {
            let h = s.geometry.polytope().filter(|h| !h.is_planar())?;
            let planes = (h.faces().iter())
                .map(|f| canon(f.plane.normal, f.plane.offset))
                .collect();
            Some((s.depth, planes))
        })
        .collect()
}

/// Checks `face_depth` and `triangle_faces` against the shells: every
/// triangle lies on its face's plane, and a face's depth is that of a
/// shell with a hull face on the same plane.
fn assert_face_depths(p: &Polyhedron, m: &MergedSurface, what: &str) {
    assert_eq!(m.face_depth.len(), m.faces.len(), "{what}");
    assert_eq!(m.triangle_faces.len(), m.triangles.len(), "{what}");
    for (t, &f) in m.triangles.iter().zip(&m.triangle_faces) {
        let face = &m.faces[f as usize];
        for &v in t {
            let q = m.vertices[v as usize];
            let dot: i64 = (0..3).map(|k| face.normal[k] * q[k]).sum();
            assert_eq!(dot, face.offset, "{what}: triangle {t:?} off face {f}");
        }
    }
    let planes = shell_planes(p);
    for (f, face) in m.faces.iter().enumerate() {
        let key = canon(face.normal, face.offset);
        let depth = m.face_depth[f];
        assert!(
            planes
                .iter()
                .any(|(d, ps)| *d == depth && ps.contains(&key)),
            "{what}: face {f} has depth {depth} but no shell of that depth has a face on its plane"
        );
    }
}

#[test]
fn merged_faces_carry_the_depth_of_the_shell_covering_them() {
    for (d_o, d_i) in [(25, 10), (50, 35)] {
        let what = format!("cylinder {d_o}/{d_i}");
        let o = object(&cylinder_tunnel(d_o, d_i, 15).unwrap());
        let p = run(&o);
        let m = p.merged_surface().unwrap();
        assert_face_depths(&p, &m, &what);
        // Combinatorial coordinates: the axis at the centre of the
        // vertices' box; tunnel walls within the inner radius (d_i voxels
        // across = d_i units of radius), outer walls at d_o.
        let (lo, hi) = m
            .vertices
            .iter()
            .fold(([i64::MAX; 2], [i64::MIN; 2]), |(lo, hi), v| {
                (
                    [lo[0].min(v[0]), lo[1].min(v[1])],
                    [hi[0].max(v[0]), hi[1].max(v[1])],
                )
            });
        let mid = (d_i + d_o) as i64 / 2;
        let (mut caps_with_deep_vertices, mut tunnel_faces) = (0, 0);
        for (f, face) in m.faces.iter().enumerate() {
            let vs: Vec<u32> = face.loops.iter().flatten().copied().collect();
            let depth = m.face_depth[f];
            if face.normal[0] == 0 && face.normal[1] == 0 {
                // A cap: the hull's ring around the tunnel, depth 0, even
                // though its inner loop runs through the tunnel's vertices.
                assert_eq!(depth, 0, "{what}: cap {f}");
                caps_with_deep_vertices +=
                    usize::from(vs.iter().any(|&v| m.vertex_depth[v as usize] == 1));
            } else {
                let inner = vs.iter().all(|&v| {
                    let q = m.vertices[v as usize];
                    let (x, y) = (2 * q[0] - lo[0] - hi[0], 2 * q[1] - lo[1] - hi[1]);
                    x * x + y * y < 4 * mid * mid
                });
                assert_eq!(depth, u32::from(inner), "{what}: side face {f}");
                tunnel_faces += usize::from(inner);
            }
        }
        assert_eq!(caps_with_deep_vertices, 2, "{what}");
        assert!(tunnel_faces >= 8, "{what}: {tunnel_faces} tunnel faces");
        // The picture mesh: three own vertices per triangle, its face's depth.
        let mesh = m.to_face_mesh(&p.frame).unwrap();
        assert_eq!(mesh.positions.len(), 3 * m.triangles.len());
        let depth = mesh.scalar("depth").unwrap();
        for (t, &f) in m.triangle_faces.iter().enumerate() {
            let want = m.face_depth[f as usize] as f32;
            assert_eq!(
                depth.values[3 * t..3 * t + 3],
                [want; 3],
                "{what}: triangle {t}"
            );
        }
    }
}

#[test]
fn convex_faces_of_random_carvings_and_a_cavity_tile_their_faces() {
    let o = common::carved(11, |x, y, z| [x, y, z].iter().all(|c| (5..=7).contains(c)));
    let p = run(&o);
    let m = p.merged_surface().unwrap();
    assert_convex_tiling(&m, "cube with cavity");
    assert_face_depths(&p, &m, "cube with cavity");
    assert_eq!(m.face_depth.iter().filter(|&&d| d == 1).count(), 6);
    // Every face of a box and of its cavity is a rectangle: one piece each.
    assert_eq!(m.n_convex_faces(), 12);
    let mut checked = 0;
    for (round, o) in common::random_carvings().into_iter().enumerate() {
        for (name, p) in [("recursion", run(&o)), ("balls", run_balls(&o))] {
            if let Ok(m) = p.merged_surface() {
                assert_convex_tiling(&m, &format!("random carving {round}, {name}"));
                assert_face_depths(&p, &m, &format!("random carving {round}, {name}"));
                checked += 1;
            }
        }
    }
    assert!(checked >= 20, "{checked}");
}

#[test]
fn a_tiling_check_catches_a_non_convex_or_missing_piece() {
    // Negative controls for the checker above: merging two convex faces
    // of the cylinder cap by hand (without KE) or dropping one must fail.
    let o = object(&cylinder_tunnel(25, 10, 15).unwrap());
    let m = run(&o).merged_surface().unwrap();
    let mut dropped = m.clone();
    dropped.convex_faces.pop();
    assert!(std::panic::catch_unwind(|| assert_convex_tiling(&dropped, "dropped")).is_err());
    let mut grown = m.clone();
    // A convex face given an extra vertex: the next loop vertex of its
    // face that it does not already use makes it non-convex or breaks the
    // tiling.
    let c = &mut grown.convex_faces[0];
    let f = &m.faces[c.face as usize];
    let extra = f.loops[0].iter().copied().find(|v| !c.vertices.contains(v));
    c.vertices.insert(1, extra.unwrap());
    assert!(std::panic::catch_unwind(|| assert_convex_tiling(&grown, "grown")).is_err());
}

#[test]
fn ray_parity_equals_voxelize_on_seed_objects() {
    for (d_o, d_i, stride) in [(25, 10, 1), (50, 35, 13), (75, 60, 29), (100, 85, 53)] {
        let o = object(&cylinder_tunnel(d_o, d_i, 15).unwrap());
        let sides = assert_ray_parity(&run(&o), &o, stride, &format!("cylinder {d_o}/{d_i}"));
        assert!(sides.contains(&Side::On) && sides.contains(&Side::Inside));
    }
    let o = object(&torus(40, 12).unwrap());
    assert_ray_parity(&run(&o), &o, 17, "torus");
    assert_ray_parity(&run_balls(&o), &o, 17, "torus, balls");
    let o = object(&ellipsoid_dent(13, 13, 8, 5).unwrap());
    assert_ray_parity(&run(&o), &o, 1, "dented ellipsoid");
}

#[test]
fn ray_parity_equals_voxelize_with_cavities_islands_and_carvings() {
    // A cavity holding one object voxel (a point label, no surface): the
    // ray parity says inside, the stored label says object.
    let o = common::carved(11, |x, y, z| {
        let c = |a: usize| (5..=7).contains(&a);
        c(x) && c(y) && c(z) && (x, y, z) != (6, 6, 6)
    });
    let p = run(&o);
    let sides = assert_ray_parity(&p, &o, 1, "cavity with island");
    let b = margin_box(&o);
    let island = (6 - b.origin[0]) as usize * (1 + b.dims[0] + b.dims[0] * b.dims[1]);
    assert_eq!(
        sides[island],
        Side::Outside,
        "the island is inside the cavity"
    );
    let (mut on_object, mut on_background) = (0, 0);
    for (round, o) in common::random_carvings().into_iter().enumerate() {
        for (name, p) in [("recursion", run(&o)), ("balls", run_balls(&o))] {
            if !p.summary().volume_exact {
                continue;
            }
            let what = format!("random carving {round}, {name}");
            let sides = assert_ray_parity(&p, &o, 1, &what);
            let b = margin_box(&o);
            let [nx, ny, _] = b.dims;
            for (k, s) in sides.iter().enumerate() {
                if *s == Side::On {
                    let v = [k % nx, k / nx % ny, k / (nx * ny)];
                    let v: [i64; 3] = std::array::from_fn(|a| b.origin[a] + v[a] as i64);
                    if o.contains(v) {
                        on_object += 1
                    } else {
                        on_background += 1
                    }
                }
            }
        }
    }
    // Both kinds of voxel centres lie on the surface: "on" alone decides
    // nothing, the stored labels are needed.
    println!("on the surface: {on_object} object, {on_background} background voxels");
    assert!(on_object > 0 && on_background > 0);
}

#[test]
fn ray_parity_detects_a_missing_triangle() {
    // Negative control: one triangle dropped from the surface changes the
    // parity of the columns under it.
    let o = object(&cylinder_tunnel(25, 10, 15).unwrap());
    let p = run(&o);
    let m = p.merged_surface().unwrap();
    assert_eq!(
        p.mismatches_ray_parity(&m, &o, Backend::Cpu, 1).unwrap().0,
        0
    );
    let mut broken = m.clone();
    // The largest triangle whose projection to xy has area (a cap piece).
    let area = |t: &[u32; 3]| {
        let q = t.map(|v| {
            let p = m.vertices[v as usize];
            [p[0], p[1]]
        });
        orient(q[0], q[1], q[2]).abs()
    };
    let k = (0..m.triangles.len())
        .max_by_key(|&k| area(&m.triangles[k]))
        .unwrap();
    broken.triangles.remove(k);
    let (n, _) = p
        .mismatches_ray_parity(&broken, &o, Backend::Cpu, 1)
        .unwrap();
    assert!(n > 0, "a missing cap triangle must show");
    // And the single-point rays see it too, for a centre under the
    // triangle's centroid column.
    let b = margin_box(&o);
    let differs = (0..b.n_voxels().unwrap()).any(|k| {
        let [nx, ny, _] = b.dims;
        let c = b.centre([k % nx, k / nx % ny, k / (nx * ny)]);
        m.side_of(c, 2).unwrap() != broken.side_of(c, 2).unwrap()
    });
    assert!(differs);
}

#[test]
fn ray_parity_refuses_out_of_range_input() {
    let o = object(&cylinder_tunnel(25, 10, 15).unwrap());
    let m = run(&o).merged_surface().unwrap();
    let far = VoxelBox {
        origin: [1 << 30, 0, 0],
        dims: [2, 2, 2],
    };
    let refused = |e: chisel::Error, param: &str| {
        assert!(
            matches!(&e, chisel::Error::InvalidParameter { name, .. } if name == param),
            "{param}: {e:?}"
        )
    };
    refused(m.classify(&far).unwrap_err(), "ray parity: box");
    refused(m.side_of([1, 1, 1], 3).unwrap_err(), "ray parity: axis");
    refused(
        m.side_of([1 << 40, 1, 1], 0).unwrap_err(),
        "ray parity: point",
    );
}

#[test]
fn real_ct_bone_convex_faces_and_ray_parity() {
    let Some(o) = common::ct_bone() else {
        return;
    };
    let p = run(&o);
    let m = p.merged_surface().unwrap();
    assert_convex_tiling(&m, "headsq bone");
    assert_face_depths(&p, &m, "headsq bone");
    eprintln!(
        "headsq bone: {} merged faces ({} split), {} convex, {} triangles",
        m.n_faces(),
        m.n_faces_split(),
        m.n_convex_faces(),
        m.triangles.len()
    );
    assert_ray_parity(&p, &o, 997, "headsq bone");
}

#[test]
fn cli_verify_reports_ray_parity() {
    let bin = env!("CARGO_BIN_EXE_chisel");
    let tmp = tempfile::tempdir().unwrap();
    let cyl = tmp.path().join("cyl.nrrd");
    let cyl = cyl.to_str().unwrap();
    let out = common::run_chisel(
        bin,
        &[
            "phantom",
            "cylinder-tunnel",
            "--outer",
            "25",
            "--inner",
            "10",
            "-o",
            cyl,
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let run = |verify: bool| {
        let mut args = vec!["polyhedrize", cyl, "--level", "1", "--json"];
        if verify {
            args.push("--verify");
        }
        let out = common::run_chisel(bin, &args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()
    };
    let v = run(true);
    assert_eq!(v["verify_ray_parity_mismatches"], 0);
    assert!(v["timings_s"]["verify_ray_parity"].as_f64().is_some());
    assert_eq!(v["merged_convex_faces"], 52);
    // Without --verify neither is there.
    let v = run(false);
    assert!(v["verify_ray_parity_mismatches"].is_null());
    assert!(v["timings_s"].get("verify_ray_parity").is_none());
}

#[test]
fn ray_parity_labels_on_the_gpu_match_the_cpu() {
    // The shell-tree labels use the hull-scan row spans; on the GPU
    // backend they must give the same voxelization.
    let Some(gpu) = common::gpu() else {
        return;
    };
    let o = object(&cylinder_tunnel(25, 10, 15).unwrap());
    let carving = common::random_carvings().swap_remove(0);
    for (what, o) in [("cylinder 25/10", o), ("random carving 0", carving)] {
        let p = run(&o);
        let Ok(m) = p.merged_surface() else {
            continue;
        };
        let b = margin_box(&o);
        let cpu = p.voxelize_ray_parity(&m, &b, Backend::Cpu).unwrap();
        let on_gpu = p.voxelize_ray_parity(&m, &b, Backend::Gpu(gpu)).unwrap();
        assert_eq!(cpu, on_gpu, "{what}");
        assert_eq!(
            p.mismatches_ray_parity(&m, &o, Backend::Gpu(gpu), 1)
                .unwrap()
                .0,
            0
        );
    }
}
