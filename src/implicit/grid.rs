//! The field on a lattice: dense samples for the engine's marching cubes,
//! which gives start meshes (coarse) and reference surfaces (dense).

use glam::DVec3;

use super::field::{FieldInput, implicit_field, reach};
use super::{Blend, Pose};
use crate::gpu::Backend;
use crate::mc::{IsoSpec, McOptions, Surface};
use crate::volume::VolumeData;
use crate::{Error, Result, Volume};

/// Most lattice samples of one grid.
pub const MAX_SAMPLES: usize = 1 << 28;

/// Samples evaluated per batch (bounds the point buffer).
const BATCH: usize = 1 << 20;

/// A box holding the surface F = I of `pose`, `None` when F < I everywhere.
///
/// With n primitives of positive w·strength, each contributes below I/n
/// outside its reach (negative ones only lower F), so F < I outside the
/// union of the reach boxes (F ≤ I on their faces).
pub fn surface_bounds(pose: &Pose) -> Option<(DVec3, DVec3)> {
    let positive: Vec<usize> = (0..pose.primitives.len())
        .filter(|&i| {
            let p = &pose.primitives[i];
            p.weight * p.influence.strength() > 0.0
        })
        .collect();
    let floor = match pose.blend {
        Blend::Max => pose.iso,
        _ => pose.iso / positive.len().max(1) as f64,
    };
    let mut lo = DVec3::INFINITY;
    let mut hi = DVec3::NEG_INFINITY;
    for &i in &positive {
        let p = &pose.primitives[i];
        if let Some(r2) = reach(&p.influence, p.weight, floor) {
            let r = DVec3::splat(r2.sqrt());
            for q in p.skeleton.points() {
                lo = lo.min(q - r);
                hi = hi.max(q + r);
            }
        }
    }
    (lo.x <= hi.x).then_some((lo, hi))
}

/// The lattice of spacing `h` over `pose`'s surface bounds, one sample
/// beyond them on every side: (corner, dims).
///
/// Errors: an empty surface ([`Error::Empty`]), a non-positive spacing or
/// more than [`MAX_SAMPLES`] samples.
pub fn lattice(pose: &Pose, h: f64) -> Result<(DVec3, [usize; 3])> {
    if !(h.is_finite() && h > 0.0) {
        return Err(Error::param("spacing", h, "must be positive and finite"));
    }
    let (lo, hi) =
        surface_bounds(pose).ok_or_else(|| Error::empty("implicit surface (F < I everywhere)"))?;
    let lo = lo - DVec3::splat(h);
    let n = ((hi - lo) / h).ceil() + DVec3::splat(2.0);
    let total = n.element_product();
    if total > MAX_SAMPLES as f64 {
        return Err(Error::limit(
            "implicit lattice samples",
            total as u64,
            MAX_SAMPLES,
        ));
    }
    Ok((lo, [n.x as usize, n.y as usize, n.z as usize]))
}

/// F − I on the lattice `(corner, dims)` of spacing `h`, as a volume.
pub fn sample(
    input: &FieldInput,
    corner: DVec3,
    dims: [usize; 3],
    h: f64,
    backend: Backend<'_>,
) -> Result<Volume> {
    let n = dims[0] * dims[1] * dims[2];
    let mut values = Vec::with_capacity(n);
    let mut points = Vec::with_capacity(BATCH.min(n));
    let mut start = 0;
    while start < n {
        let end = (start + BATCH).min(n);
        points.clear();
        points.extend((start..end).map(|i| {
            let (x, r) = (i % dims[0], i / dims[0]);
            let (y, z) = (r % dims[1], r / dims[1]);
            let p = corner + h * DVec3::new(x as f64, y as f64, z as f64);
            [p.x as f32, p.y as f32, p.z as f32, 0.0]
        }));
        values.extend(
            implicit_field(input, &points, backend)?
                .iter()
                .map(|s| s.value),
        );
        start = end;
    }
    Volume::new(dims, [h; 3], corner.to_array(), VolumeData::F32(values))
}

/// The marching-cubes surface of `pose` at lattice spacing `h` (welded,
/// closed, wound outward), sampled and extracted on `backend`.
pub fn marching_cubes(pose: &Pose, h: f64, backend: Backend<'_>) -> Result<Surface> {
    let input = FieldInput::new(pose)?;
    let (corner, dims) = lattice(pose, h)?;
    let volume = sample(&input, corner, dims, h, backend)?;
    crate::mc::marching_cubes(
        &volume,
        IsoSpec::Level(0.0),
        &McOptions {
            close_border: true,
            ..McOptions::default()
        },
        backend,
    )
}
