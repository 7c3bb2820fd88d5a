//! Min/max reductions: the bounding box of positions (kernel `bounds_reduce`)
//! and the intensity range of volume samples (kernel `range_reduce`).
//!
//! Both reduce in passes: each pass turns #N items into ceil(#N / 4096)
//! (min, max) pairs (per-invocation folds of 16 items, then a tree in
//! workgroup memory), repeated until one pair is left; no atomics. Floats are compared through order keys
//! ([`cpu::order_key`], IEEE 754 totalOrder), so min/max are exact integer
//! operations whose result does not depend on the tree shape, the chunking
//! or the backend: parity is bit-for-bit. −0 sorts below +0.
//!
//! NaN policy: inputs must not contain NaN. totalOrder puts a NaN beyond
//! ±inf, so a NaN anywhere in the input shows up in the result, and the
//! entries here return [`Error::InvalidParameter`] for it (no extra pass over
//! the data). Infinities are ordinary values. Empty input gives `Ok(None)`.

pub mod cpu;
pub mod gpu;

use glam::Vec3;

use crate::foundation::Aabb;
use crate::gpu::Backend;
use crate::{Error, Result, TriMesh, Volume};

/// Smallest and largest sample of a volume or array.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SampleRange {
    pub min: f32,
    pub max: f32,
}

/// Bounding box of `positions` (#N points as `[x, y, z, w]`, w ignored) on
/// `backend`; `None` when empty. Exact (no rounding).
pub fn bounds_reduce(positions: &[[f32; 4]], backend: Backend<'_>) -> Result<Option<Aabb>> {
    let pair = match backend {
        Backend::Cpu => cpu::bounds_reduce(positions),
        Backend::Gpu(g) => gpu::bounds_reduce(g, positions)?,
    };
    pair.map(|(lo, hi)| {
        let bounds = Aabb {
            min: Vec3::new(lo[0], lo[1], lo[2]),
            max: Vec3::new(hi[0], hi[1], hi[2]),
        };
        if bounds.min.is_nan() || bounds.max.is_nan() {
            return Err(Error::param(
                "bounds_reduce: positions",
                "NaN",
                "must not contain NaN",
            ));
        }
        Ok(bounds)
    })
    .transpose()
}

/// Bounding box of the vertices of `mesh` (unused vertices included, like
/// [`TriMesh::bounds`]); `None` for a mesh without vertices.
pub fn mesh_bounds(mesh: &TriMesh, backend: Backend<'_>) -> Result<Option<Aabb>> {
    let positions: Vec<[f32; 4]> = mesh
        .positions
        .iter()
        .map(|p| [p.x, p.y, p.z, 0.0])
        .collect();
    bounds_reduce(&positions, backend)
}

/// Range of `samples` on `backend`; `None` when empty. On the GPU, arrays
/// larger than one storage binding are reduced chunk by chunk
/// ([`crate::gpu::chunk_ranges`]) and the chunk results combined.
pub fn range_reduce(samples: &[f32], backend: Backend<'_>) -> Result<Option<SampleRange>> {
    let pair = match backend {
        Backend::Cpu => cpu::range_reduce(samples),
        Backend::Gpu(g) => gpu::range_reduce(g, samples)?,
    };
    pair.map(|(min, max)| {
        if min.is_nan() || max.is_nan() {
            return Err(Error::param(
                "range_reduce: samples",
                "NaN",
                "must not contain NaN",
            ));
        }
        Ok(SampleRange { min, max })
    })
    .transpose()
}

/// Samples per f32 chunk that [`volume_range`] converts for the GPU (64 MiB).
pub const RANGE_CHUNK: usize = 1 << 24;

/// Intensity range of `volume`, over its samples converted to f32. Exact for
/// element types with [`crate::volume::ScalarType::exact_in_f32`]; for
/// `u32`/`i32`/`f64` it is the true range rounded to nearest f32 (rounding
/// is monotonic, so it commutes with min/max). No copy of the volume is
/// made: the CPU folds the samples in their own type, the GPU gets f32
/// chunks of [`RANGE_CHUNK`] samples.
pub fn volume_range(volume: &Volume, backend: Backend<'_>) -> Result<Option<SampleRange>> {
    use crate::volume::VolumeData as D;
    let g = match backend {
        Backend::Cpu => {
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            macro_rules! fold {
                ($v:expr) => {
                    for &x in $v {
                        let x = x as f64;
                        if x.is_nan() {
                            return Err(Error::param(
                                "range_reduce: samples",
                                "NaN",
                                "must not contain NaN",
                            ));
                        }
                        lo = lo.min(x);
                        hi = hi.max(x);
                    }
                };
            }
            match &volume.data {
                D::U8(v) => fold!(v),
                D::I8(v) => fold!(v),
                D::U16(v) => fold!(v),
                D::I16(v) => fold!(v),
                D::U32(v) => fold!(v),
                D::I32(v) => fold!(v),
                D::F32(v) => fold!(v),
                D::F64(v) => fold!(v),
            }
            return Ok((lo <= hi).then_some(SampleRange {
                min: lo as f32,
                max: hi as f32,
            }));
        }
        Backend::Gpu(g) => g,
    };
    let mut out: Option<SampleRange> = None;
    let n = volume.data.len();
    for start in (0..n).step_by(RANGE_CHUNK) {
        let end = (start + RANGE_CHUNK).min(n);
        let chunk: Vec<f32> = (start..end)
            .map(|i| volume.data.get_f64(i) as f32)
            .collect();
        if let Some(r) = range_reduce(&chunk, Backend::Gpu(g))? {
            out = Some(match out {
                None => r,
                Some(o) => SampleRange {
                    min: o.min.min(r.min),
                    max: o.max.max(r.max),
                },
            });
        }
    }
    Ok(out)
}
