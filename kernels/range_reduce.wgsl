// range_reduce: one pass of the intensity-range reduction of #N f32 samples
// (one storage binding; the host splits larger volumes into chunks). Each
// workgroup reduces a block of BLOCK = WG_SIZE·ITEMS_PER_INVOCATION items to
// one (min, max) pair of order keys: each invocation folds ITEMS_PER_INVOCATION
// items (WG_SIZE apart, so neighbours read neighbours), then a tree in
// workgroup memory folds the WG_SIZE partials (no atomics). The host repeats
// the pass on the pairs until one pair is left.
//
// Dispatch: ceil(#N / BLOCK) workgroups of WG_SIZE, 2-D grid past the
// per-dimension limit (shared/dispatch.wgsl); workgroup w writes pair w.
// Buffers:
//   params:  n_items; pairs = 0: src holds #N samples as f32 bit patterns;
//            pairs = 1: src holds #N (lo, hi) key pairs of the previous pass
//   src:     #N or 2·#N u32 (see params.pairs)
//   dst:     2·ceil(#N / BLOCK) u32 out: dst[2w] = min key,
//            dst[2w + 1] = max key of workgroup w's items
// Order: IEEE totalOrder via order keys (shared/order_key.wgsl), so the
// result is exact and independent of the tree shape and of the chunking.
// Mirror: reduce::cpu::range_pass (whole reduction: reduce::cpu::range_reduce).

#import dispatch
#import order_key

struct Params {
    n_items: u32,
    pairs: u32,
}

const WG_SIZE: u32 = 256u;
const ITEMS_PER_INVOCATION: u32 = 16u;
const BLOCK: u32 = WG_SIZE * ITEMS_PER_INVOCATION;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> src: array<u32>;
@group(0) @binding(2) var<storage, read_write> dst: array<u32>;

var<workgroup> sh_lo: array<u32, WG_SIZE>;
var<workgroup> sh_hi: array<u32, WG_SIZE>;

// (lo, hi) keys of item ix.
fn load(ix: u32) -> vec2<u32> {
    if params.pairs == 0u {
        return vec2<u32>(order_key(src[ix]));
    }
    return vec2<u32>(src[2u * ix], src[2u * ix + 1u]);
}

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(workgroup_id) wid: vec3<u32>,
        @builtin(local_invocation_index) lid: u32,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let w = workgroup_index(wid, n_groups);
    let first_ix = w * BLOCK;
    // Surplus workgroups of a 2-D grid: the whole group leaves (uniform).
    if first_ix >= params.n_items {
        return;
    }
    // Lanes past the end start from the block's first item: min/max are
    // idempotent, so no identity element is needed.
    let ix = first_ix + lid;
    var acc = load(select(first_ix, ix, ix < params.n_items));
    for (var k = 1u; k < ITEMS_PER_INVOCATION; k++) {
        let item_ix = ix + k * WG_SIZE;
        if item_ix < params.n_items {
            let item = load(item_ix);
            acc = vec2<u32>(min(acc.x, item.x), max(acc.y, item.y));
        }
    }
    sh_lo[lid] = acc.x;
    sh_hi[lid] = acc.y;
    for (var stride = WG_SIZE / 2u; stride > 0u; stride >>= 1u) {
        workgroupBarrier();
        if lid < stride {
            sh_lo[lid] = min(sh_lo[lid], sh_lo[lid + stride]);
            sh_hi[lid] = max(sh_hi[lid], sh_hi[lid + stride]);
        }
    }
    if lid == 0u {
        dst[2u * w] = sh_lo[0];
        dst[2u * w + 1u] = sh_hi[0];
    }
}
