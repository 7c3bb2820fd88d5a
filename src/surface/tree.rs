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

use glam::Vec3;
use rayon::prelude::*;

use super::cpu::UnionFind;
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
    /// Vertex count of the mesh the forest was built for.
    pub n_vertices: usize,
    /// Whether the boxes are sorted along their keys: in every row the
    /// cells' `min.x` and `max.x` never decrease, likewise the rows' `y`
    /// bounds in every layer and the layers' `z` bounds in every group. True
    /// for marching-cubes forests (a cell's triangles stay inside the cell);
    /// it lets a query find the children a slab can touch by binary search
    /// (seed §4.3) instead of testing every child box.
    pub axis_sorted: bool,
}

impl Forest {
    /// Builds the forest from per-triangle cell keys (`x + cx·(y + cy·z)`)
    /// and group ids (`0..n_groups`).
    pub fn build(
        mesh: &TriMesh,
        cells: &[u32],
        cell_dims: [usize; 3],
        groups: &[u32],
        n_groups: usize,
    ) -> Forest {
        let order = order_by_group_and_cell(cells, groups, n_groups);
        let p = &mesh.positions;
        let tri_box = |t: u32| {
            let [a, b, c] = mesh.triangles[t as usize];
            Aabb::triangle(p[a as usize], p[b as usize], p[c as usize])
        };
        let [cx, cy, _] = cell_dims;
        let decode = |c: u32| {
            let c = c as usize;
            (
                (c % cx) as u32,
                ((c / cx) % cy) as u32,
                (c / (cx * cy)) as u32,
            )
        };
        let mut f = Forest {
            cell_dims,
            triangles: order,
            ..Forest::default()
        };
        let mut i = 0usize;
        let n = f.triangles.len();
        while i < n {
            let g = groups[f.triangles[i] as usize];
            let layer_start = f.layers.len() as u32;
            let mut gbox = Aabb::EMPTY;
            while i < n && groups[f.triangles[i] as usize] == g {
                let (_, _, z) = decode(cells[f.triangles[i] as usize]);
                let row_start = f.rows.len() as u32;
                let mut lbox = Aabb::EMPTY;
                while i < n && groups[f.triangles[i] as usize] == g {
                    let (_, y, z2) = decode(cells[f.triangles[i] as usize]);
                    if z2 != z {
                        break;
                    }
                    let cell_start = f.cells.len() as u32;
                    let mut rbox = Aabb::EMPTY;
                    while i < n && groups[f.triangles[i] as usize] == g {
                        let key = cells[f.triangles[i] as usize];
                        let (x, y2, z3) = decode(key);
                        if y2 != y || z3 != z {
                            break;
                        }
                        let t_start = i as u32;
                        let mut cbox = Aabb::EMPTY;
                        while i < n
                            && groups[f.triangles[i] as usize] == g
                            && cells[f.triangles[i] as usize] == key
                        {
                            cbox = cbox.union(tri_box(f.triangles[i]));
                            i += 1;
                        }
                        f.cells.push(CellNode {
                            x,
                            bbox: cbox,
                            triangles: Span {
                                start: t_start,
                                end: i as u32,
                            },
                            vertices: Span { start: 0, end: 0 },
                            next: u32::MAX,
                        });
                        rbox = rbox.union(cbox);
                    }
                    f.rows.push(RowNode {
                        y,
                        bbox: rbox,
                        cells: Span {
                            start: cell_start,
                            end: f.cells.len() as u32,
                        },
                    });
                    lbox = lbox.union(rbox);
                }
                f.layers.push(LayerNode {
                    z,
                    bbox: lbox,
                    rows: Span {
                        start: row_start,
                        end: f.rows.len() as u32,
                    },
                });
                gbox = gbox.union(lbox);
            }
            // Chain the group's leaves.
            let first_cell = f.rows[f.layers[layer_start as usize].rows.start as usize]
                .cells
                .start as usize;
            let last_cell = f.cells.len();
            for c in first_cell..last_cell.saturating_sub(1) {
                f.cells[c].next = c as u32 + 1;
            }
            f.groups.push(GroupNode {
                bbox: gbox,
                layers: Span {
                    start: layer_start,
                    end: f.layers.len() as u32,
                },
            });
        }
        f.axis_sorted = f.boxes_sorted();
        f.n_vertices = mesh.positions.len();
        f.leaf_vertex_tables(mesh);
        f
    }

