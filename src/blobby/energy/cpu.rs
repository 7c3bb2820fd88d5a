//! CPU mirror of `kernels/blobby_energy.wgsl`: the same phases, f32
//! expressions and summation order (each invocation's points in order,
//! then the tree over invocations), one workgroup per closure call.

use rayon::prelude::*;

use super::{BLOCK, EnergyInput, EnergyParams, POINTS_PER_INVOCATION, WG_SIZE};

type V3 = [f32; 3];

fn sub(a: [f32; 4], b: [f32; 4]) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: V3, b: V3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The kernel's tree over invocations: stride WG_SIZE/2 down to 1.
fn tree_sum<const Q: usize>(sh: &mut [[f32; Q]]) -> [f32; Q] {
    let mut stride = WG_SIZE / 2;
    while stride > 0 {
        for lid in 0..stride {
            let other = sh[lid + stride];
            for (mine, theirs) in sh[lid].iter_mut().zip(other) {
                *mine += theirs;
            }
        }
        stride /= 2;
    }
    sh[0]
}

/// One point's position, λ_V and λ_G (zeros past the end) and its e_j/M.
struct PointState {
    x: V3,
    lv: f32,
    lg: V3,
    energy: f32,
}

fn point_state(input: &EnergyInput, ix: usize) -> PointState {
    let u = &input.params;
    if ix >= u.n_points as usize {
        return PointState {
            x: [0.0; 3],
            lv: 0.0,
            lg: [0.0; 3],
            energy: 0.0,
        };
    }
    let x = input.points[2 * ix];
    let n = input.points[2 * ix + 1];
    let n = [n[0], n[1], n[2]];
    let mut v = 0.0f32;
    let mut g = [0.0f32; 3];
    for k in 0..u.n_prims as usize {
        let ca = input.prims[2 * k];
        let b = input.prims[2 * k + 1][0];
        let d = sub(x, ca);
        let e = b * (-ca[3] * dot(d, d)).exp();
        v += e;
        let f = -2.0 * ca[3] * e;
        g = [g[0] + f * d[0], g[1] + f * d[1], g[2] + f * d[2]];
    }
    point_terms(u, x, n, v, g)
}

/// A point's e_j/M and adjoints from V and ∇V at it (the kernel's lines
/// after its loop over primitives; the fast path runs them lane-wise).
fn point_terms(u: &EnergyParams, x: [f32; 4], n: V3, v: f32, g: V3) -> PointState {
    let g2 = dot(g, g);
    let (en, dn) = if g2 > u.g_min2 {
        let len = g2.sqrt();
        let gh = [g[0] / len, g[1] / len, g[2] / len];
        let r = [n[0] + gh[0], n[1] + gh[1], n[2] + gh[2]];
        let gn = dot(gh, n);
        (
            dot(r, r),
            [
                2.0 * (n[0] - gh[0] * gn) / len,
                2.0 * (n[1] - gh[1] * gn) / len,
                2.0 * (n[2] - gh[2] * gn) / len,
            ],
        )
    } else {
        let gm = u.g_min2.sqrt();
        let r = [n[0] + g[0] / gm, n[1] + g[1] / gm, n[2] + g[2] / gm];
        (
            dot(r, r),
            [2.0 * r[0] / gm, 2.0 * r[1] / gm, 2.0 * r[2] / gm],
        )
    };
    let res = v - u.iso;
    let w = u.alpha * u.inv_m;
    PointState {
        x: [x[0], x[1], x[2]],
        lv: 2.0 * res * u.inv_m,
        lg: [w * dn[0], w * dn[1], w * dn[2]],
        energy: (res * res + u.alpha * en) * u.inv_m,
    }
}

/// One workgroup's row: Σ e_j/M, then ∂/∂(c, a, b) per primitive.
fn workgroup(input: &EnergyInput, w: usize) -> Vec<f32> {
    let first = w * BLOCK;
    let states: Vec<Vec<PointState>> = (0..WG_SIZE)
        .map(|lid| {
            (0..POINTS_PER_INVOCATION)
                .map(|p| point_state(input, first + lid + p * WG_SIZE))
                .collect()
        })
        .collect();
    let mut row = Vec::with_capacity(input.row_len());
    let mut sh: Vec<[f32; 1]> = (states.iter())
        .map(|s| [s.iter().fold(0.0f32, |acc, p| acc + p.energy)])
        .collect();
    row.push(tree_sum(&mut sh)[0]);
    for k in 0..input.params.n_prims as usize {
        let ca = input.prims[2 * k];
        let b = input.prims[2 * k + 1][0];
        let a = ca[3];
        let mut sh: Vec<[f32; 5]> = (states.iter())
            .map(|mine| {
                let mut acc = [0.0f32; 5];
                for p in mine {
                    let d = [p.x[0] - ca[0], p.x[1] - ca[1], p.x[2] - ca[2]];
                    let s = dot(d, d);
                    let ex = (-a * s).exp();
                    let e = b * ex;
                    let ld = dot(p.lg, d);
                    let m = p.lv - 2.0 * a * ld;
                    let f = 2.0 * a * e;
                    for q in 0..3 {
                        acc[q] += f * (m * d[q] + p.lg[q]);
                    }
                    acc[3] += -s * e * p.lv - 2.0 * e * (1.0 - a * s) * ld;
                    acc[4] += ex * m;
                }
                acc
            })
            .collect();
        row.extend(tree_sum(&mut sh));
    }
    row
}

