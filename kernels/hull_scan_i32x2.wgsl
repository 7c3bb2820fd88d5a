// hull_scan_i32x2: brute-force inside/on/outside of every voxel centre of a
// box against every face n·p ≤ d, exact without SHADER_INT64: products
// i32 × i32 into 64-bit word pairs (shared/i32x2.wgsl), no floats. Seed 003
// §4.2.1, Def. VI: s = n·p − d; outside when some s > 0, on when max s = 0,
// inside when every s < 0. The portable twin of hull_scan.wgsl.
//
// Dispatch: one invocation per u32 word = 4 consecutive voxels of the slab
// (x fastest, then y, then z), WG_SIZE per workgroup, 2-D grid past the
// per-dimension limit (shared/dispatch.wgsl).
// Buffers:
//   params: n_faces, n_items = voxels in the slab, nx, ny, z0, origin
//   faces:  #F Face (shared/hull_face.wgsl)
//   sides:  ceil(n_items / 4) u32 out, byte b of word w = code of voxel
//           4w + b: 0 outside, 1 on, 2 inside (0 past n_items)
// Range (hull_scan::check_range): |n·p| < 2^49, |d| ≤ 2^60, no overflow.
// Mirror: hull_scan::cpu::hull_scan (same codes; arithmetic: cpu::i32x2).

#import dispatch
#import hull_face
#import i32x2

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> faces: array<Face>;
@group(0) @binding(2) var<storage, read_write> sides: array<u32>;

// Side code of the voxel with slab-local linear index v.
fn side_of(v: u32) -> u32 {
    let x = v % params.nx;
    let t = v / params.nx;
    let y = t % params.ny;
    let z = params.z0 + t / params.ny;
    let px = 2 * (params.origin_x + i32(x)) + 1;
    let py = 2 * (params.origin_y + i32(y)) + 1;
    let pz = 2 * (params.origin_z + i32(z)) + 1;
    var on = false;
    for (var f = 0u; f < params.n_faces; f++) {
        let face = faces[f];
        let np = w_add(w_add(w_mul(face.normal.x, px), w_mul(face.normal.y, py)),
                       w_mul(face.normal.z, pz));
        let d = face.offset.xy;
        if w_lt(d, np) {
            return 0u;
        }
        on = on || w_eq(np, d);
    }
    return select(2u, 1u, on);
}

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let ix = linear_index(gid, n_groups, WG_SIZE);
    if ix >= (params.n_items + 3u) / 4u {
        return;
    }
    var word = 0u;
    for (var b = 0u; b < 4u; b++) {
        let v = 4u * ix + b;
        if v < params.n_items {
            word |= side_of(v) << (8u * b);
        }
    }
    sides[ix] = word;
}
