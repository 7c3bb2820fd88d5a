//! CPU mirror of `kernels/vertex_normals.wgsl`.

use super::NormalsInput;
use crate::parity::Tolerance;

/// Parity tolerance on unit normals: each cross product carries ≤ 2 ulp of
/// |e1|·|e2| per component (with or without FMA contraction), which for the
/// well-shaped triangles of scan meshes (|e1||e2| / |n| ≲ 10) is ≤ 20 ulp of
/// the unit result; the CSR-ordered sum adds ≤ 1 ulp per incident triangle
/// (≤ 12 on the data) and the normalisation 3 more: ≈ 35 ulp ≈ 4.2e-6.
pub const TOL: Tolerance = Tolerance {
    abs: 1e-5,
    rel: 0.0,
};

fn sub(a: [f32; 4], b: [f32; 4]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(u: [f32; 3], v: [f32; 3]) -> [f32; 3] {
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

/// One normal per vertex, same loop and summation order as the kernel.
pub fn vertex_normals(input: &NormalsInput) -> Vec<[f32; 4]> {
    let p = &input.positions;
    let t = &input.triangles;
    (0..input.adjacency.n_rows())
        .map(|ix| {
            let mut sum = [0.0f32; 3];
            for &tri in input.adjacency.row(ix) {
                let k = 3 * tri as usize;
                let a = p[t[k] as usize];
                let b = p[t[k + 1] as usize];
                let c = p[t[k + 2] as usize];
                let n = cross(sub(b, a), sub(c, a));
                sum = [sum[0] + n[0], sum[1] + n[1], sum[2] + n[2]];
            }
            let len = (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]).sqrt();
            if len > 0.0 {
                [sum[0] / len, sum[1] / len, sum[2] / len, 0.0]
            } else {
                [0.0; 4]
            }
        })
        .collect()
}
