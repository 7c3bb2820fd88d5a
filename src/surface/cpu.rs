//! CPU marching cubes with one-pass grouping (seed 004 §1).
//!
//! Two passes over the grid, each parallel over z layers (rayon):
//! - *count*: the inside flags of every layer as bit rows (64 points per
//!   `u64`, read once from the volume's native type by
//!   [`Field::inside_row`]; 1 bit per sample kept), and per layer the number
//!   of vertices and triangles. Whole words of points or cells that are all
//!   inside or all outside cost one test. The exclusive sums give every
//!   layer its first vertex and triangle id, so
//! - *emit* writes straight into the output arrays, in chunks of z layers
//!   of about equal work, one task per chunk. Inside a chunk, layer by layer:
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
//! end `p` and `b` at `p + e_axis` ([`NativeSamples::sample`], the volume
//! read in its own type, only where an edge crosses). The clamp
//! ([`T_MIN`]) keeps every vertex strictly inside its edge, so no triangle
//! has zero area (see there).

use rayon::prelude::*;

use crate::foundation::UnionFind;

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

use super::field::{Field, NativeSamples, SampleVisitor, Scalar};
use super::tables::{self, EDGE_OWNER, corner_offset, edge_axis};
use crate::{Error, Result};

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
    /// Number of groups.
    pub n_groups: usize,
}

const NONE: u32 = u32::MAX;

/// Marching cubes of `field` on the CPU; see the module docs. Errors when
/// the surface has 2³² − 1 or more vertices or triangles.
pub fn marching_cubes(field: &Field<'_>) -> Result<RawSurface> {
    if field.dims.iter().any(|&d| d < 2) {
        return Ok(RawSurface::default());
    }
    let bits = Bits::load(field);
    let nz = field.dims[2];
    let table = tables::table();
    // Vertices of point layer z, triangles of cell layer z (none on the top).
    let counts: Vec<(u64, u64)> = (0..nz)
        .into_par_iter()
        .map(|z| {
            let tris = if z + 1 < nz {
                count_triangles(&bits, z, table)
            } else {
                0
            };
            (count_vertices(&bits, z), tris)
        })
        .collect();
    let vbase = exclusive_sum(counts.iter().map(|c| c.0), "vertices")?;
    let tbase = exclusive_sum(counts.iter().map(|c| c.1), "triangles")?;
    let (n_v, n_t) = (vbase[nz] as usize, tbase[nz] as usize);
    let chunks = chunk_bounds(&bits, &counts);

    let mut positions = vec![[0f32; 3]; n_v];
    let mut edges = vec![0u64; n_v];
    let mut triangles = vec![[0u32; 3]; n_t];
    let mut cells = vec![0u32; n_t];
    // Union-find node of each triangle, then its group.
    let mut groups = vec![0u32; n_t];
    let mut outs = Vec::with_capacity(chunks.len());
    {
        let (mut p, mut e) = (positions.as_mut_slice(), edges.as_mut_slice());
        let (mut t, mut c, mut g) = (
            triangles.as_mut_slice(),
            cells.as_mut_slice(),
            groups.as_mut_slice(),
        );
        for (k, &(z0, z1)) in chunks.iter().enumerate() {
            let own_end = if k + 1 == chunks.len() { nz } else { z1 };
            let nv = (vbase[own_end] - vbase[z0]) as usize;
            let nt = (tbase[z1] - tbase[z0]) as usize;
            let (p0, p1) = std::mem::take(&mut p).split_at_mut(nv);
            let (e0, e1) = std::mem::take(&mut e).split_at_mut(nv);
            let (t0, t1) = std::mem::take(&mut t).split_at_mut(nt);
            let (c0, c1) = std::mem::take(&mut c).split_at_mut(nt);
            let (g0, g1) = std::mem::take(&mut g).split_at_mut(nt);
            (p, e, t, c, g) = (p1, e1, t1, c1, g1);
            outs.push(ChunkOut {
                z0,
                z1,
                own_end,
                first_vertex: vbase[z0] as u32,
                n_vertices: (vbase[z1 + 1] - vbase[z0]) as usize,
                positions: p0,
                edges: e0,
                triangles: t0,
                cells: c0,
                tri_node: g0,
            });
        }
    }
    let chunk_groups = field.visit_samples(RunChunks { bits: &bits, outs });
    let n_groups = stitch(&chunk_groups, &chunks, &vbase, &tbase, &mut groups);
    Ok(RawSurface {
        positions,
        edges,
        triangles,
        cells,
        groups,
        n_groups,
    })
}

