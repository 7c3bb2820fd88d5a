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

pub mod cells;
mod incremental;

use crate::mesh::TriMesh;
use crate::voxel::{CandidateKind, DigitalObject, Frame};

pub use cells::CellList;
use crate::foundation::exact::{P3, cross, det, dot, sub};
use incremental::{Builder, primitive};
pub use incremental::{HullStats, MAX_COORD};

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

impl From<HalfSpace> for crate::hscan::HalfSpace {
    /// The same half-space as input of the inside-hull scans.
    fn from(h: HalfSpace) -> Self {
        crate::hscan::HalfSpace {
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
    /// Hull of `points` (combinatorial coordinates, |c| ≤ [`MAX_COORD`]).
    ///
    /// Errors: [`crate::Error::InvalidInput`] for coordinates out of range and
    /// when the points are collinear (no polygon, no polyhedron).
    pub fn build(points: &[[i64; 3]], options: HullOptions) -> crate::Result<ConvexHull> {
        if let Some(p) = points
            .iter()
            .find(|p| p.iter().any(|c| c.abs() > MAX_COORD))
        {
            return Err(crate::Error::InvalidInput(format!(
                "hull point {p:?} exceeds the coordinate bound ±{MAX_COORD}"
            )));
        }
        let mut pts = points.to_vec();
        pts.sort_unstable();
        pts.dedup();
        if options.order != Order::Lexicographic {
            extreme_first(&mut pts);
        }
        let Some(tet) = initial_tetrahedron(&pts) else {
            return planar_hull(&pts, options);
        };
        let mut b = Builder::new(&pts, options.coplanar, tet);
        if options.order == Order::Furthest {
            b.run_furthest()?;
        } else {
            for i in 0..pts.len() as u32 {
                if !tet.contains(&i) {
                    b.insert(i)?;
                }
            }
        }
        let vol6 = b.vol6;
        let stats = b.stats;
        let faces: Vec<_> = b.faces.into_iter().flatten().collect();
        let (vertices, faces) = compact(&pts, faces.into_iter().map(|f| (f.verts, f.n, f.d)));
        Ok(ConvexHull {
            vertices,
            faces,
            vol6,
            planar: None,
            stats,
            options,
        })
    }

    /// Hull of a digital object's candidates of `kind` (§4.1.2–4.1.3):
    /// vertices at voxel centres, or at 0-cells for
    /// [`CandidateKind::ConvexCorners`].
    pub fn of_object(
        object: &DigitalObject,
        kind: CandidateKind,
        options: HullOptions,
    ) -> crate::Result<ConvexHull> {
        ConvexHull::build(&object.candidates(kind), options)
    }

    /// Rebuilds a hull from stored vertices and face cycles (counter-clockwise
    /// from outside), e.g. a decoded cell list. Planes are recomputed
    /// exactly (`Σ vᵢ × vᵢ₊₁`, made primitive); a flat polygon is two
    /// opposite faces over the same cycle.
    ///
    /// Errors: [`crate::Error::InvalidInput`] when a coordinate is out of
    /// range, a face has fewer than three vertices, an index is out of range,
    /// a face is not planar, or some vertex lies outside a face's plane (the
    /// faces do not bound a convex polytope).
    pub fn from_faces(vertices: Vec<[i64; 3]>, cycles: Vec<Vec<u32>>) -> crate::Result<ConvexHull> {
        let bad = |what: String| crate::Error::InvalidInput(format!("convex polytope: {what}"));
        if let Some(p) = vertices
            .iter()
            .find(|p| p.iter().any(|c| c.abs() > MAX_COORD))
        {
            return Err(bad(format!("vertex {p:?} exceeds ±{MAX_COORD}")));
        }
        let mut faces = Vec::with_capacity(cycles.len());
        for (f, cycle) in cycles.into_iter().enumerate() {
            if cycle.len() < 3 {
                return Err(bad(format!("face {f} has {} vertices", cycle.len())));
            }
            if let Some(v) = cycle.iter().find(|&&v| v as usize >= vertices.len()) {
                return Err(bad(format!(
                    "face {f} names vertex {v} of {}",
                    vertices.len()
                )));
            }
            let p = |k: usize| vertices[cycle[k % cycle.len()] as usize];
            // Twice the area vector; a convex face within ±MAX_COORD has
            // |n_c| < 2³⁶, which keeps every later product below 2⁶³.
            let mut n = [0i128; 3];
            for k in 0..cycle.len() {
                let c = cross(sub(p(k), p(0)), sub(p(k + 1), p(0)));
                n = std::array::from_fn(|a| n[a] + i128::from(c[a]));
            }
            if n == [0, 0, 0] {
                return Err(bad(format!("face {f} is degenerate")));
            }
            if n.iter().any(|c| c.abs() >= 1 << 36) {
                return Err(bad(format!(
                    "face {f} is not a convex polygon of the coordinate range"
                )));
            }
            let normal = primitive(n.map(|c| c as i64));
            let plane = HalfSpace {
                normal,
                offset: dot(normal, p(0)),
            };
            if (0..cycle.len()).any(|k| plane.side(p(k)) != 0) {
                return Err(bad(format!("face {f} is not planar")));
            }
            if let Some(v) = vertices.iter().find(|&&v| plane.side(v) > 0) {
                return Err(bad(format!("vertex {v:?} lies outside face {f}")));
            }
            faces.push(HullFace {
                vertices: cycle,
                plane,
            });
        }
        let planar = match faces.as_slice() {
            [a, b] if a.plane.normal == b.plane.normal.map(|c| -c) => Some(a.plane),
            _ => None,
        };
        let mut hull = ConvexHull {
            vertices,
            faces,
            vol6: 0,
            planar,
            stats: HullStats::default(),
            options: HullOptions::default(),
        };
        if hull.faces.len() < 4 && planar.is_none() {
            return Err(bad(format!("{} faces bound no polytope", hull.faces.len())));
        }
        hull.vol6 = hull.volume6_from_faces();
        Ok(hull)
    }

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

    /// Exact half-spaces whose intersection is the hull, outward normals,
    /// combinatorial coordinates: one per face; a flat hull adds one per
    /// polygon edge (in-plane normals) to its two opposite plane faces.
    pub fn half_spaces(&self) -> Vec<HalfSpace> {
        let mut out: Vec<HalfSpace> = self.faces.iter().map(|f| f.plane).collect();
        if let (Some(plane), Some(face)) = (self.planar, self.faces.first()) {
            let k = face.vertices.len();
            for i in 0..k {
                let a = self.vertices[face.vertices[i] as usize];
                let b = self.vertices[face.vertices[(i + 1) % k] as usize];
                let normal = primitive(cross(sub(b, a), plane.normal));
                out.push(HalfSpace {
                    normal,
                    offset: dot(normal, a),
                });
            }
        }
        out
    }

    /// Per-row intervals of the voxel rows of `bbox` in the closed hull,
    /// exactly ([`crate::hscan::row_spans_culled`]: on the CPU each layer
    /// uses only the faces meeting it).
    ///
    /// Errors: the hull-scan range limits of [`crate::hscan::check_range`].
    pub fn row_spans(
        &self,
        bbox: &crate::hscan::VoxelBox,
        backend: crate::parity::Backend<'_>,
    ) -> crate::Result<crate::hscan::RowSpans> {
        let spaces: Vec<crate::hscan::HalfSpace> =
            self.half_spaces().into_iter().map(Into::into).collect();
        crate::hscan::row_spans_culled(&spaces, &self.face_z_extents(), bbox, backend)
    }

    /// The combinatorial z range `[min, max]` of each half-space of
    /// [`Self::half_spaces`], in the same order: the range of its face's
    /// vertices (a flat hull: the polygon's range for every half-space), for
    /// [`crate::hscan::row_spans_culled`].
    pub fn face_z_extents(&self) -> Vec<[i64; 2]> {
        let range = |vs: &mut dyn Iterator<Item = &u32>| {
            vs.fold([i64::MAX, i64::MIN], |r, &v| {
                let z = self.vertices[v as usize][2];
                [r[0].min(z), r[1].max(z)]
            })
        };
        if self.planar.is_some() {
            // The plane faces, then one in-plane half-space per polygon edge.
            let n = self.faces.len() + self.faces.first().map_or(0, |f| f.vertices.len());
            let all = range(&mut self.faces.iter().flat_map(|f| &f.vertices));
            return vec![all; n];
        }
        self.faces
            .iter()
            .map(|f| range(&mut f.vertices.iter()))
            .collect()
    }

    /// Exact position of `p` relative to the hull.
    pub fn containment(&self, p: [i64; 3]) -> Containment {
        let mut on = false;
        for h in self.half_spaces() {
            match h.side(p) {
                s if s > 0 => return Containment::Outside,
                0 => on = true,
                _ => {}
            }
        }
        if on || self.planar.is_some() {
            Containment::On
        } else {
            Containment::Inside
        }
    }

    /// Inclusive bounding box of the vertices, combinatorial coordinates.
    pub fn bbox(&self) -> ([i64; 3], [i64; 3]) {
        let mut lo = [i64::MAX; 3];
        let mut hi = [i64::MIN; 3];
        for v in &self.vertices {
            for a in 0..3 {
                lo[a] = lo[a].min(v[a]);
                hi[a] = hi[a].max(v[a]);
            }
        }
        (lo, hi)
    }

    /// Inclusive voxel-index range of the voxels whose centres lie in
    /// [`ConvexHull::bbox`] (centre `2i + 1`).
    pub fn voxel_bbox(&self) -> ([i64; 3], [i64; 3]) {
        let (lo, hi) = self.bbox();
        (
            lo.map(|c| (c - 1).div_euclid(2) + i64::from((c - 1).rem_euclid(2) != 0)),
            hi.map(|c| (c - 1).div_euclid(2)),
        )
    }

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
        TriMesh::new(positions, triangles)
    }
}

/// Moves the eight extreme points of §4.1.8 to the front of the
/// lexicographically sorted `pts` (duplicates among them kept once).
fn extreme_first(pts: &mut Vec<P3>) {
    if pts.is_empty() {
        return;
    }
    // (sign x, sign y, sign z): +1 prefers the maximum on that axis.
    let prefs: [[i64; 3]; 8] = [
        [-1, -1, -1],
        [1, -1, -1],
        [-1, 1, -1],
        [-1, -1, 1],
        [1, 1, 1],
        [-1, 1, 1],
        [1, -1, 1],
        [1, 1, -1],
    ];
    let mut front: Vec<usize> = Vec::new();
    for s in prefs {
        // Lexicographic extreme: axis x first, then y, then z; if only one
        // point has the extreme x and it is already taken, the next one is.
        let key = |i: usize| {
            let p = pts[i];
            (
                [s[0] * p[0], s[1] * p[1], s[2] * p[2]],
                std::cmp::Reverse(i),
            )
        };
        if let Some(i) = (0..pts.len())
            .filter(|i| !front.contains(i))
            .max_by_key(|&i| key(i))
        {
            front.push(i);
        }
    }
    let mut taken = vec![false; pts.len()];
    let mut out: Vec<P3> = front.iter().map(|&i| pts[i]).collect();
    for &i in &front {
        taken[i] = true;
    }
    out.extend(
        pts.iter()
            .enumerate()
            .filter(|(i, _)| !taken[*i])
            .map(|(_, p)| *p),
    );
    *pts = out;
}

/// First four non-coplanar points in order, or `None` when all are coplanar.
fn initial_tetrahedron(pts: &[P3]) -> Option<[u32; 4]> {
    let a = 0usize;
    let b = (1..pts.len()).find(|&i| pts[i] != pts[a])?;
    let c = (b + 1..pts.len())
        .find(|&i| cross(sub(pts[b], pts[a]), sub(pts[i], pts[a])) != [0, 0, 0])?;
    let n = cross(sub(pts[b], pts[a]), sub(pts[c], pts[a]));
    let d = (c + 1..pts.len()).find(|&i| dot(n, sub(pts[i], pts[a])) != 0)?;
    Some([a, b, c, d].map(|i| i as u32))
}

/// Renumbers the vertices used by `faces` in lexicographic order.
fn compact(
    pts: &[P3],
    faces: impl Iterator<Item = (Vec<u32>, P3, i64)>,
) -> (Vec<P3>, Vec<HullFace>) {
    let faces: Vec<_> = faces.collect();
    let mut used = vec![false; pts.len()];
    for (verts, _, _) in &faces {
        for &v in verts {
            used[v as usize] = true;
        }
    }
    let mut order: Vec<usize> = (0..pts.len()).filter(|&i| used[i]).collect();
    order.sort_unstable_by_key(|&i| pts[i]);
    let mut index = vec![u32::MAX; pts.len()];
    let mut vertices = Vec::with_capacity(order.len());
    for i in order {
        index[i] = vertices.len() as u32;
        vertices.push(pts[i]);
    }
    let faces = faces
        .into_iter()
        .map(|(verts, n, d)| HullFace {
            vertices: verts.iter().map(|&v| index[v as usize]).collect(),
            plane: HalfSpace {
                normal: n,
                offset: d,
            },
        })
        .collect();
    (vertices, faces)
}

/// Coplanar input: the convex polygon (monotone chain in the plane, exact),
/// stored as two opposite faces.
fn planar_hull(pts: &[P3], options: HullOptions) -> crate::Result<ConvexHull> {
    let degenerate = || {
        crate::Error::InvalidInput(format!(
            "the {} hull candidates are collinear: no polygon or polyhedron \
             (a line of voxels has a hull through its cell corners: `--vertices corners`)",
            pts.len()
        ))
    };
    let a = *pts.first().ok_or_else(degenerate)?;
    let b = *pts.iter().find(|&&p| p != a).ok_or_else(degenerate)?;
    let c = *pts
        .iter()
        .find(|&&p| cross(sub(b, a), sub(p, a)) != [0, 0, 0])
        .ok_or_else(degenerate)?;
    let n = primitive(cross(sub(b, a), sub(c, a)));
    // Turn test in the plane: > 0 when o→p→q turns counter-clockwise about n.
    let turn = |o: P3, p: P3, q: P3| dot(cross(sub(p, o), sub(q, o)), n);
    let mut sorted: Vec<usize> = (0..pts.len()).collect();
    sorted.sort_unstable_by_key(|&i| pts[i]);
    let mut hull: Vec<usize> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &usize>> = if pass == 0 {
            Box::new(sorted.iter())
        } else {
            Box::new(sorted.iter().rev())
        };
        for &i in iter {
            while hull.len() >= start + 2
                && turn(pts[hull[hull.len() - 2]], pts[hull[hull.len() - 1]], pts[i]) <= 0
            {
                hull.pop();
            }
            hull.push(i);
        }
        hull.pop();
    }
    let ccw: Vec<u32> = hull.iter().map(|&i| i as u32).collect();
    let cw: Vec<u32> = ccw.iter().rev().copied().collect();
    let d = dot(n, a);
    let neg = n.map(|c| -c);
    let (vertices, faces) = compact(pts, [(ccw, n, d), (cw, neg, -d)].into_iter());
    Ok(ConvexHull {
        vertices,
        faces,
        vol6: 0,
        planar: Some(HalfSpace {
            normal: n,
            offset: d,
        }),
        stats: HullStats {
            candidates: pts.len(),
            inserted: hull.len(),
            skipped: pts.len() - hull.len(),
            ..HullStats::default()
        },
        options,
    })
}
