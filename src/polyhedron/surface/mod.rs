//! The single merged surface of a polyhedron (seed 003 §4.4.1
//! "Zusammenfügen"), by exact boundary evaluation.
//!
//! When sibling shells have disjoint interiors
//! ([`super::PolyhedronSummary::volume_exact`]) the indicator of the object
//! region is `Σ sign_i·χ(H_i)` over the 3-D shells, so its boundary is the
//! 2-chain `Σ sign_i·∂H_i` (background faces reversed). Per supporting plane
//! the faces' multiplicities add up: coplanar overlapping pieces cancel (the
//! marked faces of Def. PR removed, the child's faces joined in); what is
//! left is cut into faces, each an outer loop with its holes, outward for the
//! region. Loops are then split where a neighbouring face has an edge
//! endpoint on their edge (T-junctions), so every edge is used as often in
//! one direction as in the other, and faces are triangulated by ear
//! clipping. Every face is also split into convex faces by the merges of
//! Theorem KE (§4.5.6, [`MergedSurface::convex_faces`]). Every predicate
//! is exact integer arithmetic on combinatorial coordinates (voxel centres
//! odd); no epsilons, no rounding.
//!
//! Lower-dimensional and flat shells carry no volume (they label voxels on
//! the surface) and are left out.
//!
//! Files by phase: this one holds the result types and their queries;
//! `merged.rs` builds it from a [`super::Polyhedron`]'s shells (boundary
//! evaluation per plane, loops, T-junctions, triangulation);
//! `convex_faces.rs` splits faces into convex faces (Theorem KE);
//! `polygon.rs` holds the exact 2-D polygon routines they use (projection, point in
//! polygon, ear clipping with bridges for holes).

mod convex_faces;
mod merged;
mod polygon;

pub use convex_faces::theorem_ke;

use crate::foundation::exact::det;
use crate::mesh::{ScalarField, TriMesh};
use crate::voxel::Frame;

/// One face of a [`MergedSurface`]: a planar region, possibly with holes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MergedFace {
    /// Outward normal for the region, primitive (gcd 1).
    pub normal: [i64; 3],
    /// `normal·v` for every vertex `v` of the face.
    pub offset: i64,
    /// Vertex cycles (indices into [`MergedSurface::vertices`]): the outer
    /// loop first, counter-clockwise seen from outside, then the holes,
    /// clockwise. A loop may pass through a vertex twice (a pinch).
    pub loops: Vec<Vec<u32>>,
}

/// One convex piece of a [`MergedFace`] ([`MergedSurface::convex_faces`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConvexFace {
    /// Index of the merged face (into [`MergedSurface::faces`]) it lies in.
    pub face: u32,
    /// Vertex cycle (indices into [`MergedSurface::vertices`]),
    /// counter-clockwise seen from outside, at least 3 corners, every
    /// corner convex or straight (straight corners are kept: loop vertices
    /// and T-junctions that neighbouring faces share).
    pub vertices: Vec<u32>,
}

/// The merged surface: one closed, consistently oriented polyhedral
/// surface of the object region (possibly several components, e.g. around
/// a cavity; edges at pinch vertices may be used by four faces).
#[derive(Debug, Clone)]
pub struct MergedSurface {
    /// Vertices, combinatorial coordinates (voxel centres odd).
    pub vertices: Vec<[i64; 3]>,
    /// Faces, ordered by canonical supporting plane.
    pub faces: Vec<MergedFace>,
    /// Exact triangulation of the faces, outward winding (indices into
    /// [`MergedSurface::vertices`]); every face-loop vertex is a corner.
    pub triangles: Vec<[u32; 3]>,
    /// Per vertex, the smallest depth of a shell having it as a hull vertex
    /// (every merged vertex is one).
    pub vertex_depth: Vec<u32>,
    /// Per triangle, the face it triangulates (index into
    /// [`MergedSurface::faces`]).
    pub triangle_faces: Vec<u32>,
    /// Per face, the smallest depth of a shell with a face covering the
    /// centroid of the face's first triangle: the depth of the shell the
    /// face comes from, also where it shares vertices with shells of other
    /// depths (per-vertex depths blend there). Where coplanar faces of
    /// shells of different depths join into one face, that point decides.
    pub face_depth: Vec<u32>,
    /// Every face split into convex faces (Theorem KE, §4.5.6), ordered by
    /// face: starting from the face's triangles, two pieces sharing a
    /// diagonal are merged when [`theorem_ke`] says the union stays convex.
    /// The merges are greedy (Hertel–Mehlhorn style, one pass over the
    /// diagonals): every diagonal left is essential, so a face without
    /// holes with `r` reflex corners gets at most `2r + 1` convex faces,
    /// at most four times the minimum (any convex partition needs
    /// `⌈r/2⌉ + 1`). Not optimal, and no such bound is claimed for faces
    /// with holes. The convex faces of a face tile it exactly: they meet
    /// only along whole edges and their areas sum to the face's.
    pub convex_faces: Vec<ConvexFace>,
}

