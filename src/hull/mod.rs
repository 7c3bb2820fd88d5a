//! Exact convex hulls of digital objects (seed 003 §4.1, App. C, ch. 5).
//!
//! [`ConvexHull::build`] runs the incremental algorithm of §4.1.4–4.1.8 on
//! integer (combinatorial) coordinates with exact `i64`/`i128` predicates —
//! no epsilons. The result is a convex polyhedron with primitive integer face
//! planes; [`ConvexHull::half_spaces`] is the list the inside-hull scan
//! consumes, [`ConvexHull::cell_list`] the cell list of App. C,
//! [`ConvexHull::to_mesh`] a triangle mesh for viewing.
//!
//! Guarantees (tested): every candidate point satisfies every half-space;
//! V − E + F = 2; with [`CoplanarPolicy::Merge`] the faces are exactly the
//! facets of the hull (maximal, convex, no two coplanar neighbours, no vertex
//! in the middle of an edge), so the face count is the minimum (Theorem TRM
//! for digitally convex S); the construction is deterministic.
//!
//! With 6-neighbourhood local corners in lexicographic order (the seed's
//! basic algorithm) the three policies reproduce all of seed Table 4.2 for
//! the digital balls r = 12, 16, 20, 24 (see `phantom::voxel`).

mod build;
pub mod cells;
mod incremental;
mod measure;
mod query;

pub use cells::CellList;
pub use incremental::{HullStats, MAX_COORD};

// `cross`, `sub` and `primitive` are read by `cells` as `super::…`.
use crate::foundation::exact::{cross, dot, sub};
use incremental::primitive;

/// How faces coplanar with the inserted point are treated (§4.1.6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CoplanarPolicy {
    /// Coplanar faces count as invisible: triangles only; where the point is
    /// collinear with an edge to a coplanar face that face is replaced too,
    /// so no degenerate triangle arises (counted in
    /// [`HullStats::promoted`]).
    Invisible,
    /// Coplanar faces edge-connected to the visible ones are replaced too:
    /// triangles only.
    Visible,
    /// The 2-D extension: coplanar faces grow into convex n-gons; new cone
    /// faces that are coplanar are one polygon. Gives the facets of the hull.
    Merge,
}

/// Processing order of the candidates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Order {
    /// Lexicographic (x, then y, then z), the seed's basic order.
    Lexicographic,
    /// The eight extreme points of §4.1.8 first (v1…v8: lexicographic
    /// minimum/maximum with per-axis min/max preferences), then the rest
    /// lexicographically. Fewer faces are created and deleted.
    ExtremeFirst,
    /// Tetrahedron from the §4.1.8 extreme points, then always the point
    /// furthest beyond some face (Qhull's order): the fewest insertions, so
    /// the fastest. With [`CoplanarPolicy::Merge`] the result does not depend
    /// on the order at all (the facets of the hull are unique).
    Furthest,
}

/// Options of [`ConvexHull::build`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct HullOptions {
    /// Coplanar policy; default [`CoplanarPolicy::Merge`].
    pub coplanar: CoplanarPolicy,
    /// Candidate order; default [`Order::Furthest`].
    pub order: Order,
}

impl Default for HullOptions {
    fn default() -> Self {
        HullOptions {
            coplanar: CoplanarPolicy::Merge,
            order: Order::Furthest,
        }
    }
}

/// The closed half-space `normal·x ≤ offset` (combinatorial coordinates;
/// `normal` primitive and outward).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub struct HalfSpace {
    /// Outward normal, primitive (gcd of the components is 1).
    pub normal: [i64; 3],
    /// `normal·v` for every point `v` of the bounding plane.
    pub offset: i64,
}

impl From<HalfSpace> for crate::hull_scan::HalfSpace {
    /// The same half-space as input of the inside-hull scans.
    fn from(h: HalfSpace) -> Self {
        crate::hull_scan::HalfSpace {
            normal: h.normal,
            offset: h.offset,
        }
    }
}

impl HalfSpace {
    /// `normal·p − offset`: `> 0` outside (the face is visible from `p`),
    /// `0` on the plane, `< 0` inside.
    pub fn side(&self, p: [i64; 3]) -> i64 {
        dot(self.normal, p) - self.offset
    }
}

/// Where a point lies relative to the hull.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Containment {
    /// Strictly inside every half-space.
    Inside,
    /// On the boundary.
    On,
    /// Outside some half-space.
    Outside,
}

/// A face of the hull: vertex indices CCW seen from outside, and its plane.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HullFace {
    /// Indices into [`ConvexHull::vertices`], counter-clockwise from outside.
    pub vertices: Vec<u32>,
    /// Supporting plane, outward.
    pub plane: HalfSpace,
}

/// Report figures of a hull ([`ConvexHull::summary`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct HullSummary {
    /// 2-cells.
    pub faces: usize,
    /// 0-cells.
    pub vertices: usize,
    /// 1-cells.
    pub edges: usize,
    /// Triangles of the fan triangulation (mesh export).
    pub triangles: usize,
    /// Storage estimate of eq. 8.2, `3·N_V + 5·N_F`.
    pub integers_eq_8_2: usize,
    /// Length of [`CellList::encode_compact`].
    pub integers_compact: usize,
    /// Volume in voxels.
    pub volume_voxels: f64,
    /// Area in voxel faces.
    pub area_voxels: f64,
    /// Volume in world units.
    pub volume_world: f64,
    /// Area in world units.
    pub area_world: f64,
    /// Whether the input was coplanar.
    pub planar: bool,
    /// Options used.
    pub options: HullOptions,
    /// Construction counters.
    pub stats: HullStats,
}

/// An exact convex hull (or, for coplanar input, a flat convex polygon
/// stored as two opposite faces).
#[derive(Debug, Clone)]
pub struct ConvexHull {
    vertices: Vec<[i64; 3]>,
    faces: Vec<HullFace>,
    /// 6·volume in combinatorial units (8 per voxel), accumulated
    /// incrementally during the construction.
    vol6: i128,
    planar: Option<HalfSpace>,
    stats: HullStats,
    options: HullOptions,
}

impl ConvexHull {
    /// Hull vertices (combinatorial coordinates), sorted lexicographically.
    pub fn vertices(&self) -> &[[i64; 3]] {
        &self.vertices
    }

    /// Faces, CCW from outside.
    pub fn faces(&self) -> &[HullFace] {
        &self.faces
    }

    /// Number of faces (2-cells).
    pub fn n_faces(&self) -> usize {
        self.faces.len()
    }

    /// Number of vertices (0-cells).
    pub fn n_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// Number of edges (1-cells).
    pub fn n_edges(&self) -> usize {
        self.faces.iter().map(|f| f.vertices.len()).sum::<usize>() / 2
    }

    /// Triangles of the fan triangulation of all faces.
    pub fn n_triangles(&self) -> usize {
        self.faces.iter().map(|f| f.vertices.len() - 2).sum()
    }

    /// Whether the input was coplanar (a flat polygon, volume 0).
    pub fn is_planar(&self) -> bool {
        self.planar.is_some()
    }

    /// Construction counters.
    pub fn stats(&self) -> HullStats {
        self.stats
    }

    /// The options used.
    pub fn options(&self) -> HullOptions {
        self.options
    }
}
