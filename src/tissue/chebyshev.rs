//! The accelerated equilibrium solver: Chebyshev semi-iterative
//! acceleration of block-Jacobi-preconditioned relaxation, in its
//! stationary form.
//!
//! Why this method. The static equilibrium solves g(x) = f on the free nodes
//! with the bone fixed. Chebyshev acceleration of a preconditioned
//! Richardson iteration over a spectral interval [μ, L] of P K (P the
//! preconditioner, K the stiffness) converges at rate (√κ − 1)/(√κ + 1),
//! κ = L/μ, instead of the (κ − 1)/(κ + 1)-like rate of a plain or
//! physically damped scheme. Its stationary limit (the second-order
//! Richardson iteration of Frankel / Golub–Varga, equal to Polyak's heavy
//! ball with Chebyshev-optimal parameters) has the same asymptotic rate and
//! constant coefficients:
//!
//! ```text
//! u ← β u + α P (f − g(x));   x ← x + u
//! α = 4 / (√L + √μ)²,  β = ((√L − √μ) / (√L + √μ))²
//! ```
//!
//! so one kernel, one gather over the CSR and no global reduction per
//! iteration: exactly the GPU shape of the explicit step. Methods that need
//! a global dot product per iteration (nonlinear CG, FIRE) or a sparse
//! factorisation (projective dynamics) fit the GPU worse, and their
//! data-dependent branches would make CPU/GPU parity fragile.
//!
//! The preconditioner: per free node the inverse of a 3 × 3 block B_i(x)
//! built in the kernel, at the current state, from the springs it gathers
//! anyway:
//!
//! ```text
//! B_i = Σ_j c_max r̂r̂ᵀ + t_ij (I − r̂r̂ᵀ),   t_ij = max(η c_max, f_ij / |r_ij|)
//! ```
//!
//! (r̂ the current direction; c_max I for a spring of length 0), η =
//! [`BLOCK_ISOTROPY`]. A scalar (Jacobi) preconditioner treats every
//! direction at a node alike; but a skin node whose springs nearly all lie
//! in the surface is a thousand times softer across it than along it, and
//! those directions set κ. At 408k nodes, to within 1 % of the equilibrium
//! after a 0.0625 mm increment: 400 iterations, against 1,300 with scalar
//! Jacobi and 17,950 for the explicit scheme.
//!
//! Bounds. A spring's tangent stiffness is H = f′ r̂r̂ᵀ + (f/|r|)(I − r̂r̂ᵀ)
//! with f′ ≤ c_max, so it lies below its term of B_i, and since a spring
//! couples two nodes, (x_i − x_j)ᵀ H (x_i − x_j) ≤ 2 x_iᵀ H x_i +
//! 2 x_jᵀ H x_j gives K(x) ≤ 2 B(x): no eigenvalue of B⁻¹K exceeds 2 in any
//! state, L = 2 needs no estimate, and the heavy ball with L = 2 is stable
//! for every eigenvalue below 2 + ~2√(2μ). Blocks built once at rest do not
//! have this: a spring turned or stretched by a large bone move is no
//! longer covered, and the iteration diverged on the 30 × 20 grid fixture.
//! Each spring adds at least min(c_max, t_ij) ≥ η c_max in every direction,
//! so a block's condition number stays below ~1/η while no spring pulls
//! with f/|r| > c_max. η = 0.05 was the best measured at 408k (0.1: 550
//! iterations, 0.05: 400, 0.01: 600); with small η the 160-step Lanczos
//! estimate of μ is less reliable (η = 0.01 with μ = the Ritz value itself
//! had not reached 1 % after 6,000 iterations). μ comes from Lanczos on
//! B^{-1/2} K B^{-1/2} (with the Cholesky factor of each B_i) at the rest
//! state (K with c1), in f64 on the host, once per network; a poor μ only
//! costs speed. The state keeps `v = u / h` so the stop criteria read as
//! for the explicit scheme (h = the explicit default Δt).

use rayon::prelude::*;
use serde::Serialize;

use super::network::{SpringCsr, SpringNetwork};

