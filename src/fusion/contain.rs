//! Exact check that C contains points (the vertices of A and B), for a C
//! that is star-shaped about H.
//!
//! For a point p, the ray from H towards p is cast against C; it hits one
//! triangle T. Exact signs (crate `robust`) then confirm that the line H–p
//! passes strictly inside T's three edges, and p's side of T's plane
//! decides: in front of T (where H is behind) means p lies beyond C's
//! surface, outside. When the confirmation fails (the line grazes an edge
//! of T, or the cast missed), the general exact test
//! [`crate::mesh::point_side`] decides instead.

use rayon::prelude::*;

use crate::foundation::exact::orient3d_sign as o3;
use crate::mesh::{Side, TriMesh, point_side};
use crate::ray_cast::RayCaster;
use crate::{Error, Result};

/// A point of A or B outside C, with the triangle of C its ray from H hits
/// (`u32::MAX` when the general test decided).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outside {
    pub point: usize,
    pub triangle: u32,
}

/// The points of `points` outside `c` (cast by `cc`, star-shaped about
/// `center`); points on C's surface count as contained.
pub fn outside(
    c: &TriMesh,
    cc: &RayCaster,
    center: glam::Vec3,
    points: &[glam::Vec3],
) -> Result<Vec<Outside>> {
    let dirs: Vec<[f32; 4]> = points
        .iter()
        .map(|p| {
            let d = *p - center;
            [d.x, d.y, d.z, 0.0]
        })
        .collect();
    let hits = cc.cast(center, &dirs)?;
    let h = center.as_dvec3().to_array();
    let corner = |v: u32| c.positions[v as usize].as_dvec3().to_array();
    let decided: Vec<Result<Option<Outside>>> = points
        .par_iter()
        .zip(&hits)
        .enumerate()
        .map(|(i, (p, hit))| {
            let q = p.as_dvec3().to_array();
            if q == h {
                return Ok(None);
            }
            if hit.count == 1 {
                let t = c.triangles[hit.near_tri as usize].map(corner);
                let e = [
                    o3(h, q, t[0], t[1]),
                    o3(h, q, t[1], t[2]),
                    o3(h, q, t[2], t[0]),
                ];
                let behind = o3(t[0], t[1], t[2], h);
                if e[0] != 0 && e[0] == e[1] && e[1] == e[2] && behind == -1 {
                    let out = o3(t[0], t[1], t[2], q) == 1;
                    return Ok(out.then_some(Outside {
                        point: i,
                        triangle: hit.near_tri,
                    }));
                }
            }
            match point_side(c, q) {
                Some(Side::Outside) => Ok(Some(Outside {
                    point: i,
                    triangle: u32::MAX,
                })),
                Some(_) => Ok(None),
                None => Err(Error::Internal(format!(
                    "fusion: no exact ray from point {i} avoids C's edges"
                ))),
            }
        })
        .collect();
    decided.into_iter().filter_map(Result::transpose).collect()
}
