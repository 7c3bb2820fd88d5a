//! GPU pass for `kernels/particle_update.wgsl`.

use super::{StepInput, UpdateParams};
use crate::Result;
use crate::gpu::{Gpu, GpuArray, Kernel, UniformBuffer};
use crate::implicit::field::FieldInput;
use crate::implicit::field::gpu::FieldBuffers;
use crate::particles::StepOutput;

/// Device buffers of one step.
#[derive(Debug)]
pub struct UpdateBuffers {
    params: UniformBuffer<UpdateParams>,
    cells: GpuArray<u32>,
    pos_in: GpuArray<[f32; 4]>,
    /// Output (position, σ) (NaN sentinels until written).
    pub pos_out: GpuArray<[f32; 4]>,
    /// Output (D_i, |Δp|/Δt, (F − I)/|∇F|, |∇F|).
    pub state: GpuArray<[f32; 4]>,
    n: u32,
}

impl UpdateBuffers {
    /// Uploads one step's inputs.
    pub fn upload(gpu: &Gpu, input: &StepInput<'_>) -> Result<Self> {
        let n = input.positions.len();
        Ok(UpdateBuffers {
            params: UniformBuffer::new(gpu, "particle_update.params", &input.params)?,
            cells: GpuArray::from_slice(gpu, "particle_update.cells", input.cells)?,
            pos_in: GpuArray::from_slice(gpu, "particle_update.pos_in", input.positions)?,
            pos_out: GpuArray::output(gpu, "particle_update.pos_out", n, [f32::NAN; 4])?,
            state: GpuArray::output(gpu, "particle_update.state", n, [f32::NAN; 4])?,
            n: input.params.n_particles,
        })
    }

    /// Records the step into `encoder`.
    pub fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        field: &FieldBuffers,
    ) -> Result<()> {
        let binder = gpu.kernel(Kernel::ParticleUpdate)?.uniform(&self.params);
        field
            .bind(binder)
            .read(&self.cells)
            .read(&self.pos_in)
            .write(&self.pos_out)
            .write(&self.state)
            .bind()?
            .record(gpu, encoder, self.n, None);
        Ok(())
    }
}

/// Uploads, dispatches once and reads positions and states back.
pub fn particle_update(gpu: &Gpu, field: &FieldInput, input: &StepInput<'_>) -> Result<StepOutput> {
    let field = FieldBuffers::upload(gpu, field)?;
    let buffers = UpdateBuffers::upload(gpu, input)?;
    let mut encoder = gpu.encoder("particle_update");
    buffers.record(gpu, &mut encoder, &field)?;
    gpu.submit_and_wait(encoder)?;
    Ok((buffers.pos_out.read(gpu)?, buffers.state.read(gpu)?))
}
