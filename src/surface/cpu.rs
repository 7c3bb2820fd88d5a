//! CPU marching cubes with one-pass grouping (seed 004 §1).
//!
//! The grid is walked in chunks of z layers (rayon, one chunk per task).
//! The inside flags are kept as bit rows (64 points per `u64`, read from the
//! volume's native type by [`Field::inside_row`]), so whole words of points
//! or cells that are all inside or all outside cost one test. Inside a
//! chunk, layer by layer:
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
//! Chunks number their vertices from 0 (global id = chunk base + local id)
//! and are stitched by uniting the groups of the vertices on the shared
//! layer; the output does not depend on the number of threads.
//! Interpolation (the one expression both backends use, in f32):
//! `t = (level − a) / (b − a)`, `u[axis] = f32(p[axis]) + t`, with `a` the
//! sample at the edge's lower end `p` and `b` at `p + e_axis`
//! ([`Field::sample`], only where an edge crosses).

use rayon::prelude::*;

use super::field::Field;
use super::tables::{self, EDGE_OWNER, corner_offset, edge_axis};
use crate::Result;

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

/// Union-find with path halving and union by index (smaller root wins, so
/// roots are the earliest-created node: deterministic).
#[derive(Debug, Default, Clone)]
pub struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    /// A new singleton; returns its id.
    pub fn push(&mut self) -> u32 {
        let id = self.parent.len() as u32;
        self.parent.push(id);
        id
    }

    /// `n` singletons.
    pub fn with_len(n: usize) -> Self {
        UnionFind {
            parent: (0..n as u32).collect(),
        }
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.parent.len()
    }

    /// Whether there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.parent.is_empty()
    }

    /// Root of `x`.
    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[x as usize];
            self.parent[x as usize] = self.parent[p as usize];
            x = self.parent[x as usize];
        }
        x
    }

    /// Unites the sets of `a` and `b`; returns the new root.
    pub fn union(&mut self, a: u32, b: u32) -> u32 {
        let (ra, rb) = (self.find(a), self.find(b));
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        self.parent[hi as usize] = lo;
        lo
    }
}

const NONE: u32 = u32::MAX;

/// Result of one z chunk (cell layers `z0..z1`).
#[derive(Debug, Default)]
struct Chunk {
    positions: Vec<[f32; 3]>,
    edges: Vec<u64>,
    triangles: Vec<[u32; 3]>,
    cells: Vec<u32>,
    /// Local union-find node of each triangle.
    tri_node: Vec<u32>,
    uf: UnionFind,
    /// Union-find node of each local vertex (own and shared-layer), or NONE.
    vertex_node: Vec<u32>,
    /// Vertices numbered by this chunk on its first layer `z0`.
    n_first_layer: usize,
    /// Vertices owned by this chunk (the rest lie on the next chunk's first layer).
    n_own: usize,
}

/// Marching cubes of `field` on the CPU; see the module docs.
pub fn marching_cubes(field: &Field<'_>) -> Result<RawSurface> {
    let [_, _, nz] = field.dims;
    if field.dims.iter().any(|&d| d < 2) {
        return Ok(RawSurface::default());
    }
    let n_layers = nz - 1;
    let threads = rayon::current_num_threads().max(1);
    let per = n_layers.div_ceil(4 * threads).max(4);
    let bounds: Vec<(usize, usize)> = (0..n_layers)
        .step_by(per)
        .map(|z0| (z0, (z0 + per).min(n_layers)))
        .collect();
    let chunks: Vec<Chunk> = bounds
        .par_iter()
        .map(|&(z0, z1)| run_chunk(field, z0, z1))
        .collect();
    Ok(stitch(chunks))
}

/// The bit-row geometry of the walk: row length and the mask of the
/// points that own a +x edge (`x < nx − 1`), per word.
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
                let lo = 64 * w;
                let n = (nx - 1).saturating_sub(lo).min(64);
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

    /// Row `y` of a layer of bits.
    #[inline]
    fn row<'a>(&self, layer: &'a [u64], y: usize) -> &'a [u64] {
        &layer[y * self.words..(y + 1) * self.words]
    }
}

/// Word `w` of `row` shifted down by one bit: bit `x` holds point `x + 1`.
#[inline]
fn next_bits(row: &[u64], w: usize) -> u64 {
    row[w] >> 1 | row.get(w + 1).map_or(0, |n| n << 63)
}