/// Exclusive prefix sums (one more entry than `counts`: the total last);
/// errors when the total reaches `u32::MAX`.
fn exclusive_sum(counts: impl Iterator<Item = u64>, what: &str) -> Result<Vec<u64>> {
    let mut out = vec![0u64];
    let mut sum = 0u64;
    for c in counts {
        sum += c;
        out.push(sum);
    }
    if sum >= u64::from(u32::MAX) {
        return Err(Error::InvalidInput(format!(
            "marching cubes: {sum} {what} exceed 32-bit numbering"
        )));
    }
    Ok(out)
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

/// The bit-row geometry: row length and the mask of the points that own a
/// +x edge (`x < nx − 1`), per word.
struct Rows {
    nx: usize,
    ny: usize,
    words: usize,
    has_x: Vec<u64>,
}

impl Rows {
    fn new(field: &Field<'_>) -> Self {
        let [nx, ny, _] = field.dims;
        let words = field.row_words();
        let has_x = (0..words)
            .map(|w| {
                let n = (nx - 1).saturating_sub(64 * w).min(64);
                if n == 64 { u64::MAX } else { (1u64 << n) - 1 }
            })
            .collect();
        Rows {
            nx,
            ny,
            words,
            has_x,
        }
    }
}

/// Inside flags of the whole (padded) grid: `nz` layers of `ny` rows of
/// `words` words, 1 bit per sample.
struct Bits {
    rows: Rows,
    nz: usize,
    data: Vec<u64>,
}

impl Bits {
    /// Reads every layer (in parallel) through [`Field::inside_row`].
    fn load(field: &Field<'_>) -> Self {
        let rows = Rows::new(field);
        let nz = field.dims[2];
        let plane = rows.ny * rows.words;
        let mut data = vec![0u64; nz * plane];
        data.par_chunks_mut(plane)
            .enumerate()
            .for_each(|(z, layer)| {
                for (y, row) in layer.chunks_exact_mut(rows.words).enumerate() {
                    field.inside_row(y, z, row);
                }
            });
        Bits { rows, nz, data }
    }

    /// Row `y` of layer `z`.
    #[inline]
    fn row(&self, y: usize, z: usize) -> &[u64] {
        let w = self.rows.words;
        let start = (z * self.rows.ny + y) * w;
        &self.data[start..start + w]
    }

    /// Crossing masks `[x, y, z]` of word `w` of row `y` of layer `z`: the
    /// points whose +x, +y, +z edge joins an inside and an outside sample.
    #[inline]
    fn crossings(&self, y: usize, z: usize, w: usize) -> [u64; 3] {
        let m = self.row(y, z);
        let ex = (m[w] ^ next_bits(m, w)) & self.rows.has_x[w];
        let ey = if y + 1 < self.rows.ny {
            m[w] ^ self.row(y + 1, z)[w]
        } else {
            0
        };
        let ez = if z + 1 < self.nz {
            m[w] ^ self.row(y, z + 1)[w]
        } else {
            0
        };
        [ex, ey, ez]
    }

    /// The four corner rows of cell row `y` of cell layer `z`:
    /// (y, z), (y + 1, z), (y, z + 1), (y + 1, z + 1).
    #[inline]
    fn cell_rows(&self, y: usize, z: usize) -> [&[u64]; 4] {
        [
            self.row(y, z),
            self.row(y + 1, z),
            self.row(y, z + 1),
            self.row(y + 1, z + 1),
        ]
    }
}

/// Word `w` of `row` shifted down by one bit: bit `x` holds point `x + 1`.
#[inline]
fn next_bits(row: &[u64], w: usize) -> u64 {
    row[w] >> 1 | row.get(w + 1).map_or(0, |n| n << 63)
}

/// Word `w` of 64 cells of a cell row: corner bits at `x` (`lo`) and at
/// `x + 1` (`hi`) of the four corner rows, and the mask of crossed cells
/// (corners neither all inside nor all outside).
#[inline]
fn cell_word(r: &[&[u64]; 4], w: usize, has_x: u64) -> ([u64; 4], [u64; 4], u64) {
    let lo = r.map(|row| row[w]);
    let hi = r.map(|row| next_bits(row, w));
    let any = lo[0] | lo[1] | lo[2] | lo[3] | hi[0] | hi[1] | hi[2] | hi[3];
    let all = lo[0] & lo[1] & lo[2] & lo[3] & hi[0] & hi[1] & hi[2] & hi[3];
    (lo, hi, any & !all & has_x)
}

/// Case index of the cell at bit `s` (corner `c = x + 2y + 4z` is bit `c`).
#[inline]
fn case_at(lo: &[u64; 4], hi: &[u64; 4], s: u32) -> usize {
    let mut case = 0usize;
    for k in 0..4 {
        case |= ((lo[k] >> s & 1) as usize) << (2 * k);
        case |= ((hi[k] >> s & 1) as usize) << (2 * k + 1);
    }
    case
}

/// Vertices numbered on point layer `z`.
fn count_vertices(bits: &Bits, z: usize) -> u64 {
    let mut n = 0u64;
    for y in 0..bits.rows.ny {
        for w in 0..bits.rows.words {
            let [ex, ey, ez] = bits.crossings(y, z, w);
            n += u64::from(ex.count_ones() + ey.count_ones() + ez.count_ones());
        }
    }
    n
}

/// Triangles emitted on cell layer `z`.
fn count_triangles(bits: &Bits, z: usize, table: &tables::CaseTable) -> u64 {
    let mut n = 0u64;
    for y in 0..bits.rows.ny - 1 {
        let r = bits.cell_rows(y, z);
        for w in 0..bits.rows.words {
            let (lo, hi, mut crossed) = cell_word(&r, w, bits.rows.has_x[w]);
            while crossed != 0 {
                let s = crossed.trailing_zeros();
                crossed &= crossed - 1;
                n += table.case(case_at(&lo, &hi, s)).len() as u64;
            }
        }
    }
    n
}

/// One chunk's share of the output: cell layers `z0..z1`, point layers
/// `z0..=z1` of which it stores `z0..own_end`.
struct ChunkOut<'a> {
    z0: usize,
    z1: usize,
    own_end: usize,
    /// Global id of the first vertex of layer `z0`.
    first_vertex: u32,
    /// Vertices on layers `z0..=z1`.
    n_vertices: usize,
    positions: &'a mut [[f32; 3]],
    edges: &'a mut [u64],
    triangles: &'a mut [[u32; 3]],
    cells: &'a mut [u32],
    /// Local union-find node of each triangle.
    tri_node: &'a mut [u32],
}

