//! Exact self-intersection test of a triangle mesh.
//!
//! Two triangles *intersect* when their closed point sets meet anywhere
//! beyond what their shared vertex indices imply: nothing for disjoint index
//! sets, the vertex for one shared index, the edge for two; a triangle
//! repeating another's three indices (either winding) always does. Touching
//! counts (a vertex on another triangle, coplanar overlap, a fold over a
//! shared edge); vertices at equal positions under different indices touch.
//!
//! Every decision is a sign of Shewchuk's adaptive exact `orient3d` /
//! `orient2d` (crate `robust`) on the f32 coordinates widened to f64, so
//! there is no tolerance. Coplanar pairs are decided in the coordinate plane
//! where the triangle's projected area (exact) is largest. Triangles of
//! exactly zero area (collinear or coincident corners, repeated indices)
//! take no part; they are counted apart.
//!
//! Broad phase: the mesh's bounding-box forest ([`Forest::from_triangles`]); each
//! triangle is tested against the later triangles of the leaves its box
//! meets whose own boxes meet it too.

use rayon::prelude::*;
use robust::Coord;

use super::TriMesh;
use crate::foundation::exact::orient3d_sign as o3;
use crate::foundation::{Aabb, Forest};

/// Result of [`self_intersections`].
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct SelfIntersections {
    /// Intersecting triangle pairs `[i, j]`, `i < j`, ascending.
    pub pairs: Vec<[u32; 2]>,
    /// Triangles of exactly zero area (left out of the pair tests).
    pub degenerate: Vec<u32>,
}

/// All intersecting triangle pairs of `mesh`, exactly (see module docs).
pub fn self_intersections(mesh: &TriMesh) -> SelfIntersections {
    intersections_of_first(mesh, mesh.triangles.len())
}

/// [`self_intersections`] restricted to the pairs `[i, j]` with `i < n`:
/// the first `n` triangles (a part being checked) against each other and
/// against the rest. Only those `n` query the broad phase.
pub fn intersections_of_first(mesh: &TriMesh, n: usize) -> SelfIntersections {
    let p: Vec<[f64; 3]> = mesh
        .positions
        .iter()
        .map(|v| v.as_dvec3().to_array())
        .collect();
    let planes: Vec<Option<Plane>> = mesh
        .triangles
        .par_iter()
        .map(|t| Plane::of(t.map(|v| p[v as usize])))
        .collect();
    let degenerate: Vec<u32> = (0..planes.len() as u32)
        .filter(|&t| planes[t as usize].is_none())
        .collect();
    let forest = Forest::from_triangles(mesh.view()).forest;
    let tri_box = |t: usize| {
        let [a, b, c] = mesh.triangles[t].map(|v| mesh.positions[v as usize]);
        Aabb::triangle(a, b, c)
    };
    let (p, planes) = (&p, &planes);
    let mut pairs: Vec<[u32; 2]> = (0..n.min(mesh.triangles.len()))
        .into_par_iter()
        .filter(|&i| planes[i].is_some())
        .map_init(Vec::new, |candidates, i| {
            let (bi, ti, pi) = (tri_box(i), mesh.triangles[i], planes[i].expect("filtered"));
            candidates.clear();
            forest.overlapping(&bi, candidates);
            let later = candidates.iter().filter(|&&j| j as usize > i);
            later
                .filter_map(|&j| {
                    let pj = planes[j as usize]?;
                    let hit = bi.overlaps(&tri_box(j as usize))
                        && intersect(ti, mesh.triangles[j as usize], p, pi, pj);
                    hit.then_some([i as u32, j])
                })
                .collect::<Vec<_>>()
        })
        .flatten_iter()
        .collect();
    pairs.par_sort_unstable();
    SelfIntersections { pairs, degenerate }
}

fn sign(v: f64) -> i8 {
    if v > 0.0 {
        1
    } else if v < 0.0 {
        -1
    } else {
        0
    }
}

/// A triangle's supporting plane, as the coordinate plane to project on.
#[derive(Debug, Clone, Copy)]
struct Plane {
    /// Dropped axis: the one with the largest exact projected area.
    drop: usize,
}

impl Plane {
    /// `None` for a triangle of exactly zero area.
    fn of(t: [[f64; 3]; 3]) -> Option<Plane> {
        let areas = [0, 1, 2]
            .map(|drop| robust::orient2d(to2(t[0], drop), to2(t[1], drop), to2(t[2], drop)).abs());
        let drop = (0..3).max_by(|&a, &b| areas[a].total_cmp(&areas[b]))?;
        (areas[drop] > 0.0).then_some(Plane { drop })
    }
}

