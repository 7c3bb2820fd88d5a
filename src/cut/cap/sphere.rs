//! Sphere caps: take a cap triangulated in the stereographic plane (its
//! [`Projection`], 2-D and 3-D points) and return it refined on the sphere
//! to the chord bound, then repaired where it crosses the cut surface
//! ([`CutSurface`]), for at most [`CAP_REPAIR_ROUNDS`] rounds.

use std::collections::HashMap;

use glam::{DVec2, DVec3, Vec3};
use rayon::prelude::*;

use super::Projection;
use crate::TriMesh;
use crate::cut::Located;
use crate::cut::knife::SPHERE_CHORD_ERROR;
use crate::cut::regroup::Sub;
use crate::foundation::{Aabb, Forest};

/// Longest interior cap edge on a sphere of radius `r`: the sagitta of a
/// chord of length L is `r − √(r² − L²/4) ≈ L²/(8r)`, so `L = r·√(8ε)`.
pub fn sphere_max_edge(r: f64) -> f64 {
    r * (8.0 * SPHERE_CHORD_ERROR).sqrt()
}

/// Interior cap edges may be this many times the longest loop edge: a
/// triangle on a loop edge keeps an interior edge about as long as it.
const LOOP_EDGE_FACTOR: f64 = 1.2;

/// Refinement passes at most (each halves the longest edges; the rest are
/// triangles on loop edges that bisection cannot shorten).
const MAX_PASSES: usize = 48;

/// Per edge of `tris` (key: sorted vertex pair) its first two triangles and
/// its use count.
type EdgeUses = HashMap<(usize, usize), ([usize; 2], u32)>;

fn edge_key(a: usize, b: usize) -> (usize, usize) {
    (a.min(b), a.max(b))
}

fn edge_uses(tris: &[[usize; 3]]) -> EdgeUses {
    let mut uses: EdgeUses = HashMap::with_capacity(3 * tris.len());
    for (t, tri) in tris.iter().enumerate() {
        for e in 0..3 {
            let slot = uses
                .entry(edge_key(tri[e], tri[(e + 1) % 3]))
                .or_insert(([usize::MAX; 2], 0));
            if slot.1 < 2 {
                slot.0[slot.1 as usize] = t;
            }
            slot.1 += 1;
        }
    }
    uses
}

/// Refines cap triangles `tris` (indices into `pts`, their images in the
/// stereographic plane of `proj`, and `pos`, the points on the sphere):
/// every edge used by two triangles and longer than `max_edge` in space
/// and than [`LOOP_EDGE_FACTOR`] times the longest edge used once, is
/// bisected, longest first, at the point of the sphere over its planar
/// midpoint (appended to both); edges used once (the cut loops) are kept.
/// Before the first pass and after each, `delaunay_flips` makes the
/// interior edges Delaunay in the plane. The projection is conformal and
/// keeps orientation, so the refined triangles keep theirs. Stops after `max_triangles` or [`MAX_PASSES`].
pub fn refine_on_sphere(
    tris: &mut Vec<[usize; 3]>,
    pts: &mut Vec<DVec2>,
    pos: &mut Vec<DVec3>,
    proj: &Projection,
    max_edge: f64,
    max_triangles: usize,
) {
    let mut max_edge = max_edge;
    delaunay_flips(tris, pts);
    for _ in 0..MAX_PASSES {
        let uses = edge_uses(tris);
        let longest_loop_edge = uses
            .iter()
            .filter(|(_, (_, n))| *n == 1)
            .map(|(k, _)| (pos[k.0] - pos[k.1]).length())
            .fold(0.0, f64::max);
        max_edge = max_edge.max(LOOP_EDGE_FACTOR * longest_loop_edge);
        let long: Vec<(f64, (usize, usize), [usize; 2])> = uses
            .iter()
            .filter(|(_, (_, n))| *n == 2)
            .map(|(&k, &(ts, _))| ((pos[k.0] - pos[k.1]).length(), k, ts))
            .filter(|(l, _, _)| *l > max_edge)
            .collect();
        if long.is_empty() || tris.len() >= max_triangles {
            return;
        }
        if bisect(tris, pts, pos, proj, long, max_triangles).is_empty() {
            return;
        }
        delaunay_flips(tris, pts);
    }
}

