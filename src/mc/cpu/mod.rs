//! CPU marching cubes with one-pass grouping (seed 004 §1).
//!
//! Two passes over the grid, each parallel (rayon):
//! - *scan* (`scan::scan`), over slabs of z layers: the inside flags of
//!   every layer as bit rows (64 points per `u64`, read once from the
//!   volume's native type by [`Field::inside_row`], each row checked
//!   finite while it is in cache; 1 bit per sample kept). Right after layer
//!   `z + 1` is packed, layer `z` is scanned while the samples of both are
//!   still in cache: the interpolation parameter of each of its vertices,
//!   in numbering order, and the number of triangles of its cell layer.
//!   Whole words of points or cells that are all inside or all outside
//!   cost one test. The exclusive sums give every layer its first vertex
//!   and triangle id, so
//! - *emit* writes straight into the output arrays, in chunks of z layers
//!   of about equal work, one task per chunk, and reads no samples. Inside
//!   a chunk, layer by layer:
//! 1. *points*: every sample point `p` owns its +x, +y, +z grid edges; each
//!    crossing edge becomes one vertex, numbered in point order (x fastest,
//!    then y, then z; axes x < y < z within a point) — the same numbering the
//!    GPU's scan produces, so vertices are welded by edge id and both
//!    backends give identical indices;
//! 2. *cells*: each crossed cell looks its case up in [`super::tables`] and
//!    emits triangles in table order; each new triangle joins the groups of
//!    the triangles already using its vertices — neighbours in the current
//!    and previous cells — with union-find (seed §1 cases: join, new, merge).
//!
//! Chunks number their vertices with global ids and are stitched by uniting
//! the groups of the vertices on the layer two chunks share; the output does
//! not depend on the number of threads or chunks.
//! Interpolation (the one expression both backends use, in f32):
//! `t = clamp((level − a) / (b − a), T_MIN, 1 − T_MIN)`,
//! `u[axis] = f32(p[axis]) + t`, with `a` the sample at the edge's lower
//! end `p` and `b` at `p + e_axis` ([`NativeSamples::sample`](super::field::NativeSamples::sample), the volume
//! read in its own type, only where an edge crosses; `t` by the scan). The clamp
//! ([`T_MIN`]) keeps every vertex strictly inside its edge, so no triangle
//! has zero area (see there).

mod emit;
mod scan;
mod stitch;

use rayon::prelude::*;

use emit::{ChunkGroups, ChunkOut, run_chunk};
use scan::{Bits, scan};
use stitch::stitch;

/// Least interpolation parameter, in grid steps: `2⁻¹⁰`. A sample equal to
/// the level would otherwise put the vertices of all its crossing edges on
/// the sample itself — coincident vertices and zero-area triangles, which
/// exact predicates (the mesh knife) cannot place. Kept inside the open
/// edges, a cell's triangle has its three vertices on three different cube
/// edges, and no line meets the boundary of a convex cube in three points
/// interior to different edges: every triangle has positive area. The
/// shift is at most `2⁻¹⁰` of a sample step, only at samples within that
/// fraction of the level; f32 keeps `i + T_MIN ≠ i` for grid coordinates
/// below 2¹⁴ ([`super::field::MAX_AXIS_SAMPLES`]).
pub const T_MIN: f32 = 1.0 / 1024.0;

use super::exclusive_offsets;
use super::field::Field;
use crate::Result;
use crate::foundation::alloc::zeroed;

/// Index-space output of one marching-cubes run, before world transform.
#[derive(Debug, Default)]
pub struct RawSurface {
    /// #V vertex positions in (padded) grid index space.
    pub positions: Vec<[f32; 3]>,
    /// #V global edge ids `3·point + axis` (point = linear index in the padded grid).
    pub edges: Vec<u64>,
    /// #F triangles (vertex ids), counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// #F linear cell index `x + (nx−1)·(y + (ny−1)·z)` of each triangle.
    pub cells: Vec<u32>,
    /// #F group of each triangle (canonical: groups numbered by first triangle).
    pub groups: Vec<u32>,
    /// #V group of each vertex (the group of the triangles using it;
    /// `u32::MAX` for a vertex no triangle uses).
    pub vertex_groups: Vec<u32>,
    /// Number of groups.
    pub n_groups: usize,
}

const NONE: u32 = u32::MAX;

