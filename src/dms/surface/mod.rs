//! Surface points and normals from basis rows (kernel `dms_surface`; seed
//! eq. 2.11): `F(u) = Σ w_k · x_k`, `F_u = Σ ∂w_k/∂u · x_k`, `F_v = Σ
//! ∂w_k/∂v · x_k`, normal `= normalize(F_u × F_v)`, one invocation per
//! point, a plain gather over the point's row.
//!
//! The rows depend only on the parameter domain, so a changed control net
//! is one more gather. When the controls are a fixed linear map of the mesh
//! vertices (point identification, eq. 2.13, or quasi-interpolation) that
//! map is a gather too ([`crate::dms::fit::ControlMap::gather_input`], weights `[w, 0,
//! 0, 0]`): two gathers turn a relaxation frame's vertex positions into
//! its smooth skin, on the device without a read-back.
//!
//! The parameter triangles are positively oriented, so `F_u × F_v` points
//! to the side the input triangles' winding points to: the spline's normals
//! and the output triangles follow the input's orientation.

pub mod cpu;
pub mod gpu;

use super::basis::BasisRows;
use crate::Result;
use crate::gpu::Backend;
use crate::mesh::Csr;

/// Flat inputs of `dms_surface` (without the sources, which change).
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceInput {
    /// Point → source ids (controls or vertices).
    pub rows: Csr,
    /// `[w, ∂w/∂u, ∂w/∂v, 0]` per row entry.
    pub weights: Vec<[f32; 4]>,
    /// Number of sources the rows index.
    pub n_sources: usize,
    /// Per point, added to `F` (`None`: zero). The controls of a rest state
    /// when the sources are displacements from it.
    pub base: Option<Vec<[f32; 4]>>,
}

/// Surface positions and unit normals (`[x, y, z, 0]` each).
#[derive(Debug, Clone, PartialEq)]
pub struct SurfacePoints {
    pub positions: Vec<[f32; 4]>,
    pub normals: Vec<[f32; 4]>,
}

impl SurfaceInput {
    /// Rows over the `n_controls` shared controls, as the basis gave them,
    /// without the entries whose weight and derivatives are all exactly
    /// zero (a candidate triangle whose B-splines vanish at the point adds
    /// nothing; dropping them leaves every sum the same, up to the sign of
    /// a zero, for finite controls, and shortens the gather).
    pub fn over_controls(basis: &BasisRows, n_controls: usize) -> SurfaceInput {
        let mut offsets = Vec::with_capacity(basis.rows.offsets.len());
        let mut targets = Vec::with_capacity(basis.rows.targets.len());
        let mut weights = Vec::with_capacity(basis.weights.len());
        offsets.push(0u32);
        for p in 0..basis.rows.n_rows() {
            for k in basis.rows.offsets[p] as usize..basis.rows.offsets[p + 1] as usize {
                let w = basis.weights[k];
                if w[..3] != [0.0; 3] {
                    targets.push(basis.rows.targets[k]);
                    weights.push(w);
                }
            }
            offsets.push(targets.len() as u32);
        }
        SurfaceInput {
            rows: Csr { offsets, targets },
            weights,
            n_sources: n_controls,
            base: None,
        }
    }
}

impl SurfaceInput {
    /// The rows of the points `range` alone (offsets rebased).
    pub fn part(&self, range: std::ops::Range<usize>) -> SurfaceInput {
        let (r0, r1) = (self.rows.offsets[range.start], self.rows.offsets[range.end]);
        SurfaceInput {
            rows: self.rows.slice(range.clone()),
            weights: self.weights[r0 as usize..r1 as usize].to_vec(),
            n_sources: self.n_sources,
            base: self.base.as_ref().map(|b| b[range].to_vec()),
        }
    }
}

/// The surface of `sources` (one `[x, y, z, ·]` per source) on `backend`.
///
/// Errors: a source count other than the rows' ([`crate::Error::Mismatch`]).
pub fn dms_surface(
    input: &SurfaceInput,
    sources: &[[f32; 4]],
    backend: Backend<'_>,
) -> Result<SurfacePoints> {
    if sources.len() != input.n_sources {
        return Err(crate::Error::mismatch(
            "dms_surface: sources",
            input.n_sources,
            sources.len(),
        ));
    }
    match backend {
        Backend::Cpu => Ok(cpu::dms_surface(input, sources)),
        Backend::Gpu(g) => gpu::dms_surface(g, input, sources),
    }
}