/// A plane point for the exact predicates of `robust`.
fn coord(p: DVec2) -> robust::Coord<f64> {
    robust::Coord { x: p.x, y: p.y }
}

/// Makes the interior edges of `tris` locally Delaunay in the plane of
/// `pts` (Lawson flips, exact incircle test; edges used once are kept):
/// after a bisection pass this replaces the slivers between loop points and
/// the new midpoints by well-shaped triangles, so the next pass splits far
/// fewer edges. The projection is conformal, so shapes in the plane are
/// shapes on the sphere; each flip keeps both triangles' orientation (an
/// edge that fails the test has a convex quadrilateral).
fn delaunay_flips(tris: &mut [[usize; 3]], pts: &[DVec2]) {
    let mut uses = edge_uses(tris);
    let mut stack: Vec<(usize, usize)> = uses
        .iter()
        .filter(|(_, (_, n))| *n == 2)
        .map(|(&k, _)| k)
        .collect();
    stack.sort_unstable();
    // (p, q, c): the edge as it runs in triangle t and t's third corner.
    let around = |tri: [usize; 3], k: (usize, usize)| {
        (0..3)
            .map(|e| (tri[e], tri[(e + 1) % 3], tri[(e + 2) % 3]))
            .find(|&(p, q, _)| edge_key(p, q) == k)
    };
    while let Some(k) = stack.pop() {
        let Some(&([t0, t1], 2)) = uses.get(&k) else {
            continue;
        };
        let (Some((p, q, c)), Some((q1, p1, d))) = (around(tris[t0], k), around(tris[t1], k))
        else {
            continue;
        };
        if (p1, q1) != (p, q) || c == d {
            continue;
        }
        let turn = robust::orient2d(coord(pts[p]), coord(pts[q]), coord(pts[c]));
        let inside = robust::incircle(coord(pts[p]), coord(pts[q]), coord(pts[c]), coord(pts[d]));
        if turn == 0.0 || inside * turn <= 0.0 || uses.contains_key(&edge_key(c, d)) {
            continue;
        }
        tris[t0] = [c, p, d];
        tris[t1] = [d, q, c];
        uses.remove(&k);
        uses.insert(edge_key(c, d), ([t0, t1], 2));
        for (e, from, to) in [(edge_key(q, c), t0, t1), (edge_key(p, d), t1, t0)] {
            if let Some((ts, _)) = uses.get_mut(&e) {
                ts.iter_mut().filter(|t| **t == from).for_each(|t| *t = to);
            }
        }
        stack.extend([
            edge_key(c, p),
            edge_key(p, d),
            edge_key(d, q),
            edge_key(q, c),
        ]);
    }
}

/// Rounds of [`repair_on_sphere`] without fewer crossings before it stops.
pub const STALLED_ROUNDS: usize = 3;

/// What [`repair_on_sphere`] asks about the cut surface: per cap triangle
/// `tris[check[k]]` (corners in `pos`), the number of surface and cap
/// triangles it meets beyond shared vertices.
pub trait CapCheck {
    fn crossings(&mut self, tris: &[[usize; 3]], check: &[usize], pos: &[DVec3]) -> Vec<u32>;
}

