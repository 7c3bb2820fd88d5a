//! Caps: closing a cut with the knife surface (beyond the seed). Takes the
//! cut loops' points and the prepared knife, and returns the cap triangles
//! (ids `n_v + point`, oriented for the negative side), appending a sphere
//! cap's own vertices to the points ([`make_caps`]). Loops in [`loops`],
//! plane triangulation in [`triangulate`], sphere refinement and repair in
//! [`sphere`].
//!
//! The cut segments, directed as the negative side's triangles use them
//! and reversed, chain into loops. Loops are mapped to a plane (the knife
//! plane; for a sphere a stereographic projection from the pole opposite
//! the loops), where outer loops run counter-clockwise and holes clockwise;
//! each outer loop with the holes it contains is triangulated by ear
//! clipping after bridging the holes in. The same triangles close the
//! negative pieces (as is) and the positive pieces (reversed), so the cap
//! adds no volume: the pieces' volumes add up to the original's.
//!
//! Plane caps are flat. Sphere caps follow the sphere: the loop
//! triangulation (made in the stereographic plane, which is conformal) is
//! refined by bisecting interior edges at the sphere point over their
//! planar midpoint until each is shorter than [`sphere_max_edge`] (chord
//! error below [`SPHERE_CHORD_ERROR`]·r) or than 1.2 times the longest
//! loop edge, whichever is longer; loop edges are never split, so both sides
//! still share them. Lawson flips before and after every pass keep the
//! interior edges Delaunay in that plane, so no slivers are refined. Where
//! the surface meets the sphere at a grazing angle, the cap triangles that
//! cross it (exact test) are bisected further ([`repair_on_sphere`]).

mod loops;
mod sphere;
mod triangulate;

use glam::{DVec2, DVec3, Vec3};

use super::CutStats;
use super::knife::{Kind, PreparedKnife, SPHERE_CHORD_ERROR};
use crate::{Error, Result};
pub(super) use loops::loops;
pub(crate) use sphere::CutSurface;
use sphere::{
    CAP_REPAIR_ROUNDS, SphereCapCheck, refine_on_sphere, repair_on_sphere, sphere_max_edge,
};
use triangulate::nests_as_cap;
pub(super) use triangulate::{point_in_ring, triangulate};

/// Maps points to the cap plane.
#[derive(Debug, Clone, Copy)]
pub enum Projection {
    /// Orthonormal `u, v` with `u × v` = the cap's outward normal for the
    /// negative side.
    Plane { origin: DVec3, u: DVec3, v: DVec3 },
    /// Stereographic from the pole `c − r·d`, plane basis `u × v = d`.
    Sphere {
        c: DVec3,
        r: f64,
        d: DVec3,
        u: DVec3,
        v: DVec3,
    },
}

/// Two unit vectors completing `n` to a right-handed frame (`u × v = n`).
pub fn frame(n: DVec3) -> (DVec3, DVec3) {
    let u = n.any_orthonormal_vector();
    (u, n.cross(u))
}

impl Projection {
    /// The point of the sphere whose image is `q` (inverse stereographic
    /// projection); `None` for the plane projection.
    pub fn unapply(&self, q: DVec2) -> Option<DVec3> {
        match *self {
            Projection::Plane { .. } => None,
            Projection::Sphere { c, r, d, u, v } => {
                let s = q.length_squared();
                let w = (u * (2.0 * q.x) + v * (2.0 * q.y) + d * (1.0 - s)) / (1.0 + s);
                Some(c + w * r)
            }
        }
    }

    /// The 2-D image of `p`; `None` at the projection pole.
    pub fn apply(&self, p: DVec3) -> Option<DVec2> {
        match *self {
            Projection::Plane { origin, u, v } => {
                Some(DVec2::new(u.dot(p - origin), v.dot(p - origin)))
            }
            Projection::Sphere { c, r, d, u, v } => {
                let w = (p - c) / r;
                let den = 1.0 + w.dot(d);
                (den > 1e-9).then(|| DVec2::new(w.dot(u) / den, w.dot(v) / den))
            }
        }
    }
}

