//! The independent brute-force reference: every voxel centre of the box
//! against every face, `s = n·p − d` in i128 (no range assumptions), the
//! textbook reading of seed 003 §4.2.1 ("a voxel lies inside the hull when
//! every face is invisible from it"). Shares no code with the mirrors in
//! [`super::cpu`] or the kernels, so agreement with them means something.

use rayon::prelude::*;

use super::{Classification, HalfSpace, Side, VoxelBox};
use crate::Result;

/// The side code of every voxel of `bbox` (rayon over z layers).
pub fn classify(faces: &[HalfSpace], bbox: &VoxelBox) -> Result<Classification> {
    let n = bbox.n_voxels()?;
    let [nx, ny, _] = bbox.dims;
    let mut sides = vec![0u8; n];
    if n > 0 {
        sides
            .par_chunks_mut(nx * ny)
            .enumerate()
            .for_each(|(z, layer)| {
                for (i, code) in layer.iter_mut().enumerate() {
                    let p = bbox.centre([i % nx, i / nx, z]);
                    let max_s = faces.iter().map(|f| f.side(p)).max();
                    let side = match max_s {
                        Some(s) if s > 0 => Side::Outside,
                        Some(0) => Side::On,
                        _ => Side::Inside,
                    };
                    *code = side as u8;
                }
            });
    }
    Ok(Classification { bbox: *bbox, sides })
}