/// Repairs a refined sphere cap where it crosses the surface: a surface
/// meeting the sphere at a grazing angle runs just inside it, closer than
/// a cap chord sags. Each round bisects, in every cap triangle that
/// crosses, its longest interior edge as [`refine_on_sphere`] does, and
/// counts again the triangles it changed. A new point can also land in the
/// thin band between a loop edge's chord and the sphere where the surface
/// runs outside the sphere, and cross it there, so the rounds can make
/// things worse (and a surface lying on the sphere to f32 precision only
/// touches more cap triangles the finer they get): the cap with the fewest
/// crossings seen is kept. Stops when nothing crosses, nothing can be
/// split, after [`STALLED_ROUNDS`] rounds without a new best, or after
/// `max_rounds`; returns the rounds made and the crossings left (summed
/// over the cap triangles: a pair of cap triangles counts twice).
pub fn repair_on_sphere(
    tris: &mut Vec<[usize; 3]>,
    pts: &mut Vec<DVec2>,
    pos: &mut Vec<DVec3>,
    proj: &Projection,
    max_triangles: usize,
    max_rounds: usize,
    surface: &mut impl CapCheck,
) -> (usize, u64) {
    let all: Vec<usize> = (0..tris.len()).collect();
    let mut count = surface.crossings(tris, &all, pos);
    let total = |count: &[u32]| count.iter().map(|&c| c as u64).sum::<u64>();
    // Points are only appended: a cap is its triangles and point count.
    let mut best = (total(&count), tris.clone(), pts.len());
    let (mut rounds, mut since_best) = (0, 0);
    while rounds < max_rounds && best.0 > 0 && since_best < STALLED_ROUNDS {
        let uses = edge_uses(tris);
        let chosen: Vec<(f64, (usize, usize), [usize; 2])> = (0..tris.len())
            .filter(|&t| count[t] > 0)
            .filter_map(|t| {
                let tri = tris[t];
                (0..3)
                    .map(|e| edge_key(tri[e], tri[(e + 1) % 3]))
                    .filter_map(|k| {
                        let &(ts, n) = uses.get(&k)?;
                        (n == 2).then(|| ((pos[k.0] - pos[k.1]).length(), k, ts))
                    })
                    .max_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)))
            })
            .collect();
        let changed = bisect(tris, pts, pos, proj, chosen, max_triangles);
        if changed.is_empty() {
            break;
        }
        rounds += 1;
        count.resize(tris.len(), 0);
        for (&t, c) in changed.iter().zip(surface.crossings(tris, &changed, pos)) {
            count[t] = c;
        }
        since_best += 1;
        if total(&count) < best.0 {
            best = (total(&count), tris.clone(), pts.len());
            since_best = 0;
        }
    }
    *tris = best.1;
    pts.truncate(best.2);
    pos.truncate(best.2);
    (rounds, best.0)
}

/// Bisects the interior edges `edges` (length, key, its two triangles),
/// longest first, each triangle at most once per call (an edge listed twice
/// is split once). Returns the triangles changed or added.
fn bisect(
    tris: &mut Vec<[usize; 3]>,
    pts: &mut Vec<DVec2>,
    pos: &mut Vec<DVec3>,
    proj: &Projection,
    mut edges: Vec<(f64, (usize, usize), [usize; 2])>,
    max_triangles: usize,
) -> Vec<usize> {
    edges.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut touched = vec![false; tris.len()];
    let mut changed = Vec::new();
    for (_, (a, b), ts) in edges {
        if ts.iter().any(|&t| touched[t]) || tris.len() + 2 > max_triangles {
            continue;
        }
        let mid = (pts[a] + pts[b]) * 0.5;
        let Some(q) = proj.unapply(mid) else {
            continue;
        };
        let m = pos.len();
        pts.push(mid);
        pos.push(q);
        for t in ts {
            touched[t] = true;
            let tri = tris[t];
            // Rotate so the split edge is (tri[0], tri[1]).
            let e = (0..3)
                .find(|&e| edge_key(tri[e], tri[(e + 1) % 3]) == (a, b))
                .unwrap_or(0);
            let (x, y, z) = (tri[e], tri[(e + 1) % 3], tri[(e + 2) % 3]);
            tris[t] = [x, m, z];
            tris.push([m, y, z]);
            touched.push(true);
            changed.extend([t, tris.len() - 1]);
        }
    }
    changed
}

/// Sphere-cap refinement rounds at most (each bisects one interior edge of
/// every cap triangle that crosses the surface).
pub(super) const CAP_REPAIR_ROUNDS: usize = 16;

/// The cut surface (unsplit triangles and sub-triangles) that a sphere
/// cap must not cross, for [`repair_on_sphere`]. Vertex ids as in
/// [`Sub`], cut and cap points in `points`; a cut at a mesh vertex is that
/// vertex, as in the pieces.
pub(crate) struct CutSurface<'a> {
    pub(crate) mesh: &'a TriMesh,
    /// The mesh's forest, when the cut went through it.
    pub(crate) forest: Option<&'a Forest>,
    pub(crate) located: &'a Located,
    pub(crate) subs: &'a [Vec<Sub>],
}

