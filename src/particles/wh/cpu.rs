//! CPU mirror of `kernels/particle_update.wgsl`: the same gather order and
//! f32 expressions, one particle per closure call.

use rayon::prelude::*;

use super::{StepInput, UpdateParams};
use crate::implicit::field::FieldInput;
use crate::implicit::field::cpu::skeletal_field;
use crate::particles::StepOutput;

fn sub(a: [f32; 4], b: [f32; 4]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Whether a GPU step agrees with the mirror's: positions and σ within
/// 1e-3 σ_i (one missing neighbour moves a particle by ≈ 0.1 σ, so this is
/// 100× below a real fault) plus 8 ulp of |p|; D_i within 1e-4 relative
/// plus 1e-4 α; |Δp|/Δt within 1e-3 σ_i/Δt; the residual within 1e-3 σ_i;
/// |∇F| within 1e-4 relative. The kernel's exp and divisions are not
/// correctly rounded (≤ 53 ulp per term, see `implicit::field::cpu::REL`)
/// and the repulsion sums cancel.
pub fn accepts(u: &UpdateParams, cpu: ([f32; 4], [f32; 4]), gpu: ([f32; 4], [f32; 4])) -> bool {
    let close = |a: f32, b: f32, tol: f32| !a.is_nan() && !b.is_nan() && (a - b).abs() <= tol;
    let sigma = cpu.0[3];
    let mag = cpu.0[0].abs().max(cpu.0[1].abs()).max(cpu.0[2].abs());
    let pos_tol = 1e-3 * sigma + 8.0 * f32::EPSILON * mag;
    (0..4).all(|k| close(cpu.0[k], gpu.0[k], pos_tol))
        && close(cpu.1[0], gpu.1[0], 1e-4 * cpu.1[0].abs() + 1e-4 * u.alpha)
        && close(cpu.1[1], gpu.1[1], 1e-3 * sigma / u.dt)
        && close(cpu.1[2], gpu.1[2], 1e-3 * sigma)
        && close(cpu.1[3], gpu.1[3], 1e-4 * cpu.1[3].abs() + 1e-30)
}

/// Repulsion P_i, D_i and ∂D_i/∂σ_i of particle `i` (the kernel's gather).
pub fn repulsion(
    u: &UpdateParams,
    cells: &[u32],
    pos: &[[f32; 4]],
    i: usize,
) -> ([f32; 3], f32, f32) {
    let me = pos[i];
    let s_i = me[3];
    let inv2_i = 1.0 / (2.0 * s_i * s_i);
    let inv9_i = 1.0 / (9.0 * s_i * s_i);
    let mut rep = [0.0f32; 3];
    let mut d_i = 0.0f32;
    let mut dd_i = 0.0f32;
    let dims = [u.nx, u.ny, u.nz];
    let items = u.n_cells as usize + 1;
    let h = cells[items + u.n_particles as usize + i];
    let c = [
        (h % dims[0]) as i32,
        ((h / dims[0]) % dims[1]) as i32,
        (h / (dims[0] * dims[1])) as i32,
    ];
    for dz in -1..=1 {
        for dy in -1..=1 {
            for dx in -1..=1 {
                let q = [c[0] + dx, c[1] + dy, c[2] + dz];
                if (0..3).any(|k| q[k] < 0 || q[k] >= dims[k] as i32) {
                    continue;
                }
                let cell = q[0] as usize
                    + dims[0] as usize * (q[1] as usize + dims[1] as usize * q[2] as usize);
                for k in cells[cell]..cells[cell + 1] {
                    let j = cells[items + k as usize] as usize;
                    if j == i {
                        continue;
                    }
                    let o = pos[j];
                    let r = sub(me, o);
                    let r2 = dot(r, r);
                    let mut w = 0.0f32;
                    let q_i = r2 * inv9_i;
                    if q_i < 1.0 {
                        let g = u.alpha * (-r2 * inv2_i).exp();
                        let t = 1.0 - q_i;
                        d_i += g * t * t;
                        dd_i += g * t * (r2 * 2.0 * inv2_i * t + 4.0 * q_i) / s_i;
                        w = g * t * (t + 4.0 / 9.0);
                    }
                    let s_j = o[3];
                    let q_j = r2 / (9.0 * s_j * s_j);
                    if q_j < 1.0 {
                        let t = 1.0 - q_j;
                        let ratio = s_i / s_j;
                        w += ratio
                            * ratio
                            * u.alpha
                            * (-r2 / (2.0 * s_j * s_j)).exp()
                            * t
                            * (t + 4.0 / 9.0);
                    }
                    rep = [rep[0] + w * r[0], rep[1] + w * r[1], rep[2] + w * r[2]];
                }
            }
        }
    }
    (rep, d_i, dd_i)
}

/// The kernel `particle_update`: new (position, σ) and (D_i, |Δp|/Δt,
/// (F − I)/|∇F|, |∇F|) per particle.
pub fn particle_update(field: &FieldInput, input: &StepInput<'_>) -> StepOutput {
    let u = &input.params;
    (0..input.positions.len())
        .into_par_iter()
        .map(|i| {
            let (rep, d_i, dd_i) = repulsion(u, input.cells, input.positions, i);
            let me = input.positions[i];
            let s_i = me[3];
            let (f, _) = skeletal_field(field, [me[0], me[1], me[2]]);
            let g2 = dot(f.grad, f.grad).max(u.g_min2);
            let lambda = (u.dt * dot(f.grad, rep) + u.delta * f.rate + u.kappa * f.value) / g2;
            let mut step = [
                u.dt * rep[0] - lambda * f.grad[0],
                u.dt * rep[1] - lambda * f.grad[1],
                u.dt * rep[2] - lambda * f.grad[2],
            ];
            let len = dot(step, step).sqrt();
            if len > s_i {
                let k = s_i / len;
                step = [step[0] * k, step[1] * k, step[2] * k];
            }
            let mut s_new = s_i;
            if u.adapt == 1 {
                let rate = -u.rho_sigma * (d_i - u.e_hat) / (dd_i + u.beta_sigma);
                s_new = (s_i + u.dt * rate).clamp(u.sigma_lo, u.sigma_hi);
            }
            let out = [me[0] + step[0], me[1] + step[1], me[2] + step[2], s_new];
            let state = [
                d_i,
                dot(step, step).sqrt() / u.dt,
                f.value / g2.sqrt(),
                dot(f.grad, f.grad).sqrt(),
            ];
            (out, state)
        })
        .unzip()
}
