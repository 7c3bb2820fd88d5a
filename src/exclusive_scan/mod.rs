//! Exclusive prefix sum of `u32` (kernels `exclusive_scan_blocks` and
//! `exclusive_scan_add`), the building block of stream compaction: scanning
//! per-item output counts gives each item its write offset, and the total
//! gives the output size.
//!
//! Three steps, as in Blelloch's "Prefix sums and their applications"
//! (1990, §1.4, the recursive block form): scan blocks of 256 elements in
//! workgroup memory and write each block's total; scan the totals the same
//! way (recursively, until one block is left, whose total is the grand
//! total); add each block's scanned total back to its elements.
//!
//! Arithmetic wraps mod 2³² on both backends (WGSL runtime u32 overflow
//! wraps; the CPU uses `wrapping_add`). Addition mod 2³² is associative, so
//! the result is exact and independent of the summation order: parity is
//! bit-for-bit. Callers that need true sums must keep Σ values < 2³².

pub mod cpu;
pub mod gpu;

use crate::Result;
use crate::gpu::Backend;

/// An exclusive scan and its total.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Scan {
    /// #N offsets: `offsets[i] = Σ_{j < i} values[j]` (mod 2³²).
    pub offsets: Vec<u32>,
    /// `Σ values` (mod 2³²); 0 for empty input.
    pub total: u32,
}

/// Exclusive scan of `values` on `backend`. On the GPU, `values` must fit
/// one storage binding.
pub fn exclusive_scan(values: &[u32], backend: Backend<'_>) -> Result<Scan> {
    match backend {
        Backend::Cpu => Ok(cpu::exclusive_scan(values)),
        Backend::Gpu(g) => gpu::exclusive_scan(g, values),
    }
}
