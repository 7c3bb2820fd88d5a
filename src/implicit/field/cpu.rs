//! CPU mirror of `kernels/shared/skeletal_field.wgsl` and
//! `kernels/implicit_field.wgsl`: the same rows, loops and f32 expressions.

use rayon::prelude::*;

use super::{FieldInput, Sample};
use crate::parity::Tolerance;

/// Relative parity tolerance: |Δ(F − I)| ≤ `REL`·(Σ|wᵢ fᵢ| + I),
/// |Δ∇F| ≤ `REL`·Σ|wᵢ ∇fᵢ|, |ΔF_t| ≤ `REL`·Σ|terms of F_t| (the
/// [`Scales`] of each point). The kernel's `exp` and `sqrt` are not
/// correctly rounded (WGSL allows 3 + 2|x| ulp for exp, with
/// a·s ≤ ln(1/τ) ≈ 25 after culling: ≤ 53 ulp per term) and FMA contraction
/// differs; 256 ulp covers it with a margin. Far from every skeleton the
/// terms fall below 1e-30, where GPUs flush subnormal intermediates to
/// zero: that is the absolute floor.
pub const REL: f32 = 256.0 * f32::EPSILON;

/// Magnitude scales of one sample's sums, for [`accepts`]: Σ|wᵢ fᵢ|,
/// Σ|wᵢ ∇fᵢ|, Σ|terms of F_t|.
pub type Scales = [f32; 3];

/// Whether a GPU sample agrees with the mirror's under [`REL`].
pub fn accepts(cpu: &Sample, scales: Scales, iso: f32, gpu: &Sample) -> bool {
    let tol = |s: f32| Tolerance {
        abs: REL * s + 1e-30,
        rel: 0.0,
    };
    tol(scales[0] + iso).accepts(cpu.value, gpu.value)
        && (0..3).all(|k| tol(scales[1]).accepts(cpu.grad[k], gpu.grad[k]))
        && tol(scales[2]).accepts(cpu.rate, gpu.rate)
}

/// Value, squared-distance derivative and parameter derivatives of one
/// influence: (e, de/ds, de/dp0, de/dp1).
pub fn influence(kind: u32, s: f32, p: [f32; 4]) -> [f32; 4] {
    let (p0, p1, inv_r2) = (p[0], p[1], p[3]);
    match kind {
        // blobby: p = (a, b)
        0 => {
            let ex = (-p0 * s).exp();
            let e = p1 * ex;
            [e, -p0 * e, -s * e, ex]
        }
        // wyvill: p = (R, k), t = s/R²
        1 => {
            let t = s * inv_r2;
            if t >= 1.0 {
                return [0.0; 4];
            }
            let c = 1.0 + t * (-22.0 / 9.0 + t * (17.0 / 9.0 - 4.0 / 9.0 * t));
            let dc = -22.0 / 9.0 + t * (34.0 / 9.0 - 12.0 / 9.0 * t);
            [p1 * c, p1 * dc * inv_r2, p1 * dc * (-2.0 * t / p0), c]
        }
        // metaball: p = (R, b)
        _ => {
            let t = s * inv_r2;
            if t <= 1.0 / 9.0 {
                let g = 1.0 - 3.0 * t;
                [p1 * g, -3.0 * p1 * inv_r2, 6.0 * p1 * t / p0, g]
            } else if t < 1.0 {
                let d = s.sqrt();
                let g = 1.0 - d / p0;
                [
                    1.5 * p1 * g * g,
                    -1.5 * p1 * g / (p0 * d),
                    3.0 * p1 * g * d * inv_r2,
                    1.5 * g * g,
                ]
            } else {
                [0.0; 4]
            }
        }
    }
}

fn sub(a: [f32; 4], b: [f32; 3]) -> [f32; 3] {
    [b[0] - a[0], b[1] - a[1], b[2] - a[2]]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// F − I, ∇F and F_t at `x`, with the magnitude [`Scales`] of the sums
/// (for tolerances): the shared module's `skeletal_field`.
pub fn skeletal_field(input: &FieldInput, x: [f32; 3]) -> (Sample, Scales) {
    let fp = &input.params;
    let (sk, table) = (&input.skeleton, &input.table);
    let mut out = Sample::default();
    let mut scale = [0.0f32; 3];
    let mut total = 0.0f32;
    let c = [
        ((x[0] - fp.grid_origin.x) * fp.inv_cell).floor(),
        ((x[1] - fp.grid_origin.y) * fp.inv_cell).floor(),
        ((x[2] - fp.grid_origin.z) * fp.inv_cell).floor(),
    ];
    let dims = [fp.grid_dims.x, fp.grid_dims.y, fp.grid_dims.z];
    let inside = (0..3).all(|k| c[k] >= 0.0 && c[k] < dims[k] as f32);
    if inside {
        let cell = c[0] as u32 + dims[0] * (c[1] as u32 + dims[1] * c[2] as u32);
        let at = (fp.cell_base + cell) as usize;
        for k in table[at]..table[at + 1] {
            let i = table[k as usize];
            let kind = table[i as usize];
            let end = table[(fp.n_prims + i) as usize];
            let start = if i == 0 {
                0
            } else {
                table[(fp.n_prims + i - 1) as usize]
            };
            let p = sk[2 * i as usize];
            let dp = sk[2 * i as usize + 1];
            // Closest skeleton point: squared distance, x − q and q̇.
            let mut best_s = f32::MAX;
            let mut best_d = [0.0f32; 3];
            let mut best_v = [0.0f32; 3];
            for j in start..end {
                let r = (fp.piece_base + 4 * j) as usize;
                let (a, b, va, vb) = (sk[r], sk[r + 1], sk[r + 2], sk[r + 3]);
                let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let ax = sub(a, x);
                let u = (dot(ax, ab) * a[3]).clamp(0.0, 1.0);
                let d = [ax[0] - u * ab[0], ax[1] - u * ab[1], ax[2] - u * ab[2]];
                let s = dot(d, d);
                if s < best_s {
                    best_s = s;
                    best_d = d;
                    best_v = [
                        va[0] + u * (vb[0] - va[0]),
                        va[1] + u * (vb[1] - va[1]),
                        va[2] + u * (vb[2] - va[2]),
                    ];
                }
            }
            let e = influence(kind, best_s, p);
            let w = p[2];
            let f = w * e[0];
            let g = 2.0 * w * e[1];
            let grad = [g * best_d[0], g * best_d[1], g * best_d[2]];
            let (r0, r1, r2) = (
                -2.0 * e[1] * dot(best_d, best_v),
                e[2] * dp[0],
                e[3] * dp[1],
            );
            let rate = w * (r0 + r1 + r2) + dp[2] * e[0];
            scale[0] += f.abs();
            scale[1] += g.abs() * best_s.sqrt();
            scale[2] += w.abs() * (r0.abs() + r1.abs() + r2.abs()) + (dp[2] * e[0]).abs();
            if fp.blend_max == 1 {
                if f > total {
                    total = f;
                    out.grad = grad;
                    out.rate = rate;
                }
            } else {
                total += f;
                out.grad = [
                    out.grad[0] + grad[0],
                    out.grad[1] + grad[1],
                    out.grad[2] + grad[2],
                ];
                out.rate += rate;
            }
        }
    }
    out.value = total - fp.iso;
    (out, scale)
}

/// The kernel `implicit_field`: one sample per point (`xyz`, w unused).
pub fn implicit_field(input: &FieldInput, points: &[[f32; 4]]) -> Vec<Sample> {
    points
        .par_iter()
        .map(|p| skeletal_field(input, [p[0], p[1], p[2]]).0)
        .collect()
}
