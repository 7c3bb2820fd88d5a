//! CPU mirrors of the tissue kernels: `kernels/spring_step.wgsl`,
//! `kernels/spring_chebyshev.wgsl` (with `kernels/shared/spring_network.wgsl`)
//! and `kernels/tissue_reduce_max.wgsl`.
//!
//! Each step mirror is the kernel's invocation as a plain loop over the
//! free nodes, with the WGSL's names and the same f32 operations in the
//! same order (CSR order of the springs, the same parenthesisation), to be
//! read beside it; the tolerances of their parity tests are defined next
//! to them. The relaxations run [`fast`], an optimised path tested equal
//! to these mirrors bit for bit. Lavapipe gives `spring_step` bit for bit;
//! `spring_chebyshev` differs from it by a few ulp per step
//! (`tests/parity/spring_step.rs`).

use rayon::prelude::*;

use super::network::SpringCsr;
use crate::parity::Tolerance;

pub mod fast;

/// Nodes per rayon task of the reduction mirror.
const CHUNK: usize = 512;

/// Velocity components below this magnitude are flushed to zero after each
/// update (kernel and mirror alike): subnormal floats are 100× slower on
/// CPUs (GPUs flush them anyway), and velocities this small move no
/// coordinate of any mesh in any unit.
pub const VELOCITY_FLUSH: f32 = 1e-30;

/// Parameters of `spring_step.wgsl` (its `Params`, the fields it reads,
/// and its `Materials` table).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpringStepParams {
    /// Number of free nodes (the dispatch size).
    pub n_free: u32,
    /// Whether `forces` holds external forces (otherwise f_i = 0).
    pub use_forces: bool,
    /// Δt.
    pub dt: f32,
    /// Damping γ.
    pub damping: f32,
    /// Material table rows `[c1, c2 − c1, knee, c_max]`.
    pub materials: [[f32; 4]; 16],
}

/// Parameters of `spring_chebyshev.wgsl` (its `Params` and its `Materials`
/// table).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpringChebyshevParams {
    /// Number of free nodes (the dispatch size).
    pub n_free: u32,
    /// Whether `forces` holds external forces (otherwise f_i = 0).
    pub use_forces: bool,
    /// The pseudo-time step h.
    pub h: f32,
    /// Momentum β.
    pub momentum: f32,
    /// Gain α/h on the preconditioned residual.
    pub gain: f32,
    /// η, the least stiffness across a spring in the preconditioner blocks
    /// as a share of c_max.
    pub isotropy: f32,
    /// Material table rows `[c1, c2 − c1, knee, c_max]`.
    pub materials: [[f32; 4]; 16],
}

/// Parity tolerance of positions after N iterations of either step kernel,
/// for a network of extent `diagonal` (mesh units).
///
/// Per node and iteration the kernel and this mirror may differ by FMA
/// contraction and the GPU's division/sqrt rounding: a few ulp in each
/// spring term, i.e. a relative error of ~8 ε_f32 in g_i, and half an ulp of
/// the coordinates in each update. The damped update is non-expansive for a
/// stable Δt, so differences add up at most linearly in N: we allow
/// `N · 8 ε_f32 · diagonal` absolute, i.e. for N = 200 on fran_cut
/// (diagonal ≈ 0.19 m) about 36 µm — far below any error a wrong kernel
/// makes (a missing spring or wrong sign moves nodes by the bone
/// displacement, millimetres), and the negative-control test shows a single
/// corrupted coordinate is caught.
pub fn position_tolerance(iterations: u32, diagonal: f32) -> Tolerance {
    Tolerance {
        abs: iterations.max(1) as f32 * 8.0 * f32::EPSILON * diagonal,
        rel: 0.0,
    }
}

/// The buffers of `spring_network.wgsl` (bindings 1–6) a mirror reads.
struct Network<'a> {
    materials: &'a [[f32; 4]; 16],
    csr: &'a SpringCsr,
    rest: &'a [[f32; 4]],
    forces: &'a [[f32; 4]],
    pos_in: &'a [[f32; 4]],
}

fn xyz(v: [f32; 4]) -> [f32; 3] {
    [v[0], v[1], v[2]]
}

/// `SpringTerm` of `spring_network.wgsl`.
struct SpringTerm {
    r: [f32; 3],
    len: f32,
    f: f32,
    c_max: f32,
}

/// `spring_term` of `spring_network.wgsl`: spring `k` of a row,
/// r_ij = (x_rest,i − x_rest,j) + (u_i − u_j), its length, the biphasic
/// force of its extension and c_max of its material.
fn spring_term(k: usize, x0: [f32; 3], u: [f32; 3], b: &Network<'_>) -> SpringTerm {
    let (j, m) = SpringCsr::unpack(b.csr.entries[k]);
    let m = b.materials[m];
    let d0: [f32; 3] = std::array::from_fn(|c| x0[c] - b.rest[j][c]);
    let l = (d0[0] * d0[0] + d0[1] * d0[1] + d0[2] * d0[2]).sqrt();
    let r: [f32; 3] = std::array::from_fn(|c| d0[c] + (u[c] - b.pos_in[j][c]));
    let len = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
    let ext = len - l;
    SpringTerm {
        r,
        len,
        f: m[0] * ext + m[1] * (ext - m[2] * l).max(0.0),
        c_max: m[3],
    }
}

