//! CPU marching cubes with one-pass grouping (seed 004 §1).
//!
//! The grid is walked in chunks of z layers (rayon, one chunk per task).
//! Inside a chunk, layer by layer:
//! 1. *points*: every sample point `p` owns its +x, +y, +z grid edges; each
//!    crossing edge becomes one vertex, numbered in point order (x fastest,
//!    then y, then z; axes x < y < z within a point) — the same numbering the
//!    GPU's scan produces, so vertices are welded by edge id and both
//!    backends give identical indices;
//! 2. *cells*: each cell looks its case up in [`super::tables`] and emits
//!    triangles in table order; each new triangle joins the groups of the
//!    triangles already using its vertices — neighbours in the current and
//!    previous cells — with union-find (seed §1 cases: join, new, merge).
//!
//! Chunks number their vertices from 0 (global id = chunk base + local id)
//! and are stitched by uniting the groups of the vertices on the shared
//! layer. Interpolation (the one expression both backends use, in f32):
//! `t = (level − a) / (b − a)`, `u[axis] = f32(p[axis]) + t`, with `a` the
//! sample at the edge's lower end `p` and `b` at `p + e_axis`.

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

/// Per-layer buffers of the chunk walk.
struct Layer {
    values: Vec<f32>,
    inside: Vec<u8>,
    /// Vertex id of each point's +x, +y, +z edge (NONE where not crossing).
    vid: [Vec<u32>; 3],
}

impl Layer {
    fn new(n: usize) -> Self {
        Layer {
            values: vec![0.0; n],
            inside: vec![0; n],
            vid: [vec![NONE; n], vec![NONE; n], vec![NONE; n]],
        }
    }

    fn load(&mut self, field: &Field<'_>, z: usize) {
        field.layer(z, &mut self.values);
        let level = field.level;
        for (m, &v) in self.inside.iter_mut().zip(&self.values) {
            *m = u8::from(v >= level);
        }
    }
}

fn run_chunk(field: &Field<'_>, z0: usize, z1: usize) -> Chunk {
    let [nx, ny, nz] = field.dims;
    let n = nx * ny;
    let mut out = Chunk::default();
    // Ring of three layers z, z + 1, z + 2; layer k lives in slot (k − z0) mod 3.
    let slot = |k: usize| (k - z0) % 3;
    let mut ring = [Layer::new(n), Layer::new(n), Layer::new(n)];
    ring[0].load(field, z0);
    ring[1].load(field, z0 + 1);
    let mut next_id: u32 = 0;
    number_points(field, &mut ring, 0, z0, true, &mut next_id, &mut out);
    out.n_first_layer = next_id as usize;
    let last_chunk = z1 == nz - 1;
    for z in z0..z1 {
        if z + 2 < nz {
            ring[slot(z + 2)].load(field, z + 2);
        }
        let shared_layer = z + 1 == z1 && !last_chunk;
        if shared_layer {
            out.n_own = next_id as usize;
        }
        number_points(
            field,
            &mut ring,
            slot(z + 1),
            z + 1,
            !shared_layer,
            &mut next_id,
            &mut out,
        );
        emit_cells(field, &ring[slot(z)], &ring[slot(z + 1)], z, &mut out);
    }
    if last_chunk {
        out.n_own = next_id as usize;
    }
    out
}

