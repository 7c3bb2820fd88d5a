//! Triangulated knives: where the knife surface meets the cut surface,
//! both split along the same curve, and caps from the knife (beyond the
//! seed, which only locates the crossings, §3.1).
//!
//! Topology is decided by orientation signs alone: Shewchuk's `orient3d`
//! evaluated in f64 on the f32 inputs with its static error bound; a sign
//! too close to call counts as a contact. Every sign is evaluated on
//! canonical arguments (edges lower id first, triangles as stored), so all
//! triangles sharing an edge see the same answer:
//! - surface edge `e` crosses knife triangle `K` → cut point `e×K`;
//! - knife edge `f` crosses surface triangle `T` → cut point `T×f`;
//! - a contact (a vertex on the other mesh, an edge through an edge,
//!   coplanar triangles) is an error asking to move the knife slightly.
//!
//! An intersecting pair (T, K) meets in one segment between two of these
//! points; a point lies on two segments (one at a mesh border), so the cut
//! curves are closed away from borders and shared by both meshes: a point
//! is one vertex for the surface and for the cap.
//!
//! Each split triangle (of either mesh) is cut along its chains of segments
//! into polygons (a loop inside one triangle becomes a hole plus a
//! polygon), triangulated by ear clipping in the triangle's own plane with
//! the triangle's orientation. A polygon lies left of the segments on its
//! border; from the other triangle's normal that says which side it is on
//! (surface: behind the knife = negative; knife: behind the surface =
//! inside the solid). Knife polygons and whole knife triangles joined
//! across knife edges form regions; a region inside the solid whose border
//! is cut curve only is a cap, used as is by the negative pieces and
//! reversed by the positive ones, so the cap adds no volume.

use std::collections::HashMap;

use glam::{DVec2, DVec3, Vec3};
use rayon::prelude::*;

use super::cap;
use crate::foundation::{Aabb, Forest, UnionFind, vertex_components};
use crate::{Error, Result, TriMesh};

/// How a cut point of a triangulated knife arises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PointOrigin {
    /// Surface edge `(lower id, higher id)` through a knife triangle.
    SurfaceEdge {
        edge: (u32, u32),
        knife_triangle: u32,
    },
    /// Knife edge `(lower id, higher id)` through a surface triangle.
    KnifeEdge { edge: (u32, u32), triangle: u32 },
}

/// One piece of the cut curve: where surface triangle `triangle` meets
/// knife triangle `knife_triangle`, between cut points `ends`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KnifeSegment {
    pub triangle: u32,
    pub knife_triangle: u32,
    pub ends: [u32; 2],
}

/// Segments of one surface triangle: (knife triangle, its two cut points),
/// ascending knife triangle.
pub(crate) type TriangleSegments = Vec<(u32, [PointOrigin; 2])>;

/// `orient3d`'s static error bound `(7 + 56ε)ε` (Shewchuk 1997).
const O3D_ERRBOUND: f64 = (7.0 + 56.0 * f64::EPSILON / 2.0) * f64::EPSILON / 2.0;

/// Sign of `(b − a)×(c − a)·(d − a)`: 1 when `d` is in front of `abc`
/// (right-hand normal), −1 behind, 0 when f64 cannot decide.
fn orient(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> i8 {
    let (a, b, c, d) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3(), d.as_dvec3());
    let (ad, bd, cd) = (a - d, b - d, c - d);
    let (bxcy, cxby) = (bd.x * cd.y, cd.x * bd.y);
    let (cxay, axcy) = (cd.x * ad.y, ad.x * cd.y);
    let (axby, bxay) = (ad.x * bd.y, bd.x * ad.y);
    let det = ad.z * (bxcy - cxby) + bd.z * (cxay - axcy) + cd.z * (axby - bxay);
    let permanent = (bxcy.abs() + cxby.abs()) * ad.z.abs()
        + (cxay.abs() + axcy.abs()) * bd.z.abs()
        + (axby.abs() + bxay.abs()) * cd.z.abs();
    let bound = O3D_ERRBOUND * permanent;
    // Shewchuk's determinant is positive when d is below (behind).
    if det > bound {
        -1
    } else if det < -bound {
        1
    } else {
        0
    }
}

/// Outcome of a segment–triangle test.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Hit {
    Miss,
    /// Through the open triangle, endpoints strictly on both sides.
    Cross,
    /// Touches the closed triangle otherwise (or cannot be decided).
    Contact,
}

/// From the endpoint signs against the triangle's plane and the signs of
/// the segment's line against the triangle's three edges.
fn classify(s_lo: i8, s_hi: i8, t: [i8; 3], boxes_overlap: bool) -> Hit {
    if s_lo * s_hi > 0 {
        return Hit::Miss;
    }
    if s_lo == 0 && s_hi == 0 {
        return if boxes_overlap {
            Hit::Contact
        } else {
            Hit::Miss
        };
    }
    let pos = t.iter().any(|&x| x > 0);
    let neg = t.iter().any(|&x| x < 0);
    if pos && neg {
        Hit::Miss
    } else if s_lo != 0 && s_hi != 0 && t.iter().all(|&x| x != 0) {
        Hit::Cross
    } else {
        Hit::Contact
    }
}

