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
//! blocks of [`LEAF_BLOCK`]³ cells; any other mesh (a file, a triangulated
//! knife) gets a virtual grid over its bounding box.

use std::sync::atomic::{AtomicU32, Ordering};

use glam::{Vec3, Vec3A};
use rayon::prelude::*;

use super::cpu::AtomicUnionFind;
use crate::TriMesh;

/// Edge of a leaf block in marching-cubes cells. The seed's leaf is one
/// voxel cell (≈ 2 triangles); a leaf of 4³ cells (≈ 30 triangles on a
/// surface) makes the tree ~50× smaller and the cut query several times
/// faster, while keeping the same layer → row → cell structure.
pub const LEAF_BLOCK: usize = 4;

/// Target triangles per leaf of a virtual grid ([`Forest::from_mesh`]).
pub const LEAF_TRIANGLES: usize = 32;

/// Axis-aligned box; empty when `min > max`. Serialises as
/// `{"min": [x, y, z], "max": [x, y, z]}`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (neutral for [`Aabb::union`]).
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// Box of a triangle.
    pub fn triangle(a: Vec3, b: Vec3, c: Vec3) -> Aabb {
        Aabb {
            min: a.min(b).min(c),
            max: a.max(b).max(c),
        }
    }

    /// Smallest box holding both.
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Whether the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Whether the boxes share a point (closed boxes).
    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }

    /// The eight corners.
    pub fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }
}

impl serde::Serialize for Aabb {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut st = s.serialize_struct("Aabb", 2)?;
        st.serialize_field("min", &self.min.to_array())?;
        st.serialize_field("max", &self.max.to_array())?;
        st.end()
    }
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

