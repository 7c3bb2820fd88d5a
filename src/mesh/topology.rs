//! Mesh topology: edge use counts, manifoldness, boundary loops, connected
//! components, Euler characteristic, genus and orientation (SPEC §0; printed
//! by `chisel stats --json`).
//!
//! Conventions, fixed here because the figures depend on them:
//! - A triangle with a repeated vertex index is *collapsed*: it is counted in
//!   `triangles` and `degenerate_triangles` but takes no part in any other
//!   figure (it has no well-defined edges). Every other triangle, zero-area
//!   ones included, is part of the topology.
//! - Edges are undirected vertex-index pairs. An edge used by one triangle is
//!   a boundary edge, by two a manifold edge, by more a non-manifold edge.
//! - Components are maximal sets of triangles connected through shared
//!   vertices (the `vtkPolyDataConnectivityFilter` rule), listed by
//!   triangle count, descending, ties by first triangle index.
//! - Orientation: see [`Orientation`] and [`ORIENTATION_TOLERANCE`].
//!
//! Cost: O(F log F) for F triangles (one sort of the 3F half-edges), O(V + F)
//! memory; no recursion.

use glam::DVec3;
use rayon::slice::ParallelSliceMut;

use super::TriMesh;
use crate::foundation::{Aabb, UnionFind};

/// Marks "no such half-edge / component" in the index tables below.
pub(crate) const NONE: usize = usize::MAX;

/// A component whose signed volume satisfies `|V| ≤ τ · A · D` (A its area,
/// D its bounding-box diagonal) has [`Orientation::Undetermined`] winding.
///
/// `V/(A·D)` is 1/6 for a sphere and about `h/(6a)` for a shallow cap of sag
/// `h` over radius `a`, so τ = 1e-4 leaves only (near-)flat pieces, whose
/// inside is genuinely undefined, undetermined.
pub const ORIENTATION_TOLERANCE: f64 = 1e-4;

/// Winding of a mesh's triangles relative to the side they enclose or curve
/// around.
///
/// Criterion, per component: `V = Σ_t (p0 − C) · ((p1 − p0) × (p2 − p0)) / 6`,
/// the signed volume of the cone from the component's area-weighted centroid
/// `C` over its triangles. For a closed component this is the enclosed volume
/// (independent of `C`: divergence theorem); for an open one it is positive
/// when the right-hand-rule normals point away from the concave side (e.g.
/// the outside of a face scan or of a bunny with holes in its base).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Orientation {
    /// Consistently wound, `V > τ·A·D`: normals point out of the enclosed side.
    Outward,
    /// Consistently wound, `V < −τ·A·D`: normals point into the enclosed side.
    Inward,
    /// Some manifold edge is traversed twice in the same direction, or (for a
    /// whole mesh) determined components disagree.
    Mixed,
    /// Consistently wound but (near-)flat or empty: `|V| ≤ τ·A·D`.
    Undetermined,
}

/// Figures of one connected component (triangles sharing vertices).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Component {
    /// Index of the component's first triangle in the mesh.
    pub first_triangle: usize,
    /// Non-collapsed triangles.
    pub triangles: usize,
    /// Vertices used by those triangles.
    pub vertices: usize,
    /// Undirected edges.
    pub edges: usize,
    /// Edges used by one triangle.
    pub boundary_edges: usize,
    /// Edges used by more than two triangles.
    pub nonmanifold_edges: usize,
    /// Vertices whose incident triangles do not form a single fan.
    pub nonmanifold_vertices: usize,
    /// No boundary edges.
    pub closed: bool,
    /// No non-manifold edges and no non-manifold vertices.
    pub manifold: bool,
    /// Every manifold edge is traversed once in each direction.
    pub consistently_oriented: bool,
    /// A consistent winding exists for every patch connected through
    /// manifold edges (false for a Möbius strip or a Klein bottle).
    pub orientable: bool,
    /// Euler characteristic V − E + F.
    pub euler: i64,
    /// `(2 − χ)/2` for closed, manifold, orientable components; else `None`.
    pub genus: Option<i64>,
    /// Total triangle area (units²).
    pub area: f64,
    /// Signed cone volume about the area-weighted centroid (units³); the
    /// enclosed volume when closed. See [`Orientation`].
    pub signed_volume: f64,
    pub orientation: Orientation,
}

