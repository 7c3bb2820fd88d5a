//! Hierarchical bounding boxes in a B+ tree (seed 004 §2).
//!
//! Per group one tree: group → layer (cell layer z) → row (cell row y) →
//! cell (leaf, cell x) → triangles. Every node carries the bounding box of
//! the triangles below it; the leaves of a group are chained in (z, y, x)
//! order (`next`), giving the seed's second search path along the leaves. A
//! model is a [`Forest`]: one tree per group, stored flat (one array per
//! level, children as index spans), which is how the cut walks it.
//!
//! Marching-cubes surfaces use the real cell grid (each triangle remembers
//! its cell, recorded in the same pass that makes it), grouped into leaf
//! blocks of `mc::LEAF_BLOCK`³ cells as the build sorts them; any other
//! mesh (a file, a triangulated knife) gets a virtual grid over its
//! bounding box.

mod build;

use glam::Vec3;
use rayon::prelude::*;

use super::aabb::Aabb;
use super::union_find::vertex_components;
use build::{
    KeyGrid, LayerRun, PART_TRIANGLES, PARTS_PER_THREAD, Part, layer_runs, order_by_group_and_layer,
};

/// Target triangles per leaf of a virtual grid ([`Forest::from_triangles`]).
pub const LEAF_TRIANGLES: usize = 32;

/// Most distinct vertices one leaf lists ([`Forest::corners`] are 16-bit
/// offsets into them). A marching-cubes leaf block lists a few hundred at
/// most; a cell of a virtual grid whose triangles list more (a dense patch
/// far smaller than the mesh's box) gets several leaves with the same key.
pub const LEAF_VERTICES: usize = 1 << 16;

/// A triangle mesh as the forest reads it: positions and vertex-index
/// triples (the host mesh type lies in a layer above).
#[derive(Debug, Clone, Copy)]
pub struct MeshView<'a> {
    /// #V vertex positions.
    pub positions: &'a [Vec3],
    /// #F triangles as vertex-index triples into `positions`.
    pub triangles: &'a [[u32; 3]],
}

/// A forest over a virtual grid with the groups it was built from
/// ([`Forest::from_triangles`]).
#[derive(Debug, Clone, Default)]
pub struct GroupedForest {
    pub forest: Forest,
    /// Per triangle, its vertex-connected component (numbered by first
    /// triangle).
    pub groups: Vec<u32>,
    /// Number of components.
    pub n_groups: usize,
}
/// A half-open span `start..end` of child indices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Span {
    pub start: u32,
    pub end: u32,
}

impl Span {
    /// As a `usize` range.
    pub fn range(self) -> std::ops::Range<usize> {
        self.start as usize..self.end as usize
    }

    /// Number of children.
    pub fn len(self) -> usize {
        (self.end - self.start) as usize
    }

    /// Whether the span is empty.
    pub fn is_empty(self) -> bool {
        self.end == self.start
    }
}

/// Root of one group's tree: its layers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroupNode {
    pub bbox: Aabb,
    /// Span of [`Forest::layers`].
    pub layers: Span,
}

/// A layer node (cells of one z layer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerNode {
    pub z: u32,
    pub bbox: Aabb,
    /// Span of [`Forest::rows`].
    pub rows: Span,
}

/// A row node (cells of one y row inside a layer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RowNode {
    pub y: u32,
    pub bbox: Aabb,
    /// Span of [`Forest::cells`].
    pub cells: Span,
}

/// A leaf: the triangles of one cell of one group (or a run of them, see
/// [`LEAF_VERTICES`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellNode {
    pub x: u32,
    pub bbox: Aabb,
    /// Span of [`Forest::triangles`] (and of [`Forest::corners`]).
    pub triangles: Span,
    /// Span of [`Forest::leaf_vertices`]: the leaf's distinct vertices.
    pub vertices: Span,
    /// Next leaf of the same group in (z, y, x) order; `u32::MAX` at the end.
    pub next: u32,
}

