//! Point and row queries of a built hull: its exact half-spaces, per-face z
//! extents and voxel row spans for the inside-hull scan, containment of a
//! point, and bounding boxes.

use super::incremental::primitive;
use super::{Containment, ConvexHull, HalfSpace};
use crate::foundation::exact::{cross, dot, sub};

impl ConvexHull {
    /// Exact half-spaces whose intersection is the hull, outward normals,
    /// combinatorial coordinates: one per face; a flat hull adds one per
    /// polygon edge (in-plane normals) to its two opposite plane faces.
    pub fn half_spaces(&self) -> Vec<HalfSpace> {
        let mut out: Vec<HalfSpace> = self.faces.iter().map(|f| f.plane).collect();
        if let (Some(plane), Some(face)) = (self.planar, self.faces.first()) {
            let k = face.vertices.len();
            for i in 0..k {
                let a = self.vertices[face.vertices[i] as usize];
                let b = self.vertices[face.vertices[(i + 1) % k] as usize];
                let normal = primitive(cross(sub(b, a), plane.normal));
                out.push(HalfSpace {
                    normal,
                    offset: dot(normal, a),
                });
            }
        }
        out
    }

    /// Per-row intervals of the voxel rows of `bbox` in the closed hull,
    /// exactly ([`crate::hull_scan::row_spans_culled`]: on the CPU each layer
    /// uses only the faces meeting it).
    ///
    /// Errors: the hull-scan range limits of [`crate::hull_scan::check_range`].
    pub fn row_spans(
        &self,
        bbox: &crate::hull_scan::VoxelBox,
        backend: crate::gpu::Backend<'_>,
    ) -> crate::Result<crate::hull_scan::RowSpans> {
        let spaces: Vec<crate::hull_scan::HalfSpace> =
            self.half_spaces().into_iter().map(Into::into).collect();
        crate::hull_scan::row_spans_culled(&spaces, &self.face_z_extents(), bbox, backend)
    }

    /// The combinatorial z range `[min, max]` of each half-space of
    /// [`Self::half_spaces`], in the same order: the range of its face's
    /// vertices (a flat hull: the polygon's range for every half-space), for
    /// [`crate::hull_scan::row_spans_culled`].
    pub fn face_z_extents(&self) -> Vec<[i64; 2]> {
        let range = |vs: &mut dyn Iterator<Item = &u32>| {
            vs.fold([i64::MAX, i64::MIN], |r, &v| {
                let z = self.vertices[v as usize][2];
                [r[0].min(z), r[1].max(z)]
            })
        };
        if self.planar.is_some() {
            // The plane faces, then one in-plane half-space per polygon edge.
            let n = self.faces.len() + self.faces.first().map_or(0, |f| f.vertices.len());
            let all = range(&mut self.faces.iter().flat_map(|f| &f.vertices));
            return vec![all; n];
        }
        self.faces
            .iter()
            .map(|f| range(&mut f.vertices.iter()))
            .collect()
    }

    /// Exact position of `p` relative to the hull.
    pub fn containment(&self, p: [i64; 3]) -> Containment {
        let mut on = false;
        for h in self.half_spaces() {
            match h.side(p) {
                s if s > 0 => return Containment::Outside,
                0 => on = true,
                _ => {}
            }
        }
        if on || self.planar.is_some() {
            Containment::On
        } else {
            Containment::Inside
        }
    }

    /// Inclusive bounding box of the vertices, combinatorial coordinates.
    pub fn bbox(&self) -> ([i64; 3], [i64; 3]) {
        let mut lo = [i64::MAX; 3];
        let mut hi = [i64::MIN; 3];
        for v in &self.vertices {
            for a in 0..3 {
                lo[a] = lo[a].min(v[a]);
                hi[a] = hi[a].max(v[a]);
            }
        }
        (lo, hi)
    }

    /// Inclusive voxel-index range of the voxels whose centres lie in
    /// [`ConvexHull::bbox`] (centre `2i + 1`).
    pub fn voxel_bbox(&self) -> ([i64; 3], [i64; 3]) {
        let (lo, hi) = self.bbox();
        (
            lo.map(|c| (c - 1).div_euclid(2) + i64::from((c - 1).rem_euclid(2) != 0)),
            hi.map(|c| (c - 1).div_euclid(2)),
        )
    }
}
