//! Surface points and normals from basis rows (kernel `dms_surface`; seed
//! eq. 2.11): `F(u) = Σ w_k · x_k`, `F_u = Σ ∂w_k/∂u · x_k`, `F_v = Σ
//! ∂w_k/∂v · x_k`, normal `= normalize(F_u × F_v)`, one invocation per
//! point, a plain gather over the point's row.
//!
//! The rows depend only on the parameter domain, so a changed control net
//! is one more gather. With point identification (seed eq. 2.13) the
//! controls are a fixed linear map of the mesh vertices, and
//! [`SurfaceInput::identify`] folds it into the rows: the gather then reads
//! the vertex positions themselves (a relaxation's skin, each frame).
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
}

/// Surface positions and unit normals (`[x, y, z, 0]` each).
#[derive(Debug, Clone, PartialEq)]
pub struct SurfacePoints {
    pub positions: Vec<[f32; 4]>,
    pub normals: Vec<[f32; 4]>,
}

impl SurfaceInput {
    /// Rows over the `n_controls` shared controls, as the basis gave them.
    pub fn over_controls(basis: &BasisRows, n_controls: usize) -> SurfaceInput {
        SurfaceInput {
            rows: basis.rows.clone(),
            weights: basis.weights.clone(),
            n_sources: n_controls,
        }
    }

    /// Rows over the vertices under point identification (eq. 2.13):
    /// control `v < n_vertices` is vertex `v`, edge control `n_vertices +
    /// e` is the midpoint of `edges[e]`. Weights are summed per vertex in
    /// row order, so the result is deterministic.
    pub fn identify(basis: &BasisRows, n_vertices: usize, edges: &[[u32; 2]]) -> SurfaceInput {
        let mut lists: Vec<Vec<u32>> = Vec::with_capacity(basis.rows.n_rows());
        let mut weights: Vec<[f32; 4]> = Vec::with_capacity(basis.weights.len());
        let mut terms: Vec<(u32, [f32; 4])> = Vec::new();
        for p in 0..basis.rows.n_rows() {
            terms.clear();
            let (lo, hi) = (
                basis.rows.offsets[p] as usize,
                basis.rows.offsets[p + 1] as usize,
            );
            for k in lo..hi {
                let c = basis.rows.targets[k] as usize;
                let w = basis.weights[k];
                if c < n_vertices {
                    terms.push((c as u32, w));
                } else {
                    let half = w.map(|x| 0.5 * x);
                    for v in edges[c - n_vertices] {
                        terms.push((v, half));
                    }
                }
            }
            // Stable: equal vertices keep row order for the sum.
            terms.sort_by_key(|t| t.0);
            let mut row: Vec<u32> = Vec::new();
            for &(v, w) in &terms {
                if row.last() == Some(&v) {
                    let s = weights.last_mut().expect("a row entry exists");
                    for i in 0..4 {
                        s[i] += w[i];
                    }
                } else {
                    row.push(v);
                    weights.push(w);
                }
            }
            lists.push(row);
        }
        SurfaceInput {
            rows: Csr::from_rows(&lists),
            weights,
            n_sources: n_vertices,
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
