//! Fast CPU path of `blobby_energy`, beside the mirror and tested equal to
//! it within [`super::cpu::tolerances`]: the same rows (one per workgroup
//! of [`BLOCK`] points), computed with 16 points per vector step
//! and the primitives in a scalar loop, so V and ∇V accumulate per lane
//! without horizontal sums and the per-point terms vectorise too (AVX-512
//! or AVX2 when the CPU has them, through pulp's run-time dispatch; every
//! function of the loops is `#[inline(always)]`); e^x by a polynomial
//! instead of libm, each e^{−a s} computed once per point and primitive
//! (phase 2 reads it back), and the sums carried in f64 every 64 points
//! (`SUB`), so they are closer to the exact sums than the kernel's f32 tree.

use rayon::prelude::*;

use super::{BLOCK, EnergyInput};

/// Points per vector step.
const LANES: usize = 16;
/// Points whose f32 partial sums are added into f64 at a time.
const SUB: usize = 64;

/// 1.5·2²³: adding it rounds a float of magnitude below 2²² to an integer
/// held in the low mantissa bits (no float-to-int conversion, which would
/// keep the loop scalar).
const ROUND: f32 = 12_582_912.0;

/// e^x for x ≤ 0 within 2 ulp (the value at −87.3 below that, where f32
/// underflows): x = n ln 2 + r, |r| ≤ ln 2 / 2, e^r by its degree-7 Taylor
/// polynomial, 2^n from the exponent bits.
#[inline(always)]
fn exp_neg(x: f32) -> f32 {
    let x = if x < -87.3 { -87.3 } else { x };
    let t = x * std::f32::consts::LOG2_E + ROUND;
    let n = t - ROUND;
    let r = (x - n * 0.693_145_75) - n * 1.428_606_8e-6;
    let p = 1.0
        + r * (1.0
            + r * (0.5
                + r * (1.0 / 6.0
                    + r * (1.0 / 24.0 + r * (1.0 / 120.0 + r * (1.0 / 720.0 + r / 5040.0))))));
    // The exponent of 2^n: n + 127 in bits 23.., from t's low bits.
    let e = t.to_bits().wrapping_sub(ROUND.to_bits()).wrapping_add(127) << 23;
    p * f32::from_bits(e)
}

/// One workgroup's row, run under pulp's dispatch.
struct Row<'a> {
    input: &'a EnergyInput,
    w: usize,
}

impl pulp::NullaryFnOnce for Row<'_> {
    type Output = Vec<f32>;

    #[inline(always)]
    fn call(self) -> Vec<f32> {
        row(self.input, self.w)
    }
}

