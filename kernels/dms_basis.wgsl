// dms_basis: the weights of the quadratic DMS B-splines at evaluation
// points (seed 000 eq. 2.6–2.10), summed per shared control.
//
// Dispatch: one invocation per evaluation point, WG_SIZE per workgroup,
// 2-D grid past the per-dimension limit (see shared/dispatch.wgsl).
// Buffers:
//   params:     n_points
//   points:     #P vec2<f32>, the point relative to the domain centre
//   tri_knots:  5·#T vec4<f32>: local knots r0 … t2 (xy, zw pairs), the
//               fifth's zw = the triangle's origin o (its knot r0)
//   cand_off:   #P + 1 u32, CSR starts into cand_tri
//   cand_tri:   triangles whose knot hull holds the point, ascending
//   slot_entry: 6 per candidate: the row entry of B-spline β's control
//   row_off:    #P + 1 u32, the point's row of distinct controls
//   weights:    per row entry vec4 out: (Σ N, Σ ∂N/∂u, Σ ∂N/∂v, 0)
// Per candidate the point is moved into the triangle's frame (u − o); each
// of the 36 knot lines is oriented once, in its canonical knot order, and
// zero when the point is one of its knots; the 19 degree-0 splines test
// the half-open triangle with those signs and the lexicographic tie-break
// (e₁, then up); 12 degree-1 and 6 degree-2 splines follow by eq. 2.6 with
// the DMS triples (tables below, = dms::program); ∇N by Micchelli's
// formula. No atomics: an invocation owns its row.
// Mirror: dms::basis::cpu::dms_basis.

#import dispatch

struct Params {
    n_points: u32,
}

const WG_SIZE: u32 = 64u;

// dms::program::DEGREE0
const DEGREE0 = array<vec3<u32>, 19>(
    vec3<u32>(0u, 3u, 6u), vec3<u32>(0u, 1u, 3u), vec3<u32>(0u, 1u, 6u), vec3<u32>(0u, 1u, 4u),
    vec3<u32>(0u, 1u, 2u), vec3<u32>(1u, 2u, 3u), vec3<u32>(1u, 2u, 6u), vec3<u32>(1u, 6u, 7u),
    vec3<u32>(0u, 3u, 4u), vec3<u32>(3u, 4u, 6u), vec3<u32>(3u, 4u, 7u), vec3<u32>(3u, 4u, 5u),
    vec3<u32>(0u, 4u, 5u), vec3<u32>(4u, 5u, 6u), vec3<u32>(0u, 6u, 7u), vec3<u32>(3u, 6u, 7u),
    vec3<u32>(6u, 7u, 8u), vec3<u32>(3u, 7u, 8u), vec3<u32>(0u, 7u, 8u),
);
// dms::program::Program::degree1: W, then the degree-0 child dropping w_k.
const DEGREE1_W = array<vec3<u32>, 12>(
    vec3<u32>(1u, 3u, 6u), vec3<u32>(0u, 4u, 6u), vec3<u32>(0u, 3u, 7u), vec3<u32>(1u, 4u, 3u),
    vec3<u32>(6u, 4u, 7u), vec3<u32>(1u, 0u, 7u), vec3<u32>(2u, 0u, 6u), vec3<u32>(2u, 3u, 0u),
    vec3<u32>(0u, 5u, 3u), vec3<u32>(3u, 5u, 6u), vec3<u32>(6u, 3u, 8u), vec3<u32>(0u, 6u, 8u),
);
const DEGREE1_CHILD = array<vec3<u32>, 12>(
    vec3<u32>(0u, 2u, 1u), vec3<u32>(9u, 0u, 8u), vec3<u32>(15u, 14u, 0u), vec3<u32>(8u, 1u, 3u),
    vec3<u32>(10u, 15u, 9u), vec3<u32>(14u, 7u, 2u), vec3<u32>(2u, 6u, 4u), vec3<u32>(1u, 4u, 5u),
    vec3<u32>(11u, 8u, 12u), vec3<u32>(13u, 9u, 11u), vec3<u32>(17u, 16u, 15u), vec3<u32>(16u, 18u, 14u),
);
// dms::program::Program::degree2, β in the order 200 110 101 020 011 002.
const DEGREE2_W = array<vec3<u32>, 6>(
    vec3<u32>(2u, 3u, 6u), vec3<u32>(1u, 4u, 6u), vec3<u32>(1u, 3u, 7u),
    vec3<u32>(0u, 5u, 6u), vec3<u32>(0u, 4u, 7u), vec3<u32>(0u, 3u, 8u),
);
const DEGREE2_CHILD = array<vec3<u32>, 6>(
    vec3<u32>(0u, 6u, 7u), vec3<u32>(1u, 0u, 3u), vec3<u32>(2u, 5u, 0u),
    vec3<u32>(9u, 1u, 8u), vec3<u32>(4u, 2u, 1u), vec3<u32>(10u, 11u, 2u),
);

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> points: array<vec2<f32>>;
@group(0) @binding(2) var<storage, read> tri_knots: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> cand_off: array<u32>;
@group(0) @binding(4) var<storage, read> cand_tri: array<u32>;
@group(0) @binding(5) var<storage, read> slot_entry: array<u32>;
@group(0) @binding(6) var<storage, read> row_off: array<u32>;
@group(0) @binding(7) var<storage, read_write> weights: array<vec4<f32>>;

