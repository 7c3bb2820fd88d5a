//! The fast path of the step kernels: the CPU gathers several nodes at once
//! as the lanes of a SIMD register, the way a GPU runs invocations side by
//! side ([`Lanes`]: four in a `Vec4`, eight with AVX2 or sixteen with
//! AVX-512 in `wide.rs`, arranged once per network by [`SpringGather`]),
//! and runs the groups in parallel with rayon (each node writes only its
//! own outputs, so the result does not depend on scheduling). The
//! per-spring sqrt and division become vector instructions, each lane
//! still computes its own node's sum in its own CSR order, and the results
//! stay bit for bit those of the mirror ([`super::spring_step`],
//! [`super::spring_chebyshev`]) whatever the width (`tests/tissue.rs`).
//! The relaxations ([`crate::tissue::relax()`]) run this path.

use glam::{Mat4, Vec4};
use rayon::prelude::*;
use serde::Serialize;

use super::{SpringChebyshevParams, SpringStepParams, VELOCITY_FLUSH, block_solve};
use crate::tissue::network::SpringCsr;

#[cfg(target_arch = "x86_64")]
mod wide;

/// Nodes per rayon task of the fast path for `n` nodes: about eight
/// tasks per thread (load balance on a shared machine), at least 64 and at
/// most 2048 nodes (task overhead vs. cache-sized work), whole groups of
/// the widest gather.
fn grain(n: usize) -> usize {
    (n / (8 * rayon::current_num_threads()))
        .clamp(64, 2048)
        .next_multiple_of(16)
}

/// How many nodes the fast path gathers side by side. Every width gives
/// the same bits (each lane performs one kernel invocation's operations);
/// the widest this CPU has is the fastest.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Lanes {
    /// Four nodes, one `Vec4` lane each: SSE2 on every x86-64 CPU (glam's
    /// portable scalar code on other architectures).
    Four,
    /// Eight nodes, one lane of a 256-bit register each: x86-64 CPUs with
    /// AVX2 (detected at run time).
    Eight,
    /// Sixteen nodes, one lane of a 512-bit register each: x86-64 CPUs with
    /// AVX-512 (F, BW, CD, DQ, VL).
    Sixteen,
}

impl Lanes {
    /// Every width, narrowest first.
    pub const ALL: [Lanes; 3] = [Lanes::Four, Lanes::Eight, Lanes::Sixteen];

    /// The widest width this CPU has; `CHISEL_CPU_LANES=4` or `8` asks for
    /// at most that many (to compare them). Read once.
    pub fn best() -> Lanes {
        static BEST: std::sync::OnceLock<Lanes> = std::sync::OnceLock::new();
        *BEST.get_or_init(|| {
            let cap = std::env::var("CHISEL_CPU_LANES")
                .ok()
                .and_then(|v| v.trim().parse::<usize>().ok())
                .unwrap_or(usize::MAX);
            Lanes::ALL
                .into_iter()
                .rfind(|l| l.is_available() && l.count() <= cap)
                .unwrap_or(Lanes::Four)
        })
    }

    /// Whether this CPU runs this width.
    pub fn is_available(self) -> bool {
        match self {
            Lanes::Four => true,
            #[cfg(target_arch = "x86_64")]
            Lanes::Eight => pulp::x86::V3::is_available(),
            #[cfg(target_arch = "x86_64")]
            Lanes::Sixteen => pulp::x86::V4::is_available(),
            #[cfg(not(target_arch = "x86_64"))]
            Lanes::Eight | Lanes::Sixteen => false,
        }
    }

    /// Nodes per group.
    pub fn count(self) -> usize {
        match self {
            Lanes::Four => 4,
            Lanes::Eight => 8,
            Lanes::Sixteen => 16,
        }
    }

    /// What the CPU units are called, for reports.
    pub fn name(self) -> &'static str {
        match self {
            Lanes::Four => "4 lanes (SSE2)",
            Lanes::Eight => "8 lanes (AVX2)",
            Lanes::Sixteen => "16 lanes (AVX-512)",
        }
    }
}

/// The fast path of the step kernels for one network's CSR at one gather
/// width: the CSR's first `n_free` rows arranged once for the wide gathers
/// (a copy of the entries, interleaved by group of 8 or 16 nodes), then any
/// number of steps, each equal bit for bit to the mirror's
/// ([`super::spring_step`], [`super::spring_chebyshev`]).
#[derive(Debug, Clone)]
pub struct SpringGather<'a> {
    csr: &'a SpringCsr,
    lanes: Lanes,
    #[cfg(target_arch = "x86_64")]
    wide: Option<wide::WideRows>,
}

