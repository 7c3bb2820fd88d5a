// tissue_reduce_max: the convergence scalars of a relaxation — max_i |v_i|²
// and max_i |x_i − s_i|² (change since the stall-window snapshot) — by a
// two-stage tree reduction in workgroup memory (no atomics).
//
// Values are reduced as order-preserving u32 keys: the bits of a
// non-negative f32 without the sign bit, so max is exact (the result does
// not depend on the tree) and any NaN or infinity maps above every finite
// value (a diverged state cannot hide).
// Dispatch: mode 0 (nodes → partials): G ≤ 256 workgroups, grid-stride over
// the n nodes, one partial per workgroup; mode 1 (partials → result): one
// workgroup over the n = G partials.
// Buffers:
//   params:    n (elements to reduce), mode (0 / 1)
//   vel:       #free vec4<f32>, xyz = velocity (mode 0)
//   pos:       #nodes vec4<f32>, xyz = current position (mode 0)
//   snap:      #free vec4<f32>, xyz = snapshot position (mode 0)
//   part_in:   vec2<u32> partial keys (mode 1)
//   part_out:  vec2<u32> out: one per workgroup (mode 0) / the result (mode 1)
// Mirror: tissue::cpu::tissue_reduce_max.

struct Params {
    n: u32,
    mode: u32,
}

const WG_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> vel: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> pos: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> snap: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> part_in: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read_write> part_out: array<vec2<u32>>;

var<workgroup> sh_v: array<u32, WG_SIZE>;
var<workgroup> sh_d: array<u32, WG_SIZE>;

fn key(x: f32) -> u32 {
    return bitcast<u32>(x) & 0x7fffffffu;
}

@compute @workgroup_size(256)
fn main(@builtin(local_invocation_index) lix: u32,
        @builtin(workgroup_id) wid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    var kv = 0u;
    var kd = 0u;
    let stride = n_groups.x * WG_SIZE;
    for (var i = wid.x * WG_SIZE + lix; i < params.n; i += stride) {
        if params.mode == 0u {
            let v = vel[i].xyz;
            let d = pos[i].xyz - snap[i].xyz;
            kv = max(kv, key(v.x * v.x + v.y * v.y + v.z * v.z));
            kd = max(kd, key(d.x * d.x + d.y * d.y + d.z * d.z));
        } else {
            let p = part_in[i];
            kv = max(kv, p.x);
            kd = max(kd, p.y);
        }
    }
    sh_v[lix] = kv;
    sh_d[lix] = kd;
    workgroupBarrier();
    for (var s = WG_SIZE / 2u; s > 0u; s = s / 2u) {
        if lix < s {
            sh_v[lix] = max(sh_v[lix], sh_v[lix + s]);
            sh_d[lix] = max(sh_d[lix], sh_d[lix + s]);
        }
        workgroupBarrier();
    }
    if lix == 0u {
        part_out[wid.x] = vec2<u32>(sh_v[0], sh_d[0]);
    }
}