    /// Fills [`Forest::leaf_vertices`], [`Forest::corners`] and each leaf's
    /// `vertices` span (leaves in parallel, then concatenated).
    fn leaf_vertex_tables(&mut self, mesh: &TriMesh) {
        let per_leaf: Vec<(Vec<u32>, Vec<[u32; 3]>)> = self
            .cells
            .par_iter()
            .map(|c| {
                let tris = &self.triangles[c.triangles.range()];
                let mut vs: Vec<u32> = tris
                    .iter()
                    .flat_map(|&t| mesh.triangles[t as usize])
                    .collect();
                vs.sort_unstable();
                vs.dedup();
                let local = tris
                    .iter()
                    .map(|&t| {
                        mesh.triangles[t as usize].map(|v| vs.partition_point(|&x| x < v) as u32)
                    })
                    .collect();
                (vs, local)
            })
            .collect();
        let n: usize = per_leaf.iter().map(|(vs, _)| vs.len()).sum();
        self.leaf_vertices = Vec::with_capacity(n);
        self.corners = Vec::with_capacity(self.triangles.len());
        for (c, (vs, local)) in self.cells.iter_mut().zip(per_leaf) {
            let start = self.leaf_vertices.len() as u32;
            self.leaf_vertices.extend_from_slice(&vs);
            c.vertices = Span {
                start,
                end: self.leaf_vertices.len() as u32,
            };
            self.corners
                .extend(local.into_iter().map(|l| l.map(|i| start + i)));
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
/// interval `[lo, hi]`: two binary searches (seed §4.3), as an index range
/// into `nodes`.
pub fn sorted_overlap<T>(
    nodes: &[T],
    bbox: impl Fn(&T) -> &Aabb,
    axis: usize,
    lo: f64,
    hi: f64,
) -> std::ops::Range<usize> {
    let start = nodes.partition_point(|n| f64::from(bbox(n).max[axis]) < lo);
    let end = nodes.partition_point(|n| f64::from(bbox(n).min[axis]) <= hi);
    start..end.max(start)
}

/// Stable counting sort of `items` by `key(item) < n_keys`.
fn counting_sort(items: &[u32], n_keys: usize, key: impl Fn(u32) -> usize) -> Vec<u32> {
    let mut start = vec![0u32; n_keys + 1];
    for &t in items {
        start[key(t) + 1] += 1;
    }
    for k in 0..n_keys {
        start[k + 1] += start[k];
    }
    let mut out = vec![0u32; items.len()];
    for &t in items {
        let k = key(t);
        out[start[k] as usize] = t;
        start[k] += 1;
    }
    out
}

/// Triangle ids sorted by (group, cell, id): two stable counting sorts
/// (cell, then group) when the cell keys are few enough, else a sort.
fn order_by_group_and_cell(cells: &[u32], groups: &[u32], n_groups: usize) -> Vec<u32> {
    let n = cells.len();
    let ids: Vec<u32> = (0..n as u32).collect();
    let n_keys = cells.iter().copied().max().map_or(0, |m| m as usize + 1);
    if cells.windows(2).all(|w| w[0] <= w[1]) {
        counting_sort(&ids, n_groups, |t| groups[t as usize] as usize)
    } else if n_keys <= 4 * n + (1 << 20) {
        let by_cell = counting_sort(&ids, n_keys, |t| cells[t as usize] as usize);
        counting_sort(&by_cell, n_groups, |t| groups[t as usize] as usize)
    } else {
        let mut out = ids;
        out.par_sort_unstable_by_key(|&t| {
            (
                u64::from(groups[t as usize]) << 32 | u64::from(cells[t as usize]),
                t,
            )
        });
        out
    }
}

/// Vertex-connected components of triangles: per-triangle group ids
/// numbered by first triangle, and their count (the same joining rule as
/// the one-pass grouping of marching cubes).
pub fn vertex_components(n_vertices: usize, triangles: &[[u32; 3]]) -> (Vec<u32>, usize) {
    let mut uf = UnionFind::with_len(n_vertices);
    for t in triangles {
        uf.union(t[0], t[1]);
        uf.union(t[0], t[2]);
    }
    let mut canonical = vec![u32::MAX; n_vertices];
    let mut n = 0usize;
    let groups = triangles
        .iter()
        .map(|t| {
            let r = uf.find(t[0]) as usize;
            if canonical[r] == u32::MAX {
                canonical[r] = n as u32;
                n += 1;
            }
            canonical[r]
        })
        .collect();
    (groups, n)
}