impl MergedSurface {
    /// Faces, a face with holes counted once (seed Table 8.7, "with holes").
    pub fn n_faces(&self) -> usize {
        self.faces.len()
    }

    /// Faces that have at least one hole.
    pub fn n_faces_with_holes(&self) -> usize {
        self.faces.iter().filter(|f| f.loops.len() > 1).count()
    }

    /// Faces when each face with `h` holes counts as `h + 1` simple faces
    /// (seed Table 8.7, "split").
    pub fn n_faces_split(&self) -> usize {
        self.faces.iter().map(|f| f.loops.len()).sum()
    }

    /// Convex faces ([`MergedSurface::convex_faces`]), at least
    /// [`MergedSurface::n_faces_split`].
    pub fn n_convex_faces(&self) -> usize {
        self.convex_faces.len()
    }

    /// 6·volume enclosed, combinatorial units (one voxel = 8 units, so
    /// 48 per voxel), exact from the triangles.
    pub fn volume6(&self) -> i128 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| self.vertices[v as usize]);
                det(a, b, c)
            })
            .sum()
    }

    /// Enclosed volume in voxel units (`volume6 / 48`: combinatorial
    /// coordinates are doubled), exact up to the final division.
    pub fn volume_voxels(&self) -> f64 {
        self.volume6() as f64 / 48.0
    }

    /// Surface area in voxel units: Σ |(b − a) × (c − a)| / 8 over the
    /// triangles (exact `i128` cross products, one square root each).
    pub fn area_voxels(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| self.vertices[v as usize].map(i128::from));
                let (u, w) = (
                    [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                    [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
                );
                let n = [
                    u[1] * w[2] - u[2] * w[1],
                    u[2] * w[0] - u[0] * w[2],
                    u[0] * w[1] - u[1] * w[0],
                ];
                ((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) as f64).sqrt() / 8.0
            })
            .sum()
    }

    /// The triangles as a mesh in world units (`frame`), outward winding;
    /// scalar `depth` per vertex ([`MergedSurface::vertex_depth`]).
    pub fn to_mesh(&self, frame: &Frame) -> crate::Result<TriMesh> {
        let positions = self.vertices.iter().map(|&v| frame.world_f32(v)).collect();
        let mut triangles = self.triangles.clone();
        // A reflecting frame turns the index-space winding inside out.
        if frame.reflects() {
            triangles.iter_mut().for_each(|t| t.swap(1, 2));
        }
        let mut mesh = TriMesh::new(positions, triangles)?;
        mesh.scalars.push(ScalarField {
            name: "depth".into(),
            values: self.vertex_depth.iter().map(|&d| d as f32).collect(),
        });
        mesh.validate()?;
        Ok(mesh)
    }

    /// The triangles as a mesh for pictures: each with its own three
    /// vertices and the scalar `depth` of its face
    /// ([`MergedSurface::face_depth`]), so colours do not blend across
    /// faces. Not welded: write [`MergedSurface::to_mesh`] instead.
    pub fn to_face_mesh(&self, frame: &Frame) -> crate::Result<TriMesh> {
        let flip = frame.reflects();
        let positions = (self.triangles.iter())
            .flat_map(|t| {
                let t = if flip { [t[0], t[2], t[1]] } else { *t };
                t.map(|v| frame.world_f32(self.vertices[v as usize]))
            })
            .collect();
        let triangles = (0..self.triangles.len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        let mut mesh = TriMesh::new(positions, triangles)?;
        mesh.scalars.push(ScalarField {
            name: "depth".into(),
            values: (self.triangle_faces.iter())
                .flat_map(|&f| [self.face_depth[f as usize] as f32; 3])
                .collect(),
        });
        mesh.validate()?;
        Ok(mesh)
    }
}