/// The CSR row of node `ix`.
fn row(ix: usize, csr: &SpringCsr) -> std::ops::Range<usize> {
    csr.offsets[ix] as usize..csr.offsets[ix + 1] as usize
}

/// `spring_force` of `spring_network.wgsl`: g_i = Σ_j f(|r_ij| − l_ij) /
/// |r_ij| · r_ij (eq. 4.4) over node ix's row in stored order;
/// zero-length springs add nothing.
fn spring_force(ix: usize, x0: [f32; 3], u: [f32; 3], b: &Network<'_>) -> [f32; 3] {
    let mut g = [0.0f32; 3];
    for k in row(ix, b.csr) {
        let t = spring_term(k, x0, u, b);
        if t.len > 0.0 {
            let s = t.f / t.len;
            g = std::array::from_fn(|c| g[c] + s * t.r[c]);
        }
    }
    g
}

/// `external_force` of `spring_network.wgsl`.
fn external_force(ix: usize, use_forces: bool, b: &Network<'_>) -> [f32; 3] {
    if use_forces {
        xyz(b.forces[ix])
    } else {
        [0.0; 3]
    }
}

/// `advance` of `spring_network.wgsl`: v ← v_raw flushed below
/// [`VELOCITY_FLUSH`], u ← u + step · v, w copied.
fn advance(
    ix: usize,
    p: [f32; 4],
    v_raw: [f32; 3],
    step: f32,
    pos_out: &mut [[f32; 4]],
    vel: &mut [[f32; 4]],
) {
    let v_new = v_raw.map(|v| if v.abs() < VELOCITY_FLUSH { 0.0 } else { v });
    let u_new: [f32; 3] = std::array::from_fn(|c| p[c] + step * v_new[c]);
    pos_out[ix] = [u_new[0], u_new[1], u_new[2], p[3]];
    vel[ix] = [v_new[0], v_new[1], v_new[2], 0.0];
}

/// Mirror of `spring_step.wgsl`: one semi-implicit Euler step (eq. 4.4–4.7)
/// of every free node, on displacements from rest. `rest`: #nodes rest
/// positions `[x, y, z, _]`. `pos_in`/`pos_out`: #nodes displacements
/// `[ux, uy, uz, w]` (u = x − x_rest) with `w = B_i / m_i`; only the first
/// `n_free` of `pos_out` are written (the caller keeps the fixed nodes
/// equal in both buffers). `vel`: #free `[vx, vy, vz, 0]`, updated in
/// place. `forces`: #free external forces (read only when `use_forces`).
/// Parity tolerance: [`position_tolerance`].
pub fn spring_step(
    params: &SpringStepParams,
    csr: &SpringCsr,
    rest: &[[f32; 4]],
    forces: &[[f32; 4]],
    pos_in: &[[f32; 4]],
    pos_out: &mut [[f32; 4]],
    vel: &mut [[f32; 4]],
) {
    let b = Network {
        materials: &params.materials,
        csr,
        rest,
        forces,
        pos_in,
    };
    for ix in 0..params.n_free as usize {
        let p = pos_in[ix];
        // eq. 4.4–4.7.
        let g = spring_force(ix, xyz(rest[ix]), xyz(p), &b);
        let v = xyz(vel[ix]);
        let f = external_force(ix, params.use_forces, &b);
        let a: [f32; 3] = std::array::from_fn(|c| (f[c] - params.damping * v[c] - g[c]) * p[3]);
        let v_raw = std::array::from_fn(|c| v[c] + params.dt * a[c]);
        advance(ix, p, v_raw, params.dt, pos_out, vel);
    }
}

