//! Locating a cut, the first phase of [`super::cut`]: takes a mesh, a
//! prepared knife and (for the tree) the mesh's forest, and returns a
//! [`Located`](super::Located): the crossed triangles ascending and their
//! cut points, the same from the tree walk ([`tree`]) and the brute-force locate
//! ([`brute_force`]), both finished by [`finish`].

mod brute_force;
mod finish;
mod tree;

use glam::Vec3;

use super::knife::Analytic;
use crate::TriMesh;
pub(crate) use brute_force::locate_brute_force_prepared;
pub(crate) use tree::locate_prepared;

/// One end of a triangle edge: vertex id, position, side value.
type End = (u32, Vec3, f64);

/// The corners of triangle `t`, in winding order, with their side values.
#[inline(always)]
fn ends<A: Analytic>(mesh: &TriMesh, k: A, t: u32) -> [End; 3] {
    mesh.triangles[t as usize].map(|v| {
        let q = mesh.positions[v as usize];
        (v, q, k.eval(q.as_dvec3()))
    })
}

/// Whether a bounded knife (a rectangle) reaches the crossing of one of
/// the triangle's edges whose ends change side; tree and scan both decide
/// here.
fn knife_reaches<A: Analytic>(k: A, ends: [End; 3]) -> bool {
    (0..3).any(|e| {
        let (x, y) = (ends[e], ends[(e + 1) % 3]);
        let ((_, a, fa), (_, b, fb)) = if x.0 < y.0 { (x, y) } else { (y, x) };
        k.crossing_from(a, b, fa, fb).is_some()
    })
}
