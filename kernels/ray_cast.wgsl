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
// Triangle test: watertight (Woop, Benthin & Wald 2013), with edge
// functions exactly 0 owned by the triangle walking the edge (counter-
// clockwise in the sheared plane) in a direction of angle [0, π); ties in
// distance go to the lower triangle id.
// Mirror: ray_cast::cpu::cast (same operations in the same order).

#import dispatch

struct Params {
    n_rays: u32,
    n_nodes: u32,
    origin_x: f32,
    origin_y: f32,
    origin_z: f32,
}

struct Node {
    lo: vec3<f32>,
    escape: u32,
    hi: vec3<f32>,
    leaf: u32,
}

struct RayHit {
    near: f32,
    far: f32,
    near_tri: u32,
    far_tri: u32,
    count: u32,
}

const WG_SIZE: u32 = 64u;
// Direction components below this magnitude count as 0 in the box test
// (the ray stays in its slab).
const TINY: f32 = 1e-20;
// Widening of the ray–box interval's far end: 1 + 2^-20.
const WIDEN: f32 = 1.00000095367431640625;

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
    let o = vec3<f32>(params.origin_x, params.origin_y, params.origin_z);
    let d = dirs[ix].xyz;
    let a = abs(d);
    var kz = 2u;
    if a.x >= a.y && a.x >= a.z {
        kz = 0u;
    } else if a.y >= a.z {
        kz = 1u;
    }
    let kx = (kz + 1u) % 3u;
    let ky = (kx + 1u) % 3u;
    let sx = d[kx] / d[kz];
    let sy = d[ky] / d[kz];
    let sz = 1.0 / d[kz];
    let inv = 1.0 / d;
    let flat = abs(d) < vec3<f32>(TINY);

    var out = RayHit(-1.0, -1.0, 0xffffffffu, 0xffffffffu, 0u);
    var i = 0u;
    while i < params.n_nodes {
        let node = nodes[i];
        var t_min = 0.0;
        var t_max = 3.40282346638528859812e+38;
        var inside = true;
        for (var k = 0u; k < 3u; k++) {
            if flat[k] {
                if o[k] < node.lo[k] || o[k] > node.hi[k] {
                    inside = false;
                }
                continue;
            }
            let t1 = (node.lo[k] - o[k]) * inv[k];
            let t2 = (node.hi[k] - o[k]) * inv[k];
            t_min = max(t_min, min(t1, t2));
            t_max = min(t_max, max(t1, t2));
        }
        if !inside || !(t_min <= t_max * WIDEN) {
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
            let r0 = p0.xyz - o;
            let r1 = corners[3u * t + 1u].xyz - o;
            let r2 = corners[3u * t + 2u].xyz - o;
            let x = vec3<f32>(r0[kx] - sx * r0[kz], r1[kx] - sx * r1[kz], r2[kx] - sx * r2[kz]);
            let y = vec3<f32>(r0[ky] - sy * r0[kz], r1[ky] - sy * r1[kz], r2[ky] - sy * r2[kz]);
            let e = vec3<f32>(x[0] * y[1] - y[0] * x[1],
                              x[1] * y[2] - y[1] * x[2],
                              x[2] * y[0] - y[2] * x[0]);
            let det = e[0] + e[1] + e[2];
            if det == 0.0 {
                continue;
            }
            let ccw = det > 0.0;
            var hit = true;
            for (var k = 0u; k < 3u; k++) {
                let ek = e[k];
                let inside = select(-ek, ek, ccw);
                if inside < 0.0 {
                    hit = false;
                    break;
                }
                if ek == 0.0 {
                    let j = (k + 1u) % 3u;
                    var vx = x[j] - x[k];
                    var vy = y[j] - y[k];
                    if !ccw {
                        vx = -vx;
                        vy = -vy;
                    }
                    if !(vy > 0.0 || (vy == 0.0 && vx > 0.0)) {
                        hit = false;
                        break;
                    }
                }
            }
            if !hit {
                continue;
            }
            let z = vec3<f32>(sz * r0[kz], sz * r1[kz], sz * r2[kz]);
            let dist = (e[1] * z[0] + e[2] * z[1] + e[0] * z[2]) / det;
            if !(dist > 0.0) {
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