// d(p, q, u) = (q − p) × (u − p).
fn orient(p: vec2<f32>, q: vec2<f32>, u: vec2<f32>) -> f32 {
    return (q.x - p.x) * (u.y - p.y) - (q.y - p.y) * (u.x - p.x);
}

// Index of the knot line (a, b), a ≠ b, in canonical order.
fn line_index(a: u32, b: u32) -> u32 {
    let lo = min(a, b);
    let hi = max(a, b);
    return lo * (17u - lo) / 2u + (hi - lo - 1u);
}

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let ix = linear_index(gid, n_groups, WG_SIZE);
    if ix >= params.n_points {
        return;
    }
    for (var e = row_off[ix]; e < row_off[ix + 1u]; e++) {
        weights[e] = vec4<f32>(0.0);
    }
    let u = points[ix];
    var k: array<vec2<f32>, 9>;
    var side: array<f32, 36>;
    var m0: array<f32, 19>;
    var m1: array<f32, 12>;
    for (var c = cand_off[ix]; c < cand_off[ix + 1u]; c++) {
        let t = cand_tri[c];
        let q0 = tri_knots[5u * t];
        let q1 = tri_knots[5u * t + 1u];
        let q2 = tri_knots[5u * t + 2u];
        let q3 = tri_knots[5u * t + 3u];
        let q4 = tri_knots[5u * t + 4u];
        k[0] = q0.xy; k[1] = q0.zw; k[2] = q1.xy; k[3] = q1.zw; k[4] = q2.xy;
        k[5] = q2.zw; k[6] = q3.xy; k[7] = q3.zw; k[8] = q4.xy;
        let ul = u - q4.zw;
        var l = 0u;
        for (var a = 0u; a < 9u; a++) {
            for (var b = a + 1u; b < 9u; b++) {
                let p = k[a];
                let q = k[b];
                if all(ul == p) || all(ul == q) {
                    side[l] = 0.0;
                } else {
                    side[l] = orient(p, q, ul);
                }
                l++;
            }
        }
        for (var i = 0u; i < 19u; i++) {
            let tri = DEGREE0[i];
            let d = orient(k[tri.x], k[tri.y], k[tri.z]);
            m0[i] = 0.0;
            if d == 0.0 {
                continue;
            }
            var ring = vec3<u32>(tri.x, tri.z, tri.y);
            if d > 0.0 {
                ring = tri;
            }
            var inside = true;
            for (var e = 0u; e < 3u; e++) {
                let p = ring[e];
                let q = ring[(e + 1u) % 3u];
                let s = side[line_index(p, q)];
                var o = s;
                if p > q {
                    o = -s;
                }
                var ok: bool;
                if o != 0.0 {
                    ok = o > 0.0;
                } else {
                    let ey = k[q].y - k[p].y;
                    let ex = k[q].x - k[p].x;
                    if ey != 0.0 {
                        ok = ey < 0.0;
                    } else {
                        ok = ex > 0.0;
                    }
                }
                if !ok {
                    inside = false;
                    break;
                }
            }
            if inside {
                m0[i] = 1.0 / abs(d);
            }
        }
        for (var i = 0u; i < 12u; i++) {
            let w = DEGREE1_W[i];
            let child = DEGREE1_CHILD[i];
            let w0 = k[w.x];
            let w1 = k[w.y];
            let w2 = k[w.z];
            let d = orient(w0, w1, w2);
            var s = 0.0;
            s += orient(ul, w1, w2) / d * m0[child.x];
            s += orient(w0, ul, w2) / d * m0[child.y];
            s += orient(w0, w1, ul) / d * m0[child.z];
            m1[i] = s;
        }
        for (var b = 0u; b < 6u; b++) {
            let w = DEGREE2_W[b];
            let child = DEGREE2_CHILD[b];
            let w0 = k[w.x];
            let w1 = k[w.y];
            let w2 = k[w.z];
            let ma = m1[child.x];
            let mb = m1[child.y];
            let mc = m1[child.z];
            var n = vec3<f32>(0.0);
            n += vec3<f32>(orient(ul, w1, w2) * ma, 2.0 * (w1.y - w2.y) * ma, 2.0 * (w2.x - w1.x) * ma);
            n += vec3<f32>(orient(w0, ul, w2) * mb, 2.0 * (w2.y - w0.y) * mb, 2.0 * (w0.x - w2.x) * mb);
            n += vec3<f32>(orient(w0, w1, ul) * mc, 2.0 * (w0.y - w1.y) * mc, 2.0 * (w1.x - w0.x) * mc);
            let e = slot_entry[6u * c + b];
            weights[e] += vec4<f32>(n, 0.0);
        }
    }
}