/// One chunk's grouping state.
struct ChunkGroups {
    uf: UnionFind,
    /// Union-find node of each vertex of layers `z0..=z1` (by id − first
    /// id), or NONE.
    vertex_node: Vec<u32>,
    first_vertex: u32,
}

/// Write cursors of a chunk.
struct Emit<'a, 'o> {
    out: &'a mut ChunkOut<'o>,
    groups: ChunkGroups,
    n_positions: usize,
    n_triangles: usize,
}

/// The numbered crossing edges of one point layer: per row and word the
/// crossing masks, and per row its first vertex id. A vertex id is
/// recovered by counting along the row ([`VertexRows`]).
struct Crossings {
    /// `ny · words` masks `[x, y, z]`.
    masks: Vec<[u64; 3]>,
    /// `ny` first vertex ids.
    row_base: Vec<u32>,
}

impl Crossings {
    fn new(rows: &Rows) -> Self {
        Crossings {
            masks: vec![[0; 3]; rows.ny * rows.words],
            row_base: vec![0; rows.ny],
        }
    }
}

/// The emit pass over all chunks (in parallel), with the samples read in
/// the volume's native type.
struct RunChunks<'b, 'o> {
    bits: &'b Bits,
    outs: Vec<ChunkOut<'o>>,
}