/// Mirror of `spring_chebyshev.wgsl`: one stationary Chebyshev (second-order
/// Richardson) step on the block-Jacobi-preconditioned equilibrium
/// equations, the 3 × 3 block of each node built at the current state
/// (η = `params.isotropy`). Same buffers as [`spring_step`] (the w lane is
/// not read); `vel` holds the last update divided by h. Parity tolerance:
/// [`position_tolerance`].
pub fn spring_chebyshev(
    params: &SpringChebyshevParams,
    csr: &SpringCsr,
    rest: &[[f32; 4]],
    forces: &[[f32; 4]],
    pos_in: &[[f32; 4]],
    pos_out: &mut [[f32; 4]],
    vel: &mut [[f32; 4]],
) {
    let b = Network {
        materials: &params.materials,
        csr,
        rest,
        forces,
        pos_in,
    };
    for ix in 0..params.n_free as usize {
        let p = pos_in[ix];
        let x0 = xyz(rest[ix]);
        let mut g = [0.0f32; 3];
        // B_i: diagonal (b00, b11, b22) without and off-diagonal (b01, b02,
        // b12), and the isotropic part Σ_j t_ij.
        let mut diag = [0.0f32; 3];
        let mut off = [0.0f32; 3];
        let mut iso = 0.0f32;
        for k in row(ix, csr) {
            let t = spring_term(k, x0, xyz(p), &b);
            if t.len > 0.0 {
                let s = t.f / t.len;
                g = std::array::from_fn(|c| g[c] + s * t.r[c]);
                let across = (params.isotropy * t.c_max).max(s);
                let q = (t.c_max - across) / (t.len * t.len);
                let qr = t.r.map(|x| q * x);
                diag = std::array::from_fn(|c| diag[c] + qr[c] * t.r[c]);
                // off + qr.xxy * r.yzz
                off = [
                    off[0] + qr[0] * t.r[1],
                    off[1] + qr[0] * t.r[2],
                    off[2] + qr[1] * t.r[2],
                ];
                iso += across;
            } else {
                iso += t.c_max;
            }
        }
        diag = diag.map(|x| x + iso);
        let f = external_force(ix, params.use_forces, &b);
        let d: [f32; 3] = std::array::from_fn(|c| f[c] - g[c]);
        let r = block_solve([diag[0], diag[1], diag[2], off[0], off[1], off[2]], d);
        let v = xyz(vel[ix]);
        let v_raw = std::array::from_fn(|c| params.momentum * v[c] + params.gain * r[c]);
        advance(ix, p, v_raw, params.h, pos_out, vel);
    }
}

/// B⁻¹ d for the block `b = [b00, b11, b22, b01, b02, b12]` by cofactors of
/// B / tr B, as `spring_chebyshev.wgsl` writes it out; 0 when tr B = 0 (no springs).
#[inline(always)]
pub fn block_solve(b: [f32; 6], d: [f32; 3]) -> [f32; 3] {
    let tr = b[0] + b[1] + b[2];
    if tr > 0.0 {
        let [a0, a1, a2, o0, o1, o2] = b.map(|x| x / tr);
        let c00 = a1 * a2 - o2 * o2;
        let c01 = o1 * o2 - o0 * a2;
        let c02 = o0 * o2 - o1 * a1;
        let c11 = a0 * a2 - o1 * o1;
        let c12 = o0 * o1 - a0 * o2;
        let c22 = a0 * a1 - o0 * o0;
        let det = a0 * c00 + o0 * c01 + o1 * c02;
        let w = det * tr;
        [
            (c00 * d[0] + c01 * d[1] + c02 * d[2]) / w,
            (c01 * d[0] + c11 * d[1] + c12 * d[2]) / w,
            (c02 * d[0] + c12 * d[1] + c22 * d[2]) / w,
        ]
    } else {
        [0.0; 3]
    }
}

/// Order-preserving key of a non-negative float: its bits without the sign
/// (any NaN or infinity maps above every finite value).
#[inline(always)]
pub fn max_key(x: f32) -> u32 {
    x.to_bits() & 0x7fff_ffff
}

/// Parity tolerance of [`tissue_reduce_max`] on the decoded keys: the keys
/// are f32 bit patterns of squared lengths; max is exact, only the rounding
/// of one squared length may differ (FMA contraction), so the decoded
/// values agree within 2 ulp (rel 2.4e-7).
pub const TISSUE_REDUCE_MAX_TOL: Tolerance = Tolerance {
    abs: 0.0,
    rel: 2.4e-7,
};

/// Mirror of `tissue_reduce_max.wgsl`: `[max_i key(|v_i|²), max_i
/// key(|x_i − s_i|²)]` over the first `n` nodes (`vel`, `pos`, `snapshot`
/// each hold at least `n`), in parallel chunks (max is exact whatever the
/// reduction tree). Parity tolerance: [`TISSUE_REDUCE_MAX_TOL`].
pub fn tissue_reduce_max(
    n: usize,
    vel: &[[f32; 4]],
    pos: &[[f32; 4]],
    snapshot: &[[f32; 4]],
) -> [u32; 2] {
    let sq = |d: [f32; 3]| max_key(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    vel[..n]
        .par_chunks(4 * CHUNK)
        .zip(pos[..n].par_chunks(4 * CHUNK))
        .zip(snapshot[..n].par_chunks(4 * CHUNK))
        .map(|((v, p), s)| {
            let mut keys = [0u32; 2];
            for ((v, p), s) in v.iter().zip(p).zip(s) {
                keys[0] = keys[0].max(sq([v[0], v[1], v[2]]));
                keys[1] = keys[1].max(sq([p[0] - s[0], p[1] - s[1], p[2] - s[2]]));
            }
            keys
        })
        .reduce(|| [0, 0], |a, b| [a[0].max(b[0]), a[1].max(b[1])])
}
