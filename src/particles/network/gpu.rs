//! GPU pass for `kernels/network_update.wgsl`.

use super::{NetworkInput, NetworkParams, StepOutput};
use crate::Result;
use crate::gpu::{Gpu, GpuArray, Kernel, UniformBuffer};
use crate::implicit::field::FieldInput;
use crate::implicit::field::gpu::FieldBuffers;

/// Device buffers of one step.
#[derive(Debug)]
pub struct NetworkBuffers {
    params: UniformBuffer<NetworkParams>,
    offsets: GpuArray<u32>,
    springs: GpuArray<[u32; 2]>,
    pos_in: GpuArray<[f32; 4]>,
    /// Output positions (NaN sentinels until written).
    pub pos_out: GpuArray<[f32; 4]>,
    /// Output (∇F, F − I) at the input positions.
    pub samples: GpuArray<[f32; 4]>,
    n: u32,
}

impl NetworkBuffers {
    /// Uploads one step's inputs.
    pub fn upload(gpu: &Gpu, input: &NetworkInput<'_>) -> Result<Self> {
        let n = input.positions.len();
        Ok(NetworkBuffers {
            params: UniformBuffer::new(gpu, "network_update.params", &input.params)?,
            offsets: GpuArray::from_slice(gpu, "network_update.offsets", input.offsets)?,
            springs: GpuArray::from_slice(gpu, "network_update.springs", input.springs)?,
            pos_in: GpuArray::from_slice(gpu, "network_update.pos_in", input.positions)?,
            pos_out: GpuArray::output(gpu, "network_update.pos_out", n, [f32::NAN; 4])?,
            samples: GpuArray::output(gpu, "network_update.samples", n, [f32::NAN; 4])?,
            n: input.params.n_vertices,
        })
    }

    /// Records the step into `encoder`.
    pub fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        field: &FieldBuffers,
    ) -> Result<()> {
        let binder = gpu.kernel(Kernel::NetworkUpdate)?.uniform(&self.params);
        field
            .bind(binder)
            .read(&self.offsets)
            .read(&self.springs)
            .read(&self.pos_in)
            .write(&self.pos_out)
            .write(&self.samples)
            .bind()?
            .record(gpu, encoder, self.n, None);
        Ok(())
    }
}

/// Uploads, dispatches once and reads positions and samples back.
pub fn network_update(
    gpu: &Gpu,
    field: &FieldInput,
    input: &NetworkInput<'_>,
) -> Result<StepOutput> {
    let field = FieldBuffers::upload(gpu, field)?;
    let buffers = NetworkBuffers::upload(gpu, input)?;
    let mut encoder = gpu.encoder("network_update");
    buffers.record(gpu, &mut encoder, &field)?;
    gpu.submit_and_wait(encoder)?;
    Ok((buffers.pos_out.read(gpu)?, buffers.samples.read(gpu)?))
}
