// spring_chebyshev: one step of stationary Chebyshev acceleration of Jacobi
// relaxation toward the static equilibrium g(x) = f of the tissue spring
// network (the accelerated solver; see src/tissue/chebyshev.rs), by gather
// over the CSR spring adjacency (no atomics: deterministic).
//
// Dispatch: one invocation per free node, WG_SIZE per workgroup, 2-D grid
// past the per-dimension limit (shared/dispatch). Bone nodes are fixed.
// Buffers:
//   params:    n_free; use_forces (0/1); h = pseudo time step; momentum = β;
//              gain = α / h
//   materials: rows[16] = (c1, c2 − c1, knee strain, 0) per material
//   offsets:   #free + 1 u32, CSR row starts into entries
//   entries:   #entries vec2<u32>: x = neighbour id | material << 28,
//              y = bits of the rest length l_ij (f32); rows sorted by id
//   rest:      #nodes vec4<f32>, xyz = rest position x_rest,i
//   forces:    #free vec4<f32>, external force f_i (read when use_forces = 1)
//   pos_in:    #nodes vec4<f32>, xyz = displacement u_i = x_i − x_rest,i,
//              w = 1 / D_i (D_i = Σ_j c_max); see spring_step.wgsl for why
//              the state is kept as displacements
//   pos_out:   #nodes vec4<f32>, written for the free nodes only (w copied)
//   vel:       #free vec4<f32>, xyz = last update / h, updated in place
// Per node i: g_i as in spring_step (eq. 4.4, biphasic law), then
//   r_i = (f_i − g_i) / D_i;  v_i ← β v_i + (α/h) r_i;  u_i ← u_i + h v_i.
// Mirror: tissue::cpu::spring_chebyshev (same operations in the same order).

#import dispatch
#import spring_network

struct Params {
    n_free: u32,
    use_forces: u32,
    h: f32,
    momentum: f32,
    gain: f32,
}

const WG_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: Params;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let ix = linear_index(gid, n_groups, WG_SIZE);
    if ix >= params.n_free {
        return;
    }
    let p = pos_in[ix];
    let g = spring_force(ix, rest[ix].xyz, p.xyz);
    let v = vel[ix].xyz;
    let r = (external_force(ix, params.use_forces) - g) * p.w;
    advance(ix, p, params.momentum * v + params.gain * r, params.h);
}
