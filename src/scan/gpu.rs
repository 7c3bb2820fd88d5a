//! GPU passes for `kernels/exclusive_scan_blocks.wgsl` and
//! `kernels/exclusive_scan_add.wgsl`.
//!
//! [`ScanBuffers`] holds one problem as a stack of levels: level 0 scans the
//! input, level k + 1 scans level k's block totals, and the last level has a
//! single block whose total is the grand total. Recording runs the block
//! scans upward, then the adds downward, in one compute pass.

use super::Scan;
use crate::gpu::{Gpu, GpuArray, Kernel, UniformBuffer};
use crate::{Error, Result};

/// Elements per block (`WG_SIZE` in both kernels).
pub const WG_SIZE: u32 = 256;

/// Uniform parameters of both scan kernels.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct Params {
    /// Elements at this level.
    pub n: u32,
}

/// Bindings of `exclusive_scan_blocks`, by binding number (group 0).
pub const BLOCKS_BINDINGS: &[wgpu::BufferBindingType] = &[
    wgpu::BufferBindingType::Uniform,
    wgpu::BufferBindingType::Storage { read_only: true },
    wgpu::BufferBindingType::Storage { read_only: false },
    wgpu::BufferBindingType::Storage { read_only: false },
];

/// Bindings of `exclusive_scan_add`, by binding number (group 0).
pub const ADD_BINDINGS: &[wgpu::BufferBindingType] = &[
    wgpu::BufferBindingType::Uniform,
    wgpu::BufferBindingType::Storage { read_only: true },
    wgpu::BufferBindingType::Storage { read_only: false },
];

/// One level: n elements scanned per block, ceil(n / WG_SIZE) totals.
#[derive(Debug)]
struct Level {
    params: UniformBuffer<Params>,
    n: u32,
    scanned: GpuArray<u32>,
    totals: GpuArray<u32>,
}

/// Device buffers of one scan, kept for resident reruns. Outputs start
/// filled with the `u32::MAX` sentinel.
#[derive(Debug)]
pub struct ScanBuffers {
    values: GpuArray<u32>,
    levels: Vec<Level>,
}

impl ScanBuffers {
    /// Uploads `values` (1 ≤ #N, one storage binding) and allocates the levels.
    pub fn upload(gpu: &Gpu, values: &[u32]) -> Result<Self> {
        let mut n = u32::try_from(values.len())
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| {
                Error::InvalidInput(format!(
                    "exclusive_scan: {} values (need 1 to 2^32 − 1 on the GPU)",
                    values.len()
                ))
            })?;
        let values = GpuArray::from_slice(gpu, "exclusive_scan.values", values)?;
        let mut levels = Vec::new();
        loop {
            let k = levels.len();
            let n_blocks = n.div_ceil(WG_SIZE);
            levels.push(Level {
                params: UniformBuffer::new(
                    gpu,
                    &format!("exclusive_scan.params{k}"),
                    &Params { n },
                )?,
                n,
                scanned: GpuArray::filled(
                    gpu,
                    &format!("exclusive_scan.scanned{k}"),
                    n as usize,
                    u32::MAX,
                )?,
                totals: GpuArray::filled(
                    gpu,
                    &format!("exclusive_scan.totals{k}"),
                    n_blocks as usize,
                    u32::MAX,
                )?,
            });
            if n_blocks == 1 {
                break;
            }
            n = n_blocks;
        }
        Ok(ScanBuffers { values, levels })
    }

    /// Number of levels (⌈log₂₅₆ n⌉, at least 1).
    pub fn n_levels(&self) -> usize {
        self.levels.len()
    }

    /// The #N scanned offsets (valid after the recorded work ran).
    pub fn offsets(&self) -> &GpuArray<u32> {
        &self.levels[0].scanned
    }

    /// The one-element buffer holding the total (valid after the work ran).
    pub fn total(&self) -> &GpuArray<u32> {
        &self.levels[self.levels.len() - 1].totals
    }

    /// Records block scans up the levels and adds back down (no submission).
    pub fn record(&self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        let blocks = gpu.pipeline(Kernel::ExclusiveScanBlocks)?;
        let add = gpu.pipeline(Kernel::ExclusiveScanAdd)?;
        let mut up = Vec::with_capacity(self.levels.len());
        let mut src = &self.values;
        for level in &self.levels {
            up.push(gpu.bind(
                Kernel::ExclusiveScanBlocks,
                &blocks,
                &[
                    level.params.binding(),
                    src.binding(),
                    level.scanned.binding(),
                    level.totals.binding(),
                ],
            )?);
            src = &level.totals;
        }
        let down = self
            .levels
            .windows(2)
            .map(|pair| {
                gpu.bind(
                    Kernel::ExclusiveScanAdd,
                    &add,
                    &[
                        pair[0].params.binding(),
                        pair[1].scanned.binding(),
                        pair[0].scanned.binding(),
                    ],
                )
            })
            .collect::<Result<Vec<_>>>()?;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("chisel.exclusive_scan"),
            timestamp_writes: None,
        });
        for (level, bind) in self.levels.iter().zip(&up) {
            gpu.dispatch(&mut pass, &blocks, bind, level.n, WG_SIZE);
        }
        for (level, bind) in self.levels.iter().zip(&down).rev() {
            gpu.dispatch(&mut pass, &add, bind, level.n, WG_SIZE);
        }
        Ok(())
    }

    /// Records, submits, waits and reads offsets and total back.
    pub fn run(&self, gpu: &Gpu) -> Result<Scan> {
        let mut encoder = gpu.encoder("exclusive_scan");
        self.record(gpu, &mut encoder)?;
        let offsets = self.offsets().stage(gpu, &mut encoder)?;
        let total = self.total().stage(gpu, &mut encoder)?;
        gpu.submit_and_wait(encoder)?;
        let offsets = offsets.finish(gpu)?;
        let total = total.finish(gpu)?;
        let total = total.first().copied().ok_or_else(|| Error::Readback {
            label: "chisel.exclusive_scan.total".into(),
            message: "empty readback".into(),
        })?;
        Ok(Scan { offsets, total })
    }
}

/// Uploads `values`, scans them and reads offsets and total back.
pub fn exclusive_scan(gpu: &Gpu, values: &[u32]) -> Result<Scan> {
    if values.is_empty() {
        return Ok(Scan {
            offsets: Vec::new(),
            total: 0,
        });
    }
    ScanBuffers::upload(gpu, values)?.run(gpu)
}
