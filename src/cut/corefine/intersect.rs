//! Exact intersection of the surface and a triangulated knife: takes the
//! [`Pair`] (surface, knife, the knife's forest) and surface triangle ids,
//! and returns per triangle its segments (knife triangle, two cut-point
//! origins); then each cut point's position and side.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::{PointOrigin, TriangleSegments};
use crate::foundation::{Aabb, Forest};
use crate::{Error, Result, TriMesh};

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

pub(super) fn canon(a: u32, b: u32) -> ((u32, u32), i8) {
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
        Error::from(crate::Refusal::KnifeContact {
            knife_triangle: kt,
            surface_triangle: st,
        })
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