/// Topological figures of a triangle mesh, see the module docs.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Topology {
    /// All vertices, used or not.
    pub vertices: usize,
    /// Vertices referenced by at least one non-collapsed triangle.
    pub used_vertices: usize,
    /// All triangles.
    pub triangles: usize,
    /// Triangles with a repeated index (collapsed) or zero area: height below
    /// `f32::EPSILON` times the longest edge.
    pub degenerate_triangles: usize,
    /// Triangles with a repeated index, left out of every figure below.
    pub collapsed_triangles: usize,
    /// Undirected edges.
    pub edges: usize,
    /// Edges used by exactly one triangle.
    pub boundary_edges: usize,
    /// Edges used by exactly two triangles.
    pub manifold_edges: usize,
    /// Edges used by more than two triangles.
    pub nonmanifold_edges: usize,
    /// Vertices on a non-manifold edge or whose incident triangles form more
    /// than one fan (e.g. the tip of a bowtie).
    pub nonmanifold_vertices: usize,
    /// Edge counts of the closed boundary loops, descending. Loops are
    /// separated at pinch vertices by following each vertex fan.
    pub boundary_loops: Vec<usize>,
    /// Edge counts of boundary chains that end at a non-manifold edge,
    /// descending (empty for manifold meshes).
    pub open_boundary_chains: Vec<usize>,
    /// Components, by triangle count descending.
    pub components: Vec<Component>,
    /// Euler characteristic V − E + F over used vertices and non-collapsed
    /// triangles.
    pub euler: i64,
    /// Non-empty and no boundary edges.
    pub closed: bool,
    /// Every manifold edge is traversed once in each direction.
    pub consistently_oriented: bool,
    /// `Outward`/`Inward` when every component that is not `Undetermined`
    /// says so (and at least one does), `Mixed` when any component is mixed
    /// or they disagree, otherwise `Undetermined`.
    pub orientation: Orientation,
    /// Total triangle area (units²).
    pub area: f64,
    /// Sum of the components' signed volumes (units³).
    pub signed_volume: f64,
    /// Bounding box of all vertices (used or not); `None` without vertices.
    pub bounds: Option<Aabb>,
}

/// Whether a triangle repeats a vertex index.
pub(crate) fn is_collapsed(t: &[u32; 3]) -> bool {
    t[0] == t[1] || t[1] == t[2] || t[0] == t[2]
}

/// Half-edge tables of a triangle list. Half-edge `h = 3·t + k` runs from
/// corner `k` of triangle `t` to corner `(k + 1) % 3`.
#[derive(Debug)]
pub(crate) struct HalfEdges {
    /// Per half-edge: the other half-edge of its manifold edge, else `NONE`.
    pub twin: Vec<usize>,
    /// Per edge: number of triangles using it.
    pub uses: Vec<usize>,
    /// Per edge: its half-edge with the smallest id.
    pub first: Vec<usize>,
}

impl HalfEdges {
    /// Sorts the half-edges by `(min, max)` vertex key: O(F log F),
    /// deterministic (keys are unique pairs with the half-edge id).
    pub fn of(triangles: &[[u32; 3]]) -> Self {
        let mut keyed: Vec<(u64, usize)> = Vec::with_capacity(3 * triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            if is_collapsed(tri) {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
                keyed.push((key, 3 * t + k));
            }
        }
        keyed.par_sort_unstable();
        let mut twin = vec![NONE; 3 * triangles.len()];
        let mut uses = Vec::new();
        let mut first = Vec::new();
        for group in keyed.chunk_by(|x, y| x.0 == y.0) {
            if let [(_, h), (_, g)] = *group {
                twin[h] = g;
                twin[g] = h;
            }
            uses.push(group.len());
            first.push(group[0].1);
        }
        HalfEdges { twin, uses, first }
    }

    /// Number of undirected edges.
    pub fn n_edges(&self) -> usize {
        self.uses.len()
    }
}

