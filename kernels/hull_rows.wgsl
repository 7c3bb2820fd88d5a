// hull_rows: the per-row method of the inside-hull scan, exact in i64
// (SHADER_INT64). A voxel row (fixed y, z; centres x = 2i + 1) meets the
// closed polyhedron in one interval of voxels (inside or on) and the open
// one in a sub-interval (inside); each face a·x ≤ r, r = d − b·y − c·z,
// bounds i once by exact floor/ceil division instead of testing voxels:
//   a > 0: i ≤ ⌊(r − a) / 2a⌋ (closed), one less if the division is exact
//   a < 0: i ≥ ⌈(−r − m) / 2m⌉, m = −a (closed), one more if exact
//   a = 0: r < 0 empties the row, r = 0 empties the open part.
// A face that cannot tighten the interval (one product at its end) is
// skipped without dividing. SPEC §4.3; seed 003 §4.2.1.
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
// Range (hull_scan::check_range): |r| < 2^61, 2a < 2^32, no overflow.
// Mirror: hull_scan::cpu::hull_rows (every face per layer) and
// hull_rows_culled (the faces meeting the layer).

#import dispatch
#import hull_face

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> faces: array<Face>;
@group(0) @binding(2) var<storage, read> layers: array<u32>;
@group(0) @binding(3) var<storage, read_write> spans: array<vec4<i32>>;

const EMPTY = vec4<i32>(0, -1, 0, -1);

fn offset_of(f: Face) -> i64 {
    return (i64(bitcast<i32>(f.offset.y)) << 32u) | i64(f.offset.x);
}

// ⌊a / b⌋ for b > 0 (WGSL division truncates toward zero).
fn floor_div(a: i64, b: i64) -> i64 {
    let q = a / b;
    return select(q, q - 1li, q * b != a && a < 0li);
}

// The span of the row at combinatorial (y, z) of local layer k, global
// voxel indices.
fn row_span(y: i64, z: i64, k: u32) -> vec4<i32> {
    let ox = params.origin_x;
    var lo_c = ox;
    var hi_c = ox + i32(params.nx) - 1;
    var lo_o = lo_c;
    var hi_o = hi_c;
    var open = true;
    for (var i = layers[2u * k]; i < layers[2u * k + 1u]; i++) {
        let face = faces[layers[i]];
        // Sign tests on the i32 component: with naga 30 on Mesa 22.3 lavapipe,
        // ordered comparisons of `i64(n)` (n: i32) with a literal come out
        // constant (`> 0li` always true, `< 0li` always false, even for
        // n = 0); `==` and comparisons of computed values are right.
        let a = i64(face.normal.x);
        let r = offset_of(face) - i64(face.normal.y) * y - i64(face.normal.z) * z;
        if face.normal.x == 0 {
            if r < 0li {
                return EMPTY;
            }
            open = open && r > 0li;
        } else if face.normal.x > 0 {
            let v = a * i64(2 * hi_c + 1);
            if v < r {
                continue;
            }
            if v == r {
                hi_o = min(hi_o, hi_c - 1);
                continue;
            }
            let num = r - a;
            let den = 2li * a;
            let q = floor_div(num, den);
            if q < i64(lo_c) {
                return EMPTY;
            }
            hi_c = i32(q);
            hi_o = min(hi_o, select(hi_c, hi_c - 1, q * den == num));
        } else {
            let v = a * i64(2 * lo_c + 1);
            if v < r {
                continue;
            }
            if v == r {
                lo_o = max(lo_o, lo_c + 1);
                continue;
            }
            let m = -a;
            let num = -r - m;
            let den = 2li * m;
            let q = -floor_div(-num, den);
            if q > i64(hi_c) {
                return EMPTY;
            }
            lo_c = i32(q);
            lo_o = max(lo_o, select(lo_c, lo_c + 1, q * den == num));
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
    spans[ix] = row_span(i64(y), i64(z), k);
}
