//! Large buffers made from inputs (per-voxel labels and masks, marching
//! cubes arrays, decoded samples) allocated fallibly and against one memory
//! budget: running out is [`Error::HostMemory`] naming the buffer and its
//! size, never an allocator abort.

use crate::{Error, Result};

/// Environment variable setting the memory budget, in bytes.
pub const BUDGET_ENV: &str = "CHISEL_MAX_INPUT_BYTES";

/// Default memory budget: 16 GiB.
pub const DEFAULT_BUDGET: u64 = 16 << 30;

/// The most bytes one input, or one buffer derived from it, may take:
/// `CHISEL_MAX_INPUT_BYTES` when set to an integer, else [`DEFAULT_BUDGET`].
pub fn memory_budget() -> u64 {
    std::env::var(BUDGET_ENV)
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(DEFAULT_BUDGET)
}

/// `n` copies of `value` for `what`: checked against [`memory_budget`],
/// then reserved fallibly.
pub fn filled<T: Clone>(what: &str, n: usize, value: T) -> Result<Vec<T>> {
    let mut v = reserved(what, n)?;
    v.resize(n, value);
    Ok(v)
}

/// `n` zeros for `what`, checked against [`memory_budget`]: allocated
/// zeroed (a large buffer comes as fresh zero pages, not written here), so
/// a pass that then writes every element touches its memory once instead
/// of twice ([`filled`] writes it first).
pub fn zeroed<T: bytemuck::Zeroable>(what: &str, n: usize) -> Result<Vec<T>> {
    let bytes = within_budget::<T>(what, n)?;
    bytemuck::allocation::try_zeroed_vec(n).map_err(|()| Error::HostMemory {
        what: what.to_string(),
        bytes,
    })
}

/// The bytes of `n` elements of `T`, or the error when they exceed the
/// budget.
fn within_budget<T>(what: &str, n: usize) -> Result<u64> {
    let bytes = (n as u64).saturating_mul(std::mem::size_of::<T>() as u64);
    let budget = memory_budget();
    if bytes > budget {
        return Err(Error::HostMemory {
            what: format!("{what} (over the memory budget, {BUDGET_ENV} = {budget})"),
            bytes,
        });
    }
    Ok(bytes)
}

/// An empty vector with room for exactly `n` elements, for `what`.
pub fn reserved<T>(what: &str, n: usize) -> Result<Vec<T>> {
    let bytes = within_budget::<T>(what, n)?;
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| Error::HostMemory {
        what: what.to_string(),
        bytes,
    })?;
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn too_large_is_an_error_naming_the_buffer() {
        let e = filled("test labels", usize::MAX / 8, 0u64).unwrap_err();
        assert!(matches!(e, Error::HostMemory { .. }), "{e}");
        assert!(e.to_string().contains("test labels"), "{e}");
        let z = zeroed::<[f32; 3]>("test positions", usize::MAX / 8).unwrap_err();
        assert!(matches!(z, Error::HostMemory { .. }), "{z}");
        assert!(z.to_string().contains("test positions"), "{z}");
        assert_eq!(zeroed::<[u32; 3]>("small", 2).unwrap(), vec![[0; 3]; 2]);
        assert_eq!(filled("small", 3, 7u8).unwrap(), vec![7, 7, 7]);
        assert_eq!(reserved::<u32>("room", 5).unwrap().capacity(), 5);
    }
}