impl SampleVisitor for RunChunks<'_, '_> {
    type Output = Vec<ChunkGroups>;

    fn visit<T: Scalar>(self, samples: NativeSamples<'_, '_, T>) -> Vec<ChunkGroups> {
        let bits = self.bits;
        self.outs
            .into_par_iter()
            .map(|out| run_chunk(samples, bits, out))
            .collect()
    }
}

fn run_chunk<T: Scalar>(
    samples: NativeSamples<'_, '_, T>,
    bits: &Bits,
    mut out: ChunkOut<'_>,
) -> ChunkGroups {
    let rows = &bits.rows;
    let (z0, z1, own_end) = (out.z0, out.z1, out.own_end);
    let mut emit = Emit {
        groups: ChunkGroups {
            uf: UnionFind::default(),
            vertex_node: vec![NONE; out.n_vertices],
            first_vertex: out.first_vertex,
        },
        out: &mut out,
        n_positions: 0,
        n_triangles: 0,
    };
    // Crossings of layers z, z + 1 in slot (k − z0) mod 2.
    let mut crossings = [Crossings::new(rows), Crossings::new(rows)];
    let mut vertex_rows = VertexRows::new(rows);
    let mut next_id = emit.groups.first_vertex;
    number_points(
        &samples,
        bits,
        z0,
        true,
        &mut crossings[0],
        &mut next_id,
        &mut emit,
    );
    for z in z0..z1 {
        let [c0, c1] = &mut crossings;
        let (lower, upper) = if (z - z0) % 2 == 0 {
            (c0, c1)
        } else {
            (c1, c0)
        };
        let own = z + 1 < own_end;
        number_points(&samples, bits, z + 1, own, upper, &mut next_id, &mut emit);
        vertex_rows.clear();
        emit_cells(bits, z, [&*lower, &*upper], &mut vertex_rows, &mut emit);
    }
    emit.groups
}

/// Numbers the crossing edges of point layer `z` in point order (x
/// fastest, then y; axes x < y < z within a point), a word of 64 points at
/// a time. Records the masks and row bases in `crossings`; stores positions
/// and edge ids when the layer is `own`.
fn number_points<T: Scalar>(
    samples: &NativeSamples<'_, '_, T>,
    bits: &Bits,
    z: usize,
    own: bool,
    crossings: &mut Crossings,
    next_id: &mut u32,
    emit: &mut Emit<'_, '_>,
) {
    let Rows { nx, ny, words, .. } = bits.rows;
    let level = samples.level();
    let zf = z as f32;
    for y in 0..ny {
        crossings.row_base[y] = *next_id;
        let masks = &mut crossings.masks[y * words..(y + 1) * words];
        for (w, mask) in masks.iter_mut().enumerate() {
            let [ex, ey, ez] = bits.crossings(y, z, w);
            *mask = [ex, ey, ez];
            *next_id += ex.count_ones() + ey.count_ones() + ez.count_ones();
            if !own {
                continue;
            }
            let mut any = ex | ey | ez;
            while any != 0 {
                let s = any.trailing_zeros();
                any &= any - 1;
                let x = 64 * w + s as usize;
                let point = (x + nx * (y + ny * z)) as u64;
                let a = samples.sample(x, y, z);
                let mut vertex = |axis: usize, b: f32| {
                    let t = ((level - a) / (b - a)).clamp(T_MIN, 1.0 - T_MIN);
                    let mut u = [x as f32, y as f32, zf];
                    u[axis] += t;
                    emit.out.positions[emit.n_positions] = u;
                    emit.out.edges[emit.n_positions] = 3 * point + axis as u64;
                    emit.n_positions += 1;
                };
                if ex >> s & 1 == 1 {
                    vertex(0, samples.sample(x + 1, y, z));
                }
                if ey >> s & 1 == 1 {
                    vertex(1, samples.sample(x, y + 1, z));
                }
                if ez >> s & 1 == 1 {
                    vertex(2, samples.sample(x, y, z + 1));
                }
            }
        }
    }
}

