//! GPU pass for `kernels/blobby_energy.wgsl`.

use super::{EnergyInput, EnergyParams};
use crate::gpu::{Gpu, GpuArray, Kernel, UniformBuffer};
use crate::{Error, Result};

/// Device buffers of one evaluation, kept for reruns with new primitives
/// (the points stay).
#[derive(Debug)]
pub struct EnergyBuffers {
    params: UniformBuffer<EnergyParams>,
    prims: GpuArray<[f32; 4]>,
    points: GpuArray<[f32; 4]>,
    /// Output rows, one per workgroup (NaN sentinels until written).
    pub partials: GpuArray<f32>,
    n_rows: u32,
    /// The kernel's workgroup size (from its spec).
    wg_size: u32,
}

impl EnergyBuffers {
    /// Uploads `input`.
    ///
    /// Errors: points or rows past one storage binding.
    pub fn upload(gpu: &Gpu, input: &EnergyInput) -> Result<Self> {
        let rows = input.n_rows();
        let n_rows = u32::try_from(rows)
            .map_err(|_| Error::limit("blobby_energy: workgroups", rows, u32::MAX))?;
        Ok(EnergyBuffers {
            params: UniformBuffer::new(gpu, "blobby_energy.params", &input.params)?,
            prims: GpuArray::from_slice(gpu, "blobby_energy.prims", &input.prims)?,
            points: GpuArray::from_slice(gpu, "blobby_energy.points", &input.points)?,
            partials: GpuArray::output(
                gpu,
                "blobby_energy.partials",
                rows * input.row_len(),
                f32::NAN,
            )?,
            n_rows,
            wg_size: Kernel::BlobbyEnergy.spec()?.wg_size,
        })
    }

    /// Records the kernel into `encoder`.
    pub fn record(&self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        gpu.kernel(Kernel::BlobbyEnergy)?
            .uniform(&self.params)
            .read(&self.prims)
            .read(&self.points)
            .write(&self.partials)
            .bind()?
            .record(gpu, encoder, self.n_rows.saturating_mul(self.wg_size), None);
        Ok(())
    }
}

/// Uploads, dispatches and reads the rows back.
pub fn blobby_energy(gpu: &Gpu, input: &EnergyInput) -> Result<Vec<f32>> {
    let buffers = EnergyBuffers::upload(gpu, input)?;
    let mut encoder = gpu.encoder("blobby_energy");
    buffers.record(gpu, &mut encoder)?;
    gpu.submit_and_wait(encoder)?;
    buffers.partials.read(gpu)
}
