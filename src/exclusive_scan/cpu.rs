//! CPU mirrors of `kernels/exclusive_scan_blocks.wgsl` and
//! `kernels/exclusive_scan_add.wgsl`.
//!
//! Exact (wrapping u32; parity compares with `compare_exact`). Each
//! function mirrors one dispatch; within a block the kernel scans by
//! Hillis–Steele and the mirror sequentially, which gives the same bits
//! because addition mod 2³² is associative.

use super::Scan;

/// Elements per block (`WG_SIZE` in both kernels).
pub const WG_SIZE: usize = 256;

/// One `exclusive_scan_blocks` dispatch: per-block exclusive scans of
/// `values` and the ceil(#N / WG_SIZE) block totals.
pub fn scan_blocks(values: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let mut scanned = Vec::with_capacity(values.len());
    let totals = values
        .chunks(WG_SIZE)
        .map(|block| {
            block.iter().fold(0u32, |sum, &v| {
                scanned.push(sum);
                sum.wrapping_add(v)
            })
        })
        .collect();
    (scanned, totals)
}

/// One `exclusive_scan_add` dispatch: `scanned[i] += offsets[i / WG_SIZE]`.
pub fn add_offsets(scanned: &mut [u32], offsets: &[u32]) {
    for (block, &offset) in scanned.chunks_mut(WG_SIZE).zip(offsets) {
        for v in block {
            *v = v.wrapping_add(offset);
        }
    }
}

/// Whole scan with the GPU's recursion: blocks, scan of the totals, add.
pub fn exclusive_scan(values: &[u32]) -> Scan {
    if values.is_empty() {
        return Scan {
            offsets: Vec::new(),
            total: 0,
        };
    }
    let (mut scanned, totals) = scan_blocks(values);
    if totals.len() == 1 {
        return Scan {
            offsets: scanned,
            total: totals[0],
        };
    }
    let upper = exclusive_scan(&totals);
    add_offsets(&mut scanned, &upper.offsets);
    Scan {
        offsets: scanned,
        total: upper.total,
    }
}