/// Fills `bits` (`ny` rows of `words` words) with the inside flags of layer `z`.
fn load_bits(field: &Field<'_>, rows: &Rows, z: usize, bits: &mut [u64]) {
    for (y, row) in bits.chunks_exact_mut(rows.words).enumerate() {
        field.inside_row(y, z, row);
    }
}

/// The numbered crossing edges of one point layer: per row and word the
/// crossing masks of the +x, +y, +z edges, and per row its first vertex
/// id. A vertex id is recovered by counting along the row ([`VertexRows`]).
struct Crossings {
    /// `ny · words` masks `[x, y, z]`.
    masks: Vec<[u64; 3]>,
    /// `ny` first vertex ids (chunk-local).
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

fn run_chunk(field: &Field<'_>, z0: usize, z1: usize) -> Chunk {
    let [_, _, nz] = field.dims;
    let rows = Rows::new(field);
    let mut out = Chunk::default();
    // Bits of layers z, z + 1, z + 2 in slot (k − z0) mod 3; crossings of
    // layers z, z + 1 in slot (k − z0) mod 2.
    let slot3 = |k: usize| (k - z0) % 3;
    let slot2 = |k: usize| (k - z0) % 2;
    let mut bits: [Vec<u64>; 3] = std::array::from_fn(|_| vec![0; rows.ny * rows.words]);
    let mut crossings = [Crossings::new(&rows), Crossings::new(&rows)];
    let mut vertex_rows = VertexRows::new(&rows);
    load_bits(field, &rows, z0, &mut bits[0]);
    load_bits(field, &rows, z0 + 1, &mut bits[1]);
    let mut next_id: u32 = 0;
    let layer = Layer {
        z: z0,
        bits: &bits[0],
        above: Some(&bits[1]),
        own: true,
    };
    number_points(
        field,
        &rows,
        &layer,
        &mut crossings[0],
        &mut next_id,
        &mut out,
    );
    out.n_first_layer = next_id as usize;
    let last_chunk = z1 == nz - 1;
    for z in z0..z1 {
        if z + 2 < nz {
            load_bits(field, &rows, z + 2, &mut bits[slot3(z + 2)]);
        }
        let shared_layer = z + 1 == z1 && !last_chunk;
        if shared_layer {
            out.n_own = next_id as usize;
        }
        let layer = Layer {
            z: z + 1,
            bits: &bits[slot3(z + 1)],
            above: (z + 2 < nz).then(|| bits[slot3(z + 2)].as_slice()),
            own: !shared_layer,
        };
        let [c0, c1] = &mut crossings;
        let (lower, upper) = if slot2(z) == 0 { (c0, c1) } else { (c1, c0) };
        number_points(field, &rows, &layer, upper, &mut next_id, &mut out);
        let cells = CellLayer {
            z,
            lower: &bits[slot3(z)],
            upper: &bits[slot3(z + 1)],
        };
        vertex_rows.clear();
        emit_cells(
            field,
            &rows,
            &cells,
            [&*lower, &*upper],
            &mut vertex_rows,
            &mut out,
        );
    }
    if last_chunk {
        out.n_own = next_id as usize;
    }
    out
}

/// A point layer to number: its bits, the bits of the layer above (none
/// on the top layer), and whether this chunk stores its vertices.
struct Layer<'a> {
    z: usize,
    bits: &'a [u64],
    above: Option<&'a [u64]>,
    own: bool,
}