/// Start vertex of half-edge `h`.
fn tail(triangles: &[[u32; 3]], h: usize) -> u32 {
    triangles[h / 3][h % 3]
}

/// A winding for every patch of triangles connected through manifold edges.
#[derive(Debug)]
pub(crate) struct Winding {
    /// Per triangle: flip it to make its patch consistent. In each patch the
    /// winding shared by the majority of its triangles is kept (ties: the one
    /// of its first triangle).
    pub flip: Vec<bool>,
    /// First triangle of each patch that admits no consistent winding.
    pub nonorientable_patches: Vec<usize>,
}

/// Breadth-first propagation of the first triangle's winding across manifold
/// edges, patch by patch (O(F), iterative).
pub(crate) fn propagate_winding(triangles: &[[u32; 3]], he: &HalfEdges) -> Winding {
    let n = triangles.len();
    let mut flip = vec![false; n];
    let mut seen = vec![false; n];
    let mut nonorientable_patches = Vec::new();
    let mut patch = Vec::new();
    for seed in 0..n {
        if seen[seed] || is_collapsed(&triangles[seed]) {
            continue;
        }
        seen[seed] = true;
        patch.clear();
        patch.push(seed);
        let mut orientable = true;
        let mut head = 0;
        while let Some(&t) = patch.get(head) {
            head += 1;
            for h in 3 * t..3 * t + 3 {
                let g = he.twin[h];
                if g == NONE {
                    continue;
                }
                let u = g / 3;
                let want = flip[t] ^ (tail(triangles, h) == tail(triangles, g));
                if !seen[u] {
                    seen[u] = true;
                    flip[u] = want;
                    patch.push(u);
                } else if flip[u] != want {
                    orientable = false;
                }
            }
        }
        if !orientable {
            nonorientable_patches.push(seed);
        } else if 2 * patch.iter().filter(|&&t| flip[t]).count() > patch.len() {
            for &t in &patch {
                flip[t] = !flip[t];
            }
        }
    }
    Winding {
        flip,
        nonorientable_patches,
    }
}

/// Per-component accumulator.
#[derive(Debug, Clone)]
struct Tally {
    first_triangle: usize,
    triangles: usize,
    vertices: usize,
    edges: usize,
    boundary_edges: usize,
    nonmanifold_edges: usize,
    nonmanifold_vertices: usize,
    inconsistent_edges: usize,
    orientable: bool,
    area: f64,
    weighted_centroid: DVec3,
    vertex_sum: DVec3,
    lo: DVec3,
    hi: DVec3,
    signed_volume: f64,
}

impl Tally {
    fn new(first_triangle: usize) -> Self {
        Tally {
            first_triangle,
            triangles: 0,
            vertices: 0,
            edges: 0,
            boundary_edges: 0,
            nonmanifold_edges: 0,
            nonmanifold_vertices: 0,
            inconsistent_edges: 0,
            orientable: true,
            area: 0.0,
            weighted_centroid: DVec3::ZERO,
            vertex_sum: DVec3::ZERO,
            lo: DVec3::splat(f64::INFINITY),
            hi: DVec3::splat(f64::NEG_INFINITY),
            signed_volume: 0.0,
        }
    }

    /// Area-weighted centroid; the vertex mean when the area is zero.
    fn centroid(&self) -> DVec3 {
        if self.area > 0.0 {
            self.weighted_centroid / self.area
        } else {
            self.vertex_sum / self.vertices.max(1) as f64
        }
    }

    fn finish(&self) -> Component {
        let closed = self.boundary_edges == 0;
        let manifold = self.nonmanifold_edges == 0 && self.nonmanifold_vertices == 0;
        let euler = self.vertices as i64 - self.edges as i64 + self.triangles as i64;
        let consistently_oriented = self.inconsistent_edges == 0;
        let diagonal = (self.hi - self.lo).length();
        let orientation = if !consistently_oriented {
            Orientation::Mixed
        } else if self.signed_volume.abs() <= ORIENTATION_TOLERANCE * self.area * diagonal {
            Orientation::Undetermined
        } else if self.signed_volume > 0.0 {
            Orientation::Outward
        } else {
            Orientation::Inward
        };
        Component {
            first_triangle: self.first_triangle,
            triangles: self.triangles,
            vertices: self.vertices,
            edges: self.edges,
            boundary_edges: self.boundary_edges,
            nonmanifold_edges: self.nonmanifold_edges,
            nonmanifold_vertices: self.nonmanifold_vertices,
            closed,
            manifold,
            consistently_oriented,
            orientable: self.orientable,
            euler,
            genus: (closed && manifold && self.orientable).then_some((2 - euler) / 2),
            area: self.area,
            signed_volume: self.signed_volume,
            orientation,
        }
    }
}