/// The kernel `blobby_energy`: one row of 1 + 5N floats per workgroup.
pub fn blobby_energy(input: &EnergyInput) -> Vec<f32> {
    (0..input.n_rows())
        .into_par_iter()
        .flat_map_iter(|w| workgroup(input, w))
        .collect()
}

/// Relative precision of the kernel's terms: WGSL allows exp 3 + 2|x| ulp,
/// and |x| ≤ 87 before exp underflows in f32, so ≤ 177 ulp; 256 ulp with
/// FMA contraction and the tree's ≤ 10 levels of rounding.
pub const REL: f64 = 256.0 * f32::EPSILON as f64;

/// Per-output tolerances for [`accepts`], the layout of the rows: a linear
/// bound of how errors of `REL` in every exp and product reach each output.
/// Per point, V and ∇V carry δV = REL·Σ|b e^{−as}| and
/// δG = REL·Σ|2ab e^{−as} d|; λ_V = 2(V − T)/M carries 2δV/M, and
/// λ_G = α/M·∂e_n/∂G carries α/M·6/max(|G|, g_min)²·δG (the derivative of
/// 2(n − ĝ(ĝ·n))/|G| with respect to G is at most 6/|G|² in norm). Each
/// output's bound adds, over its points, the propagated adjoint errors and
/// REL times the magnitude of its terms; twice that, plus 1e-30 (GPUs
/// flush subnormals).
pub fn tolerances(input: &EnergyInput) -> Vec<f64> {
    let u = &input.params;
    let n_prims = u.n_prims as usize;
    let len = input.row_len();
    (0..input.n_rows())
        .into_par_iter()
        .flat_map_iter(|w| {
            let mut tol = vec![0.0f64; len];
            let end = ((w + 1) * BLOCK).min(u.n_points as usize);
            for ix in w * BLOCK..end {
                let x = input.points[2 * ix];
                let x = glam::DVec3::new(f64::from(x[0]), f64::from(x[1]), f64::from(x[2]));
                let n = input.points[2 * ix + 1];
                let n = glam::DVec3::new(f64::from(n[0]), f64::from(n[1]), f64::from(n[2]));
                let terms: Vec<(glam::DVec3, f64, f64, f64)> = (0..n_prims)
                    .map(|k| {
                        let ca = input.prims[2 * k];
                        let c =
                            glam::DVec3::new(f64::from(ca[0]), f64::from(ca[1]), f64::from(ca[2]));
                        let d = x - c;
                        let a = f64::from(ca[3]);
                        let ex = (-a * d.length_squared()).exp();
                        (d, a, ex, f64::from(input.prims[2 * k + 1][0]))
                    })
                    .collect();
                let v: f64 = terms.iter().map(|t| t.3 * t.2).sum();
                let g: glam::DVec3 = terms.iter().map(|t| -2.0 * t.1 * t.3 * t.2 * t.0).sum();
                let dv = REL * terms.iter().map(|t| (t.3 * t.2).abs()).sum::<f64>();
                let dg = REL
                    * (terms.iter())
                        .map(|t| (2.0 * t.1 * t.3 * t.2).abs() * t.0.length())
                        .sum::<f64>();
                let inv_m = f64::from(u.inv_m);
                let alpha = f64::from(u.alpha);
                let glen = g.length().max(f64::from(u.g_min2).sqrt());
                let res = v - f64::from(u.iso);
                let gh = g / glen;
                let dn =
                    2.0 * (n - gh * gh.dot(n)).length() / glen + 2.0 * (n + gh).length() / glen;
                let en = (n + gh).length_squared();
                let lv = 2.0 * res.abs() * inv_m;
                let lg = alpha * inv_m * dn;
                let dlv = 2.0 * dv * inv_m;
                let dlg = alpha * inv_m * 6.0 / (glen * glen) * dg;
                tol[0] += (2.0 * res.abs() * dv + dv * dv + alpha * dn * dg) * inv_m
                    + REL * (res * res + alpha * en) * inv_m;
                for (k, &(d, a, ex, b)) in terms.iter().enumerate() {
                    let s = d.length_squared();
                    let e = (b * ex).abs();
                    let dl = d.length();
                    let m = lv + 2.0 * a * lg * dl;
                    let dm = dlv + 2.0 * a * dl * dlg;
                    let t = &mut tol[1 + 5 * k..6 + 5 * k];
                    let c = 2.0 * a * e * (dm * dl + dlg) + REL * 2.0 * a * e * (m * dl + lg);
                    t[0] += c;
                    t[1] += c;
                    t[2] += c;
                    t[3] += s * e * dlv
                        + 2.0 * e * (1.0 - a * s).abs() * dl * dlg
                        + REL * (s * e * lv + 2.0 * e * (1.0 - a * s).abs() * lg * dl);
                    t[4] += ex * dm + REL * ex * m;
                }
            }
            tol.into_iter().map(|t| 2.0 * t + 1e-30)
        })
        .collect()
}

/// Whether every GPU output is within its tolerance of the mirror's.
pub fn accepts(tolerances: &[f64], cpu: &[f32], gpu: &[f32]) -> bool {
    cpu.len() == gpu.len()
        && tolerances.len() == cpu.len()
        && (cpu.iter().zip(gpu).zip(tolerances))
            .all(|((&c, &g), &t)| !g.is_nan() && (f64::from(c) - f64::from(g)).abs() <= t)
}