/// Marching cubes of `field` on the CPU; see the module docs. Without
/// `grouping` the triangles get no groups (`groups` empty, `n_groups` 0).
/// Errors when the surface has 2³² − 1 or more vertices or triangles.
pub fn marching_cubes(field: &Field<'_>, grouping: bool) -> Result<RawSurface> {
    if field.dims.iter().any(|&d| d < 2) {
        return Ok(RawSurface::default());
    }
    let (bits, layers) = scan(field)?;
    let nz = field.dims[2];
    // Vertices of point layer z, triangles of cell layer z (none on the top).
    let counts: Vec<(u64, u64)> = layers
        .iter()
        .map(|l| (l.ts.len() as u64, l.triangles))
        .collect();
    let vbase = exclusive_offsets(counts.iter().map(|c| c.0), "vertices")?;
    let tbase = exclusive_offsets(counts.iter().map(|c| c.1), "triangles")?;
    let (n_v, n_t) = (vbase[nz] as usize, tbase[nz] as usize);
    let chunks = chunk_bounds(&bits, &counts);

    let mut positions = zeroed("marching cubes: vertex positions", n_v)?;
    let mut edges = zeroed("marching cubes: vertex edge ids", n_v)?;
    let mut triangles = zeroed("marching cubes: triangles", n_t)?;
    let mut cells = zeroed("marching cubes: triangle cells", n_t)?;
    // Union-find node of each triangle, then its group.
    let n_g = if grouping { n_t } else { 0 };
    let mut groups = zeroed("marching cubes: triangle groups", n_g)?;
    // Union-find node of each vertex, then its group.
    let n_vg = if grouping { n_v } else { 0 };
    let mut vertex_groups = zeroed("marching cubes: vertex groups", n_vg)?;
    let mut outs = Vec::with_capacity(chunks.len());
    {
        let (mut p, mut e) = (positions.as_mut_slice(), edges.as_mut_slice());
        let (mut t, mut c, mut g) = (
            triangles.as_mut_slice(),
            cells.as_mut_slice(),
            groups.as_mut_slice(),
        );
        let mut vg = vertex_groups.as_mut_slice();
        for (k, &(z0, z1)) in chunks.iter().enumerate() {
            let own_end = own_end(&chunks, k, nz);
            let nv = (vbase[own_end] - vbase[z0]) as usize;
            let nt = (tbase[z1] - tbase[z0]) as usize;
            let (p0, p1) = std::mem::take(&mut p).split_at_mut(nv);
            let (e0, e1) = std::mem::take(&mut e).split_at_mut(nv);
            let (t0, t1) = std::mem::take(&mut t).split_at_mut(nt);
            let (c0, c1) = std::mem::take(&mut c).split_at_mut(nt);
            let (g0, g1) = std::mem::take(&mut g).split_at_mut(if grouping { nt } else { 0 });
            let (vg0, vg1) = std::mem::take(&mut vg).split_at_mut(if grouping { nv } else { 0 });
            (p, e, t, c, g, vg) = (p1, e1, t1, c1, g1, vg1);
            outs.push(ChunkOut {
                z0,
                z1,
                own_end,
                first_vertex: vbase[z0],
                n_seam: (vbase[z1 + 1] - vbase[own_end]) as usize,
                positions: p0,
                edges: e0,
                triangles: t0,
                cells: c0,
                grouping,
                tri_node: g0,
                vertex_node: vg0,
            });
        }
    }
    let chunk_groups: Vec<ChunkGroups> = outs
        .into_par_iter()
        .map(|out| run_chunk(&bits, &layers, out))
        .collect();
    let n_groups = if grouping {
        stitch(
            &chunk_groups,
            &chunks,
            &vbase,
            &tbase,
            &mut groups,
            &mut vertex_groups,
        )
    } else {
        0
    };
    Ok(RawSurface {
        positions,
        edges,
        triangles,
        cells,
        groups,
        vertex_groups,
        n_groups,
    })
}

/// The end of the point layers chunk `k` owns (from its first): the next
/// chunk's first layer, which both share, belongs to the next chunk.
fn own_end(chunks: &[(usize, usize)], k: usize, nz: usize) -> usize {
    chunks.get(k + 1).map_or(nz, |c| c.0)
}

/// Cell layers `z0..z1` of each chunk: about `4 × threads` chunks of equal
/// work (triangles + vertices + a share for the words scanned).
fn chunk_bounds(bits: &Bits, counts: &[(u64, u64)]) -> Vec<(usize, usize)> {
    let n_layers = counts.len() - 1;
    let scan = (bits.rows.ny * bits.rows.words / 8) as u64 + 1;
    let work: Vec<u64> = (0..n_layers)
        .map(|z| counts[z].1 + counts[z + 1].0 + scan)
        .collect();
    let total: u64 = work.iter().sum();
    let n_chunks = (4 * rayon::current_num_threads().max(1)).min(n_layers) as u64;
    let mut out = Vec::with_capacity(n_chunks as usize);
    let (mut z0, mut acc, mut k) = (0, 0u64, 1u64);
    for (z, w) in work.iter().enumerate() {
        acc += w;
        if acc * n_chunks >= k * total && z + 1 < n_layers {
            out.push((z0, z + 1));
            z0 = z + 1;
            while acc * n_chunks >= k * total {
                k += 1;
            }
        }
    }
    out.push((z0, n_layers));
    out
}
