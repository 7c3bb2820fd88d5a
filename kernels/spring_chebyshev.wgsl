// spring_chebyshev: one step of stationary Chebyshev acceleration of
// block-Jacobi-preconditioned relaxation toward the static equilibrium
// g(x) = f of the tissue spring network (the accelerated solver; see
// src/tissue/chebyshev.rs), by gather over the CSR spring adjacency (no
// atomics: deterministic). The 3 × 3 preconditioner block of each node is
// built from the same gather, at the current state: no extra memory traffic.
//
// Dispatch: one invocation per free node, WG_SIZE per workgroup, 2-D grid
// past the per-dimension limit (shared/dispatch). Bone nodes are fixed.
// Buffers:
//   params:    n_free; use_forces (0/1); h = pseudo time step; momentum = β;
//              gain = α / h; isotropy = η
//   materials: rows[16] = (c1, c2 − c1, knee strain, c_max) per material
//   offsets:   #free + 1 u32, CSR row starts into entries
//   entries:   #entries u32: neighbour id | material << 28; rows sorted
//              by id (l_ij = |x_rest,i − x_rest,j|, see spring_network)
//   rest:      #nodes vec4<f32>, xyz = rest position x_rest,i
//   forces:    #free vec4<f32>, external force f_i (read when use_forces = 1)
//   pos_in:    #nodes vec4<f32>, xyz = displacement u_i = x_i − x_rest,i
//              (w not read); see spring_step.wgsl for why the state is kept
//              as displacements
//   pos_out:   #nodes vec4<f32>, written for the free nodes only (w copied)
//   vel:       #free vec4<f32>, xyz = last update / h, updated in place
// Per node i, over its springs j in CSR order (s_ij = f_ij / |r_ij|):
//   g_i = Σ_j s_ij r_ij                                            (eq. 4.4)
//   B_i = Σ_j c_max r̂r̂ᵀ + t_ij (I − r̂r̂ᵀ),  t_ij = max(η c_max, s_ij)
//       (c_max I for a spring of length 0), accumulated as Σ_j q r rᵀ
//       with q = (c_max − t) / |r|², plus (Σ_j t_ij) I at the end,
//   r_i = B_i⁻¹ (f_i − g_i) (cofactors of B_i / tr B_i; 0 without springs);
//   v_i ← β v_i + (α/h) r_i;  u_i ← u_i + h v_i.
// Mirror: tissue::cpu::spring_chebyshev (same operations in the same order).

#import dispatch
#import spring_network

struct Params {
    n_free: u32,
    use_forces: u32,
    h: f32,
    momentum: f32,
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
    let x0 = rest[ix].xyz;
    var g = vec3<f32>(0.0);
    // B_i: diagonal (b00, b11, b22) without and off-diagonal (b01, b02,
    // b12), and the isotropic part Σ_j t_ij.
    var diag = vec3<f32>(0.0);
    var off = vec3<f32>(0.0);
    var iso = 0.0;
    let end = offsets[ix + 1u];
    for (var k = offsets[ix]; k < end; k++) {
        let t = spring_term(k, x0, p.xyz);
        if t.len > 0.0 {
            let s = t.f / t.len;
            g = g + s * t.r;
            let across = max(params.isotropy * t.c_max, s);
            let qr = ((t.c_max - across) / (t.len * t.len)) * t.r;
            diag = diag + qr * t.r;
            off = off + qr.xxy * t.r.yzz;
            iso = iso + across;
        } else {
            iso = iso + t.c_max;
        }
    }
    diag = diag + iso;
    let d = external_force(ix, params.use_forces) - g;
    var r = vec3<f32>(0.0);
    let tr = diag.x + diag.y + diag.z;
    if tr > 0.0 {
        // The block scaled to unit trace (no overflow whatever the units).
        let a = diag / tr;
        let o = off / tr;
        let c00 = a.y * a.z - o.z * o.z;
        let c01 = o.y * o.z - o.x * a.z;
        let c02 = o.x * o.z - o.y * a.y;
        let c11 = a.x * a.z - o.y * o.y;
        let c12 = o.x * o.y - a.x * o.z;
        let c22 = a.x * a.y - o.x * o.x;
        let det = a.x * c00 + o.x * c01 + o.y * c02;
        r = vec3<f32>(
            c00 * d.x + c01 * d.y + c02 * d.z,
            c01 * d.x + c11 * d.y + c12 * d.z,
            c02 * d.x + c12 * d.y + c22 * d.z,
        ) / (det * tr);
    }
    let v = vel[ix].xyz;
    advance(ix, p, params.momentum * v + params.gain * r, params.h);
}
