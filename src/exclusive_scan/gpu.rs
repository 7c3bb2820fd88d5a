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

/// Uniform parameters of both scan kernels.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct Params {
    /// Elements at this level.
    pub n: u32,
}

/// One level: n elements scanned per block, ceil(n / WG_SIZE) totals.
#[derive(Debug)]
struct Level {
    params: UniformBuffer<Params>,
    n: u32,
    scanned: GpuArray<u32>,
    totals: GpuArray<u32>,
}

/// Device buffers of one scan, kept for resident reruns. Outputs are kernel
/// outputs ([`GpuArray::output`], sentinel `u32::MAX`).
#[derive(Debug)]
pub struct ScanBuffers {
    values: GpuArray<u32>,
    levels: Vec<Level>,
}

impl ScanBuffers {
    /// Uploads `values` (1 ≤ #N, one storage binding) and allocates the levels.
    pub fn upload(gpu: &Gpu, values: &[u32]) -> Result<Self> {
        if values.is_empty() {
            return Err(Error::empty("exclusive_scan: values"));
        }
        let mut n = u32::try_from(values.len())
            .map_err(|_| Error::limit("exclusive_scan: values", values.len(), u32::MAX))?;
        let values = GpuArray::from_slice(gpu, "exclusive_scan.values", values)?;
        // Elements per block: the workgroup size of both kernels.
        let block = Kernel::ExclusiveScanBlocks.spec()?.wg_size;
        let mut levels = Vec::new();
        loop {
            let k = levels.len();
            let n_blocks = n.div_ceil(block);
            levels.push(Level {
                params: UniformBuffer::new(
                    gpu,
                    &format!("exclusive_scan.params{k}"),
                    &Params { n },
                )?,
                n,
                scanned: GpuArray::output(
                    gpu,
                    &format!("exclusive_scan.scanned{k}"),
                    n as usize,
                    u32::MAX,
                )?,
                totals: GpuArray::output(
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
        let mut up = Vec::with_capacity(self.levels.len());
        let mut src = &self.values;
        for level in &self.levels {
            let bound = (gpu.kernel(Kernel::ExclusiveScanBlocks)?)
                .uniform(&level.params)
                .read(src)
                .write(&level.scanned)
                .write(&level.totals)
                .bind()?;
            up.push(bound);
            src = &level.totals;
        }
        let down = (self.levels.windows(2))
            .map(|pair| {
                (gpu.kernel(Kernel::ExclusiveScanAdd)?)
                    .uniform(&pair[0].params)
                    .read(&pair[1].scanned)
                    .write(&pair[0].scanned)
                    .bind()
            })
            .collect::<Result<Vec<_>>>()?;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("chisel.exclusive_scan"),
            timestamp_writes: None,
        });
        for (level, bound) in self.levels.iter().zip(&up) {
            bound.dispatch(gpu, &mut pass, level.n);
        }
        for (level, bound) in self.levels.iter().zip(&down).rev() {
            bound.dispatch(gpu, &mut pass, level.n);
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