/// Vertex ids of the point rows a cell row reads — rows `y` and `y + 1`
/// of the lower and upper layer — unpacked from [`Crossings`] into small
/// per-row arrays, each row once per cell layer.
struct VertexRows {
    nx: usize,
    words: usize,
    /// Ids at `((2·layer + y mod 2)·3 + axis)·nx + x`.
    ids: Vec<u32>,
    /// Row held by each `[layer][y mod 2]` slot (`usize::MAX`: none).
    held: [[usize; 2]; 2],
}

impl VertexRows {
    fn new(rows: &Rows) -> Self {
        VertexRows {
            nx: rows.nx,
            words: rows.words,
            ids: vec![NONE; 12 * rows.nx],
            held: [[usize::MAX; 2]; 2],
        }
    }

    /// Forgets the rows held (a new cell layer starts).
    fn clear(&mut self) {
        self.held = [[usize::MAX; 2]; 2];
    }

    /// Makes rows `y` and `y + 1` of the lower and upper layer available.
    fn hold(&mut self, layers: [&Crossings; 2], y: usize) {
        let nx = self.nx;
        for (dz, c) in layers.into_iter().enumerate() {
            for yy in [y, y + 1] {
                if self.held[dz][yy % 2] == yy {
                    continue;
                }
                let slot = 2 * dz + yy % 2;
                let ids = &mut self.ids[slot * 3 * nx..(slot + 1) * 3 * nx];
                let (ids_x, rest) = ids.split_at_mut(nx);
                let (ids_y, ids_z) = rest.split_at_mut(nx);
                let mut id = c.row_base[yy];
                let masks = &c.masks[yy * self.words..(yy + 1) * self.words];
                for (w, &[ex, ey, ez]) in masks.iter().enumerate() {
                    let mut any = ex | ey | ez;
                    while any != 0 {
                        let s = any.trailing_zeros();
                        any &= any - 1;
                        let x = 64 * w + s as usize;
                        if ex >> s & 1 == 1 {
                            ids_x[x] = id;
                            id += 1;
                        }
                        if ey >> s & 1 == 1 {
                            ids_y[x] = id;
                            id += 1;
                        }
                        if ez >> s & 1 == 1 {
                            ids_z[x] = id;
                            id += 1;
                        }
                    }
                }
                self.held[dz][yy % 2] = yy;
            }
        }
    }

    /// Offset into the held ids of each local edge of the cells of row `y`
    /// (add the cell's `x`).
    fn edge_offsets(&self, y: usize) -> [usize; 12] {
        std::array::from_fn(|e| {
            let [ox, oy, oz] = corner_offset(EDGE_OWNER[e] as usize);
            ((2 * oz + (y + oy) % 2) * 3 + edge_axis(e)) * self.nx + ox
        })
    }
}

/// Emits the triangles of cell layer `z` in cell order (x fastest, then
/// y), a word of 64 cells at a time.
fn emit_cells(
    bits: &Bits,
    z: usize,
    crossings: [&Crossings; 2],
    vertex_rows: &mut VertexRows,
    emit: &mut Emit<'_, '_>,
) {
    let Rows { nx, ny, words, .. } = bits.rows;
    let table = tables::table();
    let (cx, cy) = (nx - 1, ny - 1);
    for y in 0..cy {
        let r = bits.cell_rows(y, z);
        let mut held = false;
        let offsets = vertex_rows.edge_offsets(y);
        for w in 0..words {
            let (lo, hi, mut crossed) = cell_word(&r, w, bits.rows.has_x[w]);
            if crossed != 0 && !held {
                vertex_rows.hold(crossings, y);
                held = true;
            }
            while crossed != 0 {
                let s = crossed.trailing_zeros();
                crossed &= crossed - 1;
                let x = 64 * w + s as usize;
                let cell = (x + cx * (y + cy * z)) as u32;
                let ids = &vertex_rows.ids[x..];
                for tri in table.case(case_at(&lo, &hi, s)) {
                    let id = |e: u8| ids[offsets[e as usize]];
                    let v = [id(tri[0]), id(tri[1]), id(tri[2])];
                    let node = join_group(&mut emit.groups, v);
                    let i = emit.n_triangles;
                    emit.out.triangles[i] = v;
                    emit.out.cells[i] = cell;
                    emit.out.tri_node[i] = node;
                    emit.n_triangles += 1;
                }
            }
        }
    }
}

