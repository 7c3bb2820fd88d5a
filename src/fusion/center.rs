//! Finding a fusion centre H: a point of A ∩ B from which both meshes are
//! star-shaped.
//!
//! A closed mesh is star-shaped about x (every ray from x crosses it once)
//! exactly when x lies in its *kernel*: behind the plane of every face. So
//! a common centre is a point behind every face plane of A and of B, and
//! the deepest one solves a linear programme in (x, s):
//!
//! maximise s subject to n̂_f · x + s ≤ n̂_f · a_f for every face f,
//!
//! n̂_f the unit outward normal and a_f a corner (Chebyshev centre of the
//! two kernels' intersection; crate `microlp`). s > 0 gives H with
//! clearance s from every face plane; s ≤ 0 proves that no centre exists
//! (the kernels do not meet, or only in a flat piece), and the refusal says
//! by how much. The fusion then checks every ray it casts from H.
//!
//! Where one mesh has no kernel point in A ∩ B, a fusion can still go on
//! (seed 001 §2.6.2, [`super::layered`]) from the deepest point of the
//! other's kernel, if that lies inside the first ([`find_center_in`]).

use glam::DVec3;
use microlp::{ComparisonOp, OptimizationDirection, Problem};

use crate::mesh::{Side, TriMesh, point_side};
use crate::{Error, Refusal, Result};

/// What the search found.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Found {
    pub center: [f64; 3],
    /// Least distance from H to a face plane of A or B.
    pub clearance: f64,
    /// Face planes in the programme.
    pub planes: usize,
}

/// The deepest common point of A's and B's kernels (see the module docs).
///
/// Errors: a refusal when the meshes' boxes do not overlap or the kernels
/// do not meet; the solver's failure as an internal error.
pub fn find_center(a: &TriMesh, b: &TriMesh) -> Result<Found> {
    let (h, depth, planes) = deepest(&[a, b], overlap(a, b)?)?;
    if depth.is_nan() || depth <= 0.0 {
        return Err(Refusal::NoStarCenter(format!(
            "the kernels of A and B (the points from which each is star-shaped) do not meet: \
             the best point, ({:.6}, {:.6}, {:.6}), lies {:.3e} units in front of a face plane",
            h.x, h.y, h.z, -depth
        ))
        .into());
    }
    Ok(Found {
        center: h.to_array(),
        clearance: depth,
        planes,
    })
}

/// A centre for fusing `other`, which need not be star-shaped, with
/// `star`: the deepest point of `star`'s kernel within the boxes' overlap,
/// if it lies inside `other` (exact test). `names` name them in the
/// refusal: `[star, other]`.
///
/// Errors: a refusal when the boxes do not overlap, `star`'s kernel is
/// empty there, or its deepest point is not inside `other`.
pub fn find_center_in(star: &TriMesh, other: &TriMesh, names: [&str; 2]) -> Result<Found> {
    let (h, depth, planes) = deepest(&[star], overlap(star, other)?)?;
    let [s, o] = names;
    if depth.is_nan() || depth <= 0.0 {
        return Err(Refusal::NoStarCenter(format!(
            "neither mesh has a kernel point in A ∩ B: the best point of {s}'s kernel, \
             ({:.6}, {:.6}, {:.6}), lies {:.3e} units in front of one of its face planes",
            h.x, h.y, h.z, -depth
        ))
        .into());
    }
    if point_side(other, h.to_array()) != Some(Side::Inside) {
        return Err(Refusal::NoStarCenter(format!(
            "the deepest point of {s}'s kernel, ({:.6}, {:.6}, {:.6}), is not inside {o}",
            h.x, h.y, h.z
        ))
        .into());
    }
    Ok(Found {
        center: h.to_array(),
        clearance: depth,
        planes,
    })
}

/// The overlap of the meshes' bounding boxes.
fn overlap(a: &TriMesh, b: &TriMesh) -> Result<(DVec3, DVec3)> {
    let (Some((alo, ahi)), Some((blo, bhi))) = (a.bounds(), b.bounds()) else {
        return Err(Refusal::NoStarCenter("a mesh is empty".into()).into());
    };
    let (lo, hi) = (alo.max(blo).as_dvec3(), ahi.min(bhi).as_dvec3());
    if lo.cmpgt(hi).any() {
        return Err(Refusal::NoStarCenter(
            "the bounding boxes of A and B do not overlap, so A ∩ B is empty".into(),
        )
        .into());
    }
    Ok((lo, hi))
}

/// The deepest point of the meshes' kernels within the box `(lo, hi)`:
/// the point, its least distance to a face plane (≤ 0: the kernels do not
/// meet there) and the planes in the programme.
fn deepest(meshes: &[&TriMesh], (lo, hi): (DVec3, DVec3)) -> Result<(DVec3, f64, usize)> {
    // Coordinates about the box's centre in units of its diagonal.
    let origin = (lo + hi) * 0.5;
    let scale = (hi - lo).length().max(f64::MIN_POSITIVE);
    let mut lp = Problem::new(OptimizationDirection::Maximize);
    let half = (hi - lo) * 0.5 / scale;
    let x = [0, 1, 2].map(|k| lp.add_var(0.0, (-half[k], half[k])));
    // s is free below (a point far in front of some plane is still a
    // feasible, if useless, answer) and at most the box's diagonal.
    let s = lp.add_var(1.0, (f64::NEG_INFINITY, 1.0));
    let mut planes = 0;
    for mesh in meshes {
        let outward = if mesh.signed_volume() < 0.0 {
            -1.0
        } else {
            1.0
        };
        for t in &mesh.triangles {
            let [p, q, r] = t.map(|i| (mesh.positions[i as usize].as_dvec3() - origin) / scale);
            let n = (q - p).cross(r - p) * outward;
            let len = n.length();
            if len.is_nan() || len <= 0.0 {
                continue;
            }
            let n = n / len;
            lp.add_constraint(
                [(x[0], n.x), (x[1], n.y), (x[2], n.z), (s, 1.0)],
                ComparisonOp::Le,
                n.dot(p),
            );
            planes += 1;
        }
    }
    let solved = lp.solve().map_err(|e| {
        Error::Internal(format!("fusion centre: the linear programme failed: {e:?}"))
    })?;
    let solution = solved.solution().ok_or_else(|| {
        Error::Internal("fusion centre: the linear programme was interrupted".into())
    })?;
    let depth = solution.var_value(s) * scale;
    let h = origin
        + DVec3::new(
            solution.var_value(x[0]),
            solution.var_value(x[1]),
            solution.var_value(x[2]),
        ) * scale;
    Ok((h, depth, planes))
}
