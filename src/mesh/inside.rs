//! Exact point-in-mesh test for closed meshes.
//!
//! A point is on the surface when it lies in a closed triangle (exact
//! `orient3d` = 0, then `orient2d` in the triangle's dominant coordinate
//! plane). Otherwise a segment from the point to a far point is crossed
//! against every triangle with exact signs (`foundation::exact`): a crossing has
//! the segment's ends strictly on both sides of the triangle's plane and
//! the line strictly inside all three edges. When a sign that decides a
//! crossing is 0 (the segment grazes an edge, a vertex or a plane), the
//! direction is degenerate and the next of a fixed list is tried. The
//! parity of the crossings gives inside or outside. There is no tolerance;
//! the cost is one pass over the triangles per point (a bounding-box
//! filter first), meant for checks, not for bulk queries.

use crate::foundation::exact::{orient2d_sign as o2, orient3d_sign as o3};

use super::TriMesh;

/// Where a point lies relative to a closed mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Side {
    Inside,
    Outside,
    /// On a triangle (its closed point set).
    Surface,
}

/// Directions tried in turn (unit-free, chosen without symmetry).
const DIRECTIONS: [[f64; 3]; 8] = [
    [0.577_350_3, 0.707_206_8, 0.408_248_3],
    [-0.813_733_5, 0.469_846_3, 0.342_020_1],
    [0.267_261_2, -0.534_522_5, 0.801_783_7],
    [0.123_456_7, 0.890_123_4, -0.438_271_6],
    [-0.301_511_3, -0.904_534_0, 0.301_511_3],
    [0.912_870_9, 0.182_574_2, -0.365_148_4],
    [-0.447_213_6, 0.547_722_6, -0.707_306_8],
    [0.662_251_7, -0.331_125_8, -0.671_654_3],
];

/// Whether `p` (coplanar with triangle `t`) lies in the closed triangle.
fn in_closed_triangle(t: [[f64; 3]; 3], p: [f64; 3]) -> bool {
    // Project along the axis where the triangle's projection has an exact
    // non-zero orientation (the first such axis; a degenerate triangle has
    // none and contains nothing).
    for drop in 0..3 {
        let keep = |v: [f64; 3]| match drop {
            0 => [v[1], v[2]],
            1 => [v[2], v[0]],
            _ => [v[0], v[1]],
        };
        let [a, b, c] = t.map(keep);
        let s = o2(a, b, c);
        if s == 0 {
            continue;
        }
        let q = keep(p);
        return [o2(a, b, q), o2(b, c, q), o2(c, a, q)]
            .iter()
            .all(|&e| e == 0 || e == s);
    }
    false
}

/// Exact side of `p` with respect to the closed mesh `mesh` (see the module
/// docs). A mesh that is not closed gets an answer that depends on the
/// direction; `None` only when all eight directions are degenerate.
pub fn point_side(mesh: &TriMesh, p: [f64; 3]) -> Option<Side> {
    let corners = |t: &[u32; 3]| t.map(|v| mesh.positions[v as usize].as_dvec3().to_array());
    let (lo, hi) = mesh.bounds()?;
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    for t in &mesh.triangles {
        let c = corners(t);
        let inside_box = (0..3).all(|k| {
            let (mn, mx) = (
                c[0][k].min(c[1][k]).min(c[2][k]),
                c[0][k].max(c[1][k]).max(c[2][k]),
            );
            mn <= p[k] && p[k] <= mx
        });
        if inside_box && o3(c[0], c[1], c[2], p) == 0 && in_closed_triangle(c, p) {
            return Some(Side::Surface);
        }
    }
    let reach = 2.0 * ((hi - lo).length() + (glam::DVec3::from(p) - lo).length()) + 1.0;
    'directions: for d in DIRECTIONS {
        let q = [0, 1, 2].map(|k| p[k] + reach * d[k]);
        let (smin, smax) = (
            [0, 1, 2].map(|k| p[k].min(q[k])),
            [0, 1, 2].map(|k| p[k].max(q[k])),
        );
        let mut crossings = 0usize;
        for t in &mesh.triangles {
            let c = corners(t);
            if (0..3).any(|k| {
                c[0][k].max(c[1][k]).max(c[2][k]) < smin[k]
                    || c[0][k].min(c[1][k]).min(c[2][k]) > smax[k]
            }) {
                continue;
            }
            let (sp, sq) = (o3(c[0], c[1], c[2], p), o3(c[0], c[1], c[2], q));
            if sq == 0 {
                // The far point on the plane: the segment may end on the
                // triangle.
                continue 'directions;
            }
            if sp == 0 || sp == sq {
                // p on the plane but not on the triangle (checked above), or
                // both ends on one side: no crossing.
                continue;
            }
            let e = [
                o3(p, q, c[0], c[1]),
                o3(p, q, c[1], c[2]),
                o3(p, q, c[2], c[0]),
            ];
            if e.contains(&0) {
                if e.iter().all(|&s| s >= 0) || e.iter().all(|&s| s <= 0) {
                    // Through an edge or a vertex of this triangle.
                    continue 'directions;
                }
                continue;
            }
            if e[0] == e[1] && e[1] == e[2] {
                crossings += 1;
            }
        }
        return Some(if crossings % 2 == 1 {
            Side::Inside
        } else {
            Side::Outside
        });
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn cube() -> TriMesh {
        let p: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let t = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        TriMesh::new(p, t).unwrap()
    }

    #[test]
    fn cube_sides_are_exact() {
        let m = cube();
        assert_eq!(point_side(&m, [0.5, 0.5, 0.5]), Some(Side::Inside));
        assert_eq!(point_side(&m, [1.5, 0.5, 0.5]), Some(Side::Outside));
        // On a face, an edge, a corner, and one ulp off a face either way.
        assert_eq!(point_side(&m, [1.0, 0.5, 0.25]), Some(Side::Surface));
        assert_eq!(point_side(&m, [1.0, 1.0, 0.5]), Some(Side::Surface));
        assert_eq!(point_side(&m, [0.0, 0.0, 0.0]), Some(Side::Surface));
        let up = f64::from_bits(1.0f64.to_bits() + 1);
        let down = f64::from_bits(1.0f64.to_bits() - 1);
        assert_eq!(point_side(&m, [up, 0.5, 0.5]), Some(Side::Outside));
        assert_eq!(point_side(&m, [down, 0.5, 0.5]), Some(Side::Inside));
        // On the diagonal plane of a face split, inside: rays along the
        // split diagonals must still count once.
        assert_eq!(point_side(&m, [0.5, 0.5, 0.999_999]), Some(Side::Inside));
    }
}