/// Cap triangles (vertex ids `n_v + point id`, oriented for the negative
/// side); a sphere cap's own vertices are appended to `points`.
///
/// A sphere cap is repaired against `surface` for at most
/// [`CAP_REPAIR_ROUNDS`] rounds (counted in `stats`, with the crossings left).
pub(super) fn make_caps(
    loops: &[Vec<u32>],
    points: &mut Vec<Vec3>,
    n_v: u32,
    k: &PreparedKnife<'_>,
    surface: &CutSurface<'_>,
    stats: &mut CutStats,
) -> Result<Vec<[u32; 3]>> {
    let pos = |v: u32| points[(v - n_v) as usize].as_dvec3();
    // Loop k's points are `ids[start_k..start_k + len_k]`, in loop order.
    let ids: Vec<u32> = loops.iter().flatten().copied().collect();
    let mut next = 0;
    let index_loops: Vec<Vec<usize>> = loops
        .iter()
        .map(|lp| {
            next += lp.len();
            (next - lp.len()..next).collect()
        })
        .collect();
    let project = |proj: &Projection| -> Option<Vec<DVec2>> {
        ids.iter().map(|&v| proj.apply(pos(v))).collect()
    };
    let (projection, mut pts) = match &k.kind {
        Kind::Plane { p, n } | Kind::Rect { p, n, .. } => {
            let (u, v) = frame(*n);
            let proj = Projection::Plane { origin: *p, u, v };
            let pts = project(&proj).expect("a plane projects every point");
            (proj, pts)
        }
        Kind::Sphere { c, r } => {
            // The cap lies left of its loops seen from outside: their
            // summed vector area (about the centre) points into it, also
            // for a loop on a great circle or a cap beyond a hemisphere.
            let area: DVec3 = loops
                .iter()
                .map(|lp| {
                    (0..lp.len())
                        .map(|i| (pos(lp[i]) - *c).cross(pos(lp[(i + 1) % lp.len()]) - *c))
                        .sum::<DVec3>()
                })
                .sum();
            let mean: DVec3 = loops
                .iter()
                .flatten()
                .map(|&v| (pos(v) - *c).normalize_or_zero())
                .sum();
            // With many loops the summed area can point into a region of
            // the sphere outside the solid while the pole opposite it lies
            // in a cap; then the loops do not nest as a cap in the plane and
            // the next direction is tried (the axes and diagonals).
            let preferred = area.try_normalize().or_else(|| mean.try_normalize());
            let fallback = (0..27).filter(|&i| i != 13).map(|i| {
                DVec3::new(
                    (i % 3) as f64 - 1.0,
                    (i / 3 % 3) as f64 - 1.0,
                    (i / 9) as f64 - 1.0,
                )
                .normalize()
            });
            // Then poles just right of each loop's first edge, outside its
            // cap (the cap lies left of its loops seen from outside).
            let beside = loops.iter().map(|lp| {
                let (a, b) = (pos(lp[0]), pos(lp[1 % lp.len()]));
                let m = (a + b) * 0.5 - *c;
                let right = (b - a).cross(m).normalize_or_zero();
                let p = m.normalize_or_zero() + right * 0.01 * ((b - a).length() / *r).max(1e-6);
                -p.normalize_or_zero()
            });
            preferred
                .into_iter()
                .chain(fallback)
                .chain(beside)
                .map(|d| {
                    let (u, v) = frame(d);
                    Projection::Sphere {
                        c: *c,
                        r: *r,
                        d,
                        u,
                        v,
                    }
                })
                .find_map(|proj| {
                    project(&proj)
                        .filter(|pts| nests_as_cap(pts, &index_loops))
                        .map(|pts| (proj, pts))
                })
                .ok_or_else(|| Error::from(crate::Refusal::NoCapPole))?
        }
        Kind::Mesh { .. } => return Ok(Vec::new()),
    };
    let mut tris = triangulate(&pts, &index_loops);
    if let Kind::Sphere { r, .. } = &k.kind {
        let mut pos3: Vec<DVec3> = ids.iter().map(|&v| pos(v)).collect();
        // Enough for a whole sphere at the chord bound, with room to spare.
        let max_triangles = 64 * (1.0 / SPHERE_CHORD_ERROR) as usize + 4 * tris.len();
        refine_on_sphere(
            &mut tris,
            &mut pts,
            &mut pos3,
            &projection,
            sphere_max_edge(*r),
            max_triangles,
        );
        let mut check = SphereCapCheck {
            surface,
            first_new: points.len(),
            points,
            ids: &ids,
            n_v,
        };
        let (rounds, left) = repair_on_sphere(
            &mut tris,
            &mut pts,
            &mut pos3,
            &projection,
            max_triangles,
            CAP_REPAIR_ROUNDS,
            &mut check,
        );
        stats.cap_repair_rounds += rounds;
        stats.cap_crossings += left;
        check.place(&pos3);
        return Ok(tris.iter().map(|t| check.global(t)).collect());
    }
    Ok(tris.into_iter().map(|t| t.map(|i| ids[i])).collect())
}
