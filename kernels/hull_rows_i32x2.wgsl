// hull_rows_i32x2: the per-row method of the inside-hull scan without
// SHADER_INT64: the same intervals as hull_rows.wgsl, found by binary
// search on exact emulated 64-bit products (shared/i32x2.wgsl) instead of
// 64-bit division; no floats. A voxel row (fixed y, z; centres
// x = 2i + 1) meets the closed polyhedron in one interval (inside or on),
// the open one in a sub-interval (inside). Per face a·x ≤ r,
// r = d − b·y − c·z: a > 0 bounds i from above (largest i with
// a·(2i+1) ≤ r; one less for the open part on equality), a < 0 from below,
// a = 0 keeps all (r > 0), the closed part (r = 0) or nothing (r < 0).
// Faces that cannot tighten the interval are skipped. SPEC §4.3.
//
// Dispatch: one invocation per row of the slab (row = y + ny·(z − z0)),
// WG_SIZE per workgroup, 2-D grid past the per-dimension limit.
// Buffers:
//   params: n_items = rows in the slab, nx, ny, z0, origin
//   faces:  #F Face (shared/hull_face.wgsl)
//   layers: the faces each z layer of the slab uses: layers[2k],
//           layers[2k + 1] = start, end (in `layers`) of the ids of the
//           faces local layer k tests, or LAYER_MISSES when the polyhedron
//           misses the layer (every row empty). Every face for every layer,
//           or only those whose z range holds it (hull_scan::row_spans_culled).
//   spans:  n_items vec4<i32> out: local x of (closed lo, closed hi, open
//           lo, open hi), inclusive; empty = (0, −1)
// Range (hull_scan::check_range): |r| < 2^61, products i32 × i32, exact.
// Mirror: hull_scan::cpu::hull_rows_i32x2 (and hull_rows / hull_rows_culled:
// same spans).

#import dispatch
#import hull_face
#import i32x2

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> faces: array<Face>;
@group(0) @binding(2) var<storage, read> layers: array<u32>;
@group(0) @binding(3) var<storage, read_write> spans: array<vec4<i32>>;

const EMPTY = vec4<i32>(0, -1, 0, -1);

// The span of the row at combinatorial (y, z) of local layer k, global
// voxel indices.
fn row_span(y: i32, z: i32, k: u32) -> vec4<i32> {
    let ox = params.origin_x;
    var lo_c = ox;
    var hi_c = ox + i32(params.nx) - 1;
    var lo_o = lo_c;
    var hi_o = hi_c;
    var open = true;
    let zero = vec2<u32>(0u, 0u);
    for (var i = layers[2u * k]; i < layers[2u * k + 1u]; i++) {
        let face = faces[layers[i]];
        let a = face.normal.x;
        let r = w_sub(w_sub(face.offset.xy, w_mul(face.normal.y, y)), w_mul(face.normal.z, z));
        if a == 0 {
            if w_lt(r, zero) {
                return EMPTY;
            }
            open = open && !w_eq(r, zero);
        } else if a > 0 {
            let v = w_mul(a, 2 * hi_c + 1);
            if w_lt(v, r) {
                continue;
            }
            if w_eq(v, r) {
                hi_o = min(hi_o, hi_c - 1);
                continue;
            }
            if !w_le(w_mul(a, 2 * lo_c + 1), r) {
                return EMPTY;
            }
            // Largest i in [lo_c, hi_c − 1] with a·(2i+1) ≤ r.
            var lo = lo_c;
            var hi = hi_c - 1;
            while lo < hi {
                let mid = lo + (hi - lo + 1) / 2;
                if w_le(w_mul(a, 2 * mid + 1), r) {
                    lo = mid;
                } else {
                    hi = mid - 1;
                }
            }
            hi_c = lo;
            hi_o = min(hi_o, select(lo, lo - 1, w_eq(w_mul(a, 2 * lo + 1), r)));
        } else {
            let v = w_mul(a, 2 * lo_c + 1);
            if w_lt(v, r) {
                continue;
            }
            if w_eq(v, r) {
                lo_o = max(lo_o, lo_c + 1);
                continue;
            }
            if !w_le(w_mul(a, 2 * hi_c + 1), r) {
                return EMPTY;
            }
            // Smallest i in [lo_c + 1, hi_c] with a·(2i+1) ≤ r.
            var lo = lo_c + 1;
            var hi = hi_c;
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if w_le(w_mul(a, 2 * mid + 1), r) {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            lo_c = lo;
            lo_o = max(lo_o, select(lo, lo + 1, w_eq(w_mul(a, 2 * lo + 1), r)));
        }
    }
    if open && lo_o <= hi_o {
        return vec4<i32>(lo_c - ox, hi_c - ox, lo_o - ox, hi_o - ox);
    }
    return vec4<i32>(lo_c - ox, hi_c - ox, 0, -1);
}

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let ix = linear_index(gid, n_groups, WG_SIZE);
    if ix >= params.n_items {
        return;
    }
    if params.nx == 0u {
        spans[ix] = EMPTY;
        return;
    }
    let k = ix / params.ny;
    if layers[2u * k] == LAYER_MISSES {
        spans[ix] = EMPTY;
        return;
    }
    let y = 2 * (params.origin_y + i32(ix % params.ny)) + 1;
    let z = 2 * (params.origin_z + i32(params.z0 + k)) + 1;
    spans[ix] = row_span(y, z, k);
}
