//! Measures and exports of a built hull: exact and world volume and area,
//! the report summary, the cell list of App. C and a triangle mesh.

use super::{CellList, ConvexHull, HullSummary};
use crate::foundation::exact::{cross, det};
use crate::mesh::TriMesh;
use crate::voxel::Frame;

impl ConvexHull {
    /// 6·volume in combinatorial units (one voxel = 8 units), exact; kept
    /// incrementally during the construction (ch. 5).
    pub fn volume6(&self) -> i128 {
        self.vol6
    }

    /// 6·volume recomputed from the faces (fan tetrahedra from the origin).
    pub fn volume6_from_faces(&self) -> i128 {
        self.faces
            .iter()
            .map(|f| {
                let v = |k: usize| self.vertices[f.vertices[k] as usize];
                (1..f.vertices.len() - 1)
                    .map(|k| det(v(0), v(k), v(k + 1)))
                    .sum::<i128>()
            })
            .sum()
    }

    /// Volume in voxels (edge length 1 voxel).
    pub fn volume_voxels(&self) -> f64 {
        self.vol6 as f64 / 48.0
    }

    /// Surface area in voxel faces (edge length 1 voxel), eq. 7.1–7.3: per
    /// face half the length of `Σ vᵢ × vᵢ₊₁`.
    pub fn area_voxels(&self) -> f64 {
        self.faces
            .iter()
            .map(|f| {
                let k = f.vertices.len();
                let mut s = [0i128; 3];
                for i in 0..k {
                    let c = cross(
                        self.vertices[f.vertices[i] as usize],
                        self.vertices[f.vertices[(i + 1) % k] as usize],
                    );
                    for a in 0..3 {
                        s[a] += i128::from(c[a]);
                    }
                }
                let n = s.map(|c| c as f64);
                (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() / 2.0
            })
            .sum::<f64>()
            / 4.0
    }

    /// Surface area in world units: the faces mapped through `frame`
    /// (anisotropic spacing changes areas per face orientation).
    pub fn area_world(&self, frame: &Frame) -> f64 {
        let w: Vec<glam::DVec3> = self
            .vertices
            .iter()
            .map(|&v| glam::DVec3::from(frame.world(v)))
            .collect();
        self.faces
            .iter()
            .map(|f| {
                let p = |k: usize| w[f.vertices[k] as usize];
                (1..f.vertices.len() - 1)
                    .map(|k| (p(k) - p(0)).cross(p(k + 1) - p(0)).length() / 2.0)
                    .sum::<f64>()
            })
            .sum()
    }

    /// Volume in world units (`frame.spacing` product per voxel).
    pub fn volume_world(&self, frame: &Frame) -> f64 {
        self.volume_voxels() * frame.spacing.iter().product::<f64>()
    }

    /// The figures a report needs (faces, vertices, integers per eq. 8.2 and
    /// of the compact encoding, volume, area, counters).
    pub fn summary(&self, frame: &Frame) -> HullSummary {
        let cl = self.cell_list();
        HullSummary {
            faces: self.n_faces(),
            vertices: self.n_vertices(),
            edges: self.n_edges(),
            triangles: self.n_triangles(),
            integers_eq_8_2: cl.integers_eq_8_2(),
            integers_compact: cl.encode_compact().len(),
            volume_voxels: self.volume_voxels(),
            area_voxels: self.area_voxels(),
            volume_world: self.volume_world(frame),
            area_world: self.area_world(frame),
            planar: self.is_planar(),
            options: self.options,
            stats: self.stats,
        }
    }

    /// The cell list of App. C (0-, 1-, 2-cells with signed incidences).
    pub fn cell_list(&self) -> CellList {
        CellList::from_faces(
            &self.vertices,
            self.faces.iter().map(|f| (f.vertices.as_slice(), f.plane)),
        )
    }

    /// Fan-triangulated faces as a mesh in world coordinates (`frame`),
    /// outward winding; one mesh vertex per hull vertex.
    pub fn to_mesh(&self, frame: &Frame) -> crate::Result<TriMesh> {
        let positions = self.vertices.iter().map(|&v| frame.world_f32(v)).collect();
        let mut triangles = Vec::with_capacity(self.n_triangles());
        for f in &self.faces {
            for k in 1..f.vertices.len() - 1 {
                triangles.push([f.vertices[0], f.vertices[k], f.vertices[k + 1]]);
            }
        }
        // A reflecting frame turns the index-space winding inside out.
        if frame.reflects() {
            triangles.iter_mut().for_each(|t| t.swap(1, 2));
        }
        TriMesh::new(positions, triangles)
    }
}
