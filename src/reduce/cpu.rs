//! CPU mirrors of `kernels/bounds_reduce.wgsl` and `kernels/range_reduce.wgsl`.
//!
//! Exact: parity compares bits (`Tolerance::EXACT` and key equality). Each
//! pass mirrors one dispatch (one output pair per block of [`BLOCK`]
//! items). Within a block the kernel folds per invocation and then by a
//! tree, the mirror by one fold; integer min/max of order keys is
//! associative and commutative, so both give the same bits.

use rayon::prelude::*;

/// Items one workgroup reduces (`BLOCK` = `WG_SIZE` 256 ·
/// `ITEMS_PER_INVOCATION` 16 in both kernels).
pub const BLOCK: usize = 4096;

/// Order key of an f32 bit pattern: `order_key(a) < order_key(b)` exactly
/// when `a` precedes `b` in IEEE 754 totalOrder (mirror of
/// `kernels/shared/order_key.wgsl`).
pub fn order_key(bits: u32) -> u32 {
    if bits & 0x8000_0000 != 0 {
        !bits
    } else {
        bits | 0x8000_0000
    }
}

/// The f32 whose order key is `key` (inverse of [`order_key`]).
pub fn from_key(key: u32) -> f32 {
    f32::from_bits(if key & 0x8000_0000 != 0 {
        key & 0x7fff_ffff
    } else {
        !key
    })
}

fn key4(p: [f32; 4]) -> [u32; 4] {
    p.map(|c| order_key(c.to_bits()))
}

fn min4(a: [u32; 4], b: [u32; 4]) -> [u32; 4] {
    std::array::from_fn(|i| a[i].min(b[i]))
}

fn max4(a: [u32; 4], b: [u32; 4]) -> [u32; 4] {
    std::array::from_fn(|i| a[i].max(b[i]))
}

/// One `bounds_reduce` dispatch with `pairs = 0`: one (lo, hi) key pair
/// per block of [`BLOCK`] positions.
pub fn bounds_pass_positions(positions: &[[f32; 4]]) -> Vec<[[u32; 4]; 2]> {
    positions
        .par_chunks(BLOCK)
        .map(|block| {
            block
                .iter()
                .skip(1)
                .fold([key4(block[0]); 2], |[lo, hi], &p| {
                    let k = key4(p);
                    [min4(lo, k), max4(hi, k)]
                })
        })
        .collect()
}

/// One `bounds_reduce` dispatch with `pairs = 1`: one pair per block of
/// [`BLOCK`] pairs.
pub fn bounds_pass(items: &[[[u32; 4]; 2]]) -> Vec<[[u32; 4]; 2]> {
    items
        .chunks(BLOCK)
        .map(|block| {
            block
                .iter()
                .skip(1)
                .fold(block[0], |[lo, hi], [l, h]| [min4(lo, *l), max4(hi, *h)])
        })
        .collect()
}

/// Component-wise (min, max) of `positions` (all four lanes), pass by pass
/// like the GPU; `None` when empty.
pub fn bounds_reduce(positions: &[[f32; 4]]) -> Option<([f32; 4], [f32; 4])> {
    let mut items = bounds_pass_positions(positions);
    while items.len() > 1 {
        items = bounds_pass(&items);
    }
    items
        .first()
        .map(|[lo, hi]| (lo.map(from_key), hi.map(from_key)))
}

/// One `range_reduce` dispatch with `pairs = 0`: one (lo, hi) key pair per
/// block of [`BLOCK`] samples.
pub fn range_pass_samples(samples: &[f32]) -> Vec<[u32; 2]> {
    samples
        .par_chunks(BLOCK)
        .map(|block| {
            let first = order_key(block[0].to_bits());
            block.iter().skip(1).fold([first; 2], |[lo, hi], s| {
                let k = order_key(s.to_bits());
                [lo.min(k), hi.max(k)]
            })
        })
        .collect()
}

/// One `range_reduce` dispatch with `pairs = 1`.
pub fn range_pass(items: &[[u32; 2]]) -> Vec<[u32; 2]> {
    items
        .chunks(BLOCK)
        .map(|block| {
            block
                .iter()
                .skip(1)
                .fold(block[0], |[lo, hi], [l, h]| [lo.min(*l), hi.max(*h)])
        })
        .collect()
}

/// (min, max) of `samples`, pass by pass like the GPU; `None` when empty.
pub fn range_reduce(samples: &[f32]) -> Option<(f32, f32)> {
    let mut items = range_pass_samples(samples);
    while items.len() > 1 {
        items = range_pass(&items);
    }
    items.first().map(|[lo, hi]| (from_key(*lo), from_key(*hi)))
}