impl<'a> SpringGather<'a> {
    /// The fast path of `csr`'s first `n_free` rows gathering `lanes` nodes at
    /// a time; an error where this CPU lacks that width.
    pub fn new(csr: &'a SpringCsr, n_free: usize, lanes: Lanes) -> Result<Self, crate::Error> {
        if !lanes.is_available() {
            return Err(crate::Error::param(
                "lanes",
                lanes.name(),
                "this CPU lacks the instructions to gather that many lanes",
            ));
        }
        Ok(Self::arrange(csr, n_free, lanes))
    }

    /// [`Lanes::best`] for `csr`.
    pub fn best(csr: &'a SpringCsr, n_free: usize) -> Self {
        Self::arrange(csr, n_free, Lanes::best())
    }

    /// [`SpringGather::new`] for a width this CPU has.
    fn arrange(csr: &'a SpringCsr, n_free: usize, lanes: Lanes) -> Self {
        let n_free = n_free.min(csr.offsets.len().saturating_sub(1));
        #[cfg(target_arch = "x86_64")]
        let wide = match lanes {
            Lanes::Four => None,
            Lanes::Eight => Some(wide::WideRows::Eight(wide::LaneRows::new(csr, n_free))),
            Lanes::Sixteen => Some(wide::WideRows::Sixteen(wide::LaneRows::new(csr, n_free))),
        };
        #[cfg(not(target_arch = "x86_64"))]
        let _ = n_free;
        SpringGather {
            csr,
            lanes,
            #[cfg(target_arch = "x86_64")]
            wide,
        }
    }

    /// The gather width.
    pub fn lanes(&self) -> Lanes {
        self.lanes
    }
}

/// Nodes the portable gather takes side by side, like a SIMD group of GPU
/// invocations (one `Vec4` lane each; SSE2 on x86-64, scalar elsewhere).
const LANES: usize = 4;

/// Spring force sums g_i of eq. 4.4 of the nodes `i0..i0 + lanes`
/// (`1 ≤ lanes ≤ LANES`), with rest positions `rest` and displacements
/// `pos_in`: lane t is node `i0 + t` and sums its springs in its CSR order,
/// r_ij = (x0_i − x0_j) + (u_i − u_j), so every lane performs exactly the
/// float operations of one kernel invocation (vector sqrt, division and
/// arithmetic round like scalar ones, and nothing is contracted to FMA).
/// The rest length is l_ij = |x0_i − x0_j| from the same f32 difference.
/// A lane whose row has ended reads its own node with an all-zero material
/// (r = 0, |r| = 0, c_max = 0: nothing added). Returns `[gx, gy, gz]`
/// by lane and, with `BLOCKS`, the preconditioner blocks of
/// `spring_chebyshev.wgsl` as `[b00, b11, b22, b01, b02, b12]` by lane
/// (η = `isotropy`; zeros without `BLOCKS`).
#[inline(always)]
fn gather_group<const BLOCKS: bool>(
    i0: usize,
    lanes: usize,
    csr: &SpringCsr,
    rest: &[[f32; 4]],
    pos_in: &[[f32; 4]],
    materials: &[[f32; 4]; 16],
    isotropy: f32,
) -> ([Vec4; 3], [Vec4; 6]) {
    // One length for both node arrays: one bounds check per neighbour.
    let n = rest.len().min(pos_in.len());
    let (rest, pos_in, entries) = (&rest[..n], &pos_in[..n], &csr.entries[..]);
    let mut node = [i0; LANES];
    let mut start = [0usize; LANES];
    let mut count = [0usize; LANES];
    for t in 0..lanes {
        node[t] = i0 + t;
        start[t] = csr.offsets[i0 + t] as usize;
        count[t] = csr.offsets[i0 + t + 1] as usize - start[t];
    }
    let x0 = node.map(|i| Vec4::from_array(rest[i]));
    let u = node.map(|i| Vec4::from_array(pos_in[i]));
    let k_end = count.iter().copied().max().unwrap_or(0);
    let (mut gx, mut gy, mut gz) = (Vec4::ZERO, Vec4::ZERO, Vec4::ZERO);
    let (mut blocks, mut iso) = ([Vec4::ZERO; 6], Vec4::ZERO);
    let eta = Vec4::splat(isotropy);
    for k in 0..k_end {
        let mut d0 = [Vec4::ZERO; LANES];
        let mut r = [Vec4::ZERO; LANES];
        let mut row = [Vec4::ZERO; LANES];
        for t in 0..LANES {
            // A lane past its row: its own node and an all-zero material.
            let (j, m) = if k < count[t] {
                let (j, m) = SpringCsr::unpack(entries[start[t] + k]);
                (j, Vec4::from_array(materials[m]))
            } else {
                (node[t], Vec4::ZERO)
            };
            d0[t] = x0[t] - Vec4::from_array(rest[j]);
            r[t] = d0[t] + (u[t] - Vec4::from_array(pos_in[j]));
            row[t] = m;
        }
        // Lanes as vectors: d0 and r by component, the material rows as
        // (c1, c2 − c1, knee, c_max) by lane.
        let d0 = Mat4::from_cols(d0[0], d0[1], d0[2], d0[3]).transpose();
        let r = Mat4::from_cols(r[0], r[1], r[2], r[3]).transpose();
        let mat = Mat4::from_cols(row[0], row[1], row[2], row[3]).transpose();
        // Rest length l_ij = |x_rest,i − x_rest,j|, from the same difference.
        let (dx, dy, dz) = (d0.x_axis, d0.y_axis, d0.z_axis);
        let l = (dx * dx + dy * dy + dz * dz).sqrt();
        let (rx, ry, rz) = (r.x_axis, r.y_axis, r.z_axis);
        let len = (rx * rx + ry * ry + rz * rz).sqrt();
        // Biphasic law (seed §4.1.2): c1·e + (c2 − c1)·max(e − knee·l, 0).
        let ext = len - l;
        let f = mat.x_axis * ext + mat.y_axis * (ext - mat.z_axis * l).max(Vec4::ZERO);
        let s = f / len;
        // A zero (or NaN) length adds +0, which leaves g unchanged: g starts
        // at +0 and a sum starting at +0 is never −0.
        let on = len.cmpgt(Vec4::ZERO);
        gx += Vec4::select(on, s * rx, Vec4::ZERO);
        gy += Vec4::select(on, s * ry, Vec4::ZERO);
        gz += Vec4::select(on, s * rz, Vec4::ZERO);
        if BLOCKS {
            let c_max = mat.w_axis;
            let across = (eta * c_max).max(s);
            // q = 0 where the kernel skips the spring: its terms add ±0,
            // which leaves sums that start at +0 unchanged.
            let q = Vec4::select(on, (c_max - across) / (len * len), Vec4::ZERO);
            let (qx, qy, qz) = (q * rx, q * ry, q * rz);
            let terms = [qx * rx, qy * ry, qz * rz, qx * ry, qx * rz, qy * rz];
            for (b, term) in blocks.iter_mut().zip(terms) {
                *b += term;
            }
            // A spring of length 0 adds c_max I (a lane past its row, 0).
            iso += Vec4::select(on, across, c_max);
        }
    }
    for b in &mut blocks[..3] {
        *b += iso;
    }
    ([gx, gy, gz], blocks)
}