fn canon(a: u32, b: u32) -> ((u32, u32), i8) {
    if a < b { ((a, b), 1) } else { ((b, a), -1) }
}

fn tri_box(m: &TriMesh, t: u32) -> Aabb {
    let [a, b, c] = m.triangles[t as usize].map(|v| m.positions[v as usize]);
    Aabb::triangle(a, b, c)
}

/// The surface, the knife and the knife's forest.
#[derive(Debug)]
pub(crate) struct Pair<'a> {
    pub surface: &'a TriMesh,
    pub knife: &'a TriMesh,
    pub forest: &'a Forest,
    pub margin: f64,
}

impl Pair<'_> {
    fn s(&self, v: u32) -> Vec3 {
        self.surface.positions[v as usize]
    }

    fn k(&self, v: u32) -> Vec3 {
        self.knife.positions[v as usize]
    }

    /// The one sign shared by a surface edge and a knife edge (both canonical).
    fn edge_edge(&self, e: (u32, u32), f: (u32, u32)) -> i8 {
        orient(self.s(e.0), self.s(e.1), self.k(f.0), self.k(f.1))
    }

    /// Surface edge `e` (canonical) against knife triangle `kt`.
    fn surface_edge_hit(&self, e: (u32, u32), kt: u32) -> Hit {
        let kv = self.knife.triangles[kt as usize];
        let [k0, k1, k2] = kv.map(|v| self.k(v));
        let s_lo = orient(k0, k1, k2, self.s(e.0));
        let s_hi = orient(k0, k1, k2, self.s(e.1));
        if s_lo * s_hi > 0 {
            return Hit::Miss;
        }
        let t = std::array::from_fn(|i| {
            let (f, sign) = canon(kv[i], kv[(i + 1) % 3]);
            sign * self.edge_edge(e, f)
        });
        let seg = Aabb::triangle(self.s(e.0), self.s(e.1), self.s(e.1));
        classify(s_lo, s_hi, t, seg.overlaps(&tri_box(self.knife, kt)))
    }

    /// Knife edge `f` (canonical) against surface triangle `st`.
    fn knife_edge_hit(&self, f: (u32, u32), st: u32) -> Hit {
        let sv = self.surface.triangles[st as usize];
        let [s0, s1, s2] = sv.map(|v| self.s(v));
        let s_lo = orient(s0, s1, s2, self.k(f.0));
        let s_hi = orient(s0, s1, s2, self.k(f.1));
        if s_lo * s_hi > 0 {
            return Hit::Miss;
        }
        // orient(f, T_i, T_i+1) = orient(T_i, T_i+1, f) (even permutation).
        let t = std::array::from_fn(|i| {
            let (e, sign) = canon(sv[i], sv[(i + 1) % 3]);
            sign * self.edge_edge(e, f)
        });
        let seg = Aabb::triangle(self.k(f.0), self.k(f.1), self.k(f.1));
        classify(s_lo, s_hi, t, seg.overlaps(&tri_box(self.surface, st)))
    }

    fn contact(&self, st: u32, kt: u32) -> Error {
        Error::InvalidInput(format!(
            "triangulated knife: knife triangle {kt} touches surface triangle {st} without \
             crossing it cleanly (a vertex on the other surface, an edge through an edge, or \
             coplanar triangles); move or tilt the knife slightly"
        ))
    }

    /// The segment where surface triangle `st` meets knife triangle `kt`.
    fn segment(&self, st: u32, kt: u32) -> Result<Option<[PointOrigin; 2]>> {
        let sv = self.surface.triangles[st as usize];
        let kv = self.knife.triangles[kt as usize];
        let mut ends = Vec::with_capacity(2);
        for i in 0..3 {
            let (e, _) = canon(sv[i], sv[(i + 1) % 3]);
            match self.surface_edge_hit(e, kt) {
                Hit::Miss => {}
                Hit::Cross => ends.push(PointOrigin::SurfaceEdge {
                    edge: e,
                    knife_triangle: kt,
                }),
                Hit::Contact => return Err(self.contact(st, kt)),
            }
            let (f, _) = canon(kv[i], kv[(i + 1) % 3]);
            match self.knife_edge_hit(f, st) {
                Hit::Miss => {}
                Hit::Cross => ends.push(PointOrigin::KnifeEdge {
                    edge: f,
                    triangle: st,
                }),
                Hit::Contact => return Err(self.contact(st, kt)),
            }
        }
        match ends.len() {
            0 => Ok(None),
            2 => Ok(Some([ends[0], ends[1]])),
            _ => Err(self.contact(st, kt)),
        }
    }

    /// Segments of one surface triangle, ascending knife triangle.
    fn triangle_segments(&self, st: u32) -> Result<TriangleSegments> {
        let m = self.margin as f32;
        let b = tri_box(self.surface, st);
        let grown = Aabb {
            min: b.min - Vec3::splat(m),
            max: b.max + Vec3::splat(m),
        };
        let mut cand = Vec::new();
        self.forest.overlapping(&grown, &mut cand);
        cand.sort_unstable();
        let mut out = Vec::new();
        for kt in cand {
            if let Some(s) = self.segment(st, kt)? {
                out.push((kt, s));
            }
        }
        Ok(out)
    }

    /// Segments of each of `tris` (in parallel for large sets).
    pub fn segments_of(&self, tris: &[u32]) -> Result<Vec<TriangleSegments>> {
        if tris.len() < 1 << 12 {
            tris.iter().map(|&t| self.triangle_segments(t)).collect()
        } else {
            tris.par_iter()
                .map(|&t| self.triangle_segments(t))
                .collect()
        }
    }

    /// Position of a cut point: the edge meets the other triangle's plane (f64).
    pub fn point(&self, o: PointOrigin) -> DVec3 {
        let hit = |a: Vec3, b: Vec3, tri: [Vec3; 3]| {
            let [p0, p1, p2] = tri.map(|p| p.as_dvec3());
            let n = (p1 - p0).cross(p2 - p0);
            let (a, b) = (a.as_dvec3(), b.as_dvec3());
            let (da, db) = (n.dot(a - p0), n.dot(b - p0));
            let t = (da / (da - db)).clamp(0.0, 1.0);
            a + (b - a) * if t.is_finite() { t } else { 0.5 }
        };
        match o {
            PointOrigin::SurfaceEdge {
                edge,
                knife_triangle,
            } => hit(
                self.s(edge.0),
                self.s(edge.1),
                self.knife.triangles[knife_triangle as usize].map(|v| self.k(v)),
            ),
            PointOrigin::KnifeEdge { edge, triangle } => hit(
                self.k(edge.0),
                self.k(edge.1),
                self.surface.triangles[triangle as usize].map(|v| self.s(v)),
            ),
        }
    }

    /// Whether the lower end of the point's edge is behind the other triangle.
    pub fn lower_behind(&self, o: PointOrigin) -> bool {
        match o {
            PointOrigin::SurfaceEdge {
                edge,
                knife_triangle,
            } => {
                let [a, b, c] = self.knife.triangles[knife_triangle as usize].map(|v| self.k(v));
                orient(a, b, c, self.s(edge.0)) < 0
            }
            PointOrigin::KnifeEdge { edge, triangle } => {
                let [a, b, c] = self.surface.triangles[triangle as usize].map(|v| self.s(v));
                orient(a, b, c, self.k(edge.0)) < 0
            }
        }
    }
}