/// The B+ tree forest of a model (one tree per group).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Forest {
    /// Leaf grid size `[cx, cy, cz]` (in leaf blocks of cells) the leaves'
    /// `x`, the rows' `y` and the layers' `z` refer to.
    pub cell_dims: [usize; 3],
    pub groups: Vec<GroupNode>,
    pub layers: Vec<LayerNode>,
    pub rows: Vec<RowNode>,
    pub cells: Vec<CellNode>,
    /// Triangle ids ordered by (group, cell); leaves index this.
    pub triangles: Vec<u32>,
    /// Per entry of `triangles`, its corners as offsets into its leaf's
    /// vertices (`leaf_vertices[vertices.start + offset]`), in the
    /// triangle's winding: a query evaluates each vertex of a leaf once and
    /// tests the leaf's triangles from a contiguous table.
    pub corners: Vec<[u16; 3]>,
    /// Per leaf, its distinct mesh vertex ids, in order of first use by
    /// the leaf's triangles (in `triangles` order, corners in winding
    /// order).
    pub leaf_vertices: Vec<u32>,
    /// The positions of `leaf_vertices` (a copy, so that a query reads each
    /// leaf's vertices as one contiguous run instead of gathering them).
    pub leaf_positions: Vec<Vec3>,
    /// Vertex count of the mesh the forest was built for.
    pub n_vertices: usize,
    /// Whether the boxes are sorted along their keys: in every row the
    /// cells' `min.x` and `max.x` never decrease, likewise the rows' `y`
    /// bounds in every layer and the layers' `z` bounds in every group. True
    /// for marching-cubes forests (a cell's triangles stay inside the cell);
    /// it lets a query find the children a slab can touch by binary search
    /// (seed §4.3) instead of testing every child box.
    pub axis_sorted: bool,
    /// Whether the surface is known to be closed and wound outward: set for
    /// marching-cubes surfaces closed at the volume border (watertight, and
    /// the case table winds every triangle outward, so together they enclose
    /// the solid's positive volume). A cut then skips the orientation
    /// analysis of the whole mesh that sphere caps and triangulated knives
    /// otherwise need; false (unknown) for any other mesh.
    pub closed_outward: bool,
}

impl Forest {
    /// Builds the forest from per-triangle cell keys (`x + cx·(y + cy·z)`
    /// on a grid of `cell_dims` cells) and group ids (`0..n_groups`), one
    /// leaf per block of `leaf_block`³ cells (a power of two; another value
    /// counts as the power of two below it; 1: a leaf per cell). The tree's
    /// layers, rows and leaves are those of the block grid.
    ///
    /// Triangles are ordered by (group, block, id): one stable counting sort
    /// by group, which keeps each group's triangles in block-layer order when
    /// the layers never decrease along the ids (marching cubes emits
    /// triangles in cell order; otherwise a counting sort by layer comes
    /// first), then every (group, layer) run is sorted by block on its own.
    /// The runs, with their rows, leaves, boxes and leaf vertex tables, are
    /// built in parallel in contiguous parts and concatenated in order, so
    /// the forest does not depend on the number of threads.
    pub fn build(
        mesh: MeshView<'_>,
        cells: &[u32],
        cell_dims: [usize; 3],
        leaf_block: usize,
        groups: &[u32],
        n_groups: usize,
    ) -> Forest {
        let grid = KeyGrid::new(cell_dims, leaf_block.max(1).ilog2());
        let block_layer = grid.cells_per_block_layer();
        let (mut order, group_starts) =
            order_by_group_and_layer(cells, block_layer, groups, n_groups);
        let runs = layer_runs(&order, &group_starts, cells, block_layer);
        // Several parts per thread, so that a thread that comes back from
        // work beside the build (marching cubes' figure passes) finds parts
        // left to take; one part on one thread (each further part is copied
        // once more when the parts are concatenated).
        let threads = rayon::current_num_threads();
        let per_thread = if threads > 1 { PARTS_PER_THREAD } else { 1 };
        let n_parts = (order.len() / PART_TRIANGLES).clamp(1, per_thread * threads);
        let target = order.len().div_ceil(n_parts).max(1);
        let mut corners = vec![[0u16; 3]; order.len()];
        // Contiguous parts of whole runs, each with its slices of `order`
        // and `corners`.
        let mut jobs = Vec::with_capacity(n_parts);
        let (mut rest, mut rest_corners) = (order.as_mut_slice(), corners.as_mut_slice());
        let (mut first, mut taken) = (0usize, 0usize);
        for (i, r) in runs.iter().enumerate() {
            if r.end - taken >= target || i + 1 == runs.len() {
                let (part, tail) = rest.split_at_mut(r.end - taken);
                let (part_corners, tail_corners) = rest_corners.split_at_mut(r.end - taken);
                jobs.push((part, part_corners, &runs[first..=i]));
                (rest, rest_corners) = (tail, tail_corners);
                (first, taken) = (i + 1, r.end);
            }
        }
        let n_vertices = mesh.positions.len();
        let parts: Vec<Part> = jobs
            .into_par_iter()
            .map(|(slice, corners, runs)| {
                let base = runs[0].start;
                let mut part = Part::new(corners, base);
                for r in runs {
                    part.layer(
                        mesh,
                        cells,
                        grid,
                        r,
                        &mut slice[r.start - base..r.end - base],
                    );
                }
                part
            })
            .collect();
        let mut f = Forest {
            cell_dims: grid.blocks,
            n_vertices,
            ..Forest::default()
        };
        f.concatenate(parts, &runs);
        f.corners = corners;
        f.triangles = order;
        f.axis_sorted = f.boxes_sorted();
        f
    }

