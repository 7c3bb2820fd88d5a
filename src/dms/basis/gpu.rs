//! GPU pass for `kernels/dms_basis.wgsl`.

use super::BasisInput;
use crate::Result;
use crate::gpu::{Gpu, GpuArray, Kernel, UniformBuffer, row_chunks};

/// Uniform parameters of `dms_basis`.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct Params {
    pub n_points: u32,
}

/// Device buffers of one `dms_basis` problem.
#[derive(Debug)]
pub struct BasisBuffers {
    params: UniformBuffer<Params>,
    points: GpuArray<[f32; 2]>,
    tri_knots: GpuArray<[f32; 4]>,
    cand_off: GpuArray<u32>,
    cand_tri: GpuArray<u32>,
    slot_entry: GpuArray<u32>,
    row_off: GpuArray<u32>,
    /// One weight per row entry (NaN sentinels until written, on a device
    /// with sentinels on).
    pub weights: GpuArray<[f32; 4]>,
    n_points: u32,
}

impl BasisBuffers {
    /// Uploads `input`.
    pub fn upload(gpu: &Gpu, input: &BasisInput) -> Result<Self> {
        let n_points = u32::try_from(input.points.len())
            .map_err(|_| crate::Error::limit("dms_basis: points", input.points.len(), u32::MAX))?;
        Ok(BasisBuffers {
            params: UniformBuffer::new(gpu, "dms_basis.params", &Params { n_points })?,
            points: GpuArray::from_slice(gpu, "dms_basis.points", &input.points)?,
            tri_knots: GpuArray::from_slice(gpu, "dms_basis.tri_knots", &input.tri_knots)?,
            cand_off: GpuArray::from_slice(gpu, "dms_basis.cand_off", &input.candidates.offsets)?,
            cand_tri: GpuArray::from_slice(gpu, "dms_basis.cand_tri", &input.candidates.targets)?,
            slot_entry: GpuArray::from_slice(gpu, "dms_basis.slot_entry", &input.slot_entry)?,
            row_off: GpuArray::from_slice(gpu, "dms_basis.row_off", &input.rows.offsets)?,
            weights: GpuArray::output(
                gpu,
                "dms_basis.weights",
                input.rows.targets.len(),
                [f32::NAN; 4],
            )?,
            n_points,
        })
    }

    /// Records the kernel into `encoder` (no submission).
    pub fn record(&self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        gpu.kernel(Kernel::DmsBasis)?
            .uniform(&self.params)
            .read(&self.points)
            .read(&self.tri_knots)
            .read(&self.cand_off)
            .read(&self.cand_tri)
            .read(&self.slot_entry)
            .read(&self.row_off)
            .write(&self.weights)
            .bind()?
            .record(gpu, encoder, self.n_points, None);
        Ok(())
    }
}

/// Uploads, dispatches and reads the weights back, in ranges of points
/// whose weights and slots fit one storage binding each.
pub fn dms_basis(gpu: &Gpu, input: &BasisInput) -> Result<Vec<[f32; 4]>> {
    let parts = row_chunks(
        &[(&input.rows.offsets, 16), (&input.candidates.offsets, 24)],
        gpu.max_binding_bytes(),
    );
    let mut out = Vec::with_capacity(input.rows.targets.len());
    for range in parts {
        let part;
        let input = if range.len() == input.points.len() {
            input
        } else {
            part = input.part(range);
            &part
        };
        let buffers = BasisBuffers::upload(gpu, input)?;
        let mut encoder = gpu.encoder("dms_basis");
        buffers.record(gpu, &mut encoder)?;
        gpu.submit_and_wait(encoder)?;
        out.extend(buffers.weights.read(gpu)?);
    }
    Ok(out)
}