/// Upper bound of the spectrum of B⁻¹K in every state (see the module notes).
pub const LAMBDA_MAX: f64 = 2.0;
/// η: the least stiffness across a spring in the preconditioner blocks, as
/// a share of c_max.
pub const BLOCK_ISOTROPY: f32 = 0.05;
/// Lanczos steps for the estimate of μ (fewer for tiny networks).
const LANCZOS_STEPS: usize = 160;
/// The Ritz value overestimates λ_min; we take this fraction of it.
const MU_SAFETY: f64 = 0.5;

/// Spectral bounds of the block-Jacobi-preconditioned stiffness B⁻¹K, for
/// the Chebyshev solver: [`estimate_spectrum`] of a network, made once per
/// relaxation unless the caller passes one in
/// [`RelaxOptions::spectrum`](super::RelaxOptions::spectrum).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Spectrum {
    /// Lower estimate of the smallest eigenvalue of B⁻¹K at rest.
    pub lambda_min: f64,
    /// Upper bound of the largest eigenvalue of B⁻¹K in every state: 2.
    pub lambda_max: f64,
}

/// Coefficients of the stationary Chebyshev iteration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
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

/// The blocks B_i of the free nodes at rest (upper triangle `[b00, b01,
/// b02, b11, b12, b22]`, f64): there f = 0, so each spring adds
/// c_max ((1 − η) r̂r̂ᵀ + η I).
fn rest_blocks(net: &SpringNetwork) -> Vec<[f64; 6]> {
    let rest = &net.rest;
    let eta = f64::from(BLOCK_ISOTROPY);
    (0..net.n_free)
        .into_par_iter()
        .map(|i| {
            let pi = rest[i];
            let mut b = [0.0f64; 6];
            let row =
                &net.csr.entries[net.csr.offsets[i] as usize..net.csr.offsets[i + 1] as usize];
            for &e in row {
                let (j, m) = SpringCsr::unpack(e);
                let pj = rest[j];
                let r = [0, 1, 2].map(|k| (pi[k] - pj[k]) as f64);
                let len2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
                let c = net.materials[m].c_max() as f64;
                let (aniso, iso) = if len2 > 0.0 {
                    ((1.0 - eta) * c / len2, eta * c)
                } else {
                    (0.0, c)
                };
                b[0] += aniso * r[0] * r[0] + iso;
                b[1] += aniso * r[0] * r[1];
                b[2] += aniso * r[0] * r[2];
                b[3] += aniso * r[1] * r[1] + iso;
                b[4] += aniso * r[1] * r[2];
                b[5] += aniso * r[2] * r[2] + iso;
            }
            b
        })
        .collect()
}

/// Cholesky factor of a block, lower triangle `[l00, l10, l11, l20, l21,
/// l22]`; `None` unless positive definite.
fn cholesky(b: &[f64; 6]) -> Option<[f64; 6]> {
    let l00 = b[0].sqrt();
    let l10 = b[1] / l00;
    let l20 = b[2] / l00;
    let d1 = b[3] - l10 * l10;
    let l11 = d1.sqrt();
    let l21 = (b[4] - l20 * l10) / l11;
    let d2 = b[5] - l20 * l20 - l21 * l21;
    let l22 = d2.sqrt();
    (b[0] > 0.0 && d1 > 0.0 && d2 > 0.0 && l22.is_finite())
        .then_some([l00, l10, l11, l20, l21, l22])
}

/// Per free node S_i = L_i⁻¹ (lower triangle as in [`cholesky`]; zero for a
/// node without springs): S K Sᵀ has the spectrum of B⁻¹K.
fn inverse_factors(net: &SpringNetwork) -> Vec<[f64; 6]> {
    rest_blocks(net)
        .iter()
        .map(|b| match cholesky(b) {
            Some([l00, l10, l11, l20, l21, l22]) => {
                let (s00, s11, s22) = (1.0 / l00, 1.0 / l11, 1.0 / l22);
                let s10 = -l10 * s00 / l11;
                let s21 = -l21 * s11 / l22;
                let s20 = -(l20 * s00 + l21 * s10) / l22;
                [s00, s10, s11, s20, s21, s22]
            }
            None => [0.0; 6],
        })
        .collect()
}

