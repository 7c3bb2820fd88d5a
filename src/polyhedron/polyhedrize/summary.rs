//! What a built [`Polyhedron`] reports: its figures ([`PolyhedronSummary`])
//! and its polyhedral shells as one triangle mesh (this phase's
//! `impl Polyhedron`: `summary`, `to_mesh`).

use crate::foundation::exact::sub;
use crate::mesh::{ScalarField, TriMesh};

use super::{Polyhedron, Role, ShellGeometry};

/// Figures of a polyhedron for reports.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PolyhedronSummary {
    /// All shells.
    pub shells: usize,
    /// Shells by dimension: points, segments, polygons, polyhedra.
    pub shells_by_dimension: [usize; 4],
    /// Faces of the polyhedral shells (2-cells).
    pub faces: usize,
    /// Vertices of the polyhedral shells (0-cells).
    pub vertices: usize,
    /// Edges of the polyhedral shells (1-cells).
    pub edges: usize,
    /// Storage per eq. 8.2 summed over shells (`3·N_V + 5·N_F` per
    /// polytope; 3 per point, 6 per segment).
    pub integers_eq_8_2: usize,
    /// Length of the compact encoding ([`Polyhedron::encode`]).
    pub integers_compact: usize,
    /// Σ role sign × shell volume, in voxels: the region's volume when
    /// sibling shells have disjoint interiors (each child lies in its parent
    /// by construction).
    pub signed_volume_voxels: f64,
    /// Whether every pair of sibling polyhedra was proven interior-disjoint
    /// (a separating plane: a face plane of one, or a plane spanned by an
    /// edge direction of each — the separating-axis theorem, complete for
    /// convex polyhedra), so that [`PolyhedronSummary::signed_volume_voxels`] is exact.
    pub volume_exact: bool,
    /// Σ shell areas in voxel faces (a child sharing face area with its
    /// parent counts it twice).
    pub shell_area_voxels: f64,
    /// Degree of non-convexity (Def. NK): the depth of the deepest shell.
    pub g_nc: u32,
    /// Edges of the flat shells (polygons; the 2-D analogue of ch. 9).
    pub polygon_edges: usize,
    /// Σ perimeters of the flat shells, in voxel edges (ch. 9.3).
    pub polygon_perimeter_voxels: f64,
}

impl Polyhedron {
    /// Report figures.
    pub fn summary(&self) -> PolyhedronSummary {
        let mut by_dim = [0usize; 4];
        let (mut faces, mut vertices, mut edges, mut ints) = (0, 0, 0, 0);
        let (mut vol6, mut area) = (0i128, 0.0);
        let (mut polygon_edges, mut perimeter) = (0usize, 0.0f64);
        for s in &self.shells {
            by_dim[usize::from(s.geometry.dimension())] += 1;
            if let Some(h) = s.geometry.polytope().filter(|h| h.is_planar()) {
                let f = &h.faces()[0].vertices;
                polygon_edges += f.len();
                perimeter += (0..f.len())
                    .map(|k| {
                        let (a, b) = (
                            h.vertices()[f[k] as usize],
                            h.vertices()[f[(k + 1) % f.len()] as usize],
                        );
                        let d = sub(b, a).map(|c| c as f64);
                        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() / 2.0
                    })
                    .sum::<f64>();
            }
            match &s.geometry {
                ShellGeometry::Point(_) => ints += 3,
                ShellGeometry::Segment(..) => ints += 6,
                ShellGeometry::Polytope(h) => {
                    faces += h.n_faces();
                    vertices += h.n_vertices();
                    edges += h.n_edges();
                    ints += 3 * h.n_vertices() + 5 * h.n_faces();
                    vol6 += s.role.sign() * h.volume6();
                    area += h.area_voxels();
                }
            }
        }
        PolyhedronSummary {
            shells: self.shells.len(),
            shells_by_dimension: by_dim,
            faces,
            vertices,
            edges,
            integers_eq_8_2: ints,
            integers_compact: self.encode().len(),
            signed_volume_voxels: vol6 as f64 / 48.0,
            shell_area_voxels: area,
            g_nc: self.shells.iter().map(|s| s.depth).max().unwrap_or(0),
            polygon_edges,
            polygon_perimeter_voxels: perimeter,
            volume_exact: self.siblings_disjoint(),
        }
    }

    /// The polyhedral shells as one triangle mesh in world units: fan
    /// triangles, object shells outward, background shells reversed; scalar
    /// `depth` per vertex. Flat and lower-dimensional shells are left out.
    pub fn to_mesh(&self) -> crate::Result<TriMesh> {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        let mut depth = Vec::new();
        for s in &self.shells {
            let Some(h) = s.geometry.polytope().filter(|h| !h.is_planar()) else {
                continue;
            };
            let mut m = h.to_mesh(&self.frame)?;
            if s.role == Role::Background {
                m.flip_winding();
            }
            let base = positions.len() as u32;
            positions.extend(m.positions);
            depth.extend(std::iter::repeat_n(s.depth as f32, h.n_vertices()));
            triangles.extend(m.triangles.iter().map(|t| t.map(|v| v + base)));
        }
        let mut mesh = TriMesh::new(positions, triangles)?;
        mesh.scalars.push(ScalarField {
            name: "depth".into(),
            values: depth,
        });
        Ok(mesh)
    }
}