    /// Reads one word of every cache line of leaf `c`'s tables, folded into
    /// one value: done for many leaves before their tables are used, the
    /// loads are independent, so their cache misses overlap.
    pub(crate) fn touch_leaf(&self, c: &CellNode) -> u32 {
        let (t, v) = (c.triangles.range(), c.vertices.range());
        let line = |size: usize| 64 / size;
        (self.corners[t.clone()].iter().step_by(line(6))).fold(0, |a, x| a ^ u32::from(x[0]))
            ^ (self.triangles[t].iter().step_by(line(4))).fold(0, |a, x| a ^ x)
            ^ (self.leaf_vertices[v.clone()].iter().step_by(line(4))).fold(0, |a, x| a ^ x)
            ^ (self.leaf_positions[v].iter().step_by(line(12))).fold(0, |a, x| a ^ x.x.to_bits())
    }

    /// Takes the first part's nodes and leaf tables as the forest's (their
    /// spans are already global: no copy), appends the other parts' (their
    /// spans shifted to the concatenation) and makes the group nodes over
    /// `runs` (one layer node per run, in order).
    fn concatenate(&mut self, parts: Vec<Part<'_>>, runs: &[LayerRun]) {
        let mut parts = parts.into_iter();
        if let Some(p) = parts.next() {
            self.layers = p.layers;
            self.rows = p.rows;
            self.cells = p.cells;
            self.leaf_vertices = p.leaf_vertices;
            self.leaf_positions = p.leaf_positions;
        }
        let rest: Vec<Part<'_>> = parts.collect();
        let total = |f: fn(&Part) -> usize| rest.iter().map(f).sum::<usize>();
        self.layers.reserve_exact(total(|p| p.layers.len()));
        self.rows.reserve_exact(total(|p| p.rows.len()));
        self.cells.reserve_exact(total(|p| p.cells.len()));
        self.leaf_vertices
            .reserve_exact(total(|p| p.leaf_vertices.len()));
        self.leaf_positions
            .reserve_exact(total(|p| p.leaf_positions.len()));
        for p in rest {
            let rows = self.rows.len() as u32;
            let cells = self.cells.len() as u32;
            let vertices = self.leaf_vertices.len() as u32;
            let shift = |s: Span, by: u32| Span {
                start: s.start + by,
                end: s.end + by,
            };
            self.layers.extend(p.layers.iter().map(|l| LayerNode {
                rows: shift(l.rows, rows),
                ..*l
            }));
            self.rows.extend(p.rows.iter().map(|r| RowNode {
                cells: shift(r.cells, cells),
                ..*r
            }));
            self.cells.extend(p.cells.iter().map(|c| CellNode {
                vertices: shift(c.vertices, vertices),
                next: if c.next == u32::MAX {
                    u32::MAX
                } else {
                    c.next + cells
                },
                ..*c
            }));
            self.leaf_vertices.extend_from_slice(&p.leaf_vertices);
            self.leaf_positions.extend_from_slice(&p.leaf_positions);
        }
        let mut first = 0usize;
        for (i, r) in runs.iter().enumerate() {
            if r.last_of_group {
                let bbox = self.layers[first..=i]
                    .iter()
                    .fold(Aabb::EMPTY, |b, l| b.union(l.bbox));
                self.groups.push(GroupNode {
                    bbox,
                    layers: Span {
                        start: first as u32,
                        end: i as u32 + 1,
                    },
                });
                first = i + 1;
            }
        }
    }

