//! Marching cubes with one-pass grouping and the bounding-box B+ tree
//! (SPEC §5.1–5.2, seed 004 §1–2).
//!
//! ```text
//!  Volume ──Field (f32 layers, labels → 0/1, optional outside padding)──┐
//!     CPU: cpu::marching_cubes  (points → vertices, cells → triangles,  │
//!          union-find grouping in the same pass)                        │
//!     GPU: gpu::marching_cubes  (mc_classify → host scan of block sums → │
//!          mc_vertices → mc_triangles, in z slabs; grouping on the host)│
//!                               ▼                                        │
//!  RawSurface (index-space positions, edge ids, triangles, cells, groups)┘
//!                               ▼ world transform, group figures, Forest
//!                            Surface
//! ```
//!
//! Guarantees (tested in `tests/surface.rs`): the mesh is welded (one
//! vertex per crossed grid edge), every edge away from the volume border is
//! used by exactly two triangles in opposite directions, normals point from
//! inside (samples ≥ level, or equal to the label) to outside, and with
//! [`McOptions::close_border`] every group is closed. The connectivity
//! convention (inside 6-connected, outside 26-connected) is explained in
//! [`tables`]. CPU and GPU give the same vertices (bit for bit, same f32
//! expressions; see [`cpu`]), the same triangles in the same order, and so
//! the same groups and tree.

pub mod cpu;
pub mod field;
pub mod gpu;
pub mod tables;
pub mod tree;

use std::collections::HashSet;

use glam::DVec3;
use rayon::prelude::*;

pub use cpu::UnionFind;
pub use field::Field;
pub use tree::{Aabb, CellNode, Forest, GroupNode, LayerNode, RowNode, Span};

use crate::parity::Backend;
use crate::{Result, TriMesh, Volume};

/// Which surface to extract.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum IsoSpec {
    /// The iso-surface at this level; samples ≥ level are inside.
    Level(f32),
    /// The boundary of the voxels equal to this label value.
    Label(f64),
}

/// Options of [`marching_cubes`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct McOptions {
    /// Close the surface at the volume border: the grid is padded by one
    /// outside sample per side, and the closing faces lie half a sample
    /// beyond the border samples. Without it, surfaces end open at the border.
    pub close_border: bool,
}

/// Figures of one group (connected surface component).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Group {
    /// Number of triangles.
    pub triangles: u32,
    /// Number of vertices.
    pub vertices: u32,
    /// Bounding box (world units).
    pub bbox: Aabb,
    /// Surface area (world units²), summed in f64.
    pub area: f64,
    /// Enclosed signed volume (world units³) by the divergence theorem,
    /// positive for an outer shell, negative for a cavity; meaningful when
    /// the group is closed.
    pub volume: f64,
    /// Edges used by one triangle only (on the volume border).
    pub boundary_edges: u32,
    /// Euler characteristic V − E + F.
    pub euler: i64,
    /// Genus `(2 − χ)/2` of a closed group; `None` when open.
    pub genus: Option<i64>,
}

/// The sample grid a surface was extracted on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// Sample counts per axis of the (padded) grid.
    pub dims: [usize; 3],
    /// 1 when the border was closed (padding), else 0.
    pub pad: usize,
}

/// A marching-cubes surface with its groups and B+ tree forest.
#[derive(Debug, Clone)]
pub struct Surface {
    /// Welded, indexed mesh in world units, wound outward.
    pub mesh: TriMesh,
    /// #V global grid edge of each vertex: `3·point + axis`, `point` the
    /// linear sample index in the (padded) grid.
    pub vertex_edges: Vec<u64>,
    /// #F cell `x + (nx−1)·(y + (ny−1)·z)` of each triangle.
    pub triangle_cells: Vec<u32>,
    /// #F group of each triangle (groups numbered by first triangle).
    pub triangle_groups: Vec<u32>,
    /// Per-group figures.
    pub groups: Vec<Group>,
    /// One B+ tree per group.
    pub forest: Forest,
    /// The grid the surface was extracted on.
    pub grid: Grid,
}

/// Marching cubes of `volume` on `backend`, with grouping and the forest.
pub fn marching_cubes(
    volume: &Volume,
    iso: IsoSpec,
    opts: &McOptions,
    backend: Backend<'_>,
) -> Result<Surface> {
    let field = Field::new(volume, iso, opts.close_border)?;
    let raw = match backend {
        Backend::Cpu => cpu::marching_cubes(&field)?,
        Backend::Gpu(g) => gpu::marching_cubes(g, &field)?,
    };
    Ok(finish(&field, raw))
}

/// World transform, group figures and the forest (shared by both backends).
pub fn finish(field: &Field<'_>, raw: cpu::RawSurface) -> Surface {
    let positions: Vec<glam::Vec3> = raw
        .positions
        .par_iter()
        .map(|&u| field.to_world(u))
        .collect();
    let mesh = TriMesh {
        positions,
        triangles: raw.triangles,
        scalars: Vec::new(),
    };
    let grid = Grid {
        dims: field.dims,
        pad: field.pad,
    };
    let groups = group_figures(&mesh, &raw.edges, &raw.groups, raw.n_groups, grid);
    let forest = leaf_forest(&mesh, &raw.cells, field.dims, &raw.groups, raw.n_groups);
    Surface {
        mesh,
        vertex_edges: raw.edges,
        triangle_cells: raw.cells,
        triangle_groups: raw.groups,
        groups,
        forest,
        grid,
    }
}