impl CutSurface<'_> {
    fn canon(&self, v: u32) -> u32 {
        let n_v = self.mesh.positions.len() as u32;
        if v >= n_v
            && let Some(&(a, b)) = self.located.edges.get((v - n_v) as usize)
            && a == b
        {
            return a;
        }
        v
    }

    fn at(&self, v: u32, points: &[Vec3]) -> Vec3 {
        let n_v = self.mesh.positions.len() as u32;
        if v < n_v {
            self.mesh.positions[v as usize]
        } else {
            points[(v - n_v) as usize]
        }
    }

    fn tri_box(&self, t: &[u32; 3], points: &[Vec3]) -> Aabb {
        let [a, b, c] = t.map(|v| self.at(v, points));
        Aabb::triangle(a, b, c)
    }

    /// The surface triangles whose boxes meet `bounds` (unsplit ones in
    /// id order, from the forest's leaves that meet it when there is one,
    /// else from a scan; then the sub-triangles).
    fn near(&self, bounds: &Aabb, points: &[Vec3]) -> Vec<[u32; 3]> {
        let keep = |t: usize| {
            let tri = &self.mesh.triangles[t];
            (self.tri_box(tri, points).overlaps(bounds)
                && self.located.triangles.binary_search(&(t as u32)).is_err())
            .then_some(*tri)
        };
        let mut tris: Vec<[u32; 3]> = match self.forest {
            Some(forest) => {
                let mut ids = Vec::new();
                forest.overlapping(bounds, &mut ids);
                ids.sort_unstable();
                ids.into_iter().filter_map(|t| keep(t as usize)).collect()
            }
            None => (0..self.mesh.triangles.len())
                .into_par_iter()
                .filter_map(keep)
                .collect(),
        };
        tris.extend(
            self.subs
                .iter()
                .flatten()
                .map(|sub| sub.v.map(|v| self.canon(v)))
                .filter(|v| self.tri_box(v, points).overlaps(bounds)),
        );
        tris
    }

    /// Per cap triangle `cap[check[k]]` the number of surface and cap
    /// triangles it meets beyond their shared vertices, by the exact test
    /// of [`crate::mesh::intersections_of_first`] on one small mesh of the
    /// checked triangles and the triangles near them.
    fn crossings(&self, cap: &[[u32; 3]], check: &[usize], points: &[Vec3]) -> Vec<u32> {
        let bounds = check
            .iter()
            .fold(Aabb::EMPTY, |b, &t| b.union(self.tri_box(&cap[t], points)));
        let mut tris: Vec<[u32; 3]> = check
            .iter()
            .map(|&t| cap[t].map(|v| self.canon(v)))
            .collect();
        let mut is_checked = vec![false; cap.len()];
        check.iter().for_each(|&t| is_checked[t] = true);
        tris.extend(self.near(&bounds, points));
        tris.extend(
            cap.iter()
                .zip(&is_checked)
                .filter(|(t, c)| !**c && self.tri_box(t, points).overlaps(&bounds))
                .map(|(t, _)| t.map(|v| self.canon(v))),
        );
        let mut local: HashMap<u32, u32> = HashMap::new();
        let mut positions = Vec::new();
        for v in tris.iter_mut().flatten() {
            *v = *local.entry(*v).or_insert_with(|| {
                positions.push(self.at(*v, points));
                positions.len() as u32 - 1
            });
        }
        let small = TriMesh {
            positions,
            triangles: tris,
            scalars: Vec::new(),
        };
        let n = check.len();
        let mut count = vec![0u32; n];
        for [i, j] in crate::mesh::intersections_of_first(&small, n).pairs {
            for t in [i, j] {
                if (t as usize) < n {
                    count[t as usize] += 1;
                }
            }
        }
        count
    }
}

/// [`CapCheck`] for a sphere cap under construction: cap corner `i`
/// is loop point `ids[i]` below `ids.len()`, else a new point appended to
/// `points` after its first `first_new`.
pub(super) struct SphereCapCheck<'a> {
    pub(super) surface: &'a CutSurface<'a>,
    pub(super) points: &'a mut Vec<Vec3>,
    pub(super) ids: &'a [u32],
    pub(super) first_new: usize,
    pub(super) n_v: u32,
}