#[inline(always)]
fn flush(v: f32) -> f32 {
    if v.abs() < VELOCITY_FLUSH { 0.0 } else { v }
}

/// The per-node update after the gather (u: displacement, w = B/m, g and
/// b from [`gather_group`], v: velocity, f: external force).
#[derive(Debug, Clone, Copy)]
enum Update {
    /// `spring_step`: eq. 4.5–4.7 with Δt and damping γ.
    Explicit { dt: f32, gamma: f32 },
    /// `spring_chebyshev`: pseudo-time step h, momentum β, gain α/h.
    Chebyshev { h: f32, beta: f32, gain: f32 },
}

impl Update {
    /// `(u', v')` of one node.
    #[inline(always)]
    fn apply(
        self,
        u: [f32; 3],
        w: f32,
        g: [f32; 3],
        b: [f32; 6],
        v: [f32; 3],
        f: [f32; 3],
    ) -> ([f32; 3], [f32; 3]) {
        let mut u2 = [0.0f32; 3];
        let mut v2 = [0.0f32; 3];
        match self {
            Update::Explicit { dt, gamma } => {
                for k in 0..3 {
                    // eq. 4.5: a = (f − γ v − g) · B/m;  eq. 4.7: v += Δt a; u += Δt v.
                    let a = (f[k] - gamma * v[k] - g[k]) * w;
                    v2[k] = flush(v[k] + dt * a);
                    u2[k] = u[k] + dt * v2[k];
                }
            }
            Update::Chebyshev { h, beta, gain } => {
                let r = block_solve(b, [f[0] - g[0], f[1] - g[1], f[2] - g[2]]);
                for k in 0..3 {
                    v2[k] = flush(beta * v[k] + gain * r[k]);
                    u2[k] = u[k] + h * v2[k];
                }
            }
        }
        (u2, v2)
    }
}

