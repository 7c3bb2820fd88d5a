//! Splitting and assembly: takes a mesh, its [`Located`] cut and the
//! prepared knife; splits every crossed triangle (an analytic knife here,
//! a triangulated one in [`super::corefine`]), adds the caps, and returns
//! the [`CutResult`]: the regrouped pieces with their sides and stats.

use std::time::Instant;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::cap::{self, CutSurface, make_caps};
use super::corefine;
use super::knife::{Kind, PreparedKnife};
use super::regroup::{Regroup, Sub, chunk_bounds};
use super::{CutOptions, CutResult, CutStats, Located, Side};
use crate::foundation::Forest;
use crate::{Result, TriMesh};

/// Splits, regroups and caps (shared by the tree and the scan). The tree's
/// cut passes its forest: sphere caps then find the surface near them
/// through it, and a surface known to be closed and wound outward
/// ([`Forest::closed_outward`]) needs no orientation analysis.
pub(super) fn assemble(
    mesh: &TriMesh,
    located: Located,
    k: &PreparedKnife<'_>,
    opts: &CutOptions,
    forest: Option<&Forest>,
) -> Result<CutResult> {
    let t0 = Instant::now();
    let mut stats = located.stats.clone();
    let Split {
        subs,
        mut glued,
        points,
        caps: cap_tris,
    } = match &k.kind {
        Kind::Mesh {
            mesh: knife,
            forest: knife_forest,
        } => {
            let pair = corefine::Pair {
                surface: mesh,
                knife,
                forest: knife_forest,
                margin: k.margin(),
            };
            let ms = corefine::split(
                &pair,
                &located.triangles,
                &located.points,
                &located.origins,
                &located.segments,
                opts.cap,
                forest.is_some_and(|f| f.closed_outward),
            )?;
            stats.loops_capped = ms.regions_capped;
            stats.curves_open = ms.curves_open;
            let mut points = located.points.clone();
            points.extend(ms.extra_points);
            Split {
                subs: ms
                    .subs
                    .into_iter()
                    .map(|s| {
                        s.into_iter()
                            .map(|(v, neg)| Sub { v, side: Some(neg) })
                            .collect()
                    })
                    .collect(),
                glued: Vec::new(),
                points,
                caps: ms.caps,
            }
        }
        _ => split_analytic(mesh, &located, k, opts, forest, &mut stats)?,
    };
    glued.resize(points.len(), false);
    // Side of each input vertex for an analytic knife (an unsplit
    // triangle's side is its first vertex's).
    let negative: Vec<bool> = match k.analytic() {
        Some(a) => (mesh.positions.par_iter())
            .map(|q| a.eval(q.as_dvec3()) < 0.0)
            .collect(),
        None => Vec::new(),
    };
    let (pieces, piece_side) = Regroup {
        mesh,
        located: &located,
        subs: &subs,
        glued: &glued,
        caps: &cap_tris,
        points: &points,
        negative,
        bounds: chunk_bounds(mesh.triangles.len(), &located.triangles),
    }
    .pieces();
    // A piece a closed mesh knife never reaches lies wholly inside or
    // outside it: its winding number says which.
    let untouched_side = match &k.kind {
        Kind::Mesh { mesh: knife, .. } => {
            let topo = crate::mesh::Topology::of(knife);
            let outward = topo.signed_volume >= 0.0;
            topo.closed.then_some(move |piece: &TriMesh| {
                let q = piece.positions[0].as_dvec3();
                let inside = winding_number(knife, q).abs() > 0.5;
                if inside == outward {
                    Side::Negative
                } else {
                    Side::Positive
                }
            })
        }
        _ => None,
    };
    let sides = piece_side
        .iter()
        .zip(&pieces)
        .map(|(&(n, p), piece)| match (n, p) {
            (true, false) => Side::Negative,
            (false, true) => Side::Positive,
            (false, false) => untouched_side.as_ref().map_or(Side::Both, |f| f(piece)),
            _ => Side::Both,
        })
        .collect();
    stats.assemble_seconds = t0.elapsed().as_secs_f64();
    Ok(CutResult {
        pieces,
        sides,
        stats,
    })
}

/// Generalised winding number of `m` about `q` (Van Oosterom–Strackee solid
/// angles summed over the triangles, / 4π): ±1 inside a closed surface
/// (+ when wound outward), 0 outside.
fn winding_number(m: &TriMesh, q: DVec3) -> f64 {
    let omega: f64 = m
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| m.positions[v as usize].as_dvec3() - q);
            let (la, lb, lc) = (a.length(), b.length(), c.length());
            let det = a.dot(b.cross(c));
            let div = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
            2.0 * det.atan2(div)
        })
        .sum();
    omega / (4.0 * std::f64::consts::PI)
}

