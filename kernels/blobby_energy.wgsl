// blobby_energy: the data terms of the blobby fit (seed 001 eq. 16–22) and
// their gradient with respect to every primitive's (c, a, b), summed over a
// block of range points per workgroup.
//
// V(x) = Σ_k b_k exp(−a_k |x − c_k|²), G = ∇V, N = −G (eq. 17). Per point j
// with normal n_j: e_j = (V − T)² + α |n_j − N/|N||², |N| taken as at least
// g_min (the energy is smooth there too). The kernel sums e_j/M and the
// gradient of Σ e_j/M over its points; the host adds β E_shrink.
//
// Dispatch: ceil(#P / BLOCK) workgroups of WG_SIZE, 2-D grid past the
// per-dimension limit (shared/dispatch.wgsl). Invocation lid of workgroup w
// holds the points w·BLOCK + lid + p·WG_SIZE, p < POINTS_PER_INVOCATION.
// Buffers:
//   params:   n_points, n_prims, iso T, inv_m = 1/M, alpha, g_min2
//   prims:    2·#N vec4<f32>: (c, a), (b, 0, 0, 0)
//   points:   2·#P vec4<f32>: (x, 0), (n, 0)
//   partials: #W·(1 + 5·#N) f32 out: per workgroup Σ e_j/M, then per primitive
//             ∂/∂(c.x, c.y, c.z, a, b)
// Sums: each invocation adds its points in order, then a tree in workgroup
// memory (stride WG_SIZE/2 down to 1) adds the invocations; no atomics. The
// host adds the workgroups' rows in f64 in order.
// Mirror: blobby::energy::cpu::blobby_energy.

#import dispatch

struct Params {
    n_points: u32,
    n_prims: u32,
    iso: f32,
    inv_m: f32,
    alpha: f32,
    g_min2: f32,
}

const WG_SIZE: u32 = 256u;
const POINTS_PER_INVOCATION: u32 = 4u;
const BLOCK: u32 = WG_SIZE * POINTS_PER_INVOCATION;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> prims: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> partials: array<f32>;

var<workgroup> sh: array<array<f32, 5>, WG_SIZE>;

// Tree sum of sh[..][0..count] into sh[0]; every invocation calls it.
fn tree_sum(lid: u32, count: u32) {
    for (var stride = WG_SIZE / 2u; stride > 0u; stride >>= 1u) {
        workgroupBarrier();
        if lid < stride {
            for (var q = 0u; q < count; q++) {
                sh[lid][q] = sh[lid][q] + sh[lid + stride][q];
            }
        }
    }
    workgroupBarrier();
}

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(workgroup_id) wid: vec3<u32>,
        @builtin(local_invocation_index) lid: u32,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let w = workgroup_index(wid, n_groups);
    let first = w * BLOCK;
    // Surplus workgroups of a 2-D grid leave together (uniform).
    if first >= params.n_points {
        return;
    }
    let row = w * (1u + 5u * params.n_prims);
    // Phase 1: V, G, the energy and the adjoints λ_V = ∂e/∂V/M and
    // λ_G = ∂e/∂G/M of each of this invocation's points.
    var xs: array<vec3<f32>, POINTS_PER_INVOCATION>;
    var lv: array<f32, POINTS_PER_INVOCATION>;
    var lg: array<vec3<f32>, POINTS_PER_INVOCATION>;
    var energy = 0.0;
    for (var p = 0u; p < POINTS_PER_INVOCATION; p++) {
        let ix = first + lid + p * WG_SIZE;
        xs[p] = vec3<f32>(0.0);
        lv[p] = 0.0;
        lg[p] = vec3<f32>(0.0);
        if ix >= params.n_points {
            continue;
        }
        let x = points[2u * ix].xyz;
        let n = points[2u * ix + 1u].xyz;
        var v = 0.0;
        var g = vec3<f32>(0.0);
        for (var k = 0u; k < params.n_prims; k++) {
            let ca = prims[2u * k];
            let b = prims[2u * k + 1u].x;
            let d = x - ca.xyz;
            let e = b * exp(-ca.w * dot(d, d));
            v += e;
            g += -2.0 * ca.w * e * d;
        }
        let g2 = dot(g, g);
        var dn: vec3<f32>;
        var en: f32;
        if g2 > params.g_min2 {
            // u = N/|N| = −ĝ: e_n = |n + ĝ|², ∂e_n/∂G = 2(n − ĝ(ĝ·n))/|G|.
            let len = sqrt(g2);
            let gh = g / len;
            let r = n + gh;
            en = dot(r, r);
            dn = 2.0 * (n - gh * dot(gh, n)) / len;
        } else {
            let gm = sqrt(params.g_min2);
            let r = n + g / gm;
            en = dot(r, r);
            dn = 2.0 * r / gm;
        }
        let res = v - params.iso;
        energy += (res * res + params.alpha * en) * params.inv_m;
        xs[p] = x;
        lv[p] = 2.0 * res * params.inv_m;
        lg[p] = params.alpha * params.inv_m * dn;
    }
    sh[lid][0] = energy;
    tree_sum(lid, 1u);
    if lid == 0u {
        partials[row] = sh[0][0];
    }
    // Phase 2: per primitive, each invocation's gradient over its points,
    // then the tree. With d = x − c, s = |d|², ex = exp(−a s), e = b·ex:
    //   ∂/∂c = 2ae((λ_V − 2a λ_G·d) d + λ_G)
    //   ∂/∂a = −s e λ_V − 2e(1 − a s) λ_G·d
    //   ∂/∂b = ex (λ_V − 2a λ_G·d)
    for (var k = 0u; k < params.n_prims; k++) {
        let ca = prims[2u * k];
        let b = prims[2u * k + 1u].x;
        let a = ca.w;
        var gc = vec3<f32>(0.0);
        var ga = 0.0;
        var gb = 0.0;
        for (var p = 0u; p < POINTS_PER_INVOCATION; p++) {
            let d = xs[p] - ca.xyz;
            let s = dot(d, d);
            let ex = exp(-a * s);
            let e = b * ex;
            let ld = dot(lg[p], d);
            let m = lv[p] - 2.0 * a * ld;
            gc += 2.0 * a * e * (m * d + lg[p]);
            ga += -s * e * lv[p] - 2.0 * e * (1.0 - a * s) * ld;
            gb += ex * m;
        }
        sh[lid] = array<f32, 5>(gc.x, gc.y, gc.z, ga, gb);
        tree_sum(lid, 5u);
        if lid == 0u {
            for (var q = 0u; q < 5u; q++) {
                partials[row + 1u + 5u * k + q] = sh[0][q];
            }
        }
    }
}
