//! Voxelization of a [`Polyhedron`] by its nested convex shells and the
//! lossless check against the source object (this phase's
//! `impl Polyhedron`: `voxelize`, `mismatches`); the box and comparison
//! helpers are shared with the ray-parity check of `polyhedron::inside`.

use crate::foundation::alloc::filled;
use crate::gpu::Backend;
use crate::hull_scan::VoxelBox;
use crate::voxel::DigitalObject;

use super::{Polyhedron, try_local_index, voxel_at};

impl Polyhedron {
    /// Which voxels of `bbox` the polyhedron holds (one flag per voxel, x
    /// fastest): a voxel is held by a shell when its centre lies in the
    /// closed shell and in no child's region (exact point-in-polyhedron
    /// for the nested shells).
    ///
    /// Errors: hull-scan range limits; a malformed tree (a child listed
    /// before its parent).
    pub fn voxelize(&self, bbox: &VoxelBox, backend: Backend<'_>) -> crate::Result<Vec<bool>> {
        let n = self.shells.len();
        let mut regions: Vec<Option<(VoxelBox, Vec<bool>)>> = vec![None; n];
        let mut out = filled(
            "polyhedrize: voxels of the bounding box",
            bbox.n_voxels()?,
            false,
        )?;
        for i in (0..n).rev() {
            let region = match regions[i].take() {
                Some(r) => r,
                None => self.shells[i].geometry.closed_voxels(backend)?,
            };
            match self.shells[i].parent {
                Some(p) if (p as usize) < i => {
                    let p = p as usize;
                    let parent = match regions[p].take() {
                        Some(r) => r,
                        None => self.shells[p].geometry.closed_voxels(backend)?,
                    };
                    regions[p] = Some(subtract(parent, &region));
                }
                Some(p) => {
                    return Err(crate::Error::data(
                        "polyhedron",
                        "shell",
                        i,
                        format!("parent {p} does not come before it"),
                    ));
                }
                None => paint(&mut out, bbox, &region),
            }
        }
        Ok(out)
    }

    /// Checks losslessness: voxelizes the object's box plus a one-voxel
    /// margin and compares with S. Returns the mismatching voxels (source
    /// indices; empty when the representation is exact), at most `limit`.
    pub fn mismatches(
        &self,
        object: &DigitalObject,
        backend: Backend<'_>,
        limit: usize,
    ) -> crate::Result<(u64, Vec<[i64; 3]>)> {
        let bbox = verify_box(object);
        Ok(differences(
            object,
            &bbox,
            &self.voxelize(&bbox, backend)?,
            limit,
        ))
    }
}

/// The box a lossless check voxelizes: the object's plus a one-voxel margin.
pub(in crate::polyhedron) fn verify_box(object: &DigitalObject) -> VoxelBox {
    let (lo, hi) = object.voxel_bbox();
    VoxelBox {
        origin: lo.map(|c| c - 1),
        dims: std::array::from_fn(|a| (hi[a] - lo[a] + 3).max(0) as usize),
    }
}

/// The voxels of `bbox` where `held` (one flag per voxel, x fastest) differs
/// from `object`: their count and the first `limit`.
pub(in crate::polyhedron) fn differences(
    object: &DigitalObject,
    bbox: &VoxelBox,
    held: &[bool],
    limit: usize,
) -> (u64, Vec<[i64; 3]>) {
    let mut count = 0u64;
    let mut first = Vec::new();
    for (k, &h) in held.iter().enumerate() {
        let v = voxel_at(bbox, k);
        if h != object.contains(v) {
            count += 1;
            if first.len() < limit {
                first.push(v);
            }
        }
    }
    (count, first)
}

/// `parent` minus the voxels held by `child` (child box within the parent's).
fn subtract(parent: (VoxelBox, Vec<bool>), child: &(VoxelBox, Vec<bool>)) -> (VoxelBox, Vec<bool>) {
    let (pb, mut flags) = parent;
    let (cb, cflags) = child;
    for (k, &held) in cflags.iter().enumerate() {
        if held {
            let v = voxel_at(cb, k);
            if let Some(i) = try_local_index(&pb, v) {
                flags[i] = false;
            }
        }
    }
    (pb, flags)
}

/// Sets the voxels of `region` that lie in `bbox`.
fn paint(out: &mut [bool], bbox: &VoxelBox, region: &(VoxelBox, Vec<bool>)) {
    let (rb, flags) = region;
    for (k, &held) in flags.iter().enumerate() {
        if held && let Some(i) = try_local_index(bbox, voxel_at(rb, k)) {
            out[i] = true;
        }
    }
}
