//! Fast CPU path of `blobby_energy`, beside the mirror and tested equal to
//! it within [`super::cpu::tolerances`]: the same rows (one per workgroup
//! of [`BLOCK`] points), computed with the primitives in arrays that the
//! compiler vectorises (AVX-512 or AVX2 when the CPU has them, through
//! pulp's run-time dispatch; every function of the per-primitive loops is
//! `#[inline(always)]`), e^x by a polynomial instead of libm, each
//! e^{−a s} computed once per point and primitive (phase 2 reads it back),
//! and the sums carried in f64 every 64 points (`SUB`), so they are closer to
//! the exact sums than the kernel's f32 tree.

use rayon::prelude::*;

use super::cpu::point_terms;
use super::{BLOCK, EnergyInput};

/// Primitives per vector step (the arrays are padded to a multiple).
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

/// `v[k0..k0 + LANES]` as an array (one bounds check per step).
#[inline(always)]
fn lanes(v: &[f32], k0: usize) -> &[f32; LANES] {
    v[k0..k0 + LANES].try_into().expect("padded to LANES")
}

/// The same, mutable.
#[inline(always)]
fn lanes_mut(v: &mut [f32], k0: usize) -> &mut [f32; LANES] {
    (&mut v[k0..k0 + LANES])
        .try_into()
        .expect("padded to LANES")
}

/// The primitives as padded columns (padding: b = 0, a = 1, c = 0, so its
/// terms vanish).
struct Columns {
    cx: Vec<f32>,
    cy: Vec<f32>,
    cz: Vec<f32>,
    a: Vec<f32>,
    b: Vec<f32>,
}

impl Columns {
    fn of(input: &EnergyInput) -> Columns {
        let n = input.params.n_prims as usize;
        let padded = n.div_ceil(LANES) * LANES;
        let col = |f: &dyn Fn(usize) -> f32, pad: f32| -> Vec<f32> {
            (0..padded)
                .map(|k| if k < n { f(k) } else { pad })
                .collect()
        };
        Columns {
            cx: col(&|k| input.prims[2 * k][0], 0.0),
            cy: col(&|k| input.prims[2 * k][1], 0.0),
            cz: col(&|k| input.prims[2 * k][2], 0.0),
            a: col(&|k| input.prims[2 * k][3], 1.0),
            b: col(&|k| input.prims[2 * k + 1][0], 0.0),
        }
    }
}

/// One workgroup's row, run under pulp's dispatch.
struct Row<'a> {
    input: &'a EnergyInput,
    cols: &'a Columns,
    w: usize,
}

impl pulp::NullaryFnOnce for Row<'_> {
    type Output = Vec<f32>;

    #[inline(always)]
    fn call(self) -> Vec<f32> {
        row(self.input, self.cols, self.w)
    }
}