impl SphereCapCheck<'_> {
    pub(super) fn global(&self, t: &[usize; 3]) -> [u32; 3] {
        let n_loop = self.ids.len();
        t.map(|i| {
            if i < n_loop {
                self.ids[i]
            } else {
                self.n_v + (self.first_new + i - n_loop) as u32
            }
        })
    }

    /// Stores the new points (f32, as the pieces will hold them).
    pub(super) fn place(&mut self, pos: &[DVec3]) {
        self.points.truncate(self.first_new);
        self.points
            .extend(pos[self.ids.len()..].iter().map(|q| q.as_vec3()));
    }
}

impl CapCheck for SphereCapCheck<'_> {
    fn crossings(&mut self, tris: &[[usize; 3]], check: &[usize], pos: &[DVec3]) -> Vec<u32> {
        self.place(pos);
        let cap: Vec<[u32; 3]> = tris.iter().map(|t| self.global(t)).collect();
        self.surface.crossings(&cap, check, self.points)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cut::cap::triangulate;

    fn signed_area(t: [usize; 3], p: &[DVec2]) -> f64 {
        robust::orient2d(coord(p[t[0]]), coord(p[t[1]]), coord(p[t[2]]))
    }

    /// A band 40 long and 1 wide with 0.25 spacing along its long sides:
    /// ear clipping fans it into slivers; the flips leave a triangulation of
    /// the same region and boundary, every triangle still counter-clockwise,
    /// every interior edge locally Delaunay and no sliver spanning the band
    /// lengthwise.
    #[test]
    fn delaunay_flips_keep_the_region_and_make_edges_delaunay() {
        let mut pts: Vec<DVec2> = (0..=160)
            .map(|i| DVec2::new(i as f64 * 0.25, 0.0))
            .collect();
        pts.extend((0..=160).rev().map(|i| DVec2::new(i as f64 * 0.25, 1.0)));
        let lp: Vec<usize> = (0..pts.len()).collect();
        let mut tris = triangulate(&pts, &[lp]);
        let boundary = |tris: &[[usize; 3]]| {
            let mut b: Vec<(usize, usize)> = edge_uses(tris)
                .into_iter()
                .filter(|(_, (_, n))| *n == 1)
                .map(|(k, _)| k)
                .collect();
            b.sort_unstable();
            b
        };
        let area = |tris: &[[usize; 3]]| tris.iter().map(|&t| signed_area(t, &pts)).sum::<f64>();
        let pts_ref = &pts;
        let longest = |tris: &[[usize; 3]]| {
            tris.iter()
                .flat_map(|t| {
                    (0..3).map(move |e| (pts_ref[t[e]] - pts_ref[t[(e + 1) % 3]]).length())
                })
                .fold(0.0, f64::max)
        };
        let (b0, a0, n0) = (boundary(&tris), area(&tris), tris.len());
        assert!(
            longest(&tris) > 5.0,
            "the fan has no sliver: the test shows nothing"
        );
        delaunay_flips(&mut tris, &pts);
        assert_eq!(tris.len(), n0);
        assert_eq!(boundary(&tris), b0);
        assert!((area(&tris) - a0).abs() < 1e-9 * a0.abs());
        assert!(tris.iter().all(|&t| signed_area(t, &pts) > 0.0));
        assert!(longest(&tris) < 1.1, "a sliver is left: {}", longest(&tris));
        for (&(a, b), &([t0, t1], n)) in &edge_uses(&tris) {
            if n != 2 {
                continue;
            }
            let third = |t: [usize; 3]| t.into_iter().find(|&v| v != a && v != b).unwrap();
            let (c, d) = (third(tris[t0]), third(tris[t1]));
            let [p, q, r] = tris[t0];
            assert!(
                robust::incircle(coord(pts[p]), coord(pts[q]), coord(pts[r]), coord(pts[d])) <= 0.0,
                "edge ({a}, {b}) with opposite corners {c} and {d} is not Delaunay"
            );
        }
    }
}
