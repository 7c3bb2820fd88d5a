//! The fit energy (eq. 16–22) and its gradient: the kernel `blobby_energy`
//! sums the data terms per workgroup, the host adds the rows in f64 and
//! the shrink term.
//!
//! Rows (`prims`, `[f32; 4]`, two per primitive): (c, a), (b, 0, 0, 0);
//! `points`, two per range point: (x, 0), (n, 0). Output: one row of
//! 1 + 5N f32 per workgroup of [`BLOCK`] points: Σ e_j/M, then per primitive
//! ∂/∂(c.x, c.y, c.z, a, b) of Σ e_j/M.

pub mod cpu;
pub mod fast;
pub mod gpu;

use glam::DVec3;

use super::{Model, RangePoints, Weights};
use crate::gpu::Backend;
use crate::{Error, Result};

/// Invocations per workgroup (`WG_SIZE` in the kernel).
pub const WG_SIZE: usize = 256;
/// Points per invocation (`POINTS_PER_INVOCATION` in the kernel).
pub const POINTS_PER_INVOCATION: usize = 4;
/// Points per workgroup.
pub const BLOCK: usize = WG_SIZE * POINTS_PER_INVOCATION;

/// Most primitives (one workgroup row is 1 + 5N floats).
pub const MAX_PRIMITIVES: usize = 4096;

/// Uniform parameters of `blobby_energy`.
#[derive(Debug, Clone, Copy, PartialEq, encase::ShaderType)]
pub struct EnergyParams {
    pub n_points: u32,
    pub n_prims: u32,
    /// The iso value T.
    pub iso: f32,
    /// 1/M.
    pub inv_m: f32,
    /// α.
    pub alpha: f32,
    /// |∇V|² floor of the normal term.
    pub g_min2: f32,
}

/// The flat inputs of one evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct EnergyInput {
    pub params: EnergyParams,
    pub prims: Vec<[f32; 4]>,
    pub points: Vec<[f32; 4]>,
}

/// |∇V| below which the normal term's direction is taken as ∇V/G_MIN
/// (relative to T per unit length of the scan's bounding box).
pub const G_MIN: f64 = 1e-6;

impl EnergyInput {
    /// Flattens `model` and `points`; g_min = [`G_MIN`]·T/diagonal.
    ///
    /// Errors: more primitives than [`MAX_PRIMITIVES`] or points than
    /// `u32`, a non-positive or non-finite decay.
    pub fn new(model: &Model, points: &RangePoints, weights: Weights) -> Result<EnergyInput> {
        let n = model.blobs.len();
        if n > MAX_PRIMITIVES {
            return Err(Error::limit("blobby_energy: primitives", n, MAX_PRIMITIVES));
        }
        let m = points.len();
        let n_points =
            u32::try_from(m).map_err(|_| Error::limit("blobby_energy: points", m, u32::MAX))?;
        if let Some((k, b)) = (model.blobs.iter().enumerate()).find(|(_, b)| {
            !(b.a.is_finite() && b.a > 0.0 && b.b.is_finite() && b.centre.is_finite())
        }) {
            return Err(Error::param(
                "blobby model",
                format!("primitive {k}: centre {}, a {}, b {}", b.centre, b.a, b.b),
                "finite, with a > 0",
            ));
        }
        let diagonal = points.diagonal().max(f64::MIN_POSITIVE);
        let g_min = G_MIN * model.iso.abs() / diagonal;
        let row = |v: DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
        Ok(EnergyInput {
            params: EnergyParams {
                n_points,
                n_prims: n as u32,
                iso: model.iso as f32,
                inv_m: (1.0 / m as f64) as f32,
                alpha: weights.alpha as f32,
                g_min2: (g_min * g_min) as f32,
            },
            prims: (model.blobs.iter())
                .flat_map(|b| [row(b.centre, b.a), [b.b as f32, 0.0, 0.0, 0.0]])
                .collect(),
            points: (points.positions.iter().zip(&points.normals))
                .flat_map(|(p, n)| [row(*p, 0.0), row(*n, 0.0)])
                .collect(),
        })
    }

    /// Number of workgroup rows.
    pub fn n_rows(&self) -> usize {
        (self.params.n_points as usize).div_ceil(BLOCK)
    }

    /// Floats per row: 1 + 5N.
    pub fn row_len(&self) -> usize {
        1 + 5 * self.params.n_prims as usize
    }
}

/// The kernel's per-workgroup rows on `backend` (the CPU runs the fast
/// path, tested equal to the mirror).
pub fn blobby_energy(input: &EnergyInput, backend: Backend<'_>) -> Result<Vec<f32>> {
    match backend {
        Backend::Cpu => Ok(fast::blobby_energy(input)),
        Backend::Gpu(g) => gpu::blobby_energy(g, input),
    }
}

/// The energy of a model and its gradient.
#[derive(Debug, Clone, PartialEq)]
pub struct Energy {
    /// E = data + β·shrink.
    pub total: f64,
    /// (E_value + α E_normal)/M.
    pub data: f64,
    /// E_shrink = (Σ a^{−3/2}|b|)², unweighted.
    pub shrink: f64,
    /// ∂E/∂(c.x, c.y, c.z, a, b) per primitive.
    pub gradient: Vec<[f64; 5]>,
}

/// E_shrink and its gradient (∂/∂a, ∂/∂b per primitive).
pub fn shrink(model: &Model) -> (f64, Vec<[f64; 2]>) {
    let s: f64 = (model.blobs.iter())
        .map(|b| b.a.powf(-1.5) * b.b.abs())
        .sum();
    let grad = (model.blobs.iter())
        .map(|b| {
            [
                2.0 * s * -1.5 * b.a.powf(-2.5) * b.b.abs(),
                2.0 * s * b.a.powf(-1.5) * b.b.signum(),
            ]
        })
        .collect();
    (s * s, grad)
}

/// E and ∇E of `model` against `points` (eq. 22), the data terms on
/// `backend`.
pub fn energy(
    model: &Model,
    points: &RangePoints,
    weights: Weights,
    backend: Backend<'_>,
) -> Result<Energy> {
    let input = EnergyInput::new(model, points, weights)?;
    let rows = blobby_energy(&input, backend)?;
    let len = input.row_len();
    let mut sums = vec![0.0f64; len];
    for row in rows.chunks_exact(len) {
        for (s, &v) in sums.iter_mut().zip(row) {
            *s += f64::from(v);
        }
    }
    let (shrink, ds) = shrink(model);
    let gradient = (0..model.blobs.len())
        .map(|k| {
            let g = &sums[1 + 5 * k..6 + 5 * k];
            [
                g[0],
                g[1],
                g[2],
                g[3] + weights.beta * ds[k][0],
                g[4] + weights.beta * ds[k][1],
            ]
        })
        .collect();
    Ok(Energy {
        total: sums[0] + weights.beta * shrink,
        data: sums[0],
        shrink,
        gradient,
    })
}
