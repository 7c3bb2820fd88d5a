//! CPU mirror of `kernels/network_update.wgsl`: the same row order and f32
//! expressions.

use rayon::prelude::*;

use super::{NetworkInput, NetworkParams, StepOutput};
use crate::implicit::field::FieldInput;
use crate::implicit::field::cpu::skeletal_field;

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Whether a GPU step agrees with the mirror's: positions within 1e-4 of
/// the clamp `step_max` plus 8 ulp of |p| (an eq. 13 term left out moves a
/// vertex by ≈ Δt ρ |r| ≫ that), samples as `implicit_field` (relative
/// 256 ulp of their magnitudes, see `implicit::field::cpu::REL`).
pub fn accepts(u: &NetworkParams, cpu: ([f32; 4], [f32; 4]), gpu: ([f32; 4], [f32; 4])) -> bool {
    let close = |a: f32, b: f32, tol: f32| !a.is_nan() && !b.is_nan() && (a - b).abs() <= tol;
    let mag = cpu.0[0].abs().max(cpu.0[1].abs()).max(cpu.0[2].abs());
    let pos_tol = 1e-4 * u.step_max + 8.0 * f32::EPSILON * mag;
    let g = cpu.1[0].abs().max(cpu.1[1].abs()).max(cpu.1[2].abs());
    let rel = crate::implicit::field::cpu::REL;
    (0..3).all(|k| close(cpu.0[k], gpu.0[k], pos_tol))
        && (0..3).all(|k| close(cpu.1[k], gpu.1[k], rel * 4.0 * g + 1e-30))
        && close(cpu.1[3], gpu.1[3], rel * 4.0 * (1.0 + cpu.1[3].abs()))
}

/// The kernel `network_update`: new positions and (∇F, F − I) at the old ones.
pub fn network_update(field: &FieldInput, input: &NetworkInput<'_>) -> StepOutput {
    let u = &input.params;
    (0..input.positions.len())
        .into_par_iter()
        .map(|i| {
            let me = input.positions[i];
            let p = [me[0], me[1], me[2]];
            let mut force = [0.0f32; 3];
            for k in input.offsets[i]..input.offsets[i + 1] {
                let [j, bits] = input.springs[k as usize];
                let o = input.positions[j as usize];
                let r = [p[0] - o[0], p[1] - o[1], p[2] - o[2]];
                let rest = f32::from_bits(bits);
                let s = u.rho * (rest - dot(r, r).sqrt()) / rest;
                force = [
                    force[0] + r[0] * s,
                    force[1] + r[1] * s,
                    force[2] + r[2] * s,
                ];
            }
            let (f, _) = skeletal_field(field, p);
            let g2 = dot(f.grad, f.grad).max(u.g_min2);
            let lambda = (u.dt * dot(f.grad, force) + u.delta * f.rate + u.kappa * f.value) / g2;
            let mut step = [
                u.dt * force[0] - lambda * f.grad[0],
                u.dt * force[1] - lambda * f.grad[1],
                u.dt * force[2] - lambda * f.grad[2],
            ];
            let len = dot(step, step).sqrt();
            if len > u.step_max {
                let k = u.step_max / len;
                step = [step[0] * k, step[1] * k, step[2] * k];
            }
            (
                [p[0] + step[0], p[1] + step[1], p[2] + step[2], 0.0],
                [f.grad[0], f.grad[1], f.grad[2], f.value],
            )
        })
        .unzip()
}
