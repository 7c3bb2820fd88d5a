// spring_step: one damped semi-implicit Euler step of the layered tissue
// spring network (seed 000 eq. 4.4–4.7) for every free node, by gather over
// the CSR spring adjacency (no atomics: deterministic).
//
// Dispatch: one invocation per free node (epidermis, then subcutis), WG_SIZE
// per workgroup, 2-D grid past the per-dimension limit (shared/dispatch).
// Bone nodes are fixed (B_i = 0) and not dispatched; the host keeps their
// displacements equal in both position buffers.
// State as displacements from rest (u_i = x_i − x_rest,i): mathematically
// identical to eq. 4.4–4.7 in x (x_i − x_j = (x_rest,i − x_rest,j) +
// (u_i − u_j), and x ← x + Δt v ⇔ u ← u + Δt v), but every rounded
// quantity is small: the f32 noise floor is set by |u| (mm), not by the
// absolute coordinates (0.1 m), so soft sliding modes settle ~10–100× closer
// to the exact equilibrium.
// Buffers:
//   params:    n_free; use_forces (0/1); dt = Δt; damping = γ; gain and
//              isotropy unused
//   materials: rows[16] = (c1, c2 − c1, knee strain, c_max) per material
//   offsets:   #free + 1 u32, CSR row starts into entries
//   entries:   #entries u32: neighbour id | material << 28; rows sorted
//              by id (l_ij = |x_rest,i − x_rest,j|, see spring_network)
//   rest:      #nodes vec4<f32>, xyz = rest position x_rest,i
//   forces:    #free vec4<f32>, external force f_i in xyz (read when
//              use_forces = 1)
//   pos_in:    #nodes vec4<f32>, xyz = displacement u_i, w = B_i / m_i
//   pos_out:   #nodes vec4<f32>, written for the free nodes only (w copied)
//   vel:       #free vec4<f32>, xyz = velocity v_i, updated in place (each
//              invocation reads and writes only its own node)
// Per node i:  r_ij = (x_rest,i − x_rest,j) + (u_i − u_j),
//   g_i = Σ_j f(|r_ij| − l_ij) / |r_ij| · r_ij                     (eq. 4.4)
//   with the biphasic law f(e) = c1 e + (c2 − c1) max(e − knee l, 0),
//   a_i = (f_i − γ v_i − g_i) · B_i / m_i                           (eq. 4.5)
//   v_i ← v_i + Δt a_i;  u_i ← u_i + Δt v_i                         (eq. 4.7)
//   (velocity components below VELOCITY_FLUSH = 1e-30 are set to 0)
// Mirror: tissue::cpu::spring_step (same operations in the same order).

#import dispatch
#import spring_network

struct Params {
    n_free: u32,
    use_forces: u32,
    dt: f32,
    damping: f32,
    gain: f32,
    isotropy: f32,
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
    // eq. 4.4–4.7.
    let g = spring_force(ix, rest[ix].xyz, p.xyz);
    let v = vel[ix].xyz;
    let a = (external_force(ix, params.use_forces) - params.damping * v - g) * p.w;
    advance(ix, p, v + params.dt * a, params.dt);
}