/// A row with `LANES` points per vector step and the primitives in a
/// scalar loop: V and ∇V accumulate per lane (no horizontal sums), the
/// per-point terms of the mirror's `point_terms` run lane-wise (the same operations,
/// the branch on |∇V|² as a select), and the gradient per primitive
/// accumulates per lane and is summed into f64 every [`SUB`] points. A
/// partial last group repeats its last point with the adjoints masked to 0.
#[inline(always)]
fn row(input: &EnergyInput, w: usize) -> Vec<f32> {
    let u = &input.params;
    let n = u.n_prims as usize;
    let first = w * BLOCK;
    let last = (first + BLOCK).min(u.n_points as usize);
    let count = last - first;
    let prims: Vec<[f32; 5]> = (0..n)
        .map(|k| {
            let c = input.prims[2 * k];
            [c[0], c[1], c[2], c[3], input.prims[2 * k + 1][0]]
        })
        .collect();
    let mut energy = 0.0f64;
    let mut total = vec![0.0f64; 5 * n];
    let mut acc = vec![[0.0f32; LANES]; 5 * n];
    let mut ex = vec![[0.0f32; LANES]; n];
    let groups = count.div_ceil(LANES);
    for group in 0..groups {
        let (mut px, mut py, mut pz) = ([0.0f32; LANES], [0.0f32; LANES], [0.0f32; LANES]);
        let (mut nx, mut ny, mut nz) = ([0.0f32; LANES], [0.0f32; LANES], [0.0f32; LANES]);
        let mut mask = [0.0f32; LANES];
        for l in 0..LANES {
            let j = group * LANES + l;
            let at = first + j.min(count - 1);
            let (x, nrm) = (input.points[2 * at], input.points[2 * at + 1]);
            (px[l], py[l], pz[l]) = (x[0], x[1], x[2]);
            (nx[l], ny[l], nz[l]) = (nrm[0], nrm[1], nrm[2]);
            mask[l] = if j < count { 1.0 } else { 0.0 };
        }
        // Phase 1: V and ∇V per lane; e^{−as} kept.
        let (mut v, mut gx, mut gy, mut gz) = (
            [0.0f32; LANES],
            [0.0f32; LANES],
            [0.0f32; LANES],
            [0.0f32; LANES],
        );
        for (p, out) in prims.iter().zip(ex.iter_mut()) {
            let [cx, cy, cz, a, b] = *p;
            for l in 0..LANES {
                let (dx, dy, dz) = (px[l] - cx, py[l] - cy, pz[l] - cz);
                let s = dx * dx + dy * dy + dz * dz;
                let e1 = exp_neg(-a * s);
                out[l] = e1;
                let e = b * e1;
                let f = -2.0 * a * e;
                v[l] += e;
                gx[l] += f * dx;
                gy[l] += f * dy;
                gz[l] += f * dz;
            }
        }
        // The per-point terms, lane-wise (point_terms' operations).
        let (mut lv, mut lgx, mut lgy, mut lgz) = (
            [0.0f32; LANES],
            [0.0f32; LANES],
            [0.0f32; LANES],
            [0.0f32; LANES],
        );
        let mut e_lane = [0.0f32; LANES];
        let wgt = u.alpha * u.inv_m;
        for l in 0..LANES {
            let g2 = gx[l] * gx[l] + gy[l] * gy[l] + gz[l] * gz[l];
            let steep = g2 > u.g_min2;
            let len = if steep { g2 } else { u.g_min2 }.sqrt();
            let (hx, hy, hz) = (gx[l] / len, gy[l] / len, gz[l] / len);
            let (rx, ry, rz) = (nx[l] + hx, ny[l] + hy, nz[l] + hz);
            let en = rx * rx + ry * ry + rz * rz;
            let gn = hx * nx[l] + hy * ny[l] + hz * nz[l];
            let (dx, dy, dz) = if steep {
                (
                    2.0 * (nx[l] - hx * gn) / len,
                    2.0 * (ny[l] - hy * gn) / len,
                    2.0 * (nz[l] - hz * gn) / len,
                )
            } else {
                (2.0 * rx / len, 2.0 * ry / len, 2.0 * rz / len)
            };
            let res = v[l] - u.iso;
            lv[l] = 2.0 * res * u.inv_m * mask[l];
            lgx[l] = wgt * dx * mask[l];
            lgy[l] = wgt * dy * mask[l];
            lgz[l] = wgt * dz * mask[l];
            e_lane[l] = (res * res + u.alpha * en) * u.inv_m * mask[l];
        }
        energy += e_lane.iter().map(|&e| f64::from(e)).sum::<f64>();
        // Phase 2: the gradient per primitive, per lane.
        for (k, (p, ce)) in prims.iter().zip(&ex).enumerate() {
            let [cx, cy, cz, a, b] = *p;
            let [ox, oy, oz, oa, ob] = &mut acc[5 * k..5 * k + 5] else {
                unreachable!("five rows per primitive")
            };
            for l in 0..LANES {
                let (dx, dy, dz) = (px[l] - cx, py[l] - cy, pz[l] - cz);
                let s = dx * dx + dy * dy + dz * dz;
                let e1 = ce[l];
                let e = b * e1;
                let ld = lgx[l] * dx + lgy[l] * dy + lgz[l] * dz;
                let m = lv[l] - 2.0 * a * ld;
                let f = 2.0 * a * e;
                ox[l] += f * (m * dx + lgx[l]);
                oy[l] += f * (m * dy + lgy[l]);
                oz[l] += f * (m * dz + lgz[l]);
                oa[l] += -s * e * lv[l] - 2.0 * e * (1.0 - a * s) * ld;
                ob[l] += e1 * m;
            }
        }
        if (group + 1) % (SUB / LANES) == 0 || group + 1 == groups {
            for (t, a) in total.iter_mut().zip(acc.iter_mut()) {
                *t += a.iter().map(|&x| f64::from(x)).sum::<f64>();
                *a = [0.0; LANES];
            }
        }
    }
    let mut out = Vec::with_capacity(1 + 5 * n);
    out.push(energy as f32);
    out.extend(total.iter().map(|&t| t as f32));
    out
}

/// The kernel's rows, fast: one rayon task per workgroup of points.
pub fn blobby_energy(input: &EnergyInput) -> Vec<f32> {
    let arch = pulp::Arch::new();
    (0..input.n_rows())
        .into_par_iter()
        .flat_map_iter(|w| arch.dispatch(Row { input, w }))
        .collect()
}