/// The uniforms both step kernels read besides their update's.
struct Uniforms<'p> {
    n_free: u32,
    use_forces: bool,
    /// η (`spring_chebyshev` only; not read by the gather without blocks).
    isotropy: f32,
    materials: &'p [[f32; 4]; 16],
}

/// Runs one step of `update` over the free nodes, in groups of
/// `gather`'s width (`BLOCKS`: the gather builds the preconditioner blocks);
/// the nodes a rayon task holds past its last whole group, and those past
/// the rows arranged for the wide gather, run four at a time (the same
/// bits).
#[expect(clippy::too_many_arguments, reason = "the kernel's bindings, one each")]
#[inline(always)]
fn for_free_nodes<const BLOCKS: bool>(
    gather: &SpringGather<'_>,
    p: &Uniforms<'_>,
    update: Update,
    rest: &[[f32; 4]],
    forces: &[[f32; 4]],
    pos_in: &[[f32; 4]],
    pos_out: &mut [[f32; 4]],
    vel: &mut [[f32; 4]],
) {
    let csr = gather.csr;
    let n = p.n_free as usize;
    let chunk = grain(n);
    pos_out[..n]
        .par_chunks_mut(chunk)
        .zip(vel[..n].par_chunks_mut(chunk))
        .enumerate()
        .for_each(|(c, (po, ve))| {
            let (first, len) = (c * chunk, po.len());
            #[cfg_attr(not(target_arch = "x86_64"), expect(unused_mut))]
            let mut done = 0;
            #[cfg(target_arch = "x86_64")]
            if let Some(rows) = &gather.wide {
                // `chunk` is a multiple of every width: whole groups from `first`.
                let l = rows.width();
                let groups = first / l..((first + len) / l).min(rows.groups());
                let b = wide::Bindings {
                    csr,
                    rest,
                    pos_in,
                    forces,
                    use_forces: p.use_forces,
                    materials: p.materials,
                    isotropy: p.isotropy,
                    update,
                };
                let wide_nodes = groups.len() * l;
                if rows.run::<BLOCKS>(groups, &b, &mut po[..wide_nodes], &mut ve[..wide_nodes]) {
                    done = wide_nodes;
                }
            }
            for i in (first + done..first + len).step_by(LANES) {
                let lanes = LANES.min(first + len - i);
                let ([gx, gy, gz], blocks) =
                    gather_group::<BLOCKS>(i, lanes, csr, rest, pos_in, p.materials, p.isotropy);
                for t in 0..lanes {
                    let p_i = pos_in[i + t];
                    let f = if p.use_forces {
                        let f = forces[i + t];
                        [f[0], f[1], f[2]]
                    } else {
                        [0.0; 3]
                    };
                    let v = ve[i + t - first];
                    let (u2, v2) = update.apply(
                        [p_i[0], p_i[1], p_i[2]],
                        p_i[3],
                        [gx[t], gy[t], gz[t]],
                        blocks.map(|b| b[t]),
                        [v[0], v[1], v[2]],
                        f,
                    );
                    po[i + t - first] = [u2[0], u2[1], u2[2], p_i[3]];
                    ve[i + t - first] = [v2[0], v2[1], v2[2], 0.0];
                }
            }
        });
}

impl SpringGather<'_> {
    /// [`super::spring_step`] on this gather's CSR.
    pub fn spring_step(
        &self,
        p: &SpringStepParams,
        rest: &[[f32; 4]],
        forces: &[[f32; 4]],
        pos_in: &[[f32; 4]],
        pos_out: &mut [[f32; 4]],
        vel: &mut [[f32; 4]],
    ) {
        let update = Update::Explicit {
            dt: p.dt,
            gamma: p.damping,
        };
        let b = Uniforms {
            n_free: p.n_free,
            use_forces: p.use_forces,
            isotropy: 0.0,
            materials: &p.materials,
        };
        for_free_nodes::<false>(self, &b, update, rest, forces, pos_in, pos_out, vel);
    }

    /// [`super::spring_chebyshev`] on this gather's CSR.
    pub fn spring_chebyshev(
        &self,
        p: &SpringChebyshevParams,
        rest: &[[f32; 4]],
        forces: &[[f32; 4]],
        pos_in: &[[f32; 4]],
        pos_out: &mut [[f32; 4]],
        vel: &mut [[f32; 4]],
    ) {
        let update = Update::Chebyshev {
            h: p.h,
            beta: p.momentum,
            gain: p.gain,
        };
        let b = Uniforms {
            n_free: p.n_free,
            use_forces: p.use_forces,
            isotropy: p.isotropy,
            materials: &p.materials,
        };
        for_free_nodes::<true>(self, &b, update, rest, forces, pos_in, pos_out, vel);
    }
}
