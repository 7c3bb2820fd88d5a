//! Area-weighted vertex normals (kernel `vertex_normals`).
//!
//! For vertex i: n_i = normalize(Σ_{t ∋ i} (b_t − a_t) × (c_t − a_t)), the
//! sum running over the incident triangles in CSR order (increasing triangle
//! id). Normals follow the winding: a mesh wound inward gets inward normals.
//! A vertex whose incident area is zero (or that no triangle uses) gets 0.

pub mod cpu;
pub mod gpu;

use crate::Result;
use crate::gpu::Backend;
use crate::mesh::{Csr, TriMesh};

/// Flat inputs of the kernel, built once on the host.
#[derive(Debug, Clone)]
pub struct NormalsInput {
    /// #V positions as `[x, y, z, 0]`.
    pub positions: Vec<[f32; 4]>,
    /// 3·#F vertex indices.
    pub triangles: Vec<u32>,
    /// Vertex → triangle CSR adjacency.
    pub adjacency: Csr,
}

impl NormalsInput {
    /// Flattens `mesh` and builds its vertex → triangle adjacency.
    pub fn new(mesh: &TriMesh) -> Self {
        NormalsInput {
            positions: mesh
                .positions
                .iter()
                .map(|p| [p.x, p.y, p.z, 0.0])
                .collect(),
            triangles: mesh.triangles.iter().flatten().copied().collect(),
            adjacency: Csr::vertex_triangles(mesh.n_vertices(), &mesh.triangles),
        }
    }
}

/// Unit vertex normals of `mesh` (`[x, y, z, 0]` per vertex) on `backend`.
pub fn vertex_normals(mesh: &TriMesh, backend: Backend<'_>) -> Result<Vec<[f32; 4]>> {
    let input = NormalsInput::new(mesh);
    match backend {
        Backend::Cpu => Ok(cpu::vertex_normals(&input)),
        Backend::Gpu(g) => gpu::vertex_normals(g, &input),
    }
}
