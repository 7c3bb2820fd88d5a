//! Host-side triangle meshes and their topology.
//!
//! A [`TriMesh`] is an indexed triangle list: `positions` (#V points, units of
//! the input file) and `triangles` (#F index triples, counter-clockwise =
//! right-hand-rule normal, whatever way the file winds them). Per-vertex
//! scalar fields (e.g. displacement) ride along by name.

pub mod collapse;
pub mod csr;
pub mod distance;
pub mod icosphere;
pub mod inside;
pub mod intersect;
pub mod orient;
pub mod topology;

pub use collapse::{Collapsed, collapse_short_edges};
pub use csr::Csr;
pub use icosphere::{icosphere_sag, unit_icosphere};
pub use inside::{Side, point_side};
pub use intersect::{SelfIntersections, intersections_of_first, self_intersections};
pub use orient::{orient_consistently, orient_outward};
pub use topology::{Component, Orientation, Topology};

use glam::Vec3;

use crate::foundation::MeshView;

/// A named per-vertex scalar field: `values.len() == positions.len()`.
#[derive(Debug, Clone, PartialEq)]
pub struct ScalarField {
    pub name: String,
    pub values: Vec<f32>,
}

/// Indexed triangle mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    /// #V vertex positions.
    pub positions: Vec<Vec3>,
    /// #F triangles as vertex-index triples into `positions`.
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex scalar fields, each with #V values.
    pub scalars: Vec<ScalarField>,
}

impl TriMesh {
    /// A mesh from positions and triangles, with every index checked.
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> crate::Result<Self> {
        let mesh = TriMesh {
            positions,
            triangles,
            scalars: Vec::new(),
        };
        mesh.validate()?;
        Ok(mesh)
    }

    /// Checks indices are in range, positions finite and scalar lengths match.
    pub fn validate(&self) -> crate::Result<()> {
        let n = self.positions.len();
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(crate::Error::data(
                "mesh",
                "vertex",
                i,
                format!("coordinate {} is not finite", self.positions[i]),
            ));
        }
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&v) = tri.iter().find(|&&v| v as usize >= n) {
                return Err(crate::Error::data(
                    "mesh",
                    "triangle",
                    t,
                    format!("references vertex {v} but the mesh has {n} vertices"),
                ));
            }
        }
        for s in &self.scalars {
            if s.values.len() != n {
                return Err(crate::Error::mismatch(
                    format!("values of scalar field `{}` (one per vertex)", s.name),
                    n,
                    s.values.len(),
                ));
            }
        }
        Ok(())
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn n_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The scalar field called `name`, if any.
    pub fn scalar(&self, name: &str) -> Option<&ScalarField> {
        self.scalars.iter().find(|s| s.name == name)
    }

    /// Axis-aligned bounding box `(min, max)` of all vertices; `None` when empty.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
        )
    }

    /// The positions and triangles as the spatial index reads them.
    pub fn view(&self) -> MeshView<'_> {
        MeshView {
            positions: &self.positions,
            triangles: &self.triangles,
        }
    }

    /// Signed enclosed volume in f64: Σ (a − r)·((b − r) × (c − r))/6 over
    /// the triangles, about the bounding box's centre `r` (which keeps the
    /// terms small); positive for a closed surface wound outward.
    pub fn signed_volume(&self) -> f64 {
        let Some((lo, hi)) = self.bounds() else {
            return 0.0;
        };
        let r = ((lo + hi) * 0.5).as_dvec3();
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize].as_dvec3() - r);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Reverses the winding of every triangle (flips all normals).
    pub fn flip_winding(&mut self) {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
    }
}

/// Splits `mesh` by a per-triangle label (`labels.len() == #F`, labels
/// `0..n`): mesh `k` holds the triangles labelled `k` with its vertices
/// renumbered in first-use order; scalar fields follow their vertices.
pub fn split_by_label(mesh: &TriMesh, labels: &[u32]) -> Vec<TriMesh> {
    let n = labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
    let by_label = Csr::from_pairs(n, labels.iter().enumerate().map(|(t, &l)| (l, t as u32)));
    // `stamp[v] == k + 1`: vertex v already has id `local[v]` in part k.
    let mut stamp = vec![0u32; mesh.n_vertices()];
    let mut local = vec![0u32; mesh.n_vertices()];
    (0..n)
        .map(|k| {
            let mut part = TriMesh {
                scalars: mesh
                    .scalars
                    .iter()
                    .map(|s| ScalarField {
                        name: s.name.clone(),
                        values: Vec::new(),
                    })
                    .collect(),
                ..TriMesh::default()
            };
            for &t in by_label.row(k) {
                let tri = mesh.triangles[t as usize].map(|v| {
                    let v = v as usize;
                    if stamp[v] != k as u32 + 1 {
                        stamp[v] = k as u32 + 1;
                        local[v] = part.positions.len() as u32;
                        part.positions.push(mesh.positions[v]);
                        for (dst, src) in part.scalars.iter_mut().zip(&mesh.scalars) {
                            dst.values.push(src.values[v]);
                        }
                    }
                    local[v]
                });
                part.triangles.push(tri);
            }
            part
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_by_label_renumbers_and_keeps_scalars() {
        let p = (0..5)
            .map(|i| Vec3::new(i as f32, 0.0, (i * i) as f32))
            .collect();
        let mut m = TriMesh::new(p, vec![[0, 1, 2], [2, 3, 4], [1, 2, 3]]).unwrap();
        m.scalars.push(ScalarField {
            name: "s".into(),
            values: vec![0.0, 1.0, 2.0, 3.0, 4.0],
        });
        let parts = split_by_label(&m, &[1, 0, 1]);
        assert_eq!(parts.len(), 2);
        assert_eq!(parts[0].triangles, vec![[0, 1, 2]]);
        assert_eq!(parts[0].scalars[0].values, vec![2.0, 3.0, 4.0]);
        assert_eq!(parts[1].triangles, vec![[0, 1, 2], [1, 2, 3]]);
        assert_eq!(parts[1].positions.len(), 4);
        assert_eq!(parts[1].scalars[0].values, vec![0.0, 1.0, 2.0, 3.0]);
        for part in &parts {
            part.validate().unwrap();
        }
    }
}
