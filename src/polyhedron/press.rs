//! Face selection for pressing-in (Def. PR, seed §4.4.1, criteria (i)–(iii)).
//!
//! A face F of the polyhedron P is marked for pressing-in towards a ZKH S'
//! when some voxel `c³ ∈ S'` and one of its corners `c⁰` satisfy
//! - (i) F is visible from `c⁰` (`s > 0`), and (ii) the orthogonal
//!   projection of `c³` onto F's plane lies in F (closed polygon) — so the
//!   segment `c⁰c³` crosses F; or
//! - (i) `c⁰` is coplanar with F and (iii) lies strictly inside F, not on
//!   its boundary (faces that S' touches only along an edge or at a vertex
//!   are not marked).
//!
//! The projection test is exact without computing the (rational)
//! projection: for an edge `a → b` of F with normal `n`,
//! `((b − a) × (q − a))·n = ((b − a) × (c³ − a))·n` because the projection
//! moves `c³` along `n` and `((b − a) × n)·n = 0`.

use crate::foundation::exact::{cross_wide, sub};
use crate::hull::{ConvexHull, HullFace};
use crate::voxel::{voxel_centre, voxel_corner};

use super::Zkh;

/// `((b − a) × (p − a))·n` in `i128`.
fn edge_side(a: [i64; 3], b: [i64; 3], p: [i64; 3], n: [i64; 3]) -> i128 {
    let c = cross_wide(sub(b, a), sub(p, a));
    c[0] * i128::from(n[0]) + c[1] * i128::from(n[1]) + c[2] * i128::from(n[2])
}

/// Minimum over F's edges of the edge test (`≥ 0`: the projection of `p`
/// lies in the closed face; `> 0`: strictly inside).
fn min_edge_side(hull: &ConvexHull, face: &HullFace, p: [i64; 3]) -> i128 {
    let k = face.vertices.len();
    (0..k)
        .map(|i| {
            let a = hull.vertices()[face.vertices[i] as usize];
            let b = hull.vertices()[face.vertices[(i + 1) % k] as usize];
            edge_side(a, b, p, face.plane.normal)
        })
        .min()
        .unwrap_or(i128::MIN)
}

/// Faces of `hull` to press in towards `zkh` (indices into
/// [`ConvexHull::faces`], ascending). Empty for a cavity.
///
/// Cost: one plane test per (face, voxel); corners are tested only for
/// voxels whose centre lies within `|n|₁` of the face's plane, since a
/// corner differs from its centre by `(±1, ±1, ±1)` in combinatorial
/// coordinates.
pub fn faces_to_press(hull: &ConvexHull, zkh: &Zkh) -> Vec<u32> {
    let voxels: Vec<[i64; 3]> = zkh.object.voxels().collect();
    let marked = |face: &HullFace| {
        let reach = face.plane.normal.iter().map(|c| c.abs()).sum::<i64>();
        voxels.iter().any(|&v| {
            let c3 = voxel_centre(v);
            if face.plane.side(c3) < -reach {
                return false;
            }
            (0..8i64).any(|o| {
                let c0 = voxel_corner([v[0] + (o & 1), v[1] + (o >> 1 & 1), v[2] + (o >> 2 & 1)]);
                match face.plane.side(c0) {
                    s if s > 0 => min_edge_side(hull, face, c3) >= 0,
                    0 => min_edge_side(hull, face, c0) > 0,
                    _ => false,
                }
            })
        })
    };
    (0..hull.faces().len() as u32)
        .filter(|&f| marked(&hull.faces()[f as usize]))
        .collect()
}
