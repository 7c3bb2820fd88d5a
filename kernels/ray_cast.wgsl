// ray_cast: every hit of the half-line origin + t·dir (t > 0) on a triangle
// mesh, walked through a linear BVH without a stack; per ray the nearest
// and farthest hit and their count.
//
// Dispatch: one invocation per ray, WG_SIZE per workgroup, 2-D grid past
// the per-dimension limit (see shared/dispatch.wgsl).
// Buffers:
//   params:   n_rays, n_nodes, origin_x/y/z (the rays' common origin)
//   nodes:    n_nodes Node in depth-first preorder: box (padded), escape =
//             first node after the subtree, leaf = 0 (inner) or
//             first << 3 | count (triangles first..first+count of corners)
//   corners:  3 vec4<f32> per triangle in leaf order, w = mesh triangle id
//             (bits)
//   dirs:     n_rays vec4<f32>, xyz = direction (any length)
//   hits:     n_rays RayHit out: near, far (ray parameters, −1 without a
//             hit), near_tri, far_tri (mesh ids, 0xffffffff without a hit),
//             count (hits at t > 0)
// Box and triangle tests: shared/bvh_ray.wgsl (watertight); ties in
// distance go to the lower triangle id.
// Mirror: ray_cast::cpu::cast (same operations in the same order).

#import dispatch
#import bvh_ray

struct Params {
    n_rays: u32,
    n_nodes: u32,
    origin_x: f32,
    origin_y: f32,
    origin_z: f32,
}

struct RayHit {
    near: f32,
    far: f32,
    near_tri: u32,
    far_tri: u32,
    count: u32,
}

const WG_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var<storage, read> corners: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> dirs: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> hits: array<RayHit>;

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let ix = linear_index(gid, n_groups, WG_SIZE);
    if ix >= params.n_rays {
        return;
    }
    let ray = ray_new(vec3<f32>(params.origin_x, params.origin_y, params.origin_z), dirs[ix].xyz);
    var out = RayHit(-1.0, -1.0, 0xffffffffu, 0xffffffffu, 0u);
    var i = 0u;
    while i < params.n_nodes {
        let node = nodes[i];
        if !ray_meets(ray, node) {
            i = node.escape;
            continue;
        }
        if node.leaf == 0u {
            i += 1u;
            continue;
        }
        let first = node.leaf >> 3u;
        let last = first + (node.leaf & 7u);
        for (var t = first; t < last; t++) {
            let p0 = corners[3u * t];
            let dist = ray_hit(ray, p0.xyz, corners[3u * t + 1u].xyz, corners[3u * t + 2u].xyz);
            if dist == 0.0 {
                continue;
            }
            let id = bitcast<u32>(p0.w);
            if out.count == 0u || dist < out.near || (dist == out.near && id < out.near_tri) {
                out.near = dist;
                out.near_tri = id;
            }
            if out.count == 0u || dist > out.far || (dist == out.far && id < out.far_tri) {
                out.far = dist;
                out.far_tri = id;
            }
            out.count += 1u;
        }
        i = node.escape;
    }
    hits[ix] = out;
}
