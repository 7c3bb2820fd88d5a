//! GPU passes for `kernels/hull_scan.wgsl` / `hull_scan_i32x2.wgsl`
//! (every voxel) and `kernels/hull_rows.wgsl` / `hull_rows_i32x2.wgsl`
//! (per-row intervals). With `SHADER_INT64` the i64 kernels run, otherwise
//! their exact emulated twins ([`Arithmetic`]). Boxes larger than one storage
//! binding ([`Gpu::max_binding_bytes`]) are processed in z slabs, one
//! dispatch and readback per slab; outputs start filled with sentinels
//! ([`SCAN_SENTINEL`], [`ROWS_SENTINEL`]) so a missed write shows.

use std::ops::Range;

use bytemuck::{Pod, Zeroable};

use super::{Classification, HalfSpace, RowSpan, RowSpans, VoxelBox, check_range, cpu::i32x2};
use crate::gpu::{Gpu, GpuArray, Kernel, UniformBuffer};
use crate::{Error, Result};

/// Invocations per workgroup of all four kernels.
pub const WG_SIZE: u32 = 256;

/// Bytes of one slab's output at most, below the binding limit, so that
/// every index stays within `u32` in the kernels.
const MAX_SLAB_BYTES: u64 = 1 << 30;

/// Each `hull_scan*` output word before the kernel writes it (byte 0xFF is
/// no side code).
pub const SCAN_SENTINEL: u32 = u32::MAX;

/// Each `hull_rows*` output span before the kernel writes it.
pub const ROWS_SENTINEL: RowSpan = [i32::MIN; 4];

/// Uniform parameters of all four kernels (`kernels/shared/hull_face.wgsl`).
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct Params {
    /// Faces uploaded.
    pub n_faces: u32,
    /// Voxels (`hull_scan*`) or rows (`hull_rows*`) in this slab.
    pub n_items: u32,
    /// Voxels per row.
    pub nx: u32,
    /// Rows per z layer.
    pub ny: u32,
    /// First local z layer of the slab.
    pub z0: u32,
    /// Voxel index of the box's first voxel, per axis.
    pub origin_x: i32,
    pub origin_y: i32,
    pub origin_z: i32,
}

/// Bindings of all four kernels, by binding number (group 0): params,
/// faces, output.
pub const BINDINGS: &[wgpu::BufferBindingType] = &[
    wgpu::BufferBindingType::Uniform,
    wgpu::BufferBindingType::Storage { read_only: true },
    wgpu::BufferBindingType::Storage { read_only: false },
];

/// One face as the kernels read it (`struct Face`, 32 bytes): normal
/// `[n_x, n_y, n_z, 0]`, offset `[low word, high word, 0, 0]` of `d`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuFace {
    pub normal: [i32; 4],
    pub offset: [u32; 4],
}

impl GpuFace {
    /// Packs `h`; the caller has run [`check_range`] (normals fit `i32`).
    fn new(h: &HalfSpace) -> Self {
        let [lo, hi] = i32x2::from_i64(h.offset);
        GpuFace {
            normal: [
                h.normal[0] as i32,
                h.normal[1] as i32,
                h.normal[2] as i32,
                0,
            ],
            offset: [lo, hi, 0, 0],
        }
    }
}

/// Which integer arithmetic the kernels use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Arithmetic {
    /// Native i64 (`SHADER_INT64`): `hull_scan`, `hull_rows`.
    Int64,
    /// Exact 64-bit pairs of u32 words: `hull_scan_i32x2`, `hull_rows_i32x2`.
    I32x2,
}

impl Arithmetic {
    /// Native i64 when the device has `SHADER_INT64`, else the fallback.
    pub fn of(gpu: &Gpu) -> Self {
        if gpu.features.int64 {
            Arithmetic::Int64
        } else {
            Arithmetic::I32x2
        }
    }

    /// The brute-force kernel.
    pub fn scan_kernel(self) -> Kernel {
        match self {
            Arithmetic::Int64 => Kernel::HullScan,
            Arithmetic::I32x2 => Kernel::HullScanI32x2,
        }
    }

    /// The per-row kernel.
    pub fn rows_kernel(self) -> Kernel {
        match self {
            Arithmetic::Int64 => Kernel::HullRows,
            Arithmetic::I32x2 => Kernel::HullRowsI32x2,
        }
    }
}

/// Consecutive z ranges whose output (`layer_bytes` per layer, plus up to
/// `pad` bytes) fits one binding.
fn slabs(gpu: &Gpu, nz: usize, layer_bytes: u64, pad: u64) -> Result<Vec<Range<usize>>> {
    let cap = gpu.max_binding_bytes().min(MAX_SLAB_BYTES);
    let layers = cap.saturating_sub(pad) / layer_bytes.max(1);
    if layers == 0 {
        return Err(Error::OutOfMemory(format!(
            "hull scan: one z layer needs {layer_bytes} bytes, more than one storage \
             binding ({cap} bytes)"
        )));
    }
    let per = usize::try_from(layers).unwrap_or(usize::MAX);
    Ok((0..nz.div_ceil(per))
        .map(|s| s * per..((s + 1) * per).min(nz))
        .collect())
}