/// A polygon of a split triangle: outer cycle, holes, side label.
#[derive(Debug, Clone)]
struct Face {
    outer: Vec<u32>,
    holes: Vec<Vec<u32>>,
    /// Behind the other mesh (surface: negative side; knife: inside the solid).
    behind: bool,
    /// Holds an open end of the cut curve (knife triangles only, where the
    /// surface's own border crosses them): on both sides, never a cap.
    open: bool,
}

/// One triangle to split: corner ids and positions, cut points on each
/// edge `(c_i, c_i+1)`, and segments `(a, b, other triangle's normal)`.
struct ToSplit<'a> {
    corners: [u32; 3],
    edge_points: [Vec<u32>; 3],
    segments: Vec<(u32, u32, DVec3)>,
    pos: &'a dyn Fn(u32) -> DVec3,
    what: &'a str,
    /// Whether the cut curve may end inside (else an error).
    open_ends: bool,
}

impl ToSplit<'_> {
    fn err(&self, why: &str) -> Error {
        Error::InvalidInput(format!("triangulated knife: {} {why}", self.what))
    }

    fn ends_inside(&self) -> Error {
        self.err(
            "holds an end of the cut curve: the knife's border passes through the surface \
             (an open knife must reach beyond the surface)",
        )
    }

    fn normal(&self) -> DVec3 {
        let [a, b, c] = self.corners.map(|v| (self.pos)(v));
        (b - a).cross(c - a)
    }

    /// The triangle's border as one cycle: corners with the cut points in
    /// order along each edge.
    fn boundary(&self) -> Result<Vec<u32>> {
        let pos = self.pos;
        let mut boundary = Vec::new();
        for i in 0..3 {
            let (c0, c1) = (pos(self.corners[i]), pos(self.corners[(i + 1) % 3]));
            let d = c1 - c0;
            let mut pts: Vec<(f64, u32)> = self.edge_points[i]
                .iter()
                .map(|&p| ((pos(p) - c0).dot(d), p))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            if pts.windows(2).any(|w| w[0].0 == w[1].0) {
                return Err(self.err("has two cut points at one spot of an edge"));
            }
            boundary.push(self.corners[i]);
            boundary.extend(pts.iter().map(|&(_, p)| p));
        }
        Ok(boundary)
    }

    /// The faces: polygons between the chains, loops as holes + polygons.
    fn faces(self) -> Result<Vec<Face>> {
        let pos = self.pos;
        let n_own = self.normal();
        let boundary = self.boundary()?;
        let on_boundary: HashMap<u32, ()> = self
            .edge_points
            .iter()
            .flatten()
            .map(|&p| (p, ()))
            .collect();
        // Adjacency of the segments.
        let mut adj: HashMap<u32, Vec<u32>> = HashMap::new();
        let mut seg_normal: HashMap<(u32, u32), DVec3> = HashMap::new();
        for &(a, b, n) in &self.segments {
            if seg_normal.insert((a.min(b), a.max(b)), n).is_some() {
                return Err(self.err("has two segments between the same cut points"));
            }
            adj.entry(a).or_default().push(b);
            adj.entry(b).or_default().push(a);
        }
        if adj.values().any(|v| v.len() > 2) {
            return Err(self.err("has a cut point on more than two segments"));
        }
        // Chains from boundary point to boundary point, then interior loops.
        let mut visited: HashMap<u32, ()> = HashMap::new();
        let mut chains: Vec<Vec<u32>> = Vec::new();
        // A point of each open chain (its start).
        let mut dangling: Vec<u32> = Vec::new();
        let mut starts: Vec<u32> = on_boundary.keys().copied().collect();
        starts.sort_unstable();
        for s in starts {
            if visited.contains_key(&s) {
                continue;
            }
            let mut chain = vec![s];
            visited.insert(s, ());
            let (mut prev, mut cur) = (u32::MAX, s);
            loop {
                let next = adj
                    .get(&cur)
                    .and_then(|v| v.iter().copied().find(|&w| w != prev));
                let Some(next) = next else {
                    if !self.open_ends {
                        return Err(self.ends_inside());
                    }
                    dangling.push(s);
                    break;
                };
                chain.push(next);
                visited.insert(next, ());
                if on_boundary.contains_key(&next) {
                    chains.push(chain);
                    break;
                }
                (prev, cur) = (cur, next);
            }
        }
        // Open chains with both ends inside.
        let mut ends: Vec<u32> = adj
            .iter()
            .filter(|(p, v)| v.len() == 1 && !visited.contains_key(p))
            .map(|(&p, _)| p)
            .collect();
        ends.sort_unstable();
        for e in ends {
            if visited.insert(e, ()).is_some() {
                continue;
            }
            if !self.open_ends {
                return Err(self.ends_inside());
            }
            dangling.push(e);
            let (mut prev, mut cur) = (u32::MAX, e);
            while let Some(next) = adj[&cur].iter().copied().find(|&w| w != prev) {
                visited.insert(next, ());
                (prev, cur) = (cur, next);
            }
        }
        let mut loops: Vec<Vec<u32>> = Vec::new();
        let mut rest: Vec<u32> = adj
            .keys()
            .copied()
            .filter(|p| !visited.contains_key(p))
            .collect();
        rest.sort_unstable();
        for s in rest {
            if visited.contains_key(&s) {
                continue;
            }
            let mut lp = vec![s];
            visited.insert(s, ());
            let (mut prev, mut cur) = (u32::MAX, s);
            loop {
                let Some(next) = adj
                    .get(&cur)
                    .and_then(|v| v.iter().copied().find(|&w| w != prev))
                else {
                    return Err(self.ends_inside());
                };
                if next == s {
                    break;
                }
                if visited.insert(next, ()).is_some() {
                    return Err(self.err("has tangled cut segments"));
                }
                lp.push(next);
                (prev, cur) = (cur, next);
            }
            loops.push(lp);
        }
        // Split the boundary polygon along each chain.
        let mut polys: Vec<Vec<u32>> = vec![boundary];
        for chain in &chains {
            let (a, b) = (chain[0], chain[chain.len() - 1]);
            let Some(pi) = polys.iter().position(|p| p.contains(&a) && p.contains(&b)) else {
                return Err(self.err("has crossing cut chains (is the knife self-intersecting?)"));
            };
            let p = std::mem::take(&mut polys[pi]);
            let ia = p.iter().position(|&v| v == a).unwrap_or(0);
            let ib = p.iter().position(|&v| v == b).unwrap_or(0);
            let n = p.len();
            let walk = |from: usize, to: usize| {
                let mut out = vec![p[from]];
                let mut i = from;
                while i != to {
                    i = (i + 1) % n;
                    out.push(p[i]);
                }
                out
            };
            let interior = &chain[1..chain.len() - 1];
            let mut p1 = walk(ia, ib);
            p1.extend(interior.iter().rev());
            let mut p2 = walk(ib, ia);
            p2.extend(interior.iter());
            polys[pi] = p1;
            polys.push(p2);
        }
        // 2-D frame with the triangle's orientation counter-clockwise.
        let to2 = frame_2d(n_own);
        let area = |cyc: &[u32]| -> f64 {
            let n = cyc.len();
            (0..n)
                .map(|i| {
                    let (a, b) = (to2(pos(cyc[i])), to2(pos(cyc[(i + 1) % n])));
                    a.perp_dot(b)
                })
                .sum::<f64>()
        };
        // Side of the polygon left of `cyc`, from its cut edges (None: no
        // cut edge on `cyc` tells it).
        let label = |cyc: &[u32]| -> Result<Option<bool>> {
            let mut verdict: Option<bool> = None;
            let n = cyc.len();
            for i in 0..n {
                let (u, v) = (cyc[i], cyc[(i + 1) % n]);
                let Some(n_oth) = seg_normal.get(&(u.min(v), u.max(v))) else {
                    continue;
                };
                let d = pos(v) - pos(u);
                let val = n_oth.dot(n_own.cross(d));
                let scale = n_oth.length() * n_own.length() * d.length();
                if val.abs() <= 1e-9 * scale {
                    continue;
                }
                let behind = val < 0.0;
                if verdict.is_some_and(|b| b != behind) {
                    return Err(self.err("has a polygon on both sides of the other mesh"));
                }
                verdict = Some(behind);
            }
            Ok(verdict)
        };
        let untold = || self.err("has a polygon whose side cannot be told");
        let mut faces: Vec<Face> = Vec::with_capacity(polys.len() + loops.len());
        let mut told: Vec<Option<bool>> = Vec::with_capacity(polys.len() + loops.len());
        for p in polys {
            told.push(label(&p)?);
            faces.push(Face {
                behind: false,
                outer: p,
                holes: Vec::new(),
                open: false,
            });
        }
        // Loops: a polygon of their own, and a hole in the smallest face around them.
        let n_split = faces.len();
        for lp in &mut loops {
            if area(lp) < 0.0 {
                lp.reverse();
            }
        }
        for lp in &loops {
            told.push(Some(label(lp)?.ok_or_else(untold)?));
            faces.push(Face {
                behind: false,
                outer: lp.clone(),
                holes: Vec::new(),
                open: false,
            });
        }
        for (li, lp) in loops.iter().enumerate() {
            let q = to2(pos(lp[0]));
            let owner = (0..faces.len())
                .filter(|&f| f != n_split + li)
                .filter(|&f| {
                    let cyc: Vec<DVec2> = faces[f].outer.iter().map(|&v| to2(pos(v))).collect();
                    point_in(&cyc, q)
                })
                .min_by(|&a, &b| area(&faces[a].outer).total_cmp(&area(&faces[b].outer)));
            let Some(o) = owner else {
                return Err(self.err("has a cut loop outside itself"));
            };
            faces[o].holes.push(lp.iter().rev().copied().collect());
        }
        // Open chains mark the face they lie in: the one whose border holds
        // their boundary start, else the smallest around their inner start.
        for &d in &dangling {
            let owner = if on_boundary.contains_key(&d) {
                faces.iter().position(|f| f.outer.contains(&d))
            } else {
                let q = to2(pos(d));
                (0..faces.len())
                    .filter(|&f| {
                        let cyc: Vec<DVec2> = faces[f].outer.iter().map(|&v| to2(pos(v))).collect();
                        point_in(&cyc, q)
                    })
                    .min_by(|&a, &b| area(&faces[a].outer).total_cmp(&area(&faces[b].outer)))
            };
            let Some(o) = owner else {
                return Err(self.err("has an open cut curve outside itself"));
            };
            faces[o].open = true;
        }
        // A polygon whose outer border has no cut edge (a triangle around
        // loops only) is told by its holes: it lies left of them too.
        for (f, t) in faces.iter_mut().zip(told) {
            if f.open {
                continue;
            }
            let mut side = t;
            for h in &f.holes {
                match (side, label(h)?) {
                    (Some(a), Some(b)) if a != b => {
                        return Err(self.err("has a polygon on both sides of the other mesh"));
                    }
                    (None, b) => side = b,
                    _ => {}
                }
            }
            f.behind = side.ok_or_else(untold)?;
        }
        Ok(faces)
    }
}

