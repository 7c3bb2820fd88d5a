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

struct Params {
    n_free: u32,
    use_forces: u32,
    h: f32,
    momentum: f32,
    gain: f32,
}

// One row per material: (c1, c2 − c1, knee strain, 0).
struct Materials {
    rows: array<vec4<f32>, 16>,
}

const WG_SIZE: u32 = 256u;
const INDEX_MASK: u32 = 0x0fffffffu;
const VELOCITY_FLUSH: f32 = 1e-30;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<uniform> materials: Materials;
@group(0) @binding(2) var<storage, read> offsets: array<u32>;
@group(0) @binding(3) var<storage, read> entries: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read> rest: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> forces: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> pos_in: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> pos_out: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> vel: array<vec4<f32>>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let ix = linear_index(gid, n_groups, WG_SIZE);
    if ix >= params.n_free {
        return;
    }
    let p = pos_in[ix];
    let u = p.xyz;
    let x0 = rest[ix].xyz;
    var g = vec3<f32>(0.0);
    let end = offsets[ix + 1u];
    for (var k = offsets[ix]; k < end; k++) {
        let e = entries[k];
        let m = materials.rows[e.x >> 28u];
        let l = bitcast<f32>(e.y);
        let j = e.x & INDEX_MASK;
        // r_ij = x_i − x_j, summed as (rest difference) + (displacement
        // difference): both small, so no absolute-coordinate rounding.
        let r = (x0 - rest[j].xyz) + (u - pos_in[j].xyz);
        let len = sqrt(r.x * r.x + r.y * r.y + r.z * r.z);
        if len > 0.0 {
            let ext = len - l;
            let f = m.x * ext + m.y * max(ext - m.z * l, 0.0);
            let s = f / len;
            g = g + s * r;
        }
    }
    var f_ext = vec3<f32>(0.0);
    if params.use_forces != 0u {
        f_ext = forces[ix].xyz;
    }
    let v = vel[ix].xyz;
    let r = (f_ext - g) * p.w;
    let v_raw = params.momentum * v + params.gain * r;
    // Flush tiny components to zero (no subnormals; see VELOCITY_FLUSH).
    let v_new = select(v_raw, vec3<f32>(0.0), abs(v_raw) < vec3<f32>(VELOCITY_FLUSH));
    let u_new = u + params.h * v_new;
    pos_out[ix] = vec4<f32>(u_new, p.w);
    vel[ix] = vec4<f32>(v_new, 0.0);
}