/// One-pass grouping: the new triangle `v` joins the groups of the
/// triangles already using its vertices (seed §1: add to one group, start a
/// new group, or merge several). Returns its union-find node.
fn join_group(groups: &mut ChunkGroups, v: [u32; 3]) -> u32 {
    let base = groups.first_vertex;
    let mut node = NONE;
    for &i in &v {
        let g = groups.vertex_node[(i - base) as usize];
        if g != NONE && g != node {
            node = if node == NONE {
                groups.uf.find(g)
            } else {
                groups.uf.union(node, g)
            };
        }
    }
    if node == NONE {
        node = groups.uf.push();
    }
    for &i in &v {
        let slot = &mut groups.vertex_node[(i - base) as usize];
        if *slot == NONE {
            *slot = node;
        }
    }
    node
}

/// Joins the chunks' grouping: one union-find over all chunks' nodes, the
/// vertices of each shared layer united, then `groups` (per triangle: the
/// chunk-local node on entry) becomes the canonical group, numbered by
/// first triangle. Returns the number of groups.
fn stitch(
    chunk_groups: &[ChunkGroups],
    chunks: &[(usize, usize)],
    vbase: &[u64],
    tbase: &[u64],
    groups: &mut [u32],
) -> usize {
    let mut node_base = Vec::with_capacity(chunk_groups.len());
    let mut n_nodes = 0u32;
    for c in chunk_groups {
        node_base.push(n_nodes);
        n_nodes += c.uf.len() as u32;
    }
    let mut uf = UnionFind::default();
    for c in chunk_groups {
        uf.append(&c.uf);
    }
    // Seams: chunk k's first layer is chunk k − 1's last.
    for k in 1..chunk_groups.len() {
        let (prev, next) = (&chunk_groups[k - 1], &chunk_groups[k]);
        let z = chunks[k].0;
        for id in vbase[z] as u32..vbase[z + 1] as u32 {
            let a = prev.vertex_node[(id - prev.first_vertex) as usize];
            let b = next.vertex_node[(id - next.first_vertex) as usize];
            if a != NONE && b != NONE {
                uf.union(node_base[k - 1] + a, node_base[k] + b);
            }
        }
    }
    let root = uf.roots();
    // Per chunk: global roots in place and the distinct roots in order of
    // first triangle; then canonical numbers in chunk order.
    let mut slices = Vec::with_capacity(chunks.len());
    let mut rest = groups;
    for &(z0, z1) in chunks {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut((tbase[z1] - tbase[z0]) as usize);
        slices.push(head);
        rest = tail;
    }
    let firsts: Vec<Vec<u32>> = slices
        .par_iter_mut()
        .zip(&node_base)
        .map(|(tris, &base)| {
            let mut seen = std::collections::HashSet::new();
            let mut order = Vec::new();
            let mut prev = NONE;
            for g in tris.iter_mut() {
                *g = root[(base + *g) as usize];
                if *g != prev && seen.insert(*g) {
                    order.push(*g);
                }
                prev = *g;
            }
            order
        })
        .collect();
    let mut canonical = vec![NONE; n_nodes as usize];
    let mut n_groups = 0u32;
    for r in firsts.iter().flatten() {
        if canonical[*r as usize] == NONE {
            canonical[*r as usize] = n_groups;
            n_groups += 1;
        }
    }
    slices.into_par_iter().for_each(|tris| {
        for g in tris.iter_mut() {
            *g = canonical[*g as usize];
        }
    });
    n_groups as usize
}