/// `(p1 − p0) × (p2 − p0)` in f64: twice the area vector. Swapping `p1` and
/// `p2` negates it exactly.
fn doubled_area_vector(p: [DVec3; 3]) -> DVec3 {
    (p[1] - p[0]).cross(p[2] - p[0])
}

/// Whether the triangle `p` has zero area in the sense of
/// [`Topology::degenerate_triangles`]: its height (in f64) is below
/// `f32::EPSILON` times its longest edge.
pub(crate) fn is_flat(p: [DVec3; 3]) -> bool {
    let longest = (p[1] - p[0])
        .length_squared()
        .max((p[2] - p[1]).length_squared())
        .max((p[0] - p[2]).length_squared());
    doubled_area_vector(p).length() <= f64::from(f32::EPSILON) * longest
}

fn corners(mesh: &TriMesh, tri: &[u32; 3]) -> [DVec3; 3] {
    tri.map(|v| mesh.positions[v as usize].as_dvec3())
}

/// Boundary edges walked into loops and open chains through vertex fans.
///
/// Every boundary edge joins the fans of its two end corners; a fan holds at
/// most two boundary edges (its triangles form a path around the vertex), so
/// these links form disjoint paths (ending at non-manifold edges) and cycles.
fn walk_boundary(he: &HalfEdges, fans: &mut UnionFind<usize>) -> (Vec<usize>, Vec<usize>) {
    let ends: Vec<[usize; 2]> = (0..he.n_edges())
        .filter(|&e| he.uses[e] == 1)
        .map(|e| {
            let h = he.first[e];
            let next = 3 * (h / 3) + (h % 3 + 1) % 3;
            [fans.find(h), fans.find(next)]
        })
        .collect();
    let mut at_fan: Vec<(usize, usize)> = ends
        .iter()
        .enumerate()
        .flat_map(|(b, &[f0, f1])| [(f0, b), (f1, b)])
        .collect();
    at_fan.sort_unstable();
    let edges_at = |f: usize| {
        let lo = at_fan.partition_point(|&(g, _)| g < f);
        let hi = at_fan.partition_point(|&(g, _)| g <= f);
        &at_fan[lo..hi]
    };
    let mut used = vec![false; ends.len()];
    let walk = |start_fan: usize, start_edge: usize, used: &mut Vec<bool>| {
        let (mut fan, mut edge, mut len) = (start_fan, start_edge, 0);
        loop {
            used[edge] = true;
            len += 1;
            fan = if ends[edge][0] == fan {
                ends[edge][1]
            } else {
                ends[edge][0]
            };
            match edges_at(fan).iter().find(|&&(_, b)| !used[b]) {
                Some(&(_, b)) => edge = b,
                None => return (len, fan == start_fan),
            }
        }
    };
    let mut loops = Vec::new();
    let mut chains = Vec::new();
    let chain_starts: Vec<(usize, usize)> = at_fan
        .chunk_by(|x, y| x.0 == y.0)
        .filter(|g| g.len() == 1)
        .map(|g| g[0])
        .collect();
    for (fan, b) in chain_starts {
        if !used[b] {
            chains.push(walk(fan, b, &mut used).0);
        }
    }
    for b in 0..ends.len() {
        if !used[b] {
            match walk(ends[b][0], b, &mut used) {
                (len, true) => loops.push(len),
                (len, false) => chains.push(len),
            }
        }
    }
    loops.sort_unstable_by(|a, b| b.cmp(a));
    chains.sort_unstable_by(|a, b| b.cmp(a));
    (loops, chains)
}

