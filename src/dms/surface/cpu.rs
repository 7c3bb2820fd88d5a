//! CPU mirror of `kernels/dms_surface.wgsl`.

use rayon::prelude::*;

use super::{SurfaceInput, SurfacePoints};
use crate::parity::Tolerance;

/// Parity tolerance of positions, for sources within `extent` of the origin
/// (`extent` = the largest source coordinate): a row sums ≤ 30 products
/// with weights in [−0.1, 1.1]; each adds ≤ 1 ulp of `extent` with or
/// without fused multiply-adds, ≈ 4e-6 · extent; the bound keeps a factor
/// of 2.5.
pub fn position_tolerance(extent: f32) -> Tolerance {
    Tolerance {
        abs: 1e-5 * extent,
        rel: 0.0,
    }
}

/// Parity tolerance of unit normals: the tangents carry the position
/// error scaled by the derivative weights (≲ 1/knot spacing) against
/// tangents of length ~1; 1e-4 holds on fran_cut with a margin of 10.
pub const NORMAL_TOL: Tolerance = Tolerance {
    abs: 1e-4,
    rel: 0.0,
};

/// Position and normal of point `p`, same loop and order as the kernel.
fn point(input: &SurfaceInput, sources: &[[f32; 4]], p: usize) -> ([f32; 4], [f32; 4]) {
    let b = input.base.as_ref().map_or([0.0; 4], |b| b[p]);
    let mut f = [b[0], b[1], b[2]];
    let mut fu = [0.0f32; 3];
    let mut fv = [0.0f32; 3];
    for e in input.rows.offsets[p]..input.rows.offsets[p + 1] {
        let x = sources[input.rows.targets[e as usize] as usize];
        let w = input.weights[e as usize];
        for i in 0..3 {
            f[i] += w[0] * x[i];
            fu[i] += w[1] * x[i];
            fv[i] += w[2] * x[i];
        }
    }
    let n = [
        fu[1] * fv[2] - fu[2] * fv[1],
        fu[2] * fv[0] - fu[0] * fv[2],
        fu[0] * fv[1] - fu[1] * fv[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let normal = if len > 0.0 {
        [n[0] / len, n[1] / len, n[2] / len, 0.0]
    } else {
        [0.0; 4]
    };
    ([f[0], f[1], f[2], 0.0], normal)
}

/// Positions and normals of every point (points in parallel, each
/// written in place).
pub fn dms_surface(input: &SurfaceInput, sources: &[[f32; 4]]) -> SurfacePoints {
    const CHUNK: usize = 2048;
    let n = input.rows.n_rows();
    let mut positions = vec![[0.0f32; 4]; n];
    let mut normals = vec![[0.0f32; 4]; n];
    positions
        .par_chunks_mut(CHUNK)
        .zip(normals.par_chunks_mut(CHUNK))
        .enumerate()
        .for_each(|(c, (pos, nrm))| {
            for (k, (p, q)) in pos.iter_mut().zip(nrm.iter_mut()).enumerate() {
                (*p, *q) = point(input, sources, c * CHUNK + k);
            }
        });
    SurfacePoints { positions, normals }
}
