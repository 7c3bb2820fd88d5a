//! GPU pass for `kernels/vertex_normals.wgsl`.

use super::NormalsInput;
use crate::Result;
use crate::gpu::{Gpu, GpuArray, Kernel, UniformBuffer};

/// Uniform parameters of `vertex_normals`.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct Params {
    pub n_vertices: u32,
}

/// Device buffers of one `vertex_normals` problem, kept for resident reruns.
#[derive(Debug)]
pub struct NormalsBuffers {
    params: UniformBuffer<Params>,
    positions: GpuArray<[f32; 4]>,
    triangles: GpuArray<u32>,
    offsets: GpuArray<u32>,
    tri_ids: GpuArray<u32>,
    /// #V output normals (NaN sentinels until the kernel writes them, on a
    /// device with sentinels on).
    pub normals: GpuArray<[f32; 4]>,
    n_vertices: u32,
}

impl NormalsBuffers {
    /// Uploads `input`; the output is a kernel output ([`GpuArray::output`]).
    pub fn upload(gpu: &Gpu, input: &NormalsInput) -> Result<Self> {
        let n_vertices = u32::try_from(input.positions.len()).map_err(|_| {
            crate::Error::limit("vertex_normals: vertices", input.positions.len(), u32::MAX)
        })?;
        Ok(NormalsBuffers {
            params: UniformBuffer::new(gpu, "vertex_normals.params", &Params { n_vertices })?,
            positions: GpuArray::from_slice(gpu, "vertex_normals.positions", &input.positions)?,
            triangles: GpuArray::from_slice(gpu, "vertex_normals.triangles", &input.triangles)?,
            offsets: GpuArray::from_slice(gpu, "vertex_normals.offsets", &input.adjacency.offsets)?,
            tri_ids: GpuArray::from_slice(gpu, "vertex_normals.tri_ids", &input.adjacency.targets)?,
            normals: GpuArray::output(
                gpu,
                "vertex_normals.normals",
                input.positions.len(),
                [f32::NAN; 4],
            )?,
            n_vertices,
        })
    }

    /// Records the kernel into `encoder` (no submission).
    pub fn record(&self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        gpu.kernel(Kernel::VertexNormals)?
            .uniform(&self.params)
            .read(&self.positions)
            .read(&self.triangles)
            .read(&self.offsets)
            .read(&self.tri_ids)
            .write(&self.normals)
            .bind()?
            .record(gpu, encoder, self.n_vertices, None);
        Ok(())
    }
}

/// Uploads, dispatches once and reads the normals back.
pub fn vertex_normals(gpu: &Gpu, input: &NormalsInput) -> Result<Vec<[f32; 4]>> {
    let buffers = NormalsBuffers::upload(gpu, input)?;
    let mut encoder = gpu.encoder("vertex_normals");
    buffers.record(gpu, &mut encoder)?;
    gpu.submit_and_wait(encoder)?;
    buffers.normals.read(gpu)
}