/// Numbers the crossing edges of layer `z` (in `ring[slot]`); stores
/// positions and edge ids when the layer is `own`.
fn number_points(
    field: &Field<'_>,
    ring: &mut [Layer; 3],
    slot: usize,
    z: usize,
    own: bool,
    next_id: &mut u32,
    out: &mut Chunk,
) {
    let [nx, ny, nz] = field.dims;
    let level = field.level;
    let up = (slot + 1) % 3;
    let has_up = z + 1 < nz;
    let (lo, hi) = split_two(ring, slot, up);
    let layer = lo;
    let above = hi;
    // Stale ids are never read: cells only look up crossing edges, and every
    // crossing edge of this layer is numbered below.
    let mut vid = std::mem::take(&mut layer.vid);
    let zf = z as f32;
    for y in 0..ny {
        let row = y * nx;
        let has_y = y + 1 < ny;
        let m = &layer.inside[row..row + nx];
        let my = if has_y {
            &layer.inside[row + nx..row + 2 * nx]
        } else {
            m
        };
        let mz = if has_up {
            &above.inside[row..row + nx]
        } else {
            m
        };
        let mut x = 0;
        while x < nx {
            // Eight points at once when none of their edges cross.
            if x + 9 <= nx {
                let w = word(m, x);
                if w == word(m, x + 1) && w == word(my, x) && w == word(mz, x) {
                    x += 8;
                    continue;
                }
            }
            let q = row + x;
            let mq = m[x];
            let a = layer.values[q];
            let point = (q + z * nx * ny) as u64;
            let mut add = |axis: usize, b: f32, out: &mut Chunk, vid: &mut [Vec<u32>; 3]| {
                vid[axis][q] = *next_id;
                *next_id += 1;
                out.vertex_node.push(NONE);
                if own {
                    let t = (level - a) / (b - a);
                    let mut u = [x as f32, y as f32, zf];
                    u[axis] += t;
                    out.positions.push(u);
                    out.edges.push(3 * point + axis as u64);
                }
            };
            if x + 1 < nx && m[x + 1] != mq {
                add(0, layer.values[q + 1], out, &mut vid);
            }
            if has_y && my[x] != mq {
                add(1, layer.values[q + nx], out, &mut vid);
            }
            if has_up && mz[x] != mq {
                add(2, above.values[q], out, &mut vid);
            }
            x += 1;
        }
    }
    layer.vid = vid;
}

/// Eight inside flags starting at `x` as one word (`x + 8 <= s.len()`).
#[inline]
fn word(s: &[u8], x: usize) -> u64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&s[x..x + 8]);
    u64::from_ne_bytes(b)
}

/// Mutable references to two distinct ring slots.
fn split_two(ring: &mut [Layer; 3], a: usize, b: usize) -> (&mut Layer, &mut Layer) {
    let [r0, r1, r2] = ring;
    match (a, b) {
        (0, 1) => (r0, r1),
        (1, 2) => (r1, r2),
        (2, 0) => (r2, r0),
        (1, 0) => (r1, r0),
        (2, 1) => (r2, r1),
        _ => (r0, r2),
    }
}

/// Emits the triangles of cell layer `z` (between `lower` and `upper`).
fn emit_cells(field: &Field<'_>, lower: &Layer, upper: &Layer, z: usize, out: &mut Chunk) {
    let [nx, ny, _] = field.dims;
    let table = tables::table();
    let (cx, cy) = (nx - 1, ny - 1);
    let layers = [lower, upper];
    // Offset of each local edge's owner point from the cell origin.
    let owner: [(usize, usize); 12] = std::array::from_fn(|e| {
        let o = corner_offset(EDGE_OWNER[e] as usize);
        (o[0] + o[1] * nx, o[2])
    });
    for y in 0..cy {
        let r0 = y * nx;
        let r1 = r0 + nx;
        let rows = [
            &lower.inside[r0..r0 + nx],
            &lower.inside[r1..r1 + nx],
            &upper.inside[r0..r0 + nx],
            &upper.inside[r1..r1 + nx],
        ];
        let mut x = 0;
        while x < cx {
            // Eight empty (or full) cells at once.
            if x + 9 <= nx {
                let w = word(rows[0], x);
                if rows.iter().all(|r| word(r, x) == w && word(r, x + 1) == w) {
                    x += 8;
                    continue;
                }
            }
            let case = usize::from(rows[0][x])
                | usize::from(rows[0][x + 1]) << 1
                | usize::from(rows[1][x]) << 2
                | usize::from(rows[1][x + 1]) << 3
                | usize::from(rows[2][x]) << 4
                | usize::from(rows[2][x + 1]) << 5
                | usize::from(rows[3][x]) << 6
                | usize::from(rows[3][x + 1]) << 7;
            if case == 0 || case == 255 {
                x += 1;
                continue;
            }
            let q = r0 + x;
            let cell = (x + cx * (y + cy * z)) as u32;
            for tri in table.case(case) {
                let v = tri.map(|e| {
                    let e = e as usize;
                    let (dq, dz) = owner[e];
                    layers[dz].vid[edge_axis(e)][q + dq]
                });
                join_group(out, v);
                out.triangles.push(v);
                out.cells.push(cell);
            }
            x += 1;
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
        if g != NONE {
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
