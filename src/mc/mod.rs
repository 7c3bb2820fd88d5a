//! Marching cubes with one-pass grouping and the bounding-box B+ tree
//! (SPEC §5.1–5.2, seed 004 §1–2).
//!
//! ```text
//!  Volume ──Field (f32 layers, labels → 0/1, optional outside padding)──┐
//!     CPU: cpu::marching_cubes  (points → vertices, cells → triangles,  │
//!          union-find grouping in the same pass)                        │
//!     GPU: gpu::marching_cubes  (mc_inside → mc_classify → host scan of  │
//!          block sums → mc_vertices → mc_triangles, in z slabs;         │
//!          grouping on the host)                                        │
//!                               ▼                                        │
//!  RawSurface (index-space positions, edge ids, triangles, cells, groups)┘
//!                               ▼ world transform, group figures, Forest
//!                            Surface
//! ```
//!
//! Guarantees (tested in `tests/mc.rs`): the mesh is welded (one
//! vertex per crossed grid edge), every edge away from the volume border is
//! used by exactly two triangles in opposite directions, normals point from
//! inside (samples ≥ level, or equal to the label) to outside, and with
//! [`McOptions::close_border`] every group is closed. The connectivity
//! convention (inside 6-connected, outside 26-connected) is explained in
//! [`tables`]. CPU and GPU give the same vertices (bit for bit, same f32
//! expressions; see [`cpu`]), the same triangles in the same order, and so
//! the same groups and tree.
//!
//! Kernel contracts: [`mirror`] holds one plain CPU loop per kernel
//! (`mc_inside`, `mc_classify`, `mc_vertices`, `mc_triangles`) that reads
//! beside its WGSL; each GPU kernel is tested against its mirror on the same inputs,
//! and the bit-row CPU path ([`cpu`], the fast path) against the mirrors
//! chained (`tests/parity/mc_*.rs`).

pub mod cpu;
pub mod field;
pub mod gpu;
pub mod grid;
pub mod mirror;
pub mod tables;

use std::collections::HashSet;
use std::sync::atomic::{AtomicU32, Ordering};

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

pub use field::Field;

use crate::foundation::{Aabb, Forest};
use crate::gpu::Backend;
use crate::volume::VolumeView;
use crate::{Result, TriMesh};

/// The host prefix sum between the passes, for every marching-cubes path
/// (the fast CPU path, the mirrors and the GPU passes): exclusive offsets of
/// `counts` with the total appended (one entry more than `counts`), in
/// `u32` because vertex and triangle ids are `u32`; errors when the total
/// reaches `u32::MAX`.
pub(crate) fn exclusive_offsets(
    counts: impl IntoIterator<Item = u64>,
    what: &str,
) -> Result<Vec<u32>> {
    let mut out = vec![0u32];
    let mut sum = 0u64;
    for c in counts {
        sum += c;
        let offset = u32::try_from(sum)
            .ok()
            .filter(|&s| s < u32::MAX)
            .ok_or_else(|| {
                crate::Error::limit(format!("marching cubes: {what}"), sum, u32::MAX - 1)
            })?;
        out.push(offset);
    }
    Ok(out)
}

/// Edge of a forest leaf block in marching-cubes cells. The seed's leaf is
/// one voxel cell (≈ 2 triangles); a leaf of 4³ cells (≈ 30 triangles on a
/// surface) makes the tree ~50× smaller and the cut query several times
/// faster, while keeping the same layer → row → cell structure. A power of
/// two: the forest finds a cell's block by shifts.
pub const LEAF_BLOCK: usize = 4;
const _: () = assert!(LEAF_BLOCK.is_power_of_two());

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
    /// Only the mesh: no grouping, per-group figures or forest (the
    /// surface's `triangle_groups`, `groups` and `forest` stay empty). For
    /// callers that pass the mesh on and never cut it by group.
    pub mesh_only: bool,
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

impl Surface {
    /// Triangles as sorted, rotation-normalised triples of grid edge ids:
    /// the backend-independent identity of the surface (CPU and GPU give
    /// the same list, whatever their vertex and triangle order).
    pub fn canonical_triangles(&self) -> Vec<[u64; 3]> {
        let mut out: Vec<[u64; 3]> = self
            .mesh
            .triangles
            .iter()
            .map(|t| {
                let e = t.map(|v| self.vertex_edges[v as usize]);
                let k = (0..3).min_by_key(|&k| e[k]).unwrap_or(0);
                [e[k], e[(k + 1) % 3], e[(k + 2) % 3]]
            })
            .collect();
        out.sort_unstable();
        out
    }
}