/// [`Topology`] plus the component of every triangle (index into
/// `components`, `NONE` for collapsed triangles).
#[derive(Debug)]
pub(crate) struct Analysis {
    pub topology: Topology,
    pub triangle_component: Vec<usize>,
}

/// Computes every figure; see [`Topology::of`].
pub(crate) fn analyse(mesh: &TriMesh) -> Analysis {
    let tris = &mesh.triangles;
    let (nv, nt) = (mesh.positions.len(), tris.len());

    let mut used = vec![false; nv];
    let mut collapsed = 0;
    let mut degenerate = 0;
    for tri in tris {
        if is_collapsed(tri) {
            collapsed += 1;
            degenerate += 1;
            continue;
        }
        if is_flat(corners(mesh, tri)) {
            degenerate += 1;
        }
        for &v in tri {
            used[v as usize] = true;
        }
    }

    let he = HalfEdges::of(tris);

    // Corners (3t + k) around the same vertex joined across manifold edges:
    // each resulting set is one fan.
    let mut fans = UnionFind::<usize>::with_len(3 * nt);
    for (h, &g) in he.twin.iter().enumerate() {
        if g == NONE || g < h {
            continue;
        }
        let (hn, gn) = (3 * (h / 3) + (h % 3 + 1) % 3, 3 * (g / 3) + (g % 3 + 1) % 3);
        if tail(tris, h) == tail(tris, g) {
            fans.union(h, g);
            fans.union(hn, gn);
        } else {
            fans.union(h, gn);
            fans.union(hn, g);
        }
    }
    let mut nonmanifold_vertex = vec![false; nv];
    let mut fan_count = vec![0u32; nv];
    for (t, tri) in tris.iter().enumerate() {
        if is_collapsed(tri) {
            continue;
        }
        for (k, &v) in tri.iter().enumerate() {
            if fans.is_root(3 * t + k) {
                fan_count[v as usize] += 1;
            }
        }
    }
    for (v, &c) in fan_count.iter().enumerate() {
        nonmanifold_vertex[v] = c > 1;
    }
    for e in 0..he.n_edges() {
        if he.uses[e] > 2 {
            let h = he.first[e];
            let next = 3 * (h / 3) + (h % 3 + 1) % 3;
            nonmanifold_vertex[tail(tris, h) as usize] = true;
            nonmanifold_vertex[tail(tris, next) as usize] = true;
        }
    }

    // Components: triangles sharing vertices; provisional ids by first triangle.
    let mut vertex_sets = UnionFind::<usize>::with_len(nv);
    for tri in tris.iter().filter(|t| !is_collapsed(t)) {
        vertex_sets.union(tri[0] as usize, tri[1] as usize);
        vertex_sets.union(tri[0] as usize, tri[2] as usize);
    }
    let mut root_component = vec![NONE; nv];
    let mut tallies: Vec<Tally> = Vec::new();
    let mut triangle_component = vec![NONE; nt];
    for (t, tri) in tris.iter().enumerate() {
        if is_collapsed(tri) {
            continue;
        }
        let root = vertex_sets.find(tri[0] as usize);
        if root_component[root] == NONE {
            root_component[root] = tallies.len();
            tallies.push(Tally::new(t));
        }
        let c = root_component[root];
        triangle_component[t] = c;
        let p = corners(mesh, tri);
        let area = 0.5 * doubled_area_vector(p).length();
        let tally = &mut tallies[c];
        tally.triangles += 1;
        tally.area += area;
        tally.weighted_centroid += area * (p[0] + p[1] + p[2]) / 3.0;
    }
    for v in (0..nv).filter(|&v| used[v]) {
        let tally = &mut tallies[root_component[vertex_sets.find(v)]];
        let p = mesh.positions[v].as_dvec3();
        tally.vertices += 1;
        tally.vertex_sum += p;
        tally.lo = tally.lo.min(p);
        tally.hi = tally.hi.max(p);
        tally.nonmanifold_vertices += usize::from(nonmanifold_vertex[v]);
    }
    let mut inconsistent_edges = 0;
    for e in 0..he.n_edges() {
        let h = he.first[e];
        let tally = &mut tallies[triangle_component[h / 3]];
        tally.edges += 1;
        match he.uses[e] {
            1 => tally.boundary_edges += 1,
            2 => {
                if tail(tris, h) == tail(tris, he.twin[h]) {
                    tally.inconsistent_edges += 1;
                    inconsistent_edges += 1;
                }
            }
            _ => tally.nonmanifold_edges += 1,
        }
    }
    let centroids: Vec<DVec3> = tallies.iter().map(Tally::centroid).collect();
    for (t, tri) in tris.iter().enumerate() {
        let c = triangle_component[t];
        if c == NONE {
            continue;
        }
        let p = corners(mesh, tri);
        tallies[c].signed_volume += (p[0] - centroids[c]).dot(doubled_area_vector(p)) / 6.0;
    }
    for seed in propagate_winding(tris, &he).nonorientable_patches {
        tallies[triangle_component[seed]].orientable = false;
    }

    // Final order: triangle count descending, then first triangle.
    let mut order: Vec<usize> = (0..tallies.len()).collect();
    order.sort_by_key(|&c| {
        (
            std::cmp::Reverse(tallies[c].triangles),
            tallies[c].first_triangle,
        )
    });
    let mut rank = vec![0; tallies.len()];
    for (r, &c) in order.iter().enumerate() {
        rank[c] = r;
    }
    for c in triangle_component.iter_mut().filter(|c| **c != NONE) {
        *c = rank[*c];
    }
    let components: Vec<Component> = order.iter().map(|&c| tallies[c].finish()).collect();

    let (boundary_loops, open_boundary_chains) = walk_boundary(&he, &mut fans);
    let count_uses = |pred: fn(usize) -> bool| he.uses.iter().filter(|&&u| pred(u)).count();
    let used_vertices = used.iter().filter(|&&u| u).count();
    let boundary_edges = count_uses(|u| u == 1);
    let live_triangles = nt - collapsed;
    let topology = Topology {
        vertices: nv,
        used_vertices,
        triangles: nt,
        degenerate_triangles: degenerate,
        collapsed_triangles: collapsed,
        edges: he.n_edges(),
        boundary_edges,
        manifold_edges: count_uses(|u| u == 2),
        nonmanifold_edges: count_uses(|u| u > 2),
        nonmanifold_vertices: nonmanifold_vertex.iter().filter(|&&b| b).count(),
        boundary_loops,
        open_boundary_chains,
        euler: used_vertices as i64 - he.n_edges() as i64 + live_triangles as i64,
        closed: live_triangles > 0 && boundary_edges == 0,
        consistently_oriented: inconsistent_edges == 0,
        orientation: overall_orientation(&components),
        area: components.iter().map(|c| c.area).sum(),
        signed_volume: components.iter().map(|c| c.signed_volume).sum(),
        bounds: mesh.bounds().map(|(min, max)| Aabb { min, max }),
        components,
    };
    Analysis {
        topology,
        triangle_component,
    }
}

/// The whole-mesh rule documented on [`Topology::orientation`].
fn overall_orientation(components: &[Component]) -> Orientation {
    let mut verdict = Orientation::Undetermined;
    for c in components {
        verdict = match (verdict, c.orientation) {
            (_, Orientation::Mixed) => return Orientation::Mixed,
            (v, Orientation::Undetermined) => v,
            (Orientation::Undetermined, o) => o,
            (v, o) if v == o => v,
            _ => return Orientation::Mixed,
        };
    }
    verdict
}

impl Topology {
    /// All figures of `mesh` in O(F log F).
    ///
    /// `mesh` must have in-range indices (as [`TriMesh::new`], every reader
    /// and [`TriMesh::validate`] guarantee); an out-of-range index panics.
    pub fn of(mesh: &TriMesh) -> Topology {
        analyse(mesh).topology
    }

    /// No non-manifold edges and no non-manifold vertices (boundaries allowed).
    pub fn is_manifold(&self) -> bool {
        self.nonmanifold_edges == 0 && self.nonmanifold_vertices == 0
    }
}