#[inline(always)]
fn row(input: &EnergyInput, cols: &Columns, w: usize) -> Vec<f32> {
    let u = &input.params;
    let n = u.n_prims as usize;
    let np = cols.a.len();
    let first = w * BLOCK;
    let last = (first + BLOCK).min(u.n_points as usize);
    let count = last - first;
    // Phase 1: V, ∇V, e_j/M and the adjoints per point; e^{−as} kept.
    let mut ex = vec![0.0f32; count * np];
    let mut state = Vec::with_capacity(count);
    let mut energy = 0.0f64;
    for j in 0..count {
        let x = input.points[2 * (first + j)];
        let nrm = input.points[2 * (first + j) + 1];
        let e_row = &mut ex[j * np..(j + 1) * np];
        let (mut v, mut gx, mut gy, mut gz) = (
            [0.0f32; LANES],
            [0.0f32; LANES],
            [0.0f32; LANES],
            [0.0f32; LANES],
        );
        for k0 in (0..np).step_by(LANES) {
            let (cx, cy, cz) = (
                lanes(&cols.cx, k0),
                lanes(&cols.cy, k0),
                lanes(&cols.cz, k0),
            );
            let (ca, cb) = (lanes(&cols.a, k0), lanes(&cols.b, k0));
            let out = lanes_mut(e_row, k0);
            for l in 0..LANES {
                let (dx, dy, dz) = (x[0] - cx[l], x[1] - cy[l], x[2] - cz[l]);
                let s = dx * dx + dy * dy + dz * dz;
                let e1 = exp_neg(-ca[l] * s);
                out[l] = e1;
                let e = cb[l] * e1;
                let f = -2.0 * ca[l] * e;
                v[l] += e;
                gx[l] += f * dx;
                gy[l] += f * dy;
                gz[l] += f * dz;
            }
        }
        let v: f32 = v.iter().sum();
        let g = [
            gx.iter().sum::<f32>(),
            gy.iter().sum::<f32>(),
            gz.iter().sum::<f32>(),
        ];
        let p = point_terms(u, x, [nrm[0], nrm[1], nrm[2]], v, g);
        energy += f64::from(p.energy);
        state.push((p.x, p.lv, p.lg));
    }
    // Phase 2: the gradient per primitive, f32 over SUB points, then f64.
    let mut total = vec![0.0f64; 5 * np];
    let mut acc = vec![0.0f32; 5 * np];
    for (j, &(x, lv, lg)) in state.iter().enumerate() {
        let e_row = &ex[j * np..(j + 1) * np];
        let (gcx, rest) = acc.split_at_mut(np);
        let (gcy, rest) = rest.split_at_mut(np);
        let (gcz, rest) = rest.split_at_mut(np);
        let (ga, gb) = rest.split_at_mut(np);
        for k0 in (0..np).step_by(LANES) {
            let (cx, cy, cz) = (
                lanes(&cols.cx, k0),
                lanes(&cols.cy, k0),
                lanes(&cols.cz, k0),
            );
            let (ca, cb, ce) = (lanes(&cols.a, k0), lanes(&cols.b, k0), lanes(e_row, k0));
            let (ox, oy, oz) = (lanes_mut(gcx, k0), lanes_mut(gcy, k0), lanes_mut(gcz, k0));
            let (oa, ob) = (lanes_mut(ga, k0), lanes_mut(gb, k0));
            for l in 0..LANES {
                let (dx, dy, dz) = (x[0] - cx[l], x[1] - cy[l], x[2] - cz[l]);
                let s = dx * dx + dy * dy + dz * dz;
                let a = ca[l];
                let e1 = ce[l];
                let e = cb[l] * e1;
                let ld = lg[0] * dx + lg[1] * dy + lg[2] * dz;
                let m = lv - 2.0 * a * ld;
                let f = 2.0 * a * e;
                ox[l] += f * (m * dx + lg[0]);
                oy[l] += f * (m * dy + lg[1]);
                oz[l] += f * (m * dz + lg[2]);
                oa[l] += -s * e * lv - 2.0 * e * (1.0 - a * s) * ld;
                ob[l] += e1 * m;
            }
        }
        if (j + 1) % SUB == 0 || j + 1 == count {
            for (t, a) in total.iter_mut().zip(acc.iter_mut()) {
                *t += f64::from(*a);
                *a = 0.0;
            }
        }
    }
    let mut out = Vec::with_capacity(1 + 5 * n);
    out.push(energy as f32);
    for k in 0..n {
        for q in 0..5 {
            out.push(total[q * np + k] as f32);
        }
    }
    out
}

/// The kernel's rows, fast: one rayon task per workgroup of points.
pub fn blobby_energy(input: &EnergyInput) -> Vec<f32> {
    let cols = Columns::of(input);
    let arch = pulp::Arch::new();
    (0..input.n_rows())
        .into_par_iter()
        .flat_map_iter(|w| {
            arch.dispatch(Row {
                input,
                cols: &cols,
                w,
            })
        })
        .collect()
}
