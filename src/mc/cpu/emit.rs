//! The *emit* pass: one chunk of z layers ([`ChunkOut`], its slices of the
//! output arrays) gets its vertices and triangles written in place, and
//! returns its one-pass union-find grouping ([`ChunkGroups`]).

use super::super::tables::{self, EDGE_OWNER, corner_offset, edge_axis};
use super::NONE;
use super::scan::{Bits, LayerScan, Rows, case_at, cell_word};
use crate::foundation::UnionFind;

/// One chunk's share of the output: cell layers `z0..z1`, point layers
/// `z0..=z1` of which it stores `z0..own_end`.
pub(super) struct ChunkOut<'a> {
    pub(super) z0: usize,
    pub(super) z1: usize,
    pub(super) own_end: usize,
    /// Global id of the first vertex of layer `z0`.
    pub(super) first_vertex: u32,
    /// Vertices on layer `z1` when the next chunk owns it (the seam), else 0.
    pub(super) n_seam: usize,
    pub(super) positions: &'a mut [[f32; 3]],
    pub(super) edges: &'a mut [u64],
    pub(super) triangles: &'a mut [[u32; 3]],
    pub(super) cells: &'a mut [u32],
    /// Whether triangles are grouped.
    pub(super) grouping: bool,
    /// Local union-find node of each triangle; empty without grouping.
    pub(super) tri_node: &'a mut [u32],
    /// Local union-find node of each vertex the chunk owns (layers
    /// `z0..own_end`); empty without grouping.
    pub(super) vertex_node: &'a mut [u32],
}

/// One chunk's grouping state.
pub(super) struct ChunkGroups {
    pub(super) uf: UnionFind,
    /// Union-find node of each vertex of the seam layer (by id − its first
    /// id; see [`ChunkOut::n_seam`]), or NONE: the chunk's own nodes there,
    /// which the next chunk's first layer is united with.
    pub(super) seam_node: Vec<u32>,
}

/// Write cursors of a chunk.
struct Emit<'a, 'o> {
    out: &'a mut ChunkOut<'o>,
    groups: ChunkGroups,
    n_positions: usize,
    n_triangles: usize,
}

impl Emit<'_, '_> {
    /// The union-find node slot of vertex `id` (owned, or on the seam).
    #[inline]
    fn vertex_node(&mut self, id: u32) -> &mut u32 {
        let k = (id - self.out.first_vertex) as usize;
        let own = self.out.vertex_node.len();
        if k < own {
            &mut self.out.vertex_node[k]
        } else {
            &mut self.groups.seam_node[k - own]
        }
    }
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

/// Emits one chunk: its vertices (positions from the scan's parameters)
/// and triangles, written in place, and its grouping.
pub(super) fn run_chunk(bits: &Bits, layers: &[LayerScan], mut out: ChunkOut<'_>) -> ChunkGroups {
    let rows = &bits.rows;
    let (z0, z1, own_end) = (out.z0, out.z1, out.own_end);
    out.vertex_node.fill(NONE);
    let mut emit = Emit {
        groups: ChunkGroups {
            uf: UnionFind::default(),
            seam_node: if out.grouping {
                vec![NONE; out.n_seam]
            } else {
                Vec::new()
            },
        },
        out: &mut out,
        n_positions: 0,
        n_triangles: 0,
    };
    // Crossings of layers z, z + 1 in slot (k − z0) mod 2.
    let mut crossings = [Crossings::new(rows), Crossings::new(rows)];
    let mut vertex_rows = VertexRows::new(rows);
    let mut next_id = emit.out.first_vertex;
    number_points(
        bits,
        layers,
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
        number_points(bits, layers, z + 1, own, upper, &mut next_id, &mut emit);
        vertex_rows.clear();
        emit_cells(bits, z, [&*lower, &*upper], &mut vertex_rows, &mut emit);
    }
    emit.groups
}

/// Numbers the crossing edges of point layer `z` in point order (x
/// fastest, then y; axes x < y < z within a point), a word of 64 points at
/// a time. Records the masks and row bases in `crossings`; stores positions
/// (the scan's parameters, in the same order) and edge ids when the layer
/// is `own`.
fn number_points(
    bits: &Bits,
    layers: &[LayerScan],
    z: usize,
    own: bool,
    crossings: &mut Crossings,
    next_id: &mut u32,
    emit: &mut Emit<'_, '_>,
) {
    let Rows { nx, ny, words, .. } = bits.rows;
    let pair = bits.pair(z);
    // The scan's parameters of this layer, in the same order.
    let ts = &layers[z].ts;
    let mut k = 0;
    let zf = z as f32;
    for y in 0..ny {
        crossings.row_base[y] = *next_id;
        let masks = &mut crossings.masks[y * words..(y + 1) * words];
        for (w, mask) in masks.iter_mut().enumerate() {
            let [ex, ey, ez] = pair.crossings(y, w);
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
                let mut vertex = |axis: usize| {
                    let t = ts[k];
                    k += 1;
                    let mut u = [x as f32, y as f32, zf];
                    u[axis] += t;
                    emit.out.positions[emit.n_positions] = u;
                    emit.out.edges[emit.n_positions] = 3 * point + axis as u64;
                    emit.n_positions += 1;
                };
                if ex >> s & 1 == 1 {
                    vertex(0);
                }
                if ey >> s & 1 == 1 {
                    vertex(1);
                }
                if ez >> s & 1 == 1 {
                    vertex(2);
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
        let Some(r) = bits.pair(z).cell_rows(y) else {
            break;
        };
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
                    let i = emit.n_triangles;
                    if emit.out.grouping {
                        emit.out.tri_node[i] = join_group(emit, v);
                    }
                    emit.out.triangles[i] = v;
                    emit.out.cells[i] = cell;
                    emit.n_triangles += 1;
                }
            }
        }
    }
}

/// One-pass grouping: the new triangle `v` joins the groups of the
/// triangles already using its vertices (seed §1: add to one group, start a
/// new group, or merge several). Returns its union-find node.
fn join_group(emit: &mut Emit<'_, '_>, v: [u32; 3]) -> u32 {
    let mut node = NONE;
    for &i in &v {
        let g = *emit.vertex_node(i);
        if g != NONE && g != node {
            let uf = &mut emit.groups.uf;
            node = if node == NONE {
                uf.find(g)
            } else {
                uf.union(node, g)
            };
        }
    }
    if node == NONE {
        node = emit.groups.uf.push();
    }
    for &i in &v {
        let slot = emit.vertex_node(i);
        if *slot == NONE {
            *slot = node;
        }
    }
    node
}