/// The forest over blocks of [`tree::LEAF_BLOCK`]³ marching-cubes cells:
/// layer = block layer, row = block row, leaf = block.
fn leaf_forest(
    mesh: &TriMesh,
    cells: &[u32],
    dims: [usize; 3],
    groups: &[u32],
    n_groups: usize,
) -> Forest {
    let b = tree::LEAF_BLOCK;
    let cd = dims.map(|d| d.saturating_sub(1).max(1));
    let bd = cd.map(|c| c.div_ceil(b));
    let blocks: Vec<u32> = cells
        .par_iter()
        .map(|&c| {
            let c = c as usize;
            let (x, y, z) = (c % cd[0], (c / cd[0]) % cd[1], c / (cd[0] * cd[1]));
            (x / b + bd[0] * (y / b + bd[1] * (z / b))) as u32
        })
        .collect();
    Forest::build(mesh, &blocks, bd, groups, n_groups)
}

/// Per-group accumulators.
#[derive(Debug, Clone, Copy)]
struct Acc {
    triangles: u32,
    bbox: Aabb,
    area: f64,
    volume6: f64,
}

impl Acc {
    const ZERO: Acc = Acc {
        triangles: 0,
        bbox: Aabb::EMPTY,
        area: 0.0,
        volume6: 0.0,
    };

    fn merge(mut self, o: &Acc) -> Acc {
        self.triangles += o.triangles;
        self.bbox = self.bbox.union(o.bbox);
        self.area += o.area;
        self.volume6 += o.volume6;
        self
    }
}

/// Group figures. Edges: `E = (3F + B)/2`, which holds because every edge
/// is used once (border) or twice (the table's manifold guarantee, checked
/// independently by the tests); `B` counts directed edges lying in a
/// border plane of the grid whose reverse is absent.
fn group_figures(
    mesh: &TriMesh,
    edges: &[u64],
    groups: &[u32],
    n_groups: usize,
    grid: Grid,
) -> Vec<Group> {
    let p = &mesh.positions;
    let reference = mesh
        .bounds()
        .map_or(DVec3::ZERO, |(lo, hi)| ((lo + hi) * 0.5).as_dvec3());
    let chunk = 1 << 16;
    let acc = mesh
        .triangles
        .par_chunks(chunk)
        .zip(groups.par_chunks(chunk))
        .map(|(tris, gs)| {
            let mut acc = vec![Acc::ZERO; n_groups];
            for (t, &g) in tris.iter().zip(gs) {
                let [a, b, c] = t.map(|i| p[i as usize]);
                let e = &mut acc[g as usize];
                let (da, db, dc) = (
                    a.as_dvec3() - reference,
                    b.as_dvec3() - reference,
                    c.as_dvec3() - reference,
                );
                let n = (db - da).cross(dc - da);
                e.triangles += 1;
                e.bbox = e.bbox.union(Aabb::triangle(a, b, c));
                e.area += 0.5 * n.length();
                e.volume6 += da.dot(db.cross(dc));
            }
            acc
        })
        .reduce(
            || vec![Acc::ZERO; n_groups],
            |a, b| a.iter().zip(&b).map(|(x, y)| x.merge(y)).collect(),
        );
    let mut vertex_group = vec![u32::MAX; p.len()];
    for (t, &g) in mesh.triangles.iter().zip(groups) {
        for &v in t {
            vertex_group[v as usize] = g;
        }
    }
    let mut vertices = vec![0u32; n_groups];
    for &g in &vertex_group {
        if let Some(v) = vertices.get_mut(g as usize) {
            *v += 1;
        }
    }
    let boundary = boundary_edges(mesh, edges, groups, n_groups, grid);
    (0..n_groups)
        .map(|g| {
            let a = &acc[g];
            let f = i64::from(a.triangles);
            let b = i64::from(boundary[g]);
            let euler = i64::from(vertices[g]) - (3 * f + b) / 2 + f;
            Group {
                triangles: a.triangles,
                vertices: vertices[g],
                bbox: a.bbox,
                area: a.area,
                volume: a.volume6 / 6.0,
                boundary_edges: boundary[g],
                euler,
                genus: (b == 0).then(|| (2 - euler) / 2),
            }
        })
        .collect()
}

/// Per group, the edges used once: only edges with both ends in one border
/// plane of the grid can be (the table puts all cell-boundary segments on
/// cell faces), so only those are hashed.
fn boundary_edges(
    mesh: &TriMesh,
    edges: &[u64],
    groups: &[u32],
    n_groups: usize,
    grid: Grid,
) -> Vec<u32> {
    let mut out = vec![0u32; n_groups];
    if grid.pad == 1 {
        return out;
    }
    let [nx, ny, nz] = grid.dims;
    let planes = |key: u64| -> u8 {
        let (point, axis) = ((key / 3) as usize, (key % 3) as usize);
        let c = [point % nx, (point / nx) % ny, point / (nx * ny)];
        let d = [nx, ny, nz];
        let mut m = 0u8;
        for a in 0..3 {
            if a != axis {
                m |= u8::from(c[a] == 0) << (2 * a);
                m |= u8::from(c[a] == d[a] - 1) << (2 * a + 1);
            }
        }
        m
    };
    let mask: Vec<u8> = edges.par_iter().map(|&k| planes(k)).collect();
    let mut candidates: Vec<(u32, u32, u32)> = Vec::new();
    for (t, &g) in mesh.triangles.iter().zip(groups) {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if mask[a as usize] & mask[b as usize] != 0 {
                candidates.push((a, b, g));
            }
        }
    }
    let set: HashSet<(u32, u32)> = candidates.iter().map(|&(a, b, _)| (a, b)).collect();
    for &(a, b, g) in &candidates {
        if !set.contains(&(b, a)) {
            out[g as usize] += 1;
        }
    }
    out
}