/// A leaf: the triangles of one cell of one group.
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
    /// Cell grid size `[cx, cy, cz]` the cell keys refer to.
    pub cell_dims: [usize; 3],
    pub groups: Vec<GroupNode>,
    pub layers: Vec<LayerNode>,
    pub rows: Vec<RowNode>,
    pub cells: Vec<CellNode>,
    /// Triangle ids ordered by (group, cell); leaves index this.
    pub triangles: Vec<u32>,
    /// Per entry of `triangles`, its corners as indices into
    /// `leaf_vertices` (inside its leaf's `vertices` span), in the
    /// triangle's winding: a query evaluates each vertex of a leaf once and
    /// tests the leaf's triangles from a contiguous table.
    pub corners: Vec<[u32; 3]>,
    /// Per leaf, its distinct mesh vertex ids, ascending.
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
    /// Builds the forest from per-triangle cell keys (`x + cx·(y + cy·z)`)
    /// and group ids (`0..n_groups`).
    ///
    /// Triangles are ordered by (group, cell, id): one stable counting sort
    /// by group, which keeps each group's triangles in cell-layer order when
    /// the layers never decrease along the ids (marching cubes emits
    /// triangles in cell order; otherwise a counting sort by layer comes
    /// first), then every (group, layer) run is sorted by cell on its own.
    /// The runs, with their rows, leaves, boxes and leaf vertex tables, are
    /// built in parallel in contiguous parts and concatenated in order, so
    /// the forest does not depend on the number of threads.
    pub fn build(
        mesh: &TriMesh,
        cells: &[u32],
        cell_dims: [usize; 3],
        groups: &[u32],
        n_groups: usize,
    ) -> Forest {
        let [cx, cy, _] = cell_dims.map(|d| d.max(1));
        let grid = KeyGrid {
            cx,
            cy,
            layer: cx * cy,
        };
        let (mut order, group_starts) =
            order_by_group_and_layer(cells, grid.layer, groups, n_groups);
        let runs = layer_runs(&order, &group_starts, cells, grid.layer);
        let n_parts = (order.len() / PART_TRIANGLES).clamp(1, rayon::current_num_threads());
        let target = order.len().div_ceil(n_parts).max(1);
        // Contiguous parts of whole runs, each with its slice of `order`.
        let mut jobs: Vec<(&mut [u32], &[LayerRun])> = Vec::with_capacity(n_parts);
        let (mut rest, mut first, mut taken) = (order.as_mut_slice(), 0usize, 0usize);
        for (i, r) in runs.iter().enumerate() {
            if r.end - taken >= target || i + 1 == runs.len() {
                let (part, tail) = rest.split_at_mut(r.end - taken);
                jobs.push((part, &runs[first..=i]));
                (rest, first, taken) = (tail, i + 1, r.end);
            }
        }
        let n_vertices = mesh.positions.len();
        let parts: Vec<Part> = jobs
            .into_par_iter()
            .map(|(slice, runs)| {
                let mut part = Part::new(n_vertices, slice.len());
                let base = runs[0].start;
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
            cell_dims,
            n_vertices,
            ..Forest::default()
        };
        f.concatenate(parts, &runs);
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
        (self.corners[t.clone()].iter().step_by(line(12))).fold(0, |a, x| a ^ x[0])
            ^ (self.triangles[t].iter().step_by(line(4))).fold(0, |a, x| a ^ x)
            ^ (self.leaf_vertices[v.clone()].iter().step_by(line(4))).fold(0, |a, x| a ^ x)
            ^ (self.leaf_positions[v].iter().step_by(line(12))).fold(0, |a, x| a ^ x.x.to_bits())
    }

    /// Appends the parts' nodes and tables (their spans shifted to the
    /// concatenation) and makes the group nodes over `runs` (one layer
    /// node per run, in order).
    fn concatenate(&mut self, parts: Vec<Part>, runs: &[LayerRun]) {
        let total = |f: fn(&Part) -> usize| parts.iter().map(f).sum::<usize>();
        self.layers.reserve_exact(runs.len());
        self.rows.reserve_exact(total(|p| p.rows.len()));
        self.cells.reserve_exact(total(|p| p.cells.len()));
        self.leaf_vertices
            .reserve_exact(total(|p| p.leaf_vertices.len()));
        self.leaf_positions
            .reserve_exact(total(|p| p.leaf_positions.len()));
        self.corners.reserve_exact(total(|p| p.corners.len()));
        for mut p in parts {
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
            if vertices > 0 {
                p.corners
                    .as_flattened_mut()
                    .iter_mut()
                    .for_each(|v| *v += vertices);
            }
            self.corners.extend_from_slice(&p.corners);
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
    /// triangle in the cell of its centroid. Returns the forest and the
    /// per-triangle group ids.
    pub fn from_mesh(mesh: &TriMesh) -> (Forest, Vec<u32>, usize) {
        let (groups, n_groups) = vertex_components(mesh.n_vertices(), &mesh.triangles);
        let Some((lo, hi)) = mesh.bounds() else {
            return (Forest::default(), groups, n_groups);
        };
        let extent = (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
        let target = (mesh.n_triangles() as f64 / LEAF_TRIANGLES as f64).max(1.0);
        // Cell edge h with (extent/h)^2 ≈ target (surfaces fill ~ a 2-D set).
        let area = f64::from(extent.x * extent.y + extent.y * extent.z + extent.z * extent.x);
        let h = ((area / target).sqrt() as f32).max(extent.max_element() / 1024.0);
        let dims = [
            ((extent.x / h) as usize + 1).min(1024),
            ((extent.y / h) as usize + 1).min(1024),
            ((extent.z / h) as usize + 1).min(1024),
        ];
        let p = &mesh.positions;
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
        let forest = Forest::build(mesh, &cells, dims, &groups, n_groups);
        (forest, groups, n_groups)
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

/// Least triangles per part of the parallel build (at most one part per
/// thread: each part zeroes a table over the mesh's vertices).
const PART_TRIANGLES: usize = 1 << 13;

/// Shape of the cell keys: key `x + cx·(y + cy·z)`, `layer = cx·cy`.
#[derive(Debug, Clone, Copy)]
struct KeyGrid {
    cx: usize,
    cy: usize,
    layer: usize,
}

/// The triangles of one group in one cell layer: `order[start..end]`.
#[derive(Debug, Clone, Copy)]
struct LayerRun {
    start: usize,
    end: usize,
    z: u32,
    /// Whether the next run belongs to another group.
    last_of_group: bool,
}

/// Nodes and leaf tables of consecutive runs; spans are local to the part
/// except the triangle spans, which index the whole order.
#[derive(Debug)]
struct Part {
    layers: Vec<LayerNode>,
    rows: Vec<RowNode>,
    cells: Vec<CellNode>,
    leaf_vertices: Vec<u32>,
    leaf_positions: Vec<Vec3>,
    corners: Vec<[u32; 3]>,
    /// Per mesh vertex: tag of the last leaf that listed it (its first
    /// triangle position + 1) and its index in `leaf_vertices` there.
    seen: Vec<[u32; 2]>,
    /// Scratch of the counting sort: bucket starts, sorted ids.
    buckets: Vec<u32>,
    sorted: Vec<u32>,
}

impl Part {
    /// An empty part for `n_triangles` triangles of a mesh of `n_vertices`.
    fn new(n_vertices: usize, n_triangles: usize) -> Part {
        Part {
            layers: Vec::new(),
            rows: Vec::new(),
            cells: Vec::new(),
            leaf_vertices: Vec::with_capacity(n_triangles),
            leaf_positions: Vec::with_capacity(n_triangles),
            corners: Vec::with_capacity(n_triangles),
            seen: vec![[0; 2]; n_vertices],
            buckets: Vec::new(),
            sorted: Vec::new(),
        }
    }

    /// Sorts `tris` (the ids of `run`, ascending) by cell and appends the
    /// run's layer node with its rows and leaves.
    fn layer(
        &mut self,
        mesh: &TriMesh,
        cells: &[u32],
        grid: KeyGrid,
        run: &LayerRun,
        tris: &mut [u32],
    ) {
        self.sort_by_cell(cells, tris, run.z as usize * grid.layer, grid.layer);
        let row_start = self.rows.len() as u32;
        let mut lbox = Aabb::EMPTY;
        let mut i = 0;
        while i < tris.len() {
            let row = cells[tris[i] as usize] as usize / grid.cx;
            let cell_start = self.cells.len() as u32;
            let mut rbox = Aabb::EMPTY;
            while i < tris.len() && cells[tris[i] as usize] as usize / grid.cx == row {
                let key = cells[tris[i] as usize];
                let end = i + tris[i..].partition_point(|&t| cells[t as usize] == key);
                let leaf = self.leaf(mesh, &tris[i..end], run.start + i);
                rbox = rbox.union(leaf.bbox);
                self.cells.push(CellNode {
                    x: (key as usize % grid.cx) as u32,
                    triangles: Span {
                        start: (run.start + i) as u32,
                        end: (run.start + end) as u32,
                    },
                    next: self.cells.len() as u32 + 1,
                    ..leaf
                });
                i = end;
            }
            self.rows.push(RowNode {
                y: (row % grid.cy) as u32,
                bbox: rbox,
                cells: Span {
                    start: cell_start,
                    end: self.cells.len() as u32,
                },
            });
            lbox = lbox.union(rbox);
        }
        if run.last_of_group
            && let Some(last) = self.cells.last_mut()
        {
            last.next = u32::MAX;
        }
        self.layers.push(LayerNode {
            z: run.z,
            bbox: lbox,
            rows: Span {
                start: row_start,
                end: self.rows.len() as u32,
            },
        });
    }

    /// Stable sort of `tris` by `cells[t]`, keys in `first..first + len`
    /// (the run's layer): a counting sort over the layer when the run is
    /// long against it, else over the keys' range when that is short, else
    /// a sort by (key, id).
    fn sort_by_cell(&mut self, cells: &[u32], tris: &mut [u32], first: usize, len: usize) {
        let key = |t: u32| cells[t as usize];
        let short = |range: usize| range <= 2 * tris.len() + 64;
        let (lo, range) = if short(len) {
            (first as u32, len)
        } else {
            let (lo, hi) = tris.iter().fold((u32::MAX, 0), |(lo, hi), &t| {
                (lo.min(key(t)), hi.max(key(t)))
            });
            if lo >= hi {
                return;
            }
            (lo, (hi - lo) as usize + 1)
        };
        if !short(range) {
            tris.sort_unstable_by_key(|&t| u64::from(key(t)) << 32 | u64::from(t));
            return;
        }
        self.buckets.clear();
        self.buckets.resize(range + 1, 0);
        for &t in tris.iter() {
            self.buckets[(key(t) - lo) as usize + 1] += 1;
        }
        for k in 0..range {
            self.buckets[k + 1] += self.buckets[k];
        }
        self.sorted.clear();
        self.sorted.resize(tris.len(), 0);
        for &t in tris.iter() {
            let b = &mut self.buckets[(key(t) - lo) as usize];
            self.sorted[*b as usize] = t;
            *b += 1;
        }
        tris.copy_from_slice(&self.sorted);
    }

    /// Appends the leaf's distinct vertices (ascending) and its triangles'
    /// corners; returns a leaf node holding its box and vertex span (the
    /// box of the distinct vertices, which is that of the triangles).
    /// `first` is the position of the leaf's first triangle in the order.
    fn leaf(&mut self, mesh: &TriMesh, tris: &[u32], first: usize) -> CellNode {
        let tag = first as u32 + 1;
        let start = self.leaf_vertices.len();
        for &t in tris {
            for v in mesh.triangles[t as usize] {
                let seen = &mut self.seen[v as usize];
                if seen[0] != tag {
                    seen[0] = tag;
                    self.leaf_vertices.push(v);
                }
            }
        }
        sort_nearly_sorted(&mut self.leaf_vertices[start..]);
        let (mut lo, mut hi) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        for (i, &v) in self.leaf_vertices[start..].iter().enumerate() {
            self.seen[v as usize][1] = (start + i) as u32;
            let p = mesh.positions[v as usize];
            self.leaf_positions.push(p);
            lo = lo.min(p.into());
            hi = hi.max(p.into());
        }
        self.corners.extend(
            tris.iter()
                .map(|&t| mesh.triangles[t as usize].map(|v| self.seen[v as usize][1])),
        );
        CellNode {
            x: 0,
            bbox: Aabb {
                min: lo.into(),
                max: hi.into(),
            },
            triangles: Span { start: 0, end: 0 },
            vertices: Span {
                start: start as u32,
                end: self.leaf_vertices.len() as u32,
            },
            next: u32::MAX,
        }
    }
}

/// Sorts ascending, by insertion when short: a leaf's vertices arrive
/// nearly in order (its triangles are in cell order and marching-cubes
/// vertex ids follow the grid).
fn sort_nearly_sorted(v: &mut [u32]) {
    if v.len() > 128 {
        v.sort_unstable();
        return;
    }
    for i in 1..v.len() {
        let x = v[i];
        let mut j = i;
        while j > 0 && v[j - 1] > x {
            v[j] = v[j - 1];
            j -= 1;
        }
        v[j] = x;
    }
}

/// Triangle ids sorted by (group, layer, id), layer `cells[t] / layer`,
/// and the start of each group's ids (`n_groups + 1` entries): one stable
/// counting sort by group when the layers never decrease along the ids,
/// else a stable counting sort by layer first.
fn order_by_group_and_layer(
    cells: &[u32],
    layer: usize,
    groups: &[u32],
    n_groups: usize,
) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; n_groups + 1];
    // Keys `lo..hi` form the current layer.
    let (mut lo, mut hi, mut monotone) = (0usize, 0usize, true);
    for (&c, &g) in cells.iter().zip(groups) {
        start[g as usize + 1] += 1;
        let c = c as usize;
        if c >= hi {
            lo = c - c % layer;
            hi = lo + layer;
        } else if c < lo {
            monotone = false;
        }
    }
    for g in 0..n_groups {
        start[g + 1] += start[g];
    }
    let mut next = start.clone();
    let mut out = vec![0u32; cells.len()];
    let mut place = |t: u32| {
        let s = &mut next[groups[t as usize] as usize];
        out[*s as usize] = t;
        *s += 1;
    };
    if monotone {
        (0..cells.len() as u32).for_each(&mut place);
    } else {
        let n_layers = cells.iter().max().map_or(0, |&m| m as usize / layer + 1);
        let mut at = vec![0u32; n_layers + 1];
        for &c in cells {
            at[c as usize / layer + 1] += 1;
        }
        for z in 0..n_layers {
            at[z + 1] += at[z];
        }
        let mut by_layer = vec![0u32; cells.len()];
        for (t, &c) in cells.iter().enumerate() {
            let a = &mut at[c as usize / layer];
            by_layer[*a as usize] = t as u32;
            *a += 1;
        }
        by_layer.into_iter().for_each(&mut place);
    }
    (out, start)
}

/// The (group, layer) runs of `order` (sorted by group, layer, id).
fn layer_runs(order: &[u32], group_starts: &[u32], cells: &[u32], layer: usize) -> Vec<LayerRun> {
    let z_of = |t: u32| cells[t as usize] as usize / layer;
    let mut runs = Vec::new();
    for w in group_starts.windows(2) {
        let (mut i, end) = (w[0] as usize, w[1] as usize);
        while i < end {
            let z = z_of(order[i]);
            let stop = i + order[i..end].partition_point(|&t| z_of(t) == z);
            runs.push(LayerRun {
                start: i,
                end: stop,
                z: z as u32,
                last_of_group: stop == end,
            });
            i = stop;
        }
    }
    runs
}

/// Vertex-connected components of triangles: per-triangle group ids
/// numbered by first triangle, and their count (the same joining rule as
/// the one-pass grouping of marching cubes).
///
/// In parallel, with the same result on any number of threads: a
/// concurrent union-find links a root only by compare-and-swap of the
/// larger-index root under the smaller, so every component ends up rooted
/// at its smallest vertex whatever the schedule; then each root's first
/// triangle is found (atomic minimum) and the groups are numbered in the
/// order of those first triangles (a chunked prefix count).
pub fn vertex_components(n_vertices: usize, triangles: &[[u32; 3]]) -> (Vec<u32>, usize) {
    let uf = AtomicUnionFind::with_len(n_vertices);
    triangles.par_iter().with_min_len(1 << 12).for_each(|t| {
        uf.union(t[0], t[1]);
        uf.union(t[0], t[2]);
    });
    let roots: Vec<u32> = (triangles.par_iter().with_min_len(1 << 12))
        .map(|t| uf.find(t[0]))
        .collect();
    // First triangle of each root (u32::MAX: not a root of any triangle).
    let first = uf.into_inner();
    first
        .par_iter()
        .for_each(|f| f.store(u32::MAX, Ordering::Relaxed));
    // Within a task triangles ascend, so after a root's first one there the
    // plain load already says "not smaller" (few read-modify-writes).
    (roots.par_iter().enumerate().with_min_len(1 << 12)).for_each(|(t, &r)| {
        let f = &first[r as usize];
        if f.load(Ordering::Relaxed) > t as u32 {
            f.fetch_min(t as u32, Ordering::Relaxed);
        }
    });
    let is_first = |t: usize, r: u32| first[r as usize].load(Ordering::Relaxed) == t as u32;
    const CHUNK: usize = 1 << 14;
    let counts: Vec<u32> = roots
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(c, rs)| {
            (rs.iter().enumerate())
                .filter(|&(i, &r)| is_first(c * CHUNK + i, r))
                .count() as u32
        })
        .collect();
    let mut n_groups = 0u32;
    let starts: Vec<u32> = counts
        .iter()
        .map(|&n| {
            n_groups += n;
            n_groups - n
        })
        .collect();
    // Group id of each root, set by its first triangle (one writer each).
    let id: Vec<AtomicU32> = (0..n_vertices)
        .into_par_iter()
        .map(|_| AtomicU32::new(u32::MAX))
        .collect();
    roots
        .par_chunks(CHUNK)
        .zip(&starts)
        .enumerate()
        .for_each(|(c, (rs, &start))| {
            let mut next = start;
            for (i, &r) in rs.iter().enumerate() {
                if is_first(c * CHUNK + i, r) {
                    id[r as usize].store(next, Ordering::Relaxed);
                    next += 1;
                }
            }
        });
    let groups = (roots.par_iter().with_min_len(1 << 12))
        .map(|&r| id[r as usize].load(Ordering::Relaxed))
        .collect();
    (groups, n_groups as usize)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::cpu::UnionFind;

    /// The serial definition: union-find, groups numbered by first triangle.
    fn reference(n_vertices: usize, triangles: &[[u32; 3]]) -> (Vec<u32>, usize) {
        let mut uf = UnionFind::with_len(n_vertices);
        for t in triangles {
            uf.union(t[0], t[1]);
            uf.union(t[0], t[2]);
        }
        let mut id = vec![u32::MAX; n_vertices];
        let mut n = 0;
        let groups = triangles
            .iter()
            .map(|t| {
                let r = uf.find(t[0]) as usize;
                if id[r] == u32::MAX {
                    id[r] = n;
                    n += 1;
                }
                id[r]
            })
            .collect();
        (groups, n as usize)
    }

    #[test]
    fn vertex_components_numbers_groups_by_first_triangle() {
        let tris = [[5, 4, 3], [0, 1, 2], [2, 6, 7], [8, 9, 3], [10, 11, 12]];
        assert_eq!(vertex_components(13, &tris), (vec![0, 1, 1, 0, 2], 3));
        assert_eq!(vertex_components(4, &[]), (vec![], 0));
    }

    #[test]
    fn vertex_components_equal_the_serial_union_find_on_any_pool() {
        // Random triangles over few vertices (long chains, many unions per
        // root) and over many (thousands of small groups).
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = |n: u32| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % u64::from(n)) as u32
        };
        for (n_vertices, n_triangles, spread) in [(60_000, 40_000, 60_000), (300_000, 150_000, 40)]
        {
            let tris: Vec<[u32; 3]> = (0..n_triangles)
                .map(|_| {
                    let a = next(n_vertices);
                    [
                        a,
                        (a + next(spread)) % n_vertices,
                        (a + next(spread)) % n_vertices,
                    ]
                })
                .collect();
            let want = reference(n_vertices as usize, &tris);
            assert!(want.1 > 10, "{} groups", want.1);
            for threads in [1, 2, 8] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let got = pool.install(|| vertex_components(n_vertices as usize, &tris));
                assert_eq!(got, want, "{threads} threads");
            }
        }
    }
}
