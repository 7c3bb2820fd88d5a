// ray_hits: every hit of the half-line origin + t·dir (t > 0) on a triangle
// mesh, as a list per ray: the second pass after ray_cast, whose hit counts
// the host scans into the offsets here.
//
// Dispatch: one invocation per ray, WG_SIZE per workgroup, 2-D grid past
// the per-dimension limit (see shared/dispatch.wgsl).
// Buffers:
//   params:   n_rays, n_nodes, origin_x/y/z (the rays' common origin)
//   nodes, corners: the BVH as in ray_cast
//   dirs:     n_rays vec4<f32>, xyz = direction (any length)
//   offsets:  n_rays + 1 u32, exclusive scan of the rays' hit counts (the
//             first ray's offset need not be 0: a batch's slice)
//   hits:     Hit out at offsets[i] - offsets[0] + k for the k-th hit of ray
//             i in walk order (preorder, then leaf order): ray parameter
//             and mesh triangle id; writes past the ray's slots are dropped
//   counts:   n_rays u32 out: the hits this walk found (the host checks
//             them against the scanned counts)
// Box and triangle tests: shared/bvh_ray.wgsl (watertight).
// Mirror: ray_cast::cpu::ray_hits (same walk, same operations).

#import dispatch
#import bvh_ray

struct Params {
    n_rays: u32,
    n_nodes: u32,
    origin_x: f32,
    origin_y: f32,
    origin_z: f32,
}

struct Hit {
    t: f32,
    tri: u32,
}

const WG_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var<storage, read> corners: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> dirs: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> offsets: array<u32>;
@group(0) @binding(5) var<storage, read_write> hits: array<Hit>;
@group(0) @binding(6) var<storage, read_write> counts: array<u32>;

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let ix = linear_index(gid, n_groups, WG_SIZE);
    if ix >= params.n_rays {
        return;
    }
    let ray = ray_new(vec3<f32>(params.origin_x, params.origin_y, params.origin_z), dirs[ix].xyz);
    let base = offsets[ix] - offsets[0];
    let slots = offsets[ix + 1u] - offsets[ix];
    var count = 0u;
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
            if count < slots {
                hits[base + count] = Hit(dist, bitcast<u32>(p0.w));
            }
            count += 1u;
        }
        i = node.escape;
    }
    counts[ix] = count;
}