/// Numbers the crossing edges of a point layer in point order (x fastest,
/// then y; axes x < y < z within a point), a word of 64 points at a time:
/// the crossing edges of a word are `m ^ next_bits(m)`, `m ^ m_y+1` and
/// `m ^ m_z+1`. Records the masks and row bases in `crossings`; stores
/// positions and edge ids when the layer is `own`.
fn number_points(
    field: &Field<'_>,
    rows: &Rows,
    layer: &Layer<'_>,
    crossings: &mut Crossings,
    next_id: &mut u32,
    out: &mut Chunk,
) {
    let (nx, ny) = (rows.nx, rows.ny);
    let level = field.level;
    let z = layer.z;
    let zf = z as f32;
    for y in 0..ny {
        crossings.row_base[y] = *next_id;
        let m = rows.row(layer.bits, y);
        let my = (y + 1 < ny).then(|| rows.row(layer.bits, y + 1));
        let mz = layer.above.map(|a| rows.row(a, y));
        let masks = &mut crossings.masks[y * rows.words..(y + 1) * rows.words];
        for (w, mask) in masks.iter_mut().enumerate() {
            let ex = (m[w] ^ next_bits(m, w)) & rows.has_x[w];
            let ey = my.map_or(0, |r| m[w] ^ r[w]);
            let ez = mz.map_or(0, |r| m[w] ^ r[w]);
            *mask = [ex, ey, ez];
            let n = ex.count_ones() + ey.count_ones() + ez.count_ones();
            if n == 0 {
                continue;
            }
            *next_id += n;
            out.vertex_node
                .extend(std::iter::repeat_n(NONE, n as usize));
            if !layer.own {
                continue;
            }
            let mut any = ex | ey | ez;
            while any != 0 {
                let s = any.trailing_zeros();
                any &= any - 1;
                let x = 64 * w + s as usize;
                let point = (x + nx * (y + ny * z)) as u64;
                let a = field.sample(x, y, z);
                for (axis, e) in [ex, ey, ez].into_iter().enumerate() {
                    if e >> s & 1 == 0 {
                        continue;
                    }
                    let b = match axis {
                        0 => field.sample(x + 1, y, z),
                        1 => field.sample(x, y + 1, z),
                        _ => field.sample(x, y, z + 1),
                    };
                    let t = (level - a) / (b - a);
                    let mut u = [x as f32, y as f32, zf];
                    u[axis] += t;
                    out.positions.push(u);
                    out.edges.push(3 * point + axis as u64);
                }
            }
        }
    }
}

/// Vertex ids of the point rows a cell row reads — rows `y` and `y + 1`
/// of the lower and upper layer — unpacked from [`Crossings`] into small
/// per-row arrays (`[layer][y mod 2][axis][x]`), each row once per cell layer.
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
                let slot =
                    &mut self.ids[(2 * dz + yy % 2) * 3 * nx..(2 * dz + yy % 2 + 1) * 3 * nx];
                let (ids_x, rest) = slot.split_at_mut(nx);
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

    /// Id of the vertex on the `axis` edge of point `(x, y)` of layer `dz`
    /// (row `y` held).
    #[inline]
    fn get(&self, dz: usize, y: usize, axis: usize, x: usize) -> u32 {
        self.ids[((2 * dz + y % 2) * 3 + axis) * self.nx + x]
    }
}

/// A cell layer `z`: the bits of its lower and upper point layers.
struct CellLayer<'a> {
    z: usize,
    lower: &'a [u64],
    upper: &'a [u64],
}

/// Emits the triangles of a cell layer in cell order (x fastest, then y),
/// a word of 64 cells at a time: a cell is crossed when its eight corners
/// (bits `x` and `x + 1` of four rows) are neither all 0 nor all 1.
fn emit_cells(
    field: &Field<'_>,
    rows: &Rows,
    cells: &CellLayer<'_>,
    crossings: [&Crossings; 2],
    vertex_rows: &mut VertexRows,
    out: &mut Chunk,
) {
    let [nx, ny, _] = field.dims;
    let table = tables::table();
    let (cx, cy) = (nx - 1, ny - 1);
    // Offset `[x, y, z]` and axis of each local edge's owner point.
    let owner: [([usize; 3], usize); 12] =
        std::array::from_fn(|e| (corner_offset(EDGE_OWNER[e] as usize), edge_axis(e)));
    for y in 0..cy {
        // Corner rows: 0 = (y, z), 1 = (y + 1, z), 2 = (y, z + 1), 3 = (y + 1, z + 1).
        let r = [
            rows.row(cells.lower, y),
            rows.row(cells.lower, y + 1),
            rows.row(cells.upper, y),
            rows.row(cells.upper, y + 1),
        ];
        let mut held = false;
        for w in 0..rows.words {
            let lo = r.map(|row| row[w]);
            let hi = r.map(|row| next_bits(row, w));
            let any = lo[0] | lo[1] | lo[2] | lo[3] | hi[0] | hi[1] | hi[2] | hi[3];
            let all = lo[0] & lo[1] & lo[2] & lo[3] & hi[0] & hi[1] & hi[2] & hi[3];
            let mut crossed = any & !all & rows.has_x[w];
            if crossed != 0 && !held {
                vertex_rows.hold(crossings, y);
                held = true;
            }
            while crossed != 0 {
                let s = crossed.trailing_zeros();
                crossed &= crossed - 1;
                let mut case = 0usize;
                for k in 0..4 {
                    case |= ((lo[k] >> s & 1) as usize) << (2 * k);
                    case |= ((hi[k] >> s & 1) as usize) << (2 * k + 1);
                }
                let x = 64 * w + s as usize;
                let cell = (x + cx * (y + cy * cells.z)) as u32;
                for tri in table.case(case) {
                    let id = |e: u8| {
                        let ([ox, oy, oz], axis) = owner[e as usize];
                        vertex_rows.get(oz, y + oy, axis, x + ox)
                    };
                    let v = [id(tri[0]), id(tri[1]), id(tri[2])];
                    join_group(out, v);
                    out.triangles.push(v);
                    out.cells.push(cell);
                }
            }
        }
    }
}

