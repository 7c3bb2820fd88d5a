// Shared by spring_step and spring_chebyshev: the tissue network's buffers
// (bindings 1–8; each kernel declares its own `Params` at binding 0), the
// biphasic spring gather of eq. 4.4 and the flushed state update.
// Mirror: tissue::cpu (gather, flush; shared by spring_step and
// spring_chebyshev there too).

// One row per material: (c1, c2 − c1, knee strain, c_max = max(c1, c2)).
struct Materials {
    rows: array<vec4<f32>, 16>,
}

const INDEX_MASK: u32 = 0x0fffffffu;
const VELOCITY_FLUSH: f32 = 1e-30;

@group(0) @binding(1) var<uniform> materials: Materials;
@group(0) @binding(2) var<storage, read> offsets: array<u32>;
@group(0) @binding(3) var<storage, read> entries: array<u32>;
@group(0) @binding(4) var<storage, read> rest: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> forces: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> pos_in: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> pos_out: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> vel: array<vec4<f32>>;

// Spring k of a row: r_ij = (x_rest,i − x_rest,j) + (u_i − u_j) (both
// differences are small, so no absolute-coordinate rounding), its length,
// the biphasic force f(e) = c1 e + (c2 − c1) max(e − knee l, 0) of its
// extension e = |r_ij| − l_ij (eq. 4.4), and c_max of its material. The
// rest length l_ij = |x_rest,i − x_rest,j| (= initial length) comes from the
// same difference, so a spring at rest has e = 0 exactly.
struct SpringTerm {
    r: vec3<f32>,
    len: f32,
    f: f32,
    c_max: f32,
}

fn spring_term(k: u32, x0: vec3<f32>, u: vec3<f32>) -> SpringTerm {
    let e = entries[k];
    let m = materials.rows[e >> 28u];
    let j = e & INDEX_MASK;
    let d0 = x0 - rest[j].xyz;
    let l = sqrt(d0.x * d0.x + d0.y * d0.y + d0.z * d0.z);
    let r = d0 + (u - pos_in[j].xyz);
    let len = sqrt(r.x * r.x + r.y * r.y + r.z * r.z);
    let ext = len - l;
    return SpringTerm(r, len, m.x * ext + m.y * max(ext - m.z * l, 0.0), m.w);
}

// g_i = Σ_j f(|r_ij| − l_ij) / |r_ij| · r_ij (eq. 4.4) over node ix's CSR
// row in stored order; zero-length springs add nothing.
fn spring_force(ix: u32, x0: vec3<f32>, u: vec3<f32>) -> vec3<f32> {
    var g = vec3<f32>(0.0);
    let end = offsets[ix + 1u];
    for (var k = offsets[ix]; k < end; k++) {
        let t = spring_term(k, x0, u);
        if t.len > 0.0 {
            g = g + (t.f / t.len) * t.r;
        }
    }
    return g;
}

// External force f_i (0 unless the host uploaded forces).
fn external_force(ix: u32, use_forces: u32) -> vec3<f32> {
    if use_forces != 0u {
        return forces[ix].xyz;
    }
    return vec3<f32>(0.0);
}

// v_i ← v_raw with components below VELOCITY_FLUSH set to 0 (no
// subnormals); u_i ← u_i + step · v_i; w lane copied.
fn advance(ix: u32, p: vec4<f32>, v_raw: vec3<f32>, step: f32) {
    let v_new = select(v_raw, vec3<f32>(0.0), abs(v_raw) < vec3<f32>(VELOCITY_FLUSH));
    let u_new = p.xyz + step * v_new;
    pos_out[ix] = vec4<f32>(u_new, p.w);
    vel[ix] = vec4<f32>(v_new, 0.0);
}
