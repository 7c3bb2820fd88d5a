// hull_scan: brute-force inside/on/outside of every voxel centre of a box
// against every face n·p ≤ d of a convex polyhedron, exact in i64
// (SHADER_INT64). Seed 003 §4.2.1, Def. VI: s = n·p − d; outside when some
// s > 0, on when max s = 0, inside when every s < 0.
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
// Mirror: hull_scan::cpu::hull_scan.

#import dispatch
#import hull_face

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> faces: array<Face>;
@group(0) @binding(2) var<storage, read_write> sides: array<u32>;

fn offset_of(f: Face) -> i64 {
    return (i64(bitcast<i32>(f.offset.y)) << 32u) | i64(f.offset.x);
}

// Side code of the voxel with slab-local linear index v.
fn side_of(v: u32) -> u32 {
    let x = v % params.nx;
    let t = v / params.nx;
    let y = t % params.ny;
    let z = params.z0 + t / params.ny;
    let px = i64(2 * (params.origin_x + i32(x)) + 1);
    let py = i64(2 * (params.origin_y + i32(y)) + 1);
    let pz = i64(2 * (params.origin_z + i32(z)) + 1);
    var on = false;
    for (var f = 0u; f < params.n_faces; f++) {
        let face = faces[f];
        let n = vec3<i64>(face.normal.xyz);
        let s = n.x * px + n.y * py + n.z * pz - offset_of(face);
        if s > 0li {
            return 0u;
        }
        on = on || s == 0li;
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