/// Marching cubes of `volume` (a [`crate::Volume`], or a [`VolumeView`] of
/// samples read in place) on `backend`, with grouping and the forest.
pub fn marching_cubes<'a>(
    volume: impl Into<VolumeView<'a>>,
    iso: IsoSpec,
    opts: &McOptions,
    backend: Backend<'_>,
) -> Result<Surface> {
    let field = Field::new(volume, iso, opts.close_border)?;
    let grouping = !opts.mesh_only;
    let raw = match backend {
        Backend::Cpu => cpu::marching_cubes(&field, grouping)?,
        Backend::Gpu(g) => gpu::marching_cubes(g, &field, grouping)?,
    };
    Ok(if grouping {
        finish(&field, raw)
    } else {
        finish_mesh(&field, raw)
    })
}

/// The world transform of a raw surface, in place, with the winding
/// turned where the axes reflect.
fn world_mesh(field: &Field<'_>, positions: Vec<[f32; 3]>, triangles: Vec<[u32; 3]>) -> TriMesh {
    let mut positions: Vec<glam::Vec3> = bytemuck::cast_vec(positions);
    positions
        .par_iter_mut()
        .for_each(|p| *p = field.to_world(p.to_array()));
    let mut triangles = triangles;
    if field.volume().reflects() {
        triangles.iter_mut().for_each(|t| t.swap(1, 2));
    }
    TriMesh {
        positions,
        triangles,
        scalars: Vec::new(),
    }
}

/// [`McOptions::mesh_only`]: the mesh, vertex edges and triangle cells;
/// no groups, figures or forest.
fn finish_mesh(field: &Field<'_>, raw: cpu::RawSurface) -> Surface {
    Surface {
        mesh: world_mesh(field, raw.positions, raw.triangles),
        vertex_edges: raw.edges,
        triangle_cells: raw.cells,
        triangle_groups: Vec::new(),
        groups: Vec::new(),
        forest: Forest::default(),
        grid: Grid {
            dims: field.dims,
            pad: field.pad,
        },
    }
}