    /// Whether every level's child boxes are sorted along its axis (see
    /// [`Forest::axis_sorted`]).
    fn boxes_sorted(&self) -> bool {
        fn sorted<'a>(mut it: impl Iterator<Item = &'a Aabb>, axis: usize) -> bool {
            let Some(first) = it.next() else {
                return true;
            };
            let mut prev = (first.min[axis], first.max[axis]);
            it.all(|b| {
                let ok = b.min[axis] >= prev.0 && b.max[axis] >= prev.1;
                prev = (b.min[axis], b.max[axis]);
                ok
            })
        }
        self.groups
            .iter()
            .all(|g| sorted(self.layers[g.layers.range()].iter().map(|l| &l.bbox), 2))
            && self
                .layers
                .iter()
                .all(|l| sorted(self.rows[l.rows.range()].iter().map(|r| &r.bbox), 1))
            && self
                .rows
                .iter()
                .all(|r| sorted(self.cells[r.cells.range()].iter().map(|c| &c.bbox), 0))
    }

    /// A forest for any mesh: groups = vertex-connected components
    /// (numbered by first triangle), cells of a virtual grid over the mesh's
    /// bounding box with about [`LEAF_TRIANGLES`] triangles per occupied cell, each
    /// triangle in the cell of its centroid.
    pub fn from_triangles(mesh: MeshView<'_>) -> GroupedForest {
        let (groups, n_groups) = vertex_components(mesh.positions.len(), mesh.triangles);
        let Some(first) = mesh.positions.first() else {
            return GroupedForest {
                forest: Forest::default(),
                groups,
                n_groups,
            };
        };
        let (lo, hi) =
            (mesh.positions.iter()).fold((*first, *first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let extent = (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
        let target = (mesh.triangles.len() as f64 / LEAF_TRIANGLES as f64).max(1.0);
        // Cell edge h with (extent/h)^2 ≈ target (surfaces fill ~ a 2-D set).
        let area = f64::from(extent.x * extent.y + extent.y * extent.z + extent.z * extent.x);
        let h = ((area / target).sqrt() as f32).max(extent.max_element() / 1024.0);
        let dims = [
            ((extent.x / h) as usize + 1).min(1024),
            ((extent.y / h) as usize + 1).min(1024),
            ((extent.z / h) as usize + 1).min(1024),
        ];
        let p = mesh.positions;
        let cells: Vec<u32> = mesh
            .triangles
            .par_iter()
            .map(|t| {
                let c = (p[t[0] as usize] + p[t[1] as usize] + p[t[2] as usize]) / 3.0;
                let q = ((c - lo) / extent).clamp(Vec3::ZERO, Vec3::ONE);
                let ix = |v: f32, d: usize| ((v * d as f32) as usize).min(d - 1);
                (ix(q.x, dims[0]) + dims[0] * (ix(q.y, dims[1]) + dims[1] * ix(q.z, dims[2])))
                    as u32
            })
            .collect();
        let forest = Forest::build(mesh, &cells, dims, 1, &groups, n_groups);
        GroupedForest {
            forest,
            groups,
            n_groups,
        }
    }

    /// The leaves whose boxes meet `b` (closed boxes), walking down only
    /// through nodes whose boxes meet it.
    pub fn leaves_overlapping<'a>(
        &'a self,
        b: &'a Aabb,
    ) -> impl Iterator<Item = &'a CellNode> + 'a {
        self.groups
            .iter()
            .filter(move |g| g.bbox.overlaps(b))
            .flat_map(move |g| {
                self.layers[g.layers.range()]
                    .iter()
                    .filter(move |l| l.bbox.overlaps(b))
            })
            .flat_map(move |l| {
                self.rows[l.rows.range()]
                    .iter()
                    .filter(move |r| r.bbox.overlaps(b))
            })
            .flat_map(move |r| {
                self.cells[r.cells.range()]
                    .iter()
                    .filter(move |c| c.bbox.overlaps(b))
            })
    }

    /// Appends the triangles of every leaf whose box meets `b`: a superset
    /// of the triangles whose own boxes meet it.
    pub fn overlapping(&self, b: &Aabb, out: &mut Vec<u32>) {
        for c in self.leaves_overlapping(b) {
            out.extend_from_slice(&self.triangles[c.triangles.range()]);
        }
    }

    /// Total number of nodes (groups + layers + rows + cells).
    pub fn n_nodes(&self) -> usize {
        self.groups.len() + self.layers.len() + self.rows.len() + self.cells.len()
    }

    /// Triangle ids of group `g` in leaf order.
    pub fn group_triangles(&self, g: usize) -> &[u32] {
        let Some(node) = self.groups.get(g) else {
            return &[];
        };
        let first = self.rows[self.layers[node.layers.start as usize].rows.start as usize]
            .cells
            .start as usize;
        let last_layer = &self.layers[node.layers.end as usize - 1];
        let last = self.rows[last_layer.rows.end as usize - 1].cells.end as usize - 1;
        &self.triangles
            [self.cells[first].triangles.start as usize..self.cells[last].triangles.end as usize]
    }
}

/// The nodes among `nodes` (boxes sorted along `axis`, see
/// [`Forest::axis_sorted`]) whose extent along `axis` can meet the closed
/// interval `[lo, hi]` (seed §4.3): a binary search for the first whose
/// `max` reaches `lo`, then the run while `min` stays within `hi` (the
/// nodes a caller visits anyway, instead of a second binary search).
/// `[−∞, ∞]` gives every node, sorted or not. Yields (index, node).
pub fn sorted_overlap<'a, T>(
    nodes: &'a [T],
    bbox: impl Fn(&T) -> &Aabb + 'a,
    axis: usize,
    lo: f64,
    hi: f64,
) -> impl Iterator<Item = (usize, &'a T)> + 'a {
    let start = nodes.partition_point(|n| f64::from(bbox(n).max[axis]) < lo);
    (start..)
        .zip(&nodes[start..])
        .take_while(move |(_, n)| hi == f64::INFINITY || f64::from(bbox(n).min[axis]) <= hi)
}