/// A split before regrouping: sub-triangles per crossed triangle, glued
/// cut vertices, all new vertices (cut points, then cap vertices) and the
/// caps (ids `n_v + point`, oriented for the negative side).
struct Split {
    subs: Vec<Vec<Sub>>,
    glued: Vec<bool>,
    points: Vec<Vec3>,
    caps: Vec<[u32; 3]>,
}

/// The split by an analytic knife (one cut vertex per crossed edge).
fn split_analytic(
    mesh: &TriMesh,
    located: &Located,
    k: &PreparedKnife<'_>,
    opts: &CutOptions,
    forest: Option<&Forest>,
    stats: &mut CutStats,
) -> Result<Split> {
    let n_v = mesh.positions.len() as u32;
    let n_c = located.points.len() as u32;
    let side = k.analytic().expect("an analytic knife");
    // Sub-triangles of each crossed triangle.
    let mut subs: Vec<Vec<Sub>> = Vec::with_capacity(located.triangles.len());
    let mut glued = vec![false; n_c as usize];
    let mut segments: Vec<(u32, u32)> = Vec::new();
    for (&t, cuts) in located.triangles.iter().zip(&located.edge_cuts) {
        let tri = mesh.triangles[t as usize];
        let n_cut = cuts.iter().filter(|&&c| c != u32::MAX).count();
        let cv = |e: usize| n_v + cuts[e];
        let mut s = Vec::with_capacity(4);
        match n_cut {
            2 => {
                // Rotate so edges 0 (L→B) and 2 (C→L) are the crossed ones.
                let r = (0..3)
                    .find(|&r| cuts[r] != u32::MAX && cuts[(r + 2) % 3] != u32::MAX)
                    .unwrap_or(0);
                let (l, b, c) = (tri[r], tri[(r + 1) % 3], tri[(r + 2) % 3]);
                let (pp, qq) = (cv(r), cv((r + 2) % 3));
                // L's side, as `finish_locate` evaluated it (a cut vertex
                // may stand for several edges once coincident ones join).
                let l_neg = side.eval(mesh.positions[l as usize].as_dvec3()) < 0.0;
                s.push(Sub {
                    v: [l, pp, qq],
                    side: Some(l_neg),
                });
                s.push(Sub {
                    v: [pp, b, c],
                    side: Some(!l_neg),
                });
                s.push(Sub {
                    v: [pp, c, qq],
                    side: Some(!l_neg),
                });
                // Both crossings at one vertex: the curve only touches it.
                if pp != qq {
                    segments.push(if l_neg { (pp, qq) } else { (qq, pp) });
                }
            }
            1 => {
                stats.triangles_partial += 1;
                let r = (0..3).find(|&r| cuts[r] != u32::MAX).unwrap_or(0);
                let (x, y, z) = (tri[r], tri[(r + 1) % 3], tri[(r + 2) % 3]);
                glued[cuts[r] as usize] = true;
                s.push(Sub {
                    v: [x, cv(r), z],
                    side: None,
                });
                s.push(Sub {
                    v: [cv(r), y, z],
                    side: None,
                });
            }
            _ => {
                stats.triangles_partial += 1;
                let (pp, qq, rr) = (cv(0), cv(1), cv(2));
                for c in cuts {
                    glued[*c as usize] = true;
                }
                s.extend(
                    [
                        [tri[0], pp, rr],
                        [pp, tri[1], qq],
                        [rr, qq, tri[2]],
                        [pp, qq, rr],
                    ]
                    .map(|v| Sub { v, side: None }),
                );
            }
        }
        subs.push(s);
    }
    // Caps; a sphere cap adds its own vertices after the cut vertices.
    let mut points = located.points.clone();
    let mut cap_tris: Vec<[u32; 3]> = Vec::new();
    if opts.cap {
        let (mut loops, open) = cap::loops(&segments);
        stats.curves_open = open;
        stats.loops_capped = loops.len();
        // A sphere cap is placed by which side of its loops it lies on, so a
        // surface wound inward is capped as its outward twin, then turned
        // back (planes need no such care: their caps fill the loops).
        let inward = matches!(k.kind, Kind::Sphere { .. }) && !loops.is_empty() && {
            let front = corefine::inward_triangles(mesh, forest.is_some_and(|f| f.closed_outward));
            located.triangles.iter().any(|&t| front[t as usize])
        };
        if inward {
            loops.iter_mut().for_each(|lp| lp.reverse());
        }
        if !loops.is_empty() {
            let surface = CutSurface {
                mesh,
                forest,
                located,
                subs: &subs,
            };
            cap_tris = make_caps(&loops, &mut points, n_v, k, &surface, stats)?;
        }
        if inward {
            cap_tris.iter_mut().for_each(|t| t.swap(1, 2));
        }
    }
    Ok(Split {
        subs,
        glued,
        points,
        caps: cap_tris,
    })
}
