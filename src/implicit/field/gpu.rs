//! GPU pass for `kernels/implicit_field.wgsl`, and the field's device
//! buffers shared by every kernel that imports `skeletal_field`.

use super::{FieldInput, FieldParams, Sample};
use crate::Result;
use crate::gpu::{Binder, Gpu, GpuArray, Kernel, UniformBuffer, chunk_ranges};

/// The field of one pose on the device (bindings 1–3 of the kernels that
/// import `skeletal_field`).
#[derive(Debug)]
pub struct FieldBuffers {
    field: UniformBuffer<FieldParams>,
    skeleton: GpuArray<[f32; 4]>,
    table: GpuArray<u32>,
}

impl FieldBuffers {
    /// Uploads `input`.
    pub fn upload(gpu: &Gpu, input: &FieldInput) -> Result<Self> {
        Ok(FieldBuffers {
            field: UniformBuffer::new(gpu, "skeletal_field.field", &input.params)?,
            skeleton: GpuArray::from_slice(gpu, "skeletal_field.skeleton", &input.skeleton)?,
            table: GpuArray::from_slice(gpu, "skeletal_field.table", &input.table)?,
        })
    }

    /// Adds bindings 1–3 to a kernel's binder.
    pub fn bind<'a>(&'a self, binder: Binder<'a>) -> Binder<'a> {
        binder
            .uniform(&self.field)
            .read(&self.skeleton)
            .read(&self.table)
    }
}

/// Uniform parameters of `implicit_field`.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct Params {
    pub n_points: u32,
}

/// Device buffers of one batch of points.
#[derive(Debug)]
pub struct PointBuffers {
    params: UniformBuffer<Params>,
    points: GpuArray<[f32; 4]>,
    /// Output (∇F, F − I) per point (NaN sentinels until written).
    pub samples: GpuArray<[f32; 4]>,
    /// Output ∂F/∂t per point.
    pub rates: GpuArray<f32>,
    n_points: u32,
}

impl PointBuffers {
    /// Uploads `points` (`xyz`, w unused).
    pub fn upload(gpu: &Gpu, points: &[[f32; 4]]) -> Result<Self> {
        let n = points.len();
        let n_points = u32::try_from(n)
            .map_err(|_| crate::Error::limit("implicit_field: points", n, u32::MAX))?;
        Ok(PointBuffers {
            params: UniformBuffer::new(gpu, "implicit_field.params", &Params { n_points })?,
            points: GpuArray::from_slice(gpu, "implicit_field.points", points)?,
            samples: GpuArray::output(gpu, "implicit_field.samples", n, [f32::NAN; 4])?,
            rates: GpuArray::output(gpu, "implicit_field.rates", n, f32::NAN)?,
            n_points,
        })
    }

    /// Records the kernel over these points into `encoder`.
    pub fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        field: &FieldBuffers,
    ) -> Result<()> {
        let binder = gpu.kernel(Kernel::ImplicitField)?.uniform(&self.params);
        field
            .bind(binder)
            .read(&self.points)
            .write(&self.samples)
            .write(&self.rates)
            .bind()?
            .record(gpu, encoder, self.n_points, None);
        Ok(())
    }

    /// Reads the samples back.
    pub fn read(&self, gpu: &Gpu) -> Result<Vec<Sample>> {
        let samples = self.samples.read(gpu)?;
        let rates = self.rates.read(gpu)?;
        Ok(samples
            .iter()
            .zip(rates)
            .map(|(s, rate)| Sample {
                value: s[3],
                grad: [s[0], s[1], s[2]],
                rate,
            })
            .collect())
    }
}

/// Uploads, dispatches and reads back, in batches of points that fit one
/// storage binding each.
pub fn implicit_field(gpu: &Gpu, input: &FieldInput, points: &[[f32; 4]]) -> Result<Vec<Sample>> {
    let field = FieldBuffers::upload(gpu, input)?;
    let mut out = Vec::with_capacity(points.len());
    for range in chunk_ranges(points.len(), 16, gpu.max_binding_bytes()) {
        let batch = PointBuffers::upload(gpu, &points[range])?;
        let mut encoder = gpu.encoder("implicit_field");
        batch.record(gpu, &mut encoder, &field)?;
        gpu.submit_and_wait(encoder)?;
        out.extend(batch.read(gpu)?);
    }
    Ok(out)
}