/// Maps points to the plane of a triangle with normal `n`, keeping its
/// orientation counter-clockwise.
fn frame_2d(n: DVec3) -> impl Fn(DVec3) -> DVec2 {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
    let flip = n[axis] < 0.0;
    move |p: DVec3| {
        if flip {
            DVec2::new(p[j], p[i])
        } else {
            DVec2::new(p[i], p[j])
        }
    }
}

fn point_in(cyc: &[DVec2], q: DVec2) -> bool {
    let n = cyc.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (cyc[i], cyc[(i + 1) % n]);
        if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y) {
            inside = !inside;
        }
    }
    inside
}

/// Triangles of a face (ids of its cycles), oriented like its triangle.
fn triangulate_face(f: &Face, pos: &dyn Fn(u32) -> DVec3, n_own: DVec3) -> Vec<[u32; 3]> {
    let to2 = frame_2d(n_own);
    let mut ids: Vec<u32> = Vec::new();
    let mut pts: Vec<DVec2> = Vec::new();
    let mut loops: Vec<Vec<usize>> = Vec::new();
    for cyc in std::iter::once(&f.outer).chain(&f.holes) {
        let mut l = Vec::with_capacity(cyc.len());
        for &v in cyc {
            l.push(pts.len());
            pts.push(to2(pos(v)));
            ids.push(v);
        }
        loops.push(l);
    }
    if f.holes.is_empty() && f.outer.len() == 3 {
        return vec![[f.outer[0], f.outer[1], f.outer[2]]];
    }
    cap::triangulate(&pts, &loops)
        .into_iter()
        .map(|t| t.map(|i| ids[i]))
        .collect()
}

