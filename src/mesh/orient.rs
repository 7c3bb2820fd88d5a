//! Re-winding triangles: consistent winding per patch, outward winding per
//! component. Only the order of indices inside triangles changes (the
//! `swap(1, 2)` of [`TriMesh::flip_winding`]); positions, triangle order and
//! every figure of [`Topology`](super::Topology) other than orientation stay
//! the same.

use super::TriMesh;
use super::topology::{HalfEdges, NONE, Orientation, analyse, propagate_winding};
use crate::{Refusal, Result};

/// Flips triangles so that, in every patch of triangles connected through
/// manifold edges, each manifold edge is traversed once in each direction.
/// Each patch keeps the winding of the majority of its triangles (ties: the
/// winding of its first triangle). Returns the number of triangles flipped.
///
/// Guarantee on `Ok`: [`Topology::of`](super::Topology::of) reports
/// `consistently_oriented`. Patches meeting only at non-manifold edges or
/// vertices are wound independently. O(F log F).
///
/// Errors: [`Refusal::NonOrientable`] when some patch is non-orientable (a
/// Möbius strip, a Klein bottle); the mesh is then left unchanged.
pub fn orient_consistently(mesh: &mut TriMesh) -> Result<usize> {
    let he = HalfEdges::of(&mesh.triangles);
    let winding = propagate_winding(&mesh.triangles, &he);
    if let Some(&seed) = winding.nonorientable_patches.first() {
        return Err(Refusal::NonOrientable {
            patches: winding.nonorientable_patches.len(),
            triangle: seed as u32,
        }
        .into());
    }
    let mut flipped = 0;
    for (tri, &flip) in mesh.triangles.iter_mut().zip(&winding.flip) {
        if flip {
            tri.swap(1, 2);
            flipped += 1;
        }
    }
    Ok(flipped)
}

/// Flips every triangle of each component judged [`Orientation::Inward`];
/// returns the number of components flipped.
///
/// Guarantee: each flipped component's signed volume changes sign exactly
/// (same centroid, negated area vectors), so it is then judged
/// [`Orientation::Outward`]; `Outward`, `Undetermined` and `Mixed`
/// components are untouched (run [`orient_consistently`] first to resolve
/// `Mixed` ones). O(F log F).
pub fn orient_outward(mesh: &mut TriMesh) -> usize {
    let analysis = analyse(mesh);
    let inward: Vec<bool> = analysis
        .topology
        .components
        .iter()
        .map(|c| c.orientation == Orientation::Inward)
        .collect();
    for (tri, &c) in mesh.triangles.iter_mut().zip(&analysis.triangle_component) {
        if c != NONE && inward[c] {
            tri.swap(1, 2);
        }
    }
    inward.iter().filter(|&&i| i).count()
}
