//! Exact predicates on two convex polyhedra (separating-axis tests):
//! disjoint interiors, common face area, separation; each takes two hulls
//! and returns a bool. Also this phase's `impl Polyhedron`: whether every
//! pair of sibling shells passes one.

use crate::foundation::exact::{cross_wide, sub};
use crate::hull::{ConvexHull, HullFace};

use super::Polyhedron;

impl Polyhedron {
    /// Whether all sibling polyhedra (dimension 3, same parent) have
    /// disjoint interiors (separating-axis theorem, exact).
    pub(super) fn siblings_disjoint(&self) -> bool {
        self.siblings_all(interiors_disjoint)
    }

    /// Whether all sibling polyhedra are separated: disjoint interiors and
    /// no face area in common (what the merged surface needs).
    pub(in crate::polyhedron) fn siblings_separated(&self) -> bool {
        self.siblings_all(separated)
    }

    fn siblings_all(&self, pair: fn(&ConvexHull, &ConvexHull) -> bool) -> bool {
        let mut by_parent: std::collections::BTreeMap<u32, Vec<&ConvexHull>> = Default::default();
        for s in &self.shells {
            if let (Some(p), Some(h)) = (s.parent, s.geometry.polytope())
                && !h.is_planar()
            {
                by_parent.entry(p).or_default().push(h);
            }
        }
        by_parent.values().all(|hulls| {
            (0..hulls.len()).all(|i| (i + 1..hulls.len()).all(|j| pair(hulls[i], hulls[j])))
        })
    }
}

/// Whether two convex polyhedra are *separated*: disjoint interiors and no
/// face area in common. Two touching polyhedra may share part of a plane
/// through opposite faces; where those polygons overlap with positive area
/// their edges can cross properly — and so can faces of their descendants
/// in that plane — at points that are not lattice points, which the
/// merged surface cannot represent. Separated siblings exclude this for
/// every pair of shells that do not nest: such a pair lies in two
/// different children of its lowest common ancestor, whose contact has
/// zero area in every plane.
pub(super) fn separated(a: &ConvexHull, b: &ConvexHull) -> bool {
    let (ba, bb) = (a.bbox(), b.bbox());
    if (0..3).any(|k| ba.1[k] < bb.0[k] || bb.1[k] < ba.0[k]) {
        return true;
    }
    interiors_disjoint(a, b) && !share_face_area(a, b)
}

/// Whether faces of `a` and `b` on one plane (opposite normals; normals
/// are primitive, so equal planes compare equal) overlap with positive
/// area: no edge line of either polygon separates them (2-D
/// separating-axis test, touching counts as separated; exact in `i128`).
fn share_face_area(a: &ConvexHull, b: &ConvexHull) -> bool {
    let points = |h: &ConvexHull, f: &HullFace| -> Vec<[i64; 3]> {
        f.vertices
            .iter()
            .map(|&v| h.vertices()[v as usize])
            .collect()
    };
    // An edge p → q of a face listed counter-clockwise about its normal n
    // has the face on the side of n × (q − p).
    let edge_separates = |n: [i64; 3], poly: &[[i64; 3]], other: &[[i64; 3]]| {
        (0..poly.len()).any(|i| {
            let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
            let inward = cross_wide(n, sub(q, p));
            other.iter().all(|&x| {
                let w = sub(x, p).map(i128::from);
                inward[0] * w[0] + inward[1] * w[1] + inward[2] * w[2] <= 0
            })
        })
    };
    a.faces().iter().any(|fa| {
        let opposite = (fa.plane.normal.map(|c| -c), -fa.plane.offset);
        b.faces()
            .iter()
            .filter(|fb| (fb.plane.normal, fb.plane.offset) == opposite)
            .any(|fb| {
                let (pa, pb) = (points(a, fa), points(b, fb));
                !edge_separates(fa.plane.normal, &pa, &pb)
                    && !edge_separates(fb.plane.normal, &pb, &pa)
            })
    })
}

/// Whether two convex polyhedra have disjoint interiors, exactly: a
/// separating plane exists among the face planes of either and the planes
/// spanned by an edge direction of each (separating-axis theorem).
fn interiors_disjoint(a: &ConvexHull, b: &ConvexHull) -> bool {
    let (ba, bb) = (a.bbox(), b.bbox());
    if (0..3).any(|k| ba.1[k] <= bb.0[k] || bb.1[k] <= ba.0[k]) {
        return true;
    }
    let face_separates = |a: &ConvexHull, b: &ConvexHull| {
        a.faces()
            .iter()
            .any(|f| b.vertices().iter().all(|&v| f.plane.side(v) >= 0))
    };
    if face_separates(a, b) || face_separates(b, a) {
        return true;
    }
    // Quick certificates of overlap: a vertex or the vertex centroid of one
    // strictly inside the other (all sides < 0; the centroid scaled by n).
    let strictly_inside = |h: &ConvexHull, p: [i64; 3], scale: i64| {
        h.faces().iter().all(|f| {
            let s = (0..3).map(|k| f.plane.normal[k] * p[k]).sum::<i64>() - f.plane.offset * scale;
            s < 0
        })
    };
    let centroid_inside = |g: &ConvexHull, h: &ConvexHull| {
        let n = g.vertices().len() as i64;
        let sum = g
            .vertices()
            .iter()
            .fold([0i64; 3], |acc, v| std::array::from_fn(|k| acc[k] + v[k]));
        strictly_inside(h, sum, n)
    };
    if centroid_inside(a, b)
        || centroid_inside(b, a)
        || a.vertices().iter().any(|&v| strictly_inside(b, v, 1))
        || b.vertices().iter().any(|&v| strictly_inside(a, v, 1))
    {
        return false;
    }
    // Edge–edge planes. |edge| ≤ 2¹⁷ per component, so |n| ≤ 2³⁵ and every
    // projection stays below 3·2³⁵·2¹⁶ < 2⁵³: exact in i64.
    let project = |h: &ConvexHull, n: [i64; 3]| {
        h.vertices()
            .iter()
            .fold((i64::MAX, i64::MIN), |(lo, hi), v| {
                let d = n[0] * v[0] + n[1] * v[1] + n[2] * v[2];
                (lo.min(d), hi.max(d))
            })
    };
    let eb = edge_directions(b);
    edge_directions(a).iter().any(|&u| {
        eb.iter().any(|&w| {
            let n = cross_wide(u, w).map(|c| c as i64);
            if n == [0, 0, 0] {
                return false;
            }
            let (pa, pb) = (project(a, n), project(b, n));
            pa.1 <= pb.0 || pb.1 <= pa.0
        })
    })
}

/// The distinct edge directions of a hull (each undirected edge once).
fn edge_directions(h: &ConvexHull) -> Vec<[i64; 3]> {
    let mut out = Vec::new();
    for f in h.faces() {
        let k = f.vertices.len();
        for i in 0..k {
            let (a, b) = (f.vertices[i], f.vertices[(i + 1) % k]);
            if a < b {
                out.push(sub(h.vertices()[b as usize], h.vertices()[a as usize]));
            }
        }
    }
    out
}