/// The split of a surface by a triangulated knife, ready for assembly.
#[derive(Debug, Default)]
pub(crate) struct MeshSplit {
    /// Per crossed surface triangle, its sub-triangles and whether each is
    /// on the negative side.
    pub subs: Vec<Vec<([u32; 3], bool)>>,
    /// Knife vertices used by the caps, appended after the cut points.
    pub extra_points: Vec<Vec3>,
    /// Cap triangles oriented for the negative side (ids `n_v + point`).
    pub caps: Vec<[u32; 3]>,
    /// Knife regions used as caps.
    pub regions_capped: usize,
    /// Cut curves with an end (at a surface border), and knife regions
    /// inside the solid that reach the knife's border (not capped).
    pub curves_open: usize,
}

/// Per triangle, whether its solid lies in front of it: on the closed
/// components when, together, they enclose a negative volume (the surface
/// is wound inward; cavities count against their outer surface, as they
/// should). Open components enclose nothing and keep the convention that
/// triangles face outward. With `closed_outward` (the surface is known to
/// be closed and wound outward, [`Forest::closed_outward`]) none does, and
/// nothing is computed.
pub(crate) fn inward_triangles(surface: &TriMesh, closed_outward: bool) -> Vec<bool> {
    if closed_outward {
        return vec![false; surface.triangles.len()];
    }
    let (comp, n) = vertex_components(surface.n_vertices(), &surface.triangles);
    // Closed: every edge used twice, once in each direction. The half-edges
    // are bucketed by their lower vertex (a counting sort, O(F)) as (higher
    // vertex << 1 | runs upward); each bucket holds a vertex's few edges to
    // higher vertices, and an edge's component is its lower vertex's.
    let half_edges = |t: &[u32; 3]| {
        let t = *t;
        (0..3).map(move |i| (t[i], t[(i + 1) % 3]))
    };
    let n_v = surface.n_vertices();
    let mut volume6 = vec![0.0f64; n];
    let mut start = vec![0usize; n_v + 1];
    let mut vertex_comp = vec![0u32; n_v];
    for (t, &c) in surface.triangles.iter().zip(&comp) {
        let [a, b, c3] = t.map(|v| surface.positions[v as usize].as_dvec3());
        volume6[c as usize] += a.dot(b.cross(c3));
        for (a, b) in half_edges(t) {
            start[a.min(b) as usize + 1] += 1;
            vertex_comp[a as usize] = c;
        }
    }
    for v in 1..start.len() {
        start[v] += start[v - 1];
    }
    let mut fill = start.clone();
    let mut bucket = vec![0u64; start[n_v]];
    for (a, b) in surface.triangles.iter().flat_map(half_edges) {
        let lo = a.min(b) as usize;
        bucket[fill[lo]] = u64::from(a.max(b)) << 1 | u64::from(a < b);
        fill[lo] += 1;
    }
    let open: Vec<u32> = start
        .par_windows(2)
        .enumerate()
        .filter_map(|(v, w)| {
            // A vertex has a few edges: sorted on the stack unless many.
            let run = &bucket[w[0]..w[1]];
            let (mut small, mut many) = ([0; 16], Vec::new());
            let edges = if run.len() <= small.len() {
                &mut small[..run.len()]
            } else {
                many.resize(run.len(), 0);
                &mut many[..]
            };
            edges.copy_from_slice(run);
            edges.sort_unstable();
            let open = (edges.chunk_by(|x, y| x >> 1 == y >> 1))
                .any(|run| !(run.len() == 2 && run[0] != run[1]));
            open.then_some(vertex_comp[v])
        })
        .collect();
    let mut closed = vec![true; n];
    for c in open {
        closed[c as usize] = false;
    }
    let enclosed: f64 = (0..n).filter(|&c| closed[c]).map(|c| volume6[c]).sum();
    comp.iter()
        .map(|&c| closed[c as usize] && enclosed < 0.0)
        .collect()
}

