// particle_update: one Euler step of Witkin–Heckbert particles on a moving
// skeletal implicit surface (SPEC §3.2, seed 002 eq. 6–11), with adaptive
// repulsion radii (WH94: D_i, ∂D_i/∂σ_i, σ̇_i).
//
// Dispatch: one invocation per particle, WG_SIZE per workgroup, 2-D grid
// past the per-dimension limit (see shared/dispatch.wgsl).
// Buffers:
//   params:   grid dims, counts, step sizes and WH constants (below)
//   field, skeleton, table: the scene (shared/skeletal_field.wgsl)
//   cells:    u32 [starts (n_cells + 1) | particle ids by cell | home cell per particle]
//   pos_in:   #N vec4<f32>, xyz = position, w = σ_i
//   pos_out:  #N vec4<f32> out, the same after the step
//   state:    #N vec4<f32> out, (D_i, |Δp|/Δt, (F − I)/|∇F| before the step, |∇F|)
// Energy of i from j: E^i_ij = α exp(−r²/2σ_i²)·(1 − q_i)², q_i = r²/9σ_i²
// (a C¹ taper to zero at 3σ_i). Repulsion P_i = Σ_j r_ij (W^i_ij + (σ_i/σ_j)² W^j_ji),
// W = −σ² ∂E/∂p / r = α exp(−r²/2σ²)(1 − q)(1 − q + 4/9) (the gradient of Σ D).
// Step (eq. 8 with the guard, the two clocks):
//   Δp = Δt P − [(Δt ∇F·P + δ F_t + κ (F − I)) / max(|∇F|², g_min²)] ∇F, |Δp| ≤ σ_i
//   σ_i ← clamp(σ_i − Δt ρ_σ (D_i − Ê)/(∂D_i/∂σ_i + β_σ), σ_lo, σ_hi) when adapt = 1
// Sums run over the 27 cells around the home cell (dz, dy, dx from −1 to 1),
// ids ascending within a cell: no atomics, deterministic.
// Mirror: particles::wh::cpu::particle_update.

#import dispatch
#import skeletal_field

struct Params {
    nx: u32,
    ny: u32,
    nz: u32,
    n_particles: u32,
    n_cells: u32,
    dt: f32,
    delta: f32,
    kappa: f32,
    alpha: f32,
    e_hat: f32,
    rho_sigma: f32,
    beta_sigma: f32,
    sigma_lo: f32,
    sigma_hi: f32,
    g_min2: f32,
    adapt: u32,
}

const WG_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(4) var<storage, read> cells: array<u32>;
@group(0) @binding(5) var<storage, read> pos_in: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> pos_out: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> state: array<vec4<f32>>;

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let i = linear_index(gid, n_groups, WG_SIZE);
    if i >= params.n_particles {
        return;
    }
    let me = pos_in[i];
    let p = me.xyz;
    let s_i = me.w;
    let inv2_i = 1.0 / (2.0 * s_i * s_i);
    let inv9_i = 1.0 / (9.0 * s_i * s_i);
    var rep = vec3<f32>(0.0);
    var d_i = 0.0;
    var dd_i = 0.0;
    let dims = vec3<u32>(params.nx, params.ny, params.nz);
    let items = params.n_cells + 1u;
    let h = cells[items + params.n_particles + i];
    let c = vec3<i32>(vec3<u32>(h % dims.x, (h / dims.x) % dims.y, h / (dims.x * dims.y)));
    for (var dz = -1; dz <= 1; dz++) {
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let q = c + vec3<i32>(dx, dy, dz);
                if any(q < vec3<i32>(0)) || any(q >= vec3<i32>(dims)) {
                    continue;
                }
                let cell = u32(q.x) + dims.x * (u32(q.y) + dims.y * u32(q.z));
                for (var k = cells[cell]; k < cells[cell + 1u]; k++) {
                    let j = cells[items + k];
                    if j == i {
                        continue;
                    }
                    let o = pos_in[j];
                    let r = p - o.xyz;
                    let r2 = dot(r, r);
                    var w = 0.0;
                    let q_i = r2 * inv9_i;
                    if q_i < 1.0 {
                        let g = params.alpha * exp(-r2 * inv2_i);
                        let t = 1.0 - q_i;
                        d_i += g * t * t;
                        dd_i += g * t * (r2 * 2.0 * inv2_i * t + 4.0 * q_i) / s_i;
                        w = g * t * (t + 4.0 / 9.0);
                    }
                    let s_j = o.w;
                    let q_j = r2 / (9.0 * s_j * s_j);
                    if q_j < 1.0 {
                        let t = 1.0 - q_j;
                        let ratio = s_i / s_j;
                        w += ratio * ratio * params.alpha * exp(-r2 / (2.0 * s_j * s_j)) * t * (t + 4.0 / 9.0);
                    }
                    rep += w * r;
                }
            }
        }
    }
    let f = skeletal_field(p);
    let g2 = max(dot(f.grad, f.grad), params.g_min2);
    let lambda = (params.dt * dot(f.grad, rep) + params.delta * f.rate + params.kappa * f.value) / g2;
    var step = params.dt * rep - lambda * f.grad;
    let len = length(step);
    if len > s_i {
        step *= s_i / len;
    }
    var s_new = s_i;
    if params.adapt == 1u {
        let rate = -params.rho_sigma * (d_i - params.e_hat) / (dd_i + params.beta_sigma);
        s_new = clamp(s_i + params.dt * rate, params.sigma_lo, params.sigma_hi);
    }
    pos_out[i] = vec4<f32>(p + step, s_new);
    state[i] = vec4<f32>(d_i, length(step) / params.dt, f.value / sqrt(g2), length(f.grad));
}
