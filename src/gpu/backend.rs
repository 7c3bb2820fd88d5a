//! Where a data-parallel operation runs: the crate's one run-time switch.

use super::Gpu;

/// Where a data-parallel operation runs.
#[derive(Debug, Clone, Copy)]
pub enum Backend<'a> {
    /// The CPU path (the mirror, or its fast path tested equal to it).
    Cpu,
    /// The WGSL kernel on this device.
    Gpu(&'a Gpu),
}

impl Backend<'_> {
    /// `cpu` or `gpu`.
    pub fn name(&self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
            Backend::Gpu(_) => "gpu",
        }
    }
}