/// World transform, group figures and the forest (shared by both backends).
/// [`Forest::build`] runs alongside the (parallel) figure passes.
pub fn finish(field: &Field<'_>, raw: cpu::RawSurface) -> Surface {
    // To world coordinates in place (a vertex array is not copied); axes
    // with a reflection turn the index-space winding inside out.
    let mesh = world_mesh(field, raw.positions, raw.triangles);
    let grid = Grid {
        dims: field.dims,
        pad: field.pad,
    };
    let (forest, groups) = rayon::join(
        || Forest {
            closed_outward: field.pad == 1,
            ..Forest::build(
                mesh.view(),
                &raw.cells,
                field.dims.map(|d| d.saturating_sub(1)),
                LEAF_BLOCK,
                &raw.groups,
                raw.n_groups,
            )
        },
        || {
            group_figures(
                &mesh,
                &raw.edges,
                &raw.cells,
                &raw.groups,
                &raw.vertex_groups,
                raw.n_groups,
                grid,
            )
        },
    );
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

/// Chunk of triangles or vertices per task of the figure passes; partial
/// sums are combined in chunk order, so the figures do not depend on the
/// number of threads.
const FIGURE_CHUNK: usize = 1 << 16;

/// Group of a vertex used by no triangle.
const NO_GROUP: u32 = u32::MAX;

/// The group of each vertex from the groups of the triangles using it
/// (which all share it; [`NO_GROUP`] where none does), for a path that
/// groups triangles only (the GPU's host grouping). The CPU path numbers
/// its vertices' groups while it stitches its chunks.
pub(crate) fn vertex_groups(n_vertices: usize, triangles: &[[u32; 3]], groups: &[u32]) -> Vec<u32> {
    let vertex_group: Vec<AtomicU32> = (0..n_vertices).map(|_| AtomicU32::new(NO_GROUP)).collect();
    triangles
        .par_chunks(FIGURE_CHUNK)
        .zip(groups.par_chunks(FIGURE_CHUNK))
        .for_each(|(tris, gs)| {
            for (t, &g) in tris.iter().zip(gs) {
                for &v in t {
                    vertex_group[v as usize].store(g, Ordering::Relaxed);
                }
            }
        });
    vertex_group
        .into_iter()
        .map(AtomicU32::into_inner)
        .collect()
}

/// Per-group sums over triangles.
#[derive(Debug, Clone, Copy, Default)]
struct TriangleSums {
    triangles: u32,
    area: f64,
    volume6: f64,
}

impl TriangleSums {
    fn add(&self, o: &TriangleSums) -> TriangleSums {
        TriangleSums {
            triangles: self.triangles + o.triangles,
            area: self.area + o.area,
            volume6: self.volume6 + o.volume6,
        }
    }
}

/// Per-group sums over vertices.
#[derive(Debug, Clone, Copy)]
struct VertexSums {
    vertices: u32,
    bbox: Aabb,
}

/// Consecutive vertices of one group: their count and bounds, kept in
/// registers until the group changes.
struct VertexRun {
    group: usize,
    vertices: u32,
    lo: Vec3A,
    hi: Vec3A,
}

impl VertexRun {
    fn new(group: usize) -> Self {
        VertexRun {
            group,
            vertices: 0,
            lo: Vec3A::INFINITY,
            hi: Vec3A::NEG_INFINITY,
        }
    }

    /// Adds the run to its group's sums (an empty run changes nothing).
    fn add_to(&self, sums: &mut [VertexSums]) {
        let s = &mut sums[self.group];
        s.vertices += self.vertices;
        s.bbox = s.bbox.union(Aabb {
            min: self.lo.into(),
            max: self.hi.into(),
        });
    }
}

/// Group figures from the groups of the triangles and of the vertices.
/// Edges: `E = (3F + B)/2`, which holds because every edge
/// is used once (border) or twice (the table's manifold guarantee, checked
/// independently by the tests); `B` counts directed edges lying in a
/// border plane of the grid whose reverse is absent. Every vertex lies in
/// one group (groups are vertex-connected), so vertex counts and boxes are
/// summed over vertices; area and volume over triangles, in f64.
fn group_figures(
    mesh: &TriMesh,
    edges: &[u64],
    cells: &[u32],
    groups: &[u32],
    vertex_group: &[u32],
    n_groups: usize,
    grid: Grid,
) -> Vec<Group> {
    let p = &mesh.positions;
    let no_vertices = VertexSums {
        vertices: 0,
        bbox: Aabb::EMPTY,
    };
    let vertex_sums = p
        .par_chunks(FIGURE_CHUNK)
        .zip(vertex_group.par_chunks(FIGURE_CHUNK))
        .map(|(ps, gs)| {
            // Slot n_groups: vertices of no group (none in a mesh from
            // marching cubes, but they still count for the bounds).
            let mut sums = vec![no_vertices; n_groups + 1];
            // Runs of one group are summed in locals, as the triangles are.
            let slot = |g: u32| (g as usize).min(n_groups);
            let mut run = VertexRun::new(gs.first().map_or(0, |&g| slot(g)));
            for (&q, &g) in ps.iter().zip(gs) {
                let g = slot(g);
                if g != run.group {
                    run.add_to(&mut sums);
                    run = VertexRun::new(g);
                }
                run.vertices += 1;
                run.lo = run.lo.min(q.into());
                run.hi = run.hi.max(q.into());
            }
            run.add_to(&mut sums);
            sums
        })
        .collect::<Vec<_>>()
        .into_iter()
        .reduce(|a, b| {
            a.iter()
                .zip(&b)
                .map(|(x, y)| VertexSums {
                    vertices: x.vertices + y.vertices,
                    bbox: x.bbox.union(y.bbox),
                })
                .collect()
        })
        .unwrap_or_else(|| vec![no_vertices; n_groups + 1]);
    // The mesh's bounds (all vertices, in any group or none).
    let bounds = vertex_sums.iter().fold(Aabb::EMPTY, |b, s| b.union(s.bbox));
    let reference = if bounds.is_empty() {
        DVec3::ZERO
    } else {
        ((bounds.min + bounds.max) * 0.5).as_dvec3()
    };
    let triangle_sums = mesh
        .triangles
        .par_chunks(FIGURE_CHUNK)
        .zip(groups.par_chunks(FIGURE_CHUNK))
        .map(|(tris, gs)| {
            let mut sums = vec![TriangleSums::default(); n_groups];
            // Runs of one group are summed in locals (same order as summing
            // into `sums` directly, without a round trip through memory).
            let mut run = TriangleSums::default();
            let mut run_group = gs.first().copied().unwrap_or(0) as usize;
            for (t, &g) in tris.iter().zip(gs) {
                if g as usize != run_group {
                    sums[run_group] = sums[run_group].add(&run);
                    run = sums[g as usize];
                    sums[g as usize] = TriangleSums::default();
                    run_group = g as usize;
                }
                let da = p[t[0] as usize].as_dvec3() - reference;
                let db = p[t[1] as usize].as_dvec3() - reference;
                let dc = p[t[2] as usize].as_dvec3() - reference;
                let n = (db - da).cross(dc - da);
                run.triangles += 1;
                run.area += 0.5 * n.length();
                run.volume6 += da.dot(db.cross(dc));
            }
            if let Some(s) = sums.get_mut(run_group) {
                *s = s.add(&run);
            }
            sums
        })
        .collect::<Vec<_>>()
        .into_iter()
        .reduce(|a, b| a.iter().zip(&b).map(|(x, y)| x.add(y)).collect())
        .unwrap_or_else(|| vec![TriangleSums::default(); n_groups]);
    let boundary = boundary_edges(mesh, edges, cells, groups, n_groups, grid);
    (0..n_groups)
        .map(|g| {
            let (t, v) = (&triangle_sums[g], &vertex_sums[g]);
            let f = i64::from(t.triangles);
            let b = i64::from(boundary[g]);
            let euler = i64::from(v.vertices) - (3 * f + b) / 2 + f;
            Group {
                triangles: t.triangles,
                vertices: v.vertices,
                bbox: v.bbox,
                area: t.area,
                volume: t.volume6 / 6.0,
                boundary_edges: boundary[g],
                euler,
                genus: (b == 0).then(|| (2 - euler) / 2),
            }
        })
        .collect()
}

/// Per group, the edges used once: only edges with both ends in one border
/// plane of the grid can be (the table puts all cell-boundary segments on
/// cell faces), and only triangles of border cells have such edges (a
/// vertex on a border plane lies on an edge of a border cell, and a
/// triangle's vertices lie on its own cell's edges), so only those are
/// examined and hashed.
fn boundary_edges(
    mesh: &TriMesh,
    edges: &[u64],
    cells: &[u32],
    groups: &[u32],
    n_groups: usize,
    grid: Grid,
) -> Vec<u32> {
    let mut out = vec![0u32; n_groups];
    if grid.pad == 1 {
        return out;
    }
    let d = grid.dims;
    let [cx, cy, cz] = d.map(|n| n.saturating_sub(1).max(1));
    // Border planes a vertex lies in: bit 2a for coordinate 0 along axis
    // a, bit 2a + 1 for the last one (the vertex's own axis excluded).
    let planes = |v: u32| -> u8 {
        let key = edges[v as usize];
        let (point, axis) = ((key / 3) as usize, (key % 3) as usize);
        let c = [point % d[0], (point / d[0]) % d[1], point / (d[0] * d[1])];
        let mut m = 0u8;
        for a in (0..3).filter(|&a| a != axis) {
            m |= u8::from(c[a] == 0) << (2 * a);
            m |= u8::from(c[a] == d[a] - 1) << (2 * a + 1);
        }
        m
    };
    // Triangles come in cell order, so consecutive cells mostly share a
    // row: a cell's row is decoded only when it changes.
    let mut row = (usize::MAX, false);
    let mut candidates: Vec<(u32, u32, u32)> = Vec::new();
    // Only the cells are read for every triangle.
    for (i, &c) in cells.iter().enumerate() {
        let c = c as usize;
        if !(row.0..row.0.saturating_add(cx)).contains(&c) {
            let q = c / cx;
            let (y, z) = (q % cy, q / cy);
            row = (q * cx, y == 0 || y + 1 == cy || z == 0 || z + 1 == cz);
        }
        let x = c - row.0;
        if !(row.1 || x == 0 || x + 1 == cx) {
            continue;
        }
        let (t, g) = (mesh.triangles[i], groups[i]);
        let m = t.map(planes);
        for k in 0..3 {
            if m[k] & m[(k + 1) % 3] != 0 {
                candidates.push((t[k], t[(k + 1) % 3], g));
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
