//! Splitting one triangle along its cut: takes its corners, the cut points
//! on its edges and its segments (each with the other mesh's normal), and
//! returns its polygons, each labelled with its side ([`Face`]), and their
//! triangles in the triangle's own plane ([`triangulate_face`]).

use std::collections::HashMap;

use glam::{DVec2, DVec3};

use crate::cut::cap;
use crate::{Error, Result};

/// A polygon of a split triangle: outer cycle, holes, side label.
#[derive(Debug, Clone)]
pub(super) struct Face {
    pub(super) outer: Vec<u32>,
    pub(super) holes: Vec<Vec<u32>>,
    /// Behind the other mesh (surface: negative side; knife: inside the solid).
    pub(super) behind: bool,
    /// Holds an open end of the cut curve (knife triangles only, where the
    /// surface's own border crosses them): on both sides, never a cap.
    pub(super) open: bool,
}

/// One triangle to split: corner ids and positions, cut points on each
/// edge `(c_i, c_i+1)`, and segments `(a, b, other triangle's normal)`.
pub(super) struct ToSplit<'a> {
    pub(super) corners: [u32; 3],
    pub(super) edge_points: [Vec<u32>; 3],
    pub(super) segments: Vec<(u32, u32, DVec3)>,
    pub(super) pos: &'a dyn Fn(u32) -> DVec3,
    pub(super) what: &'a str,
    /// Whether the cut curve may end inside (else an error).
    pub(super) open_ends: bool,
}

impl ToSplit<'_> {
    fn err(&self, why: &'static str) -> Error {
        crate::Refusal::CutCurve {
            triangle: self.what.to_string(),
            problem: why,
        }
        .into()
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
    pub(super) fn faces(self) -> Result<Vec<Face>> {
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
    cap::point_in_ring(cyc.len(), |i| cyc[i], q)
}

/// Triangles of a face (ids of its cycles), oriented like its triangle.
pub(super) fn triangulate_face(
    f: &Face,
    pos: &dyn Fn(u32) -> DVec3,
    n_own: DVec3,
) -> Vec<[u32; 3]> {
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