/// Splits the surface and (with `cap`) makes the caps. `points` are the cut
/// points (f32, as in the pieces), `origins` their origins, `segments`
/// sorted by surface triangle, `crossed` the crossed surface triangles.
pub(crate) fn split(
    pair: &Pair<'_>,
    crossed: &[u32],
    points: &[Vec3],
    origins: &[PointOrigin],
    segments: &[KnifeSegment],
    cap: bool,
    closed_outward: bool,
) -> Result<MeshSplit> {
    let surface = pair.surface;
    let knife = pair.knife;
    let n_v = surface.positions.len() as u32;
    let n_p = points.len() as u32;
    let kbase = n_v + n_p;
    let pos = |v: u32| -> DVec3 {
        if v < n_v {
            surface.positions[v as usize].as_dvec3()
        } else if v < kbase {
            points[(v - n_v) as usize].as_dvec3()
        } else {
            knife.positions[(v - kbase) as usize].as_dvec3()
        }
    };
    let normal = |m: &TriMesh, t: u32| {
        let [a, b, c] = m.triangles[t as usize].map(|v| m.positions[v as usize].as_dvec3());
        (b - a).cross(c - a)
    };
    let mut out = MeshSplit::default();
    // Surface triangles.
    let mut s = 0;
    for &t in crossed {
        let tri = surface.triangles[t as usize];
        let mut edge_points: [Vec<u32>; 3] = Default::default();
        let mut segs = Vec::new();
        while s < segments.len() && segments[s].triangle == t {
            let sg = segments[s];
            for &p in &sg.ends {
                if let PointOrigin::SurfaceEdge { edge, .. } = origins[p as usize] {
                    let i = (0..3)
                        .find(|&i| canon(tri[i], tri[(i + 1) % 3]).0 == edge)
                        .unwrap_or(0);
                    if !edge_points[i].contains(&(n_v + p)) {
                        edge_points[i].push(n_v + p);
                    }
                }
            }
            segs.push((
                n_v + sg.ends[0],
                n_v + sg.ends[1],
                normal(knife, sg.knife_triangle),
            ));
            s += 1;
        }
        let what = format!("surface triangle {t}");
        let faces = ToSplit {
            corners: tri,
            edge_points,
            segments: segs,
            pos: &pos,
            what: &what,
            open_ends: false,
        }
        .faces()?;
        let n_own = normal(surface, t);
        out.subs.push(
            faces
                .iter()
                .flat_map(|f| {
                    triangulate_face(f, &pos, n_own)
                        .into_iter()
                        .map(move |v| (v, f.behind))
                })
                .collect(),
        );
    }
    // Open curve ends: points used by one segment only (surface borders).
    let mut uses = vec![0u8; points.len()];
    for sg in segments {
        for &p in &sg.ends {
            uses[p as usize] = uses[p as usize].saturating_add(1);
        }
    }
    let mut curve_uf = UnionFind::with_len(points.len());
    for sg in segments {
        curve_uf.union(sg.ends[0], sg.ends[1]);
    }
    let mut open_curve = vec![false; points.len()];
    for (p, &u) in uses.iter().enumerate() {
        if u == 1 {
            open_curve[curve_uf.find(p as u32) as usize] = true;
        }
    }
    out.curves_open = open_curve.iter().filter(|&&o| o).count();
    if !cap {
        return Ok(out);
    }
    // The solid is behind a surface triangle, or in front where its
    // component is closed and wound inward.
    let inward = inward_triangles(surface, closed_outward);
    // Knife triangles with segments, split.
    let mut by_knife: Vec<usize> = (0..segments.len()).collect();
    by_knife.sort_by_key(|&i| (segments[i].knife_triangle, segments[i].triangle));
    let mut knife_faces: Vec<(u32, Face)> = Vec::new();
    // Knife triangles cut by inward-wound surface: their caps face inward too.
    let mut knife_inward = vec![false; knife.triangles.len()];
    let mut split_knife = vec![false; knife.triangles.len()];
    let mut i = 0;
    while i < by_knife.len() {
        let kt = segments[by_knife[i]].knife_triangle;
        let tri = knife.triangles[kt as usize];
        let corners = tri.map(|v| kbase + v);
        let mut edge_points: [Vec<u32>; 3] = Default::default();
        let mut segs = Vec::new();
        while i < by_knife.len() && segments[by_knife[i]].knife_triangle == kt {
            let sg = segments[by_knife[i]];
            knife_inward[kt as usize] |= inward[sg.triangle as usize];
            for &p in &sg.ends {
                if let PointOrigin::KnifeEdge { edge, .. } = origins[p as usize] {
                    let e = (0..3)
                        .find(|&e| canon(tri[e], tri[(e + 1) % 3]).0 == edge)
                        .unwrap_or(0);
                    if !edge_points[e].contains(&(n_v + p)) {
                        edge_points[e].push(n_v + p);
                    }
                }
            }
            let n_solid = normal(surface, sg.triangle);
            segs.push((
                n_v + sg.ends[0],
                n_v + sg.ends[1],
                if inward[sg.triangle as usize] {
                    -n_solid
                } else {
                    n_solid
                },
            ));
            i += 1;
        }
        let what = format!("knife triangle {kt}");
        let faces = ToSplit {
            corners,
            edge_points,
            segments: segs,
            pos: &pos,
            what: &what,
            open_ends: true,
        }
        .faces()?;
        split_knife[kt as usize] = true;
        knife_faces.extend(faces.into_iter().map(|f| (kt, f)));
    }
    // Regions: faces and whole knife triangles joined across shared
    // non-curve edges; an edge used once lies on the knife's border.
    let whole: Vec<u32> = (0..knife.triangles.len() as u32)
        .filter(|&t| !split_knife[t as usize])
        .collect();
    let n_units = knife_faces.len() + whole.len();
    let mut uf = UnionFind::with_len(n_units);
    let curve: std::collections::HashSet<(u32, u32)> = segments
        .iter()
        .map(|sg| {
            let (a, b) = (n_v + sg.ends[0], n_v + sg.ends[1]);
            (a.min(b), a.max(b))
        })
        .collect();
    let mut first_user: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
    let mut add_cycle = |cyc: &[u32], unit: u32, uf: &mut UnionFind| {
        let n = cyc.len();
        for j in 0..n {
            let (a, b) = (cyc[j], cyc[(j + 1) % n]);
            let key = (a.min(b), a.max(b));
            if curve.contains(&key) {
                continue;
            }
            let e = first_user.entry(key).or_insert((unit, 0));
            e.1 += 1;
            uf.union(e.0, unit);
        }
    };
    for (u, (_, f)) in knife_faces.iter().enumerate() {
        add_cycle(&f.outer, u as u32, &mut uf);
        for h in &f.holes {
            add_cycle(h, u as u32, &mut uf);
        }
    }
    for (j, &t) in whole.iter().enumerate() {
        let cyc = knife.triangles[t as usize].map(|v| kbase + v);
        add_cycle(&cyc, (knife_faces.len() + j) as u32, &mut uf);
    }
    // Per region: what its faces say, and whether it reaches the knife's border.
    #[derive(Default)]
    struct Votes {
        inside: bool,
        outside: bool,
        open: bool,
        border: bool,
        inward: bool,
    }
    let mut region: HashMap<u32, Votes> = HashMap::new();
    for (u, (kt, f)) in knife_faces.iter().enumerate() {
        let r = region.entry(uf.find(u as u32)).or_default();
        r.inward |= knife_inward[*kt as usize];
        r.open |= f.open;
        r.inside |= f.behind && !f.open;
        r.outside |= !f.behind && !f.open;
    }
    for (&_key, &(unit, count)) in &first_user {
        if count == 1
            && let Some(r) = region.get_mut(&uf.find(unit))
        {
            r.border = true;
        }
    }
    // Regions at an open curve are counted with it; an inside region
    // bounded by the knife's border as well is counted here.
    let mut capped: Vec<(u32, bool)> = Vec::new();
    for (&root, r) in &region {
        if r.inside && !r.outside && !r.border && !r.open {
            capped.push((root, r.inward));
        } else if r.inside && !r.open {
            out.curves_open += 1;
        }
    }
    capped.sort_unstable();
    out.regions_capped = capped.len();
    // Whether unit `u` is in a cap, and whether that cap faces inward.
    let mut cap_of = |u: u32| {
        let root = uf.find(u);
        capped
            .binary_search_by_key(&root, |c| c.0)
            .ok()
            .map(|i| capped[i].1)
    };
    let oriented = |t: [u32; 3], inward: bool| if inward { [t[0], t[2], t[1]] } else { t };
    let mut knife_id: HashMap<u32, u32> = HashMap::new();
    let mut remap = |v: u32, extra: &mut Vec<Vec3>| -> u32 {
        if v < kbase {
            return v;
        }
        *knife_id.entry(v).or_insert_with(|| {
            extra.push(knife.positions[(v - kbase) as usize]);
            kbase + extra.len() as u32 - 1
        })
    };
    let mut caps = Vec::new();
    for (u, (kt, f)) in knife_faces.iter().enumerate() {
        if let Some(inward) = cap_of(u as u32) {
            for t in triangulate_face(f, &pos, normal(knife, *kt)) {
                caps.push(oriented(t, inward).map(|v| remap(v, &mut out.extra_points)));
            }
        }
    }
    for (j, &t) in whole.iter().enumerate() {
        if let Some(inward) = cap_of((knife_faces.len() + j) as u32) {
            let cyc = knife.triangles[t as usize].map(|v| kbase + v);
            caps.push(oriented(cyc, inward).map(|v| remap(v, &mut out.extra_points)));
        }
    }
    out.caps = caps;
    Ok(out)
}