fn to2(v: [f64; 3], drop: usize) -> Coord<f64> {
    let (u, w) = ((drop + 1) % 3, (drop + 2) % 3);
    Coord { x: v[u], y: v[w] }
}

/// Exact orientation of three points projected along `drop`.
fn o2(a: [f64; 3], b: [f64; 3], c: [f64; 3], drop: usize) -> i8 {
    sign(robust::orient2d(to2(a, drop), to2(b, drop), to2(c, drop)))
}

/// Whether closed segments `pq` and `ab` of one plane meet.
fn segments_meet(p: [f64; 3], q: [f64; 3], a: [f64; 3], b: [f64; 3], drop: usize) -> bool {
    let (d1, d2) = (o2(a, b, p, drop), o2(a, b, q, drop));
    let (d3, d4) = (o2(p, q, a, drop), o2(p, q, b, drop));
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    let on = |s: [f64; 3], e: [f64; 3], x: [f64; 3]| {
        (0..3).all(|k| x[k] >= s[k].min(e[k]) && x[k] <= s[k].max(e[k]))
    };
    (d1 == 0 && on(a, b, p))
        || (d2 == 0 && on(a, b, q))
        || (d3 == 0 && on(p, q, a))
        || (d4 == 0 && on(p, q, b))
}

/// Whether `x` lies in closed triangle `t` of the same plane.
fn in_triangle(x: [f64; 3], t: [[f64; 3]; 3], drop: usize) -> bool {
    let s = [0, 1, 2].map(|k| o2(t[k], t[(k + 1) % 3], x, drop));
    s.iter().all(|&v| v >= 0) || s.iter().all(|&v| v <= 0)
}

/// Whether closed segment `pq` meets closed triangle `t` (of plane `plane`).
fn segment_meets_triangle(p: [f64; 3], q: [f64; 3], t: [[f64; 3]; 3], plane: Plane) -> bool {
    let (sp, sq) = (o3(t[0], t[1], t[2], p), o3(t[0], t[1], t[2], q));
    if sp * sq > 0 {
        return false;
    }
    if sp == 0 && sq == 0 {
        let d = plane.drop;
        return in_triangle(p, t, d)
            || in_triangle(q, t, d)
            || (0..3).any(|k| segments_meet(p, q, t[k], t[(k + 1) % 3], d));
    }
    let s = [0, 1, 2].map(|k| o3(p, q, t[k], t[(k + 1) % 3]));
    s.iter().all(|&v| v >= 0) || s.iter().all(|&v| v <= 0)
}

/// Whether the ray from `v` through `x` (both in the plane of triangle
/// `(v, a, b)`) starts into the closed corner of that triangle at `v`.
fn in_corner(v: [f64; 3], a: [f64; 3], b: [f64; 3], x: [f64; 3], drop: usize) -> bool {
    let turn = o2(v, a, b, drop);
    o2(v, a, x, drop) * turn >= 0 && o2(v, x, b, drop) * turn >= 0
}

/// Necessary condition for [`intersect`], in 2-D only: whether the
/// projections along `drop` (the first triangle's plane, so its projection
/// is one-to-one) meet beyond the shared corners' images. A point where
/// the triangles meet projects into both, and onto the image of a shared
/// corner only if it is that corner. Most neighbouring pairs stop here,
/// before any (possibly adaptive) `orient3d`:
/// - no shared corner: unless a line through an edge of either separates
///   them (separating axis theorem for closed convex polygons);
/// - one shared corner `v`: each lies in its corner at `v` (and fills it
///   near `v`), so they cannot meet beyond `v` unless the corners do;
/// - a shared edge: they meet beyond it only folded flat, far corners on
///   one side.
fn projections_meet(a: [[f64; 3]; 3], b: [[f64; 3]; 3], shared: usize, drop: usize) -> bool {
    match shared {
        0 => !(separates(a, b, drop) || separates(b, a, drop)),
        1 => {
            let v = a[0];
            [a[1], a[2]]
                .iter()
                .any(|&x| in_corner(v, b[1], b[2], x, drop))
                || [b[1], b[2]]
                    .iter()
                    .any(|&x| in_corner(v, a[1], a[2], x, drop))
        }
        2 => o2(a[0], a[1], a[2], drop) * o2(a[0], a[1], b[2], drop) >= 0,
        _ => true,
    }
}

