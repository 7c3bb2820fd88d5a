// Shared by ray_cast and ray_hits: a ray from a common origin against the
// nodes of a linear BVH and against triangles, with the watertight test of
// Woop, Benthin & Wald 2013. Edge functions exactly 0 are owned by the
// triangle walking the edge (counter-clockwise in the sheared plane) in a
// direction of angle [0, π), so a ray through an edge or a vertex of a
// closed mesh hits it once.
// Mirror: ray_cast::cpu::Ray (same operations in the same order).

struct Node {
    lo: vec3<f32>,
    escape: u32,
    hi: vec3<f32>,
    leaf: u32,
}

// Per-ray constants: kz the axis of the direction's largest component, the
// shear (sx, sy, sz) that maps the ray onto +z, the inverse direction of
// the box test.
struct Ray {
    o: vec3<f32>,
    d: vec3<f32>,
    kx: u32,
    ky: u32,
    kz: u32,
    sx: f32,
    sy: f32,
    sz: f32,
    inv: vec3<f32>,
}

// Direction components below this magnitude count as 0 in the box test
// (the ray stays in its slab).
const TINY: f32 = 1e-20;
// Widening of the ray–box interval's far end: 1 + 2^-20.
const WIDEN: f32 = 1.00000095367431640625;
const F32_MAX: f32 = 3.40282346638528859812e+38;

fn ray_new(o: vec3<f32>, d: vec3<f32>) -> Ray {
    let a = abs(d);
    var kz = 2u;
    if a.x >= a.y && a.x >= a.z {
        kz = 0u;
    } else if a.y >= a.z {
        kz = 1u;
    }
    let kx = (kz + 1u) % 3u;
    let ky = (kx + 1u) % 3u;
    return Ray(o, d, kx, ky, kz, d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz], 1.0 / d);
}

// Whether the ray meets the node's box at a parameter ≥ 0 (slab test, far
// end widened; along a flat axis, whether the origin is inside the slab).
fn ray_meets(ray: Ray, node: Node) -> bool {
    var t_min = 0.0;
    var t_max = F32_MAX;
    for (var k = 0u; k < 3u; k++) {
        if abs(ray.d[k]) < TINY {
            if ray.o[k] < node.lo[k] || ray.o[k] > node.hi[k] {
                return false;
            }
            continue;
        }
        let t1 = (node.lo[k] - ray.o[k]) * ray.inv[k];
        let t2 = (node.hi[k] - ray.o[k]) * ray.inv[k];
        t_min = max(t_min, min(t1, t2));
        t_max = min(t_max, max(t1, t2));
    }
    return t_min <= t_max * WIDEN;
}

// The ray parameter of a hit on triangle (p0, p1, p2), or 0 without one.
fn ray_hit(ray: Ray, p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>) -> f32 {
    let r0 = p0 - ray.o;
    let r1 = p1 - ray.o;
    let r2 = p2 - ray.o;
    let kx = ray.kx;
    let ky = ray.ky;
    let kz = ray.kz;
    let x = vec3<f32>(r0[kx] - ray.sx * r0[kz], r1[kx] - ray.sx * r1[kz], r2[kx] - ray.sx * r2[kz]);
    let y = vec3<f32>(r0[ky] - ray.sy * r0[kz], r1[ky] - ray.sy * r1[kz], r2[ky] - ray.sy * r2[kz]);
    let e = vec3<f32>(x[0] * y[1] - y[0] * x[1],
                      x[1] * y[2] - y[1] * x[2],
                      x[2] * y[0] - y[2] * x[0]);
    let det = e[0] + e[1] + e[2];
    if det == 0.0 {
        return 0.0;
    }
    let ccw = det > 0.0;
    for (var k = 0u; k < 3u; k++) {
        let ek = e[k];
        if select(-ek, ek, ccw) < 0.0 {
            return 0.0;
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
                return 0.0;
            }
        }
    }
    let z = vec3<f32>(ray.sz * r0[kz], ray.sz * r1[kz], ray.sz * r2[kz]);
    let dist = (e[1] * z[0] + e[2] * z[1] + e[0] * z[2]) / det;
    return select(0.0, dist, dist > 0.0);
}
