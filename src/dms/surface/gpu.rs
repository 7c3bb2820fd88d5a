//! GPU pass for `kernels/dms_surface.wgsl`.

use super::{SurfaceInput, SurfacePoints};
use crate::Result;
use crate::gpu::{Gpu, GpuArray, Kernel, UniformBuffer, row_chunks};

/// Uniform parameters of `dms_surface`.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct Params {
    pub n_points: u32,
}

/// Device buffers of the rows; the sources are bound per recording, so a
/// buffer another pass keeps up to date (a relaxation's positions) is
/// gathered from without a read-back.
#[derive(Debug)]
pub struct SurfaceBuffers {
    params: UniformBuffer<Params>,
    row_off: GpuArray<u32>,
    row_src: GpuArray<u32>,
    weights: GpuArray<[f32; 4]>,
    /// Per-point base (zeros, cleared on the device, when the input has none).
    base: GpuArray<[f32; 4]>,
    /// Output positions (NaN sentinels until written, on a device with
    /// sentinels on).
    pub positions: GpuArray<[f32; 4]>,
    /// Output unit normals.
    pub normals: GpuArray<[f32; 4]>,
    n_points: u32,
    n_sources: usize,
}

impl SurfaceBuffers {
    /// Uploads the rows of `input`.
    pub fn upload(gpu: &Gpu, input: &SurfaceInput) -> Result<Self> {
        let n = input.rows.n_rows();
        let n_points = u32::try_from(n)
            .map_err(|_| crate::Error::limit("dms_surface: points", n, u32::MAX))?;
        Ok(SurfaceBuffers {
            params: UniformBuffer::new(gpu, "dms_surface.params", &Params { n_points })?,
            row_off: GpuArray::from_slice(gpu, "dms_surface.row_off", &input.rows.offsets)?,
            row_src: GpuArray::from_slice(gpu, "dms_surface.row_src", &input.rows.targets)?,
            weights: GpuArray::from_slice(gpu, "dms_surface.weights", &input.weights)?,
            base: match &input.base {
                Some(b) => GpuArray::from_slice(gpu, "dms_surface.base", b)?,
                None => GpuArray::zeroed(gpu, "dms_surface.base", n)?,
            },
            positions: GpuArray::output(gpu, "dms_surface.positions", n, [f32::NAN; 4])?,
            normals: GpuArray::output(gpu, "dms_surface.normals", n, [f32::NAN; 4])?,
            n_points,
            n_sources: input.n_sources,
        })
    }

    /// Records the gather from `sources` (at least the rows' source count
    /// of `[x, y, z, ·]`) into `encoder`.
    ///
    /// Errors: too few sources ([`crate::Error::Mismatch`]).
    pub fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        sources: &GpuArray<[f32; 4]>,
    ) -> Result<()> {
        if sources.len() < self.n_sources {
            return Err(crate::Error::mismatch(
                "dms_surface: sources on the device",
                self.n_sources,
                sources.len(),
            ));
        }
        gpu.kernel(Kernel::DmsSurface)?
            .uniform(&self.params)
            .read(&self.row_off)
            .read(&self.row_src)
            .read(&self.weights)
            .read(&self.base)
            .read(sources)
            .write(&self.positions)
            .write(&self.normals)
            .bind()?
            .record(gpu, encoder, self.n_points, None);
        Ok(())
    }
}

/// Uploads, gathers and reads positions and normals back, in ranges of
/// points whose rows fit one storage binding each.
pub fn dms_surface(gpu: &Gpu, input: &SurfaceInput, sources: &[[f32; 4]]) -> Result<SurfacePoints> {
    let src = GpuArray::from_slice(gpu, "dms_surface.sources", sources)?;
    let n = input.rows.n_rows();
    let mut out = SurfacePoints {
        positions: Vec::with_capacity(n),
        normals: Vec::with_capacity(n),
    };
    for range in row_chunks(&[(&input.rows.offsets, 16)], gpu.max_binding_bytes()) {
        let part;
        let input = if range.len() == n {
            input
        } else {
            part = input.part(range);
            &part
        };
        let buffers = SurfaceBuffers::upload(gpu, input)?;
        let mut encoder = gpu.encoder("dms_surface");
        buffers.record(gpu, &mut encoder, &src)?;
        gpu.submit_and_wait(encoder)?;
        out.positions.extend(buffers.positions.read(gpu)?);
        out.normals.extend(buffers.normals.read(gpu)?);
    }
    Ok(out)
}