/// One-pass grouping: the new triangle `v` joins the groups of the
/// triangles already using its vertices (seed §1: add to one group, start a
/// new group, or merge several).
fn join_group(out: &mut Chunk, v: [u32; 3]) {
    let mut node = NONE;
    for &i in &v {
        let g = out.vertex_node[i as usize];
        if g != NONE && g != node {
            node = if node == NONE {
                out.uf.find(g)
            } else {
                out.uf.union(node, g)
            };
        }
    }
    if node == NONE {
        node = out.uf.push();
    }
    for &i in &v {
        if out.vertex_node[i as usize] == NONE {
            out.vertex_node[i as usize] = node;
        }
    }
    out.tri_node.push(node);
}

/// Joins the chunks: global vertex ids, global union-find across the shared
/// layers, canonical group numbers (by first triangle).
fn stitch(chunks: Vec<Chunk>) -> RawSurface {
    let mut uf = UnionFind::default();
    let mut node_base = Vec::with_capacity(chunks.len());
    let mut vert_base = Vec::with_capacity(chunks.len());
    let (mut nodes, mut verts) = (0u32, 0u32);
    for c in &chunks {
        node_base.push(nodes);
        vert_base.push(verts);
        nodes += c.uf.len() as u32;
        verts += c.n_own as u32;
    }
    uf.parent = Vec::with_capacity(nodes as usize);
    for (c, &base) in chunks.iter().zip(&node_base) {
        let mut local = c.uf.clone();
        for i in 0..local.len() as u32 {
            let r = local.find(i);
            uf.parent.push(base + r);
        }
    }
    // Seams: the shared layer is numbered by both neighbours in the same order.
    for k in 1..chunks.len() {
        let (prev, next) = (&chunks[k - 1], &chunks[k]);
        let shared = &prev.vertex_node[prev.n_own..];
        for (i, &a) in shared.iter().enumerate().take(next.n_first_layer) {
            let b = next.vertex_node.get(i).copied().unwrap_or(NONE);
            if a != NONE && b != NONE {
                uf.union(node_base[k - 1] + a, node_base[k] + b);
            }
        }
    }
    let n_tris: usize = chunks.iter().map(|c| c.triangles.len()).sum();
    let mut out = RawSurface {
        positions: Vec::with_capacity(verts as usize),
        edges: Vec::with_capacity(verts as usize),
        triangles: Vec::with_capacity(n_tris),
        cells: Vec::with_capacity(n_tris),
        groups: Vec::with_capacity(n_tris),
        n_groups: 0,
    };
    let mut canonical = vec![NONE; nodes as usize];
    for (k, c) in chunks.into_iter().enumerate() {
        let vb = vert_base[k];
        out.positions.extend_from_slice(&c.positions);
        out.edges.extend_from_slice(&c.edges);
        out.triangles
            .extend(c.triangles.iter().map(|t| t.map(|i| i + vb)));
        out.cells.extend_from_slice(&c.cells);
        for &node in &c.tri_node {
            let root = uf.find(node_base[k] + node) as usize;
            if canonical[root] == NONE {
                canonical[root] = out.n_groups as u32;
                out.n_groups += 1;
            }
            out.groups.push(canonical[root]);
        }
    }
    out
}