fn to_u32(what: &str, v: usize) -> Result<u32> {
    u32::try_from(v).map_err(|_| Error::InvalidInput(format!("hull scan: {what} {v} exceeds u32")))
}

/// Uploaded faces and the box, shared by the slabs of one scan.
#[derive(Debug)]
pub struct HullScanInput {
    faces: GpuArray<GpuFace>,
    n_faces: u32,
    bbox: VoxelBox,
}

impl HullScanInput {
    /// Checks the range and uploads the faces.
    pub fn upload(gpu: &Gpu, half_spaces: &[HalfSpace], bbox: &VoxelBox) -> Result<Self> {
        check_range(half_spaces, bbox)?;
        let packed: Vec<GpuFace> = half_spaces.iter().map(GpuFace::new).collect();
        Ok(HullScanInput {
            faces: GpuArray::from_slice(gpu, "hull_scan.faces", &packed)?,
            n_faces: to_u32("faces", packed.len())?,
            bbox: *bbox,
        })
    }

    fn params(&self, n_items: usize, z0: usize) -> Result<Params> {
        let [nx, ny, _] = self.bbox.dims;
        // check_range keeps the origin within ±2^15.
        let o = self.bbox.origin.map(|v| v as i32);
        Ok(Params {
            n_faces: self.n_faces,
            n_items: to_u32("slab items", n_items)?,
            nx: to_u32("nx", nx)?,
            ny: to_u32("ny", ny)?,
            z0: to_u32("z0", z0)?,
            origin_x: o[0],
            origin_y: o[1],
            origin_z: o[2],
        })
    }

    /// Dispatches `kernel` over `n_invocations` into a fresh output of
    /// `out_len` sentinel-filled elements and reads it back.
    fn run<T: Pod>(
        &self,
        gpu: &Gpu,
        kernel: Kernel,
        params: &Params,
        n_invocations: u32,
        out_len: usize,
        sentinel: T,
    ) -> Result<Vec<T>> {
        let name = kernel.name();
        let uniform = UniformBuffer::new(gpu, &format!("{name}.params"), params)?;
        let out = GpuArray::filled(gpu, &format!("{name}.out"), out_len, sentinel)?;
        let pipeline = gpu.pipeline(kernel)?;
        let bind = gpu.bind(
            kernel,
            &pipeline,
            &[uniform.binding(), self.faces.binding(), out.binding()],
        )?;
        let mut encoder = gpu.encoder(name);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&kernel.label()),
                timestamp_writes: None,
            });
            gpu.dispatch(&mut pass, &pipeline, &bind, n_invocations, WG_SIZE);
        }
        gpu.submit_and_wait(encoder)?;
        out.read(gpu)
    }

    /// Side codes of every voxel with `arithmetic`'s brute-force kernel,
    /// slab by slab.
    pub fn scan(&self, gpu: &Gpu, arithmetic: Arithmetic) -> Result<Classification> {
        let n = self.bbox.n_voxels()?;
        let [nx, ny, nz] = self.bbox.dims;
        let mut sides = Vec::with_capacity(n);
        if n > 0 {
            for zs in slabs(gpu, nz, (nx * ny) as u64, 4)? {
                let n_voxels = nx * ny * zs.len();
                let n_words = n_voxels.div_ceil(4);
                let params = self.params(n_voxels, zs.start)?;
                let words = self.run(
                    gpu,
                    arithmetic.scan_kernel(),
                    &params,
                    to_u32("words", n_words)?,
                    n_words,
                    SCAN_SENTINEL,
                )?;
                sides.extend_from_slice(&bytemuck::cast_slice::<u32, u8>(&words)[..n_voxels]);
            }
        }
        Ok(Classification {
            bbox: self.bbox,
            sides,
        })
    }

    /// Per-row spans with `arithmetic`'s row kernel, slab by slab.
    pub fn rows(&self, gpu: &Gpu, arithmetic: Arithmetic) -> Result<RowSpans> {
        let [_, ny, nz] = self.bbox.dims;
        let mut spans = Vec::with_capacity(self.bbox.n_rows());
        if ny > 0 && nz > 0 {
            let span_bytes = std::mem::size_of::<RowSpan>() as u64;
            for zs in slabs(gpu, nz, ny as u64 * span_bytes, 0)? {
                let n_rows = ny * zs.len();
                let params = self.params(n_rows, zs.start)?;
                spans.extend(self.run(
                    gpu,
                    arithmetic.rows_kernel(),
                    &params,
                    to_u32("rows", n_rows)?,
                    n_rows,
                    ROWS_SENTINEL,
                )?);
            }
        }
        Ok(RowSpans {
            bbox: self.bbox,
            spans,
        })
    }
}

/// Brute-force classification on the GPU (arithmetic by device features).
pub fn hull_scan(gpu: &Gpu, half_spaces: &[HalfSpace], bbox: &VoxelBox) -> Result<Classification> {
    HullScanInput::upload(gpu, half_spaces, bbox)?.scan(gpu, Arithmetic::of(gpu))
}

/// Per-row spans on the GPU (arithmetic by device features).
pub fn hull_rows(gpu: &Gpu, half_spaces: &[HalfSpace], bbox: &VoxelBox) -> Result<RowSpans> {
    HullScanInput::upload(gpu, half_spaces, bbox)?.rows(gpu, Arithmetic::of(gpu))
}
