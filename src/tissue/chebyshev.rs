//! The accelerated equilibrium solver: Chebyshev semi-iterative
//! acceleration of Jacobi-preconditioned relaxation, in its stationary form.
//!
//! Why this method. The static equilibrium solves g(x) = f on the free nodes
//! with the bone fixed. With D = diag(Σ_j c_max,ij) (per node), the
//! eigenvalues of the preconditioned stiffness D⁻¹K lie in (0, 2] by
//! Gershgorin, for every state in which no spring is compressed below half
//! its rest length. Chebyshev acceleration of the Jacobi iteration over an
//! interval [μ, L] converges at rate (√κ − 1)/(√κ + 1), κ = L/μ, instead of
//! the (κ − 1)/(κ + 1)-like rate of a plain or physically damped scheme —
//! for the ~10⁴–10⁶ condition numbers of large networks, tens to hundreds
//! of times fewer passes. Its stationary limit (the second-order
//! Richardson iteration of Frankel / Golub–Varga, equal to Polyak's heavy
//! ball with Chebyshev-optimal parameters) has the same asymptotic rate and
//! constant coefficients:
//!
//! ```text
//! u ← β u + α D⁻¹ (f − g(x));   x ← x + u
//! α = 4 / (√L + √μ)²,  β = ((√L − √μ) / (√L + √μ))²
//! ```
//!
//! so one kernel, one gather over the CSR and no global reduction per
//! iteration: exactly the GPU shape of the explicit step, with per-node
//! scaling in the position's w lane. Methods that need a global dot product
//! per iteration (nonlinear CG, FIRE) or a sparse factorisation
//! (projective dynamics) fit the GPU worse, and their data-dependent
//! branches would make CPU/GPU parity fragile. The heavy ball with L = 2 is
//! stable for every eigenvalue below 2 + μ, so the method is robust whatever
//! the estimate of μ; a poor μ only costs speed.
//!
//! μ comes from Lanczos on D^{-1/2} K D^{-1/2} at the rest state (K the
//! linearised stiffness with c1), in f64 on the host, once per network.
//! The state keeps `v = u / h` so the stop criteria read as for the explicit
//! scheme (h = the explicit default Δt).

use rayon::prelude::*;

use super::network::{Spectrum, SpringCsr, SpringNetwork};

/// Upper bound of the spectrum of D⁻¹K (Gershgorin).
pub const LAMBDA_MAX: f64 = 2.0;
/// Lanczos steps for the estimate of μ (fewer for tiny networks).
const LANCZOS_STEPS: usize = 160;
/// The Ritz value overestimates λ_min; we take this fraction of it.
const MU_SAFETY: f64 = 0.5;

/// Coefficients of the stationary Chebyshev iteration.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ChebyshevCoefficients {
    /// μ used (lower end of the interval).
    pub lambda_min: f64,
    /// L used (upper end).
    pub lambda_max: f64,
    /// β.
    pub momentum: f64,
    /// α.
    pub step: f64,
}

impl ChebyshevCoefficients {
    /// Optimal coefficients for the interval of `spectrum`.
    pub fn new(spectrum: Spectrum) -> Self {
        let l = spectrum.lambda_max;
        let mu = spectrum.lambda_min.clamp(f64::MIN_POSITIVE, l);
        let (sl, sm) = (l.sqrt(), mu.sqrt());
        ChebyshevCoefficients {
            lambda_min: mu,
            lambda_max: l,
            momentum: ((sl - sm) / (sl + sm)).powi(2),
            step: 4.0 / (sl + sm).powi(2),
        }
    }
}