/// S x_i (lower triangular S as in [`inverse_factors`]).
fn lower(s: &[f64; 6], x: [f64; 3]) -> [f64; 3] {
    [
        s[0] * x[0],
        s[1] * x[0] + s[2] * x[1],
        s[3] * x[0] + s[4] * x[1] + s[5] * x[2],
    ]
}

/// Sᵀ x_i.
fn upper(s: &[f64; 6], x: [f64; 3]) -> [f64; 3] {
    [
        s[0] * x[0] + s[1] * x[1] + s[3] * x[2],
        s[2] * x[1] + s[4] * x[2],
        s[5] * x[2],
    ]
}

/// y = S K Sᵀ x on the free nodes (3 dofs each), K the linearised stiffness
/// at rest: Σ c1 r̂r̂ᵀ per spring (c1·I for a spring of rest length 0),
/// fixed nodes as Dirichlet (zero) neighbours.
fn apply(net: &SpringNetwork, factors: &[[f64; 6]], x: &[f64], y: &mut [f64]) {
    let nf = net.n_free;
    let rest = &net.rest;
    let xs: Vec<[f64; 3]> = factors
        .par_iter()
        .enumerate()
        .map(|(i, s)| upper(s, [x[3 * i], x[3 * i + 1], x[3 * i + 2]]))
        .collect();
    y.par_chunks_mut(3).enumerate().for_each(|(i, yi)| {
        let pi = rest[i];
        let xi = xs[i];
        let mut acc = [0.0f64; 3];
        let row = &net.csr.entries[net.csr.offsets[i] as usize..net.csr.offsets[i + 1] as usize];
        for &e in row {
            let (j, m) = SpringCsr::unpack(e);
            let pj = rest[j];
            let r = [0, 1, 2].map(|k| (pi[k] - pj[k]) as f64);
            let len2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
            let xj = if j < nf { xs[j] } else { [0.0; 3] };
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
        yi.copy_from_slice(&lower(&factors[i], acc));
    });
}

/// Dot product summed in a fixed order (within chunks of 4,096, then the
/// chunk sums in order), so the spectrum, and with it every Chebyshev
/// relaxation, is the same whatever the number of threads and however
/// rayon splits the work.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    const CHUNK: usize = 1 << 12;
    let sums: Vec<f64> = (a.par_chunks(CHUNK).zip(b.par_chunks(CHUNK)))
        .map(|(x, y)| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>())
        .collect();
    sums.iter().sum()
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

/// Estimates the spectral interval of P K at rest: λ_max = 2 (see the
/// module notes), λ_min = `MU_SAFETY` × the smallest Ritz value of Lanczos
/// on S K Sᵀ, S = L⁻¹ per node (plain Lanczos, which is reliable for the
/// extreme eigenvalues; deterministic start vector).
pub fn estimate_spectrum(net: &SpringNetwork) -> Spectrum {
    let nf = net.n_free;
    let dims = 3 * nf;
    if dims == 0 {
        return Spectrum {
            lambda_min: LAMBDA_MAX,
            lambda_max: LAMBDA_MAX,
        };
    }
    let factors = inverse_factors(net);
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
        apply(net, &factors, &q, &mut w);
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

    /// Fixed-order sums: the same bits on 1, 2 and 8 threads (rayon's own
    /// parallel sum depends on how the work is split).
    #[test]
    fn dot_is_the_same_on_any_number_of_threads() {
        let n = 100_003;
        let a: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 1000) as f64 * 1e-3 + 1e-9)
            .collect();
        let b: Vec<f64> = (0..n).map(|i| 1.0 / (1.0 + i as f64)).collect();
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            (0..8)
                .map(|_| pool.install(|| dot(&a, &b)).to_bits())
                .collect::<Vec<_>>()
        };
        let one = on(1);
        assert!(one.iter().all(|&d| d == one[0]));
        assert_eq!(on(2), one);
        assert_eq!(on(8), one);
    }

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
