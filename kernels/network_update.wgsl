// network_update: one Euler step of the particle spring network on a
// moving skeletal implicit surface (SPEC §3.3, seed 002 eq. 12–13 projected
// by eq. 8): springs S_ij = ρ (R_ij − |r_ij|)/R_ij along the
// triangulation's edges, P_i = Σ_j r_ij S_ij, r_ij = p_i − p_j.
//
// Dispatch: one invocation per vertex, WG_SIZE per workgroup, 2-D grid past
// the per-dimension limit (see shared/dispatch.wgsl).
// Buffers:
//   params:   n_vertices, Δt, δ (scene-time advance), κ = φΔt, ρ, g_min², step_max
//   field, skeleton, table: the scene (shared/skeletal_field.wgsl)
//   offsets:  #V + 1 u32, CSR row starts into springs
//   springs:  vec2<u32> per directed edge: (neighbour j, bitcast<u32>(R_ij))
//   pos_in:   #V vec4<f32>, xyz = position
//   pos_out:  #V vec4<f32> out, xyz = position after the step, w = 0
//   samples:  #V vec4<f32> out, (∇F, F − I) at pos_in
// Step: Δp = Δt P − [(Δt ∇F·P + δ F_t + κ (F − I)) / max(|∇F|², g_min²)] ∇F,
// clamped to |Δp| ≤ step_max. Sums in stored row order: no atomics.
// Mirror: particles::network::cpu::network_update.

#import dispatch
#import skeletal_field

struct Params {
    n_vertices: u32,
    dt: f32,
    delta: f32,
    kappa: f32,
    rho: f32,
    g_min2: f32,
    step_max: f32,
}

const WG_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(4) var<storage, read> offsets: array<u32>;
@group(0) @binding(5) var<storage, read> springs: array<vec2<u32>>;
@group(0) @binding(6) var<storage, read> pos_in: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> pos_out: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> samples: array<vec4<f32>>;

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let i = linear_index(gid, n_groups, WG_SIZE);
    if i >= params.n_vertices {
        return;
    }
    let p = pos_in[i].xyz;
    var force = vec3<f32>(0.0);
    for (var k = offsets[i]; k < offsets[i + 1u]; k++) {
        let s = springs[k];
        let r = p - pos_in[s.x].xyz;
        let rest = bitcast<f32>(s.y);
        force += r * (params.rho * (rest - length(r)) / rest);
    }
    let f = skeletal_field(p);
    let g2 = max(dot(f.grad, f.grad), params.g_min2);
    let lambda = (params.dt * dot(f.grad, force) + params.delta * f.rate + params.kappa * f.value) / g2;
    var step = params.dt * force - lambda * f.grad;
    let len = length(step);
    if len > params.step_max {
        step *= params.step_max / len;
    }
    pos_out[i] = vec4<f32>(p + step, 0.0);
    samples[i] = vec4<f32>(f.grad, f.value);
}