/// y = D^{-1/2} K D^{-1/2} x on the free nodes (3 dofs each), K the
/// linearised stiffness at rest: Σ c1 r̂ r̂ᵀ per spring (c1·I for a spring
/// of rest length 0), fixed nodes as
/// Dirichlet (zero) neighbours.
fn apply(net: &SpringNetwork, inv_sqrt_d: &[f64], x: &[f64], y: &mut [f64]) {
    let nf = net.n_free;
    let rest = &net.rest;
    y.par_chunks_mut(3).enumerate().for_each(|(i, yi)| {
        let pi = rest[i];
        let xi = [
            x[3 * i] * inv_sqrt_d[i],
            x[3 * i + 1] * inv_sqrt_d[i],
            x[3 * i + 2] * inv_sqrt_d[i],
        ];
        let mut acc = [0.0f64; 3];
        let row = &net.csr.entries[net.csr.offsets[i] as usize..net.csr.offsets[i + 1] as usize];
        for &e in row {
            let (j, m, _) = SpringCsr::unpack(e);
            let pj = rest[j];
            let r = [
                (pi[0] - pj[0]) as f64,
                (pi[1] - pj[1]) as f64,
                (pi[2] - pj[2]) as f64,
            ];
            let len2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
            let xj = if j < nf {
                [
                    x[3 * j] * inv_sqrt_d[j],
                    x[3 * j + 1] * inv_sqrt_d[j],
                    x[3 * j + 2] * inv_sqrt_d[j],
                ]
            } else {
                [0.0; 3]
            };
            let d = [xi[0] - xj[0], xi[1] - xj[1], xi[2] - xj[2]];
            let c = net.materials[m].c1 as f64;
            if len2 == 0.0 {
                // A spring of rest length 0 (coincident nodes) pulls back
                // along any separation: stiffness c·I, not c·r̂r̂ᵀ.
                for k in 0..3 {
                    acc[k] += c * d[k];
                }
                continue;
            }
            let proj = c * (r[0] * d[0] + r[1] * d[1] + r[2] * d[2]) / len2;
            for k in 0..3 {
                acc[k] += proj * r[k];
            }
        }
        for k in 0..3 {
            yi[k] = acc[k] * inv_sqrt_d[i];
        }
    });
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.par_iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Number of eigenvalues of the symmetric tridiagonal (a, b) below `x`
/// (Sturm sequence).
fn count_below(a: &[f64], b: &[f64], x: f64) -> usize {
    let mut count = 0;
    let mut q = 1.0f64;
    for k in 0..a.len() {
        let off = if k == 0 { 0.0 } else { b[k - 1] * b[k - 1] };
        q = a[k] - x - if k == 0 { 0.0 } else { off / q };
        if q == 0.0 {
            q = f64::EPSILON * (a[k].abs() + x.abs()).max(f64::MIN_POSITIVE);
        }
        if q < 0.0 {
            count += 1;
        }
    }
    count
}

/// Smallest eigenvalue of the tridiagonal by bisection.
fn smallest_eigenvalue(a: &[f64], b: &[f64]) -> f64 {
    let bound = (0..a.len())
        .map(|k| {
            a[k].abs()
                + if k > 0 { b[k - 1].abs() } else { 0.0 }
                + if k < b.len() { b[k].abs() } else { 0.0 }
        })
        .fold(0.0f64, f64::max);
    let (mut lo, mut hi) = (-bound, bound);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if count_below(a, b, mid) >= 1 {
            hi = mid;
        } else {
            lo = mid;
        }
        if hi - lo <= 1e-15 * bound.max(1e-300) {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// Estimates the spectral interval of D⁻¹K at rest: λ_max = 2
/// (Gershgorin), λ_min = `MU_SAFETY` × the smallest Ritz value of
/// Lanczos on D^{-1/2} K D^{-1/2} (plain Lanczos, which is reliable for
/// the extreme eigenvalues; deterministic start vector).
pub fn estimate_spectrum(net: &SpringNetwork) -> Spectrum {
    let nf = net.n_free;
    let dims = 3 * nf;
    if dims == 0 {
        return Spectrum {
            lambda_min: LAMBDA_MAX,
            lambda_max: LAMBDA_MAX,
        };
    }
    let d = net.nodal_stiffness();
    let inv_sqrt_d: Vec<f64> = d
        .iter()
        .map(|&s| {
            if s > 0.0 {
                1.0 / (s as f64).sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut q: Vec<f64> = (0..dims)
        .map(|_| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 + 0.5
        })
        .collect();
    let norm = dot(&q, &q).sqrt();
    q.iter_mut().for_each(|v| *v /= norm);
    let mut q_prev = vec![0.0; dims];
    let mut w = vec![0.0; dims];
    let (mut alpha, mut beta) = (Vec::new(), Vec::new());
    let mut b_prev = 0.0;
    for _ in 0..LANCZOS_STEPS.min(dims) {
        apply(net, &inv_sqrt_d, &q, &mut w);
        let a = dot(&w, &q);
        w.par_iter_mut()
            .zip(&q)
            .zip(&q_prev)
            .for_each(|((wk, &qk), &pk)| *wk -= a * qk + b_prev * pk);
        alpha.push(a);
        let b = dot(&w, &w).sqrt();
        if b <= 1e-12 * a.abs().max(1e-300) {
            break;
        }
        beta.push(b);
        std::mem::swap(&mut q_prev, &mut q);
        q.par_iter_mut().zip(&w).for_each(|(qk, &wk)| *qk = wk / b);
        b_prev = b;
    }
    beta.truncate(alpha.len().saturating_sub(1));
    let ritz_min = smallest_eigenvalue(&alpha, &beta);
    Spectrum {
        lambda_min: (MU_SAFETY * ritz_min).clamp(1e-12, LAMBDA_MAX),
        lambda_max: LAMBDA_MAX,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sturm_bisection_finds_smallest_eigenvalue() {
        // Tridiagonal (2, -1) of size n: eigenvalues 2 − 2cos(kπ/(n+1)).
        let n = 50;
        let a = vec![2.0; n];
        let b = vec![-1.0; n - 1];
        let expect = 2.0 - 2.0 * (std::f64::consts::PI / (n as f64 + 1.0)).cos();
        assert!((smallest_eigenvalue(&a, &b) - expect).abs() < 1e-12);
        assert_eq!(count_below(&a, &b, 4.1), n);
    }

    #[test]
    fn coefficients_are_polyak_optimal() {
        let c = ChebyshevCoefficients::new(Spectrum {
            lambda_min: 0.02,
            lambda_max: 2.0,
        });
        assert!((c.momentum - (0.9f64 / 1.1).powi(2)).abs() < 1e-12);
        assert!((c.step - 4.0 / (2f64.sqrt() + 0.02f64.sqrt()).powi(2)).abs() < 1e-12);
    }
}