/// Whether the line through some edge of `t` has `u` strictly on one side
/// and `t` on the other, closed side (2-D along `drop`).
fn separates(t: [[f64; 3]; 3], u: [[f64; 3]; 3], drop: usize) -> bool {
    (0..3).any(|k| {
        let (p, q, r) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        let s = o2(p, q, u[0], drop);
        s != 0 && o2(p, q, u[1], drop) == s && o2(p, q, u[2], drop) == s && o2(p, q, r, drop) != s
    })
}

/// Whether triangles `ti`, `tj` (vertex indices into `p`) intersect beyond
/// their shared indices.
fn intersect(ti: [u32; 3], tj: [u32; 3], p: &[[f64; 3]], pi: Plane, pj: Plane) -> bool {
    let shared = ti.iter().filter(|v| tj.contains(v)).count();
    // Rotate each so the shared indices come first, in `ti`'s order.
    let lead = |t: [u32; 3], other: [u32; 3]| -> [u32; 3] {
        let r = (0..3)
            .find(|&k| (0..shared).all(|s| other.contains(&t[(k + s) % 3])))
            .expect("the shared indices are consecutive in a triangle");
        [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
    };
    let (ti, tj) = (lead(ti, tj), lead(tj, ti));
    let a = ti.map(|v| p[v as usize]);
    let b = tj.map(|v| p[v as usize]);
    if !projections_meet(a, b, shared, pi.drop) {
        return false;
    }
    match shared {
        0 => {
            (0..3).any(|k| segment_meets_triangle(a[k], a[(k + 1) % 3], b, pj))
                || (0..3).any(|k| segment_meets_triangle(b[k], b[(k + 1) % 3], a, pi))
        }
        1 => {
            // a[0] = b[0] = v. Beyond v: an opposite edge meets the other
            // triangle, or an edge from v runs into the other's corner at v.
            let v = a[0];
            segment_meets_triangle(a[1], a[2], b, pj)
                || segment_meets_triangle(b[1], b[2], a, pi)
                || [a[1], a[2]]
                    .iter()
                    .any(|&x| o3(b[0], b[1], b[2], x) == 0 && in_corner(v, b[1], b[2], x, pj.drop))
                || [b[1], b[2]]
                    .iter()
                    .any(|&x| o3(a[0], a[1], a[2], x) == 0 && in_corner(v, a[1], a[2], x, pi.drop))
        }
        2 => {
            // Shared edge: a fold when the far corners are coplanar and on
            // one side of it.
            let (u, w) = (a[0], a[1]);
            o3(a[0], a[1], a[2], b[2]) == 0 && o2(u, w, a[2], pi.drop) == o2(u, w, b[2], pi.drop)
        }
        _ => true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn mesh(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> TriMesh {
        TriMesh::new(
            positions.iter().map(|&p| Vec3::from(p)).collect(),
            triangles.to_vec(),
        )
        .unwrap()
    }

    #[test]
    fn crossing_triangles_are_found_and_a_tetrahedron_is_clean() {
        let crossing = mesh(
            &[
                [0., 0., 0.],
                [2., 0., 0.],
                [0., 2., 0.],
                [0.5, 0.5, -1.],
                [0.5, 0.5, 1.],
                [3., 3., 0.],
            ],
            &[[0, 1, 2], [3, 4, 5]],
        );
        assert_eq!(self_intersections(&crossing).pairs, vec![[0, 1]]);
        let tet = mesh(
            &[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]],
            &[[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        );
        assert_eq!(self_intersections(&tet), SelfIntersections::default());
    }

    #[test]
    fn touching_coplanar_folded_and_shared_vertex_cases() {
        // A vertex of one triangle on the other's face.
        let touch = mesh(
            &[
                [0., 0., 0.],
                [2., 0., 0.],
                [0., 2., 0.],
                [0.5, 0.5, 0.],
                [0.5, 0.5, 1.],
                [1., 0.5, 1.],
            ],
            &[[0, 1, 2], [3, 4, 5]],
        );
        assert_eq!(self_intersections(&touch).pairs, vec![[0, 1]]);
        // Coplanar overlap without shared vertices.
        let flat = mesh(
            &[
                [0., 0., 0.],
                [2., 0., 0.],
                [0., 2., 0.],
                [0.5, 0.5, 0.],
                [3., 0.5, 0.],
                [0.5, 3., 0.],
            ],
            &[[0, 1, 2], [3, 4, 5]],
        );
        assert_eq!(self_intersections(&flat).pairs, vec![[0, 1]]);
        // Two triangles folded onto each other over their shared edge, and
        // the same pair opened flat.
        let fold = mesh(
            &[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0.5, 2., 0.]],
            &[[0, 1, 2], [1, 0, 3]],
        );
        assert_eq!(self_intersections(&fold).pairs, vec![[0, 1]]);
        let open = mesh(
            &[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0.5, -2., 0.]],
            &[[0, 1, 2], [1, 0, 3]],
        );
        assert!(self_intersections(&open).pairs.is_empty());
        // Sharing one vertex: an edge running through the other triangle,
        // then a coplanar fan that overlaps, then one that does not.
        let pierce = mesh(
            &[
                [0., 0., 0.],
                [2., 0., 0.],
                [0., 2., 0.],
                [1., 1., -1.],
                [0.5, 0.5, 1.],
            ],
            &[[0, 1, 2], [0, 3, 4]],
        );
        assert_eq!(self_intersections(&pierce).pairs, vec![[0, 1]]);
        let fan = mesh(
            &[
                [0., 0., 0.],
                [2., 0., 0.],
                [0., 2., 0.],
                [2., 1., 0.],
                [1., 2., 0.],
            ],
            &[[0, 1, 2], [0, 3, 4]],
        );
        assert_eq!(self_intersections(&fan).pairs, vec![[0, 1]]);
        let apart = mesh(
            &[
                [0., 0., 0.],
                [2., 0., 0.],
                [1., 2., 0.],
                [-2., 0., 0.],
                [-1., 2., 0.],
            ],
            &[[0, 1, 2], [0, 4, 3]],
        );
        assert!(self_intersections(&apart).pairs.is_empty());
    }

    #[test]
    fn zero_area_triangles_are_set_apart() {
        let m = mesh(
            &[[0., 0., 0.], [1., 0., 0.], [2., 0., 0.], [0., 1., 0.]],
            &[[0, 1, 2], [0, 1, 3]],
        );
        let s = self_intersections(&m);
        assert_eq!(s.degenerate, vec![0]);
        assert!(s.pairs.is_empty());
    }

    /// Independent oracle for triangles without shared indices: closed
    /// triangles are disjoint iff one of the separating-axis candidates
    /// (normals, edge × edge, normal × edge for the coplanar case)
    /// separates their projections. Exact on integer coordinates.
    fn sat_meet(a: [[i64; 3]; 3], b: [[i64; 3]; 3]) -> bool {
        let sub = |p: [i64; 3], q: [i64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
        let cross = |u: [i64; 3], v: [i64; 3]| {
            [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ]
        };
        let dot = |u: [i64; 3], v: [i64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
        let edges = |t: [[i64; 3]; 3]| [0, 1, 2].map(|k| sub(t[(k + 1) % 3], t[k]));
        let (ea, eb) = (edges(a), edges(b));
        let (na, nb) = (cross(ea[0], ea[1]), cross(eb[0], eb[1]));
        let mut axes = vec![na, nb];
        for (&e, &f) in ea.iter().zip(&eb) {
            axes.push(cross(na, e));
            axes.push(cross(nb, f));
            axes.extend(eb.map(|g| cross(e, g)));
        }
        !axes.iter().any(|&ax| {
            let pa = a.map(|p| dot(p, ax));
            let pb = b.map(|p| dot(p, ax));
            let (amin, amax) = (*pa.iter().min().unwrap(), *pa.iter().max().unwrap());
            let (bmin, bmax) = (*pb.iter().min().unwrap(), *pb.iter().max().unwrap());
            amax < bmin || bmax < amin
        })
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]
        /// A tiny grid makes coplanar, touching and coincident cases common.
        #[test]
        fn pairs_equal_a_separating_axis_oracle(
            raw in proptest::collection::vec((0i64..4, 0i64..4, 0i64..4), 6..36)
        ) {
            let n = raw.len() / 3 * 3;
            let pts: Vec<[i64; 3]> = raw[..n].iter().map(|&(x, y, z)| [x, y, z]).collect();
            let triangles: Vec<[u32; 3]> = (0..n as u32 / 3).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
            let m = mesh(&pts.iter().map(|p| p.map(|c| c as f32)).collect::<Vec<_>>(), &triangles);
            let got = self_intersections(&m);
            let corners = |t: usize| [pts[3 * t], pts[3 * t + 1], pts[3 * t + 2]];
            let flat = |t: usize| {
                let [a, b, c] = corners(t);
                let (u, v) = ([b[0] - a[0], b[1] - a[1], b[2] - a[2]], [c[0] - a[0], c[1] - a[1], c[2] - a[2]]);
                [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]] == [0; 3]
            };
            let degenerate: Vec<u32> = (0..triangles.len()).filter(|&t| flat(t)).map(|t| t as u32).collect();
            proptest::prop_assert_eq!(&got.degenerate, &degenerate);
            let mut want = Vec::new();
            for i in 0..triangles.len() {
                for j in i + 1..triangles.len() {
                    if !flat(i) && !flat(j) && sat_meet(corners(i), corners(j)) {
                        want.push([i as u32, j as u32]);
                    }
                }
            }
            proptest::prop_assert_eq!(got.pairs, want);
        }
    }

    use crate::foundation::exact::{P3 as P, cross, dot, sub};

    /// Whether the origin lies in the convex hull of `pts` (nonzero
    /// points): in a segment, triangle or tetrahedron of them (Carathéodory).
    fn origin_in_hull(pts: &[P]) -> bool {
        let n = pts.len();
        let in_segment = |p: P, q: P| cross(p, q) == [0; 3] && dot(p, q) < 0;
        let in_triangle = |p: P, q: P, r: P| {
            let nrm = cross(sub(q, p), sub(r, p));
            nrm != [0; 3]
                && dot(nrm, p) == 0
                && [(p, q), (q, r), (r, p)]
                    .iter()
                    .all(|&(x, y)| dot(nrm, cross(sub(y, x), sub([0; 3], x))) >= 0)
        };
        let in_tetra = |t: [P; 4]| {
            let vol = |a: P, b: P, c: P, d: P| dot(cross(sub(b, a), sub(c, a)), sub(d, a));
            let whole = vol(t[0], t[1], t[2], t[3]);
            let o = [0; 3];
            let parts = [
                vol(o, t[1], t[2], t[3]),
                vol(t[0], o, t[2], t[3]),
                vol(t[0], t[1], o, t[3]),
                vol(t[0], t[1], t[2], o),
            ];
            whole != 0 && parts.iter().all(|&v| v * whole.signum() >= 0)
        };
        (0..n).any(|i| (i + 1..n).any(|j| in_segment(pts[i], pts[j])))
            || (0..n).any(|i| {
                (i + 1..n).any(|j| (j + 1..n).any(|k| in_triangle(pts[i], pts[j], pts[k])))
            })
            || (n == 4 && in_tetra([pts[0], pts[1], pts[2], pts[3]]))
    }

    fn is_flat(a: P, b: P, c: P) -> bool {
        cross(sub(b, a), sub(c, a)) == [0; 3]
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2048))]
        /// Triangles sharing a vertex `v` meet beyond it iff their corners at
        /// `v` share a ray: iff the origin is in the hull of a − v and v − b
        /// over the other corners (Gordan). Sharing an edge, they meet beyond
        /// it iff folded flat onto one side.
        #[test]
        fn shared_vertex_and_edge_pairs_equal_cone_oracles(
            raw in proptest::collection::vec((-2i64..3, -2i64..3, -2i64..3), 5)
        ) {
            let q: Vec<P> = raw.iter().map(|&(x, y, z)| [x, y, z]).collect();
            let f32s: Vec<[f32; 3]> = q.iter().map(|p| p.map(|c| c as f32)).collect();
            // One shared vertex: (0, 1, 2) and (0, 3, 4).
            if !is_flat(q[0], q[1], q[2]) && !is_flat(q[0], q[3], q[4]) {
                let m = mesh(&f32s, &[[0, 1, 2], [0, 3, 4]]);
                let d = |i: usize| sub(q[i], q[0]);
                let neg = |p: P| p.map(|c| -c);
                let want = origin_in_hull(&[d(1), d(2), neg(d(3)), neg(d(4))]);
                proptest::prop_assert_eq!(self_intersections(&m).pairs.len() == 1, want);
            }
            // One shared edge: (0, 1, 2) and (1, 0, 3).
            if !is_flat(q[0], q[1], q[2]) && !is_flat(q[0], q[1], q[3]) {
                let m = mesh(&f32s, &[[0, 1, 2], [1, 0, 3]]);
                let e = sub(q[1], q[0]);
                let (n2, n3) = (cross(e, sub(q[2], q[0])), cross(e, sub(q[3], q[0])));
                let want = cross(n2, n3) == [0; 3] && dot(n2, n3) > 0;
                proptest::prop_assert_eq!(self_intersections(&m).pairs.len() == 1, want);
            }
        }
    }
}
