//! Building a [`Forest`]'s parts in parallel: per part a run of (group,
//! layer) runs sorted by cell, with its rows, leaves, boxes and leaf vertex
//! tables.

use glam::{Vec3, Vec3A};

use super::{CellNode, LEAF_VERTICES, LayerNode, MeshView, RowNode, Span};
use crate::foundation::aabb::Aabb;

/// Least triangles per part of the parallel build.
pub(super) const PART_TRIANGLES: usize = 1 << 13;

/// Most parts per thread of the parallel build (with more than one thread).
pub(super) const PARTS_PER_THREAD: usize = 4;

/// Shape of the keys: cell keys `x + cx·(y + cy·z)`, and the leaf blocks
/// of `2^shift` cells a side they fall in (block keys `bx + bdx·(by +
/// bdy·bz)`, the leaves' keys).
#[derive(Debug, Clone, Copy)]
pub(super) struct KeyGrid {
    /// Cells per row and per column.
    cx: usize,
    cy: usize,
    shift: u32,
    /// The block grid `[bdx, bdy, bdz]`, and blocks per block layer.
    pub(super) blocks: [usize; 3],
    pub(super) layer: usize,
}

impl KeyGrid {
    /// The keys of a grid of `cell_dims` cells in blocks of `2^shift`.
    pub(super) fn new(cell_dims: [usize; 3], shift: u32) -> Self {
        let [cx, cy, _] = cell_dims.map(|d| d.max(1));
        let blocks = cell_dims.map(|d| d.max(1).div_ceil(1 << shift));
        KeyGrid {
            cx,
            cy,
            shift,
            blocks,
            layer: blocks[0] * blocks[1],
        }
    }

    /// Cells per block layer: a cell key divided by it is its block layer.
    pub(super) fn cells_per_block_layer(&self) -> usize {
        (self.cx * self.cy) << self.shift
    }

    /// Appends the block key of each of `tris`' cells to `out`. The cells
    /// of triangles in id order mostly share a row (marching cubes emits
    /// in cell order), so a key is decoded only when the row changes;
    /// inside a row the block is the row's first block plus `x >> shift`.
    fn block_keys(&self, cells: &[u32], tris: &[u32], out: &mut Vec<u32>) {
        if self.shift == 0 {
            out.extend(tris.iter().map(|&t| cells[t as usize]));
            return;
        }
        // Cells `row.0..row.1` form the current row, of first block `row.2`.
        let mut row = (0usize, 0usize, 0usize);
        out.extend(tris.iter().map(|&t| {
            let c = cells[t as usize] as usize;
            if !(row.0..row.1).contains(&c) {
                let (x, q) = (c % self.cx, c / self.cx);
                let (y, z) = (q % self.cy, q / self.cy);
                let [bdx, bdy, _] = self.blocks;
                let first = bdx * ((y >> self.shift) + bdy * (z >> self.shift));
                row = (c - x, c - x + self.cx, first);
            }
            (row.2 + ((c - row.0) >> self.shift)) as u32
        }));
    }
}

/// The triangles of one group in one cell layer: `order[start..end]`.
#[derive(Debug, Clone, Copy)]
pub(super) struct LayerRun {
    pub(super) start: usize,
    pub(super) end: usize,
    pub(super) z: u32,
    /// Whether the next run belongs to another group.
    pub(super) last_of_group: bool,
}

/// Nodes and leaf tables of consecutive runs; spans are local to the part
/// except the triangle spans, which index the whole order. The corners
/// are written in place, into the part's slice of the forest's table.
#[derive(Debug)]
pub(super) struct Part<'a> {
    pub(super) layers: Vec<LayerNode>,
    pub(super) rows: Vec<RowNode>,
    pub(super) cells: Vec<CellNode>,
    pub(super) leaf_vertices: Vec<u32>,
    pub(super) leaf_positions: Vec<Vec3>,
    /// The part's slice of [`super::Forest::corners`], and the position in
    /// the order of its first entry.
    corners: &'a mut [[u16; 3]],
    base: usize,
    /// The vertices the current leaf has listed.
    seen: LeafVertices,
    /// Scratch of one run: its cell keys (in sorted order once sorted),
    /// the counting sort's bucket starts, sorted ids and keys, and the
    /// run's triangles gathered in sorted order.
    keys: Vec<u32>,
    buckets: Vec<u32>,
    sorted: Vec<u32>,
    sorted_keys: Vec<u32>,
    gathered: Vec<[u32; 3]>,
}

/// The distinct vertices of the leaf being built and their indices in
/// `leaf_vertices`, each entry tagged with the leaf it belongs to so that a
/// new leaf starts without clearing anything. Two tables:
/// - a *window*, indexed by a vertex id's offset from the run's least id,
///   for runs whose ids lie within [`LeafVertices::WINDOW`] of each other
///   (marching cubes numbers the vertices of a block layer together);
/// - otherwise an open-addressing hash table (linear probing) small enough
///   to stay in the L1 cache, which grows when a leaf lists more than half
///   as many vertices as it has slots.
#[derive(Debug)]
pub(super) struct LeafVertices {
    /// (leaf tag, vertex id, index) per slot; tag 0 is an empty slot.
    slots: Vec<[u32; 3]>,
    /// `32 − log2(slots.len())`: the hash's shift.
    shift: u32,
    /// (leaf tag, index) of vertex `first + i`; tag 0 is unset.
    window: Vec<[u32; 2]>,
    /// The current run's least vertex id `first`, when the run uses the
    /// window.
    window_first: Option<u32>,
}

impl LeafVertices {
    const INITIAL_BITS: u32 = 10;

    fn new() -> Self {
        LeafVertices {
            slots: vec![[0; 3]; 1 << Self::INITIAL_BITS],
            shift: 32 - Self::INITIAL_BITS,
            window: Vec::new(),
            window_first: None,
        }
    }

    /// Most vertex ids a run's window spans (512 KiB of entries).
    const WINDOW: usize = 1 << 16;

    /// Picks the table for a run whose triangles are `tris`: the window
    /// when their vertex ids span at most [`Self::WINDOW`] ids. Entries
    /// left by earlier runs carry other leaves' tags.
    fn start_run(&mut self, tris: &[[u32; 3]]) {
        let (lo, hi) =
            (tris.iter().flatten()).fold((u32::MAX, 0), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let span = hi.checked_sub(lo).map(|d| d as usize + 1);
        self.window_first = match span {
            Some(n) if n <= Self::WINDOW => {
                if self.window.len() < n {
                    self.window.resize(n, [0; 2]);
                }
                Some(lo)
            }
            _ => None,
        };
    }

    fn slot(&self, v: u32) -> usize {
        (v.wrapping_mul(0x9E37_79B1) >> self.shift) as usize
    }

    /// The index of vertex `v` in leaf `tag`, or `None` after recording
    /// `next` as its index.
    #[inline]
    fn get_or_insert(&mut self, tag: u32, v: u32, next: u32) -> Option<u32> {
        let mask = self.slots.len() - 1;
        let mut i = self.slot(v);
        loop {
            let s = &mut self.slots[i];
            if s[0] != tag {
                *s = [tag, v, next];
                return None;
            }
            if s[1] == v {
                return Some(s[2]);
            }
            i = (i + 1) & mask;
        }
    }

    /// Lists the distinct vertices of leaf `tag`'s triangles `tris` through
    /// the window, appending them to `listed` and each triangle's offsets
    /// into them to `corners`; false (nothing done) when the run does not
    /// use the window.
    fn list_in_window(
        &mut self,
        tag: u32,
        tris: &[[u32; 3]],
        listed: &mut Vec<u32>,
        corners: &mut [[u16; 3]],
    ) -> bool {
        let Some(first) = self.window_first else {
            return false;
        };
        let start = listed.len();
        for (tri, corner) in tris.iter().zip(corners) {
            for (c, &v) in corner.iter_mut().zip(tri) {
                let s = &mut self.window[(v - first) as usize];
                if s[0] != tag {
                    *s = [tag, (listed.len() - start) as u32];
                    listed.push(v);
                }
                *c = s[1] as u16;
            }
        }
        true
    }

    /// Doubles the hash table when three more vertices could fill more
    /// than half of it, keeping leaf `tag`'s entries (`listed`: its
    /// vertices in index order).
    fn reserve(&mut self, tag: u32, listed: &[u32]) {
        if 2 * (listed.len() + 3) <= self.slots.len() {
            return;
        }
        let bits = 33 - self.shift;
        self.slots = vec![[0; 3]; 1 << bits];
        self.shift = 32 - bits;
        for (k, &v) in listed.iter().enumerate() {
            self.get_or_insert(tag, v, k as u32);
        }
    }
}

impl<'a> Part<'a> {
    /// An empty part whose triangles (from position `base` of the order
    /// on) write their corners to `corners`.
    pub(super) fn new(corners: &'a mut [[u16; 3]], base: usize) -> Self {
        let n_triangles = corners.len();
        Part {
            layers: Vec::new(),
            rows: Vec::new(),
            cells: Vec::new(),
            leaf_vertices: Vec::with_capacity(n_triangles),
            leaf_positions: Vec::with_capacity(n_triangles),
            corners,
            base,
            seen: LeafVertices::new(),
            keys: Vec::new(),
            buckets: Vec::new(),
            sorted: Vec::new(),
            sorted_keys: Vec::new(),
            gathered: Vec::new(),
        }
    }

    /// Sorts `tris` (the ids of `run`, ascending) by cell and appends the
    /// run's layer node with its rows and leaves.
    ///
    /// The run is built in passes, each a loop over arrays: the sort, which
    /// also places each triangle's vertex triple (read in id order, a
    /// stream); the leaves' vertex tables and corners from those triples;
    /// the leaves' positions gathered; the boxes. The gather's loads do
    /// not depend on each other, so their cache misses overlap, where the
    /// vertex table's branches between them would let only few be in
    /// flight.
    pub(super) fn layer(
        &mut self,
        mesh: MeshView<'_>,
        cells: &[u32],
        grid: KeyGrid,
        run: &LayerRun,
        tris: &mut [u32],
    ) {
        self.sort_by_cell(mesh, cells, grid, tris, run.z as usize * grid.layer);
        self.seen.start_run(&self.gathered);
        let (first_row, first_vertex) = (self.rows.len(), self.leaf_vertices.len());
        let bdx = grid.blocks[0];
        let mut i = 0;
        while i < tris.len() {
            let row = self.keys[i] as usize / bdx;
            // Keys of the row: `row_start..row_end` (no division per triangle).
            let row_start = (row * bdx) as u32;
            let row_end = row_start + bdx as u32;
            let cell_start = self.cells.len() as u32;
            while i < tris.len() && self.keys[i] < row_end {
                let key = self.keys[i];
                // The cell's end: the keys are sorted.
                let end = i + self.keys[i..].partition_point(|&k| k == key);
                // One leaf, or several where the cell's triangles list more
                // than `LEAF_VERTICES` vertices.
                while i < end {
                    let (vertices, stop) = self.leaf(i..end, run.start + i);
                    self.cells.push(CellNode {
                        x: key - row_start,
                        bbox: Aabb::EMPTY,
                        triangles: Span {
                            start: (run.start + i) as u32,
                            end: (run.start + stop) as u32,
                        },
                        vertices,
                        next: self.cells.len() as u32 + 1,
                    });
                    i = stop;
                }
            }
            self.rows.push(RowNode {
                y: (row % grid.blocks[1]) as u32,
                bbox: Aabb::EMPTY,
                cells: Span {
                    start: cell_start,
                    end: self.cells.len() as u32,
                },
            });
        }
        self.leaf_positions.extend(
            self.leaf_vertices[first_vertex..]
                .iter()
                .map(|&v| mesh.positions[v as usize]),
        );
        let mut lbox = Aabb::EMPTY;
        for row in &mut self.rows[first_row..] {
            for c in &mut self.cells[row.cells.range()] {
                // The box of the distinct vertices, which is that of the
                // triangles.
                let (lo, hi) = self.leaf_positions[c.vertices.range()]
                    .iter()
                    .fold((Vec3A::INFINITY, Vec3A::NEG_INFINITY), |(lo, hi), &p| {
                        (lo.min(p.into()), hi.max(p.into()))
                    });
                c.bbox = Aabb {
                    min: lo.into(),
                    max: hi.into(),
                };
                row.bbox = row.bbox.union(c.bbox);
            }
            lbox = lbox.union(row.bbox);
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
                start: first_row as u32,
                end: self.rows.len() as u32,
            },
        });
    }

    /// Stable sort of `tris` by the block key of `cells[t]`, keys in
    /// `first..first + grid.layer` (the run's block layer), leaving the
    /// sorted keys in `keys` and the triangles' vertex triples in
    /// `gathered`: a counting sort over the layer when the run is long
    /// against it, else over the keys' range when that is short, else a
    /// sort by (key, id).
    fn sort_by_cell(
        &mut self,
        mesh: MeshView<'_>,
        cells: &[u32],
        grid: KeyGrid,
        tris: &mut [u32],
        first: usize,
    ) {
        let len = grid.layer;
        self.gathered.clear();
        self.keys.clear();
        grid.block_keys(cells, tris, &mut self.keys);
        let short = |range: usize| range <= 2 * tris.len() + 64;
        let (lo, range) = if short(len) {
            (first as u32, len)
        } else {
            let (lo, hi) =
                (self.keys.iter()).fold((u32::MAX, 0), |(lo, hi), &k| (lo.min(k), hi.max(k)));
            (lo, hi.saturating_sub(lo) as usize + 1)
        };
        if !short(range) {
            let mut pairs: Vec<u64> = (self.keys.iter().zip(tris.iter()))
                .map(|(&k, &t)| u64::from(k) << 32 | u64::from(t))
                .collect();
            pairs.sort_unstable();
            for ((k, t), p) in self.keys.iter_mut().zip(tris.iter_mut()).zip(pairs) {
                (*k, *t) = ((p >> 32) as u32, p as u32);
            }
            self.gathered
                .extend(tris.iter().map(|&t| mesh.triangles[t as usize]));
            return;
        }
        self.buckets.clear();
        self.buckets.resize(range + 1, 0);
        for &k in &self.keys {
            self.buckets[(k - lo) as usize + 1] += 1;
        }
        // Bucket starts (the running sum in a register, not reloaded
        // from the bucket just stored).
        let mut sum = 0;
        for b in &mut self.buckets {
            sum += *b;
            *b = sum;
        }
        self.sorted.clear();
        self.sorted.resize(tris.len(), 0);
        self.sorted_keys.clear();
        self.sorted_keys.resize(tris.len(), 0);
        self.gathered.resize(tris.len(), [0; 3]);
        // Distinct slices, so that the bucket is read once per triangle,
        // not again after each store.
        let (buckets, sorted) = (&mut self.buckets[..], &mut self.sorted[..]);
        let (sorted_keys, gathered) = (&mut self.sorted_keys[..], &mut self.gathered[..]);
        for (&t, &k) in tris.iter().zip(&self.keys) {
            let slot = &mut buckets[(k - lo) as usize];
            let b = *slot as usize;
            *slot += 1;
            sorted[b] = t;
            sorted_keys[b] = k;
            gathered[b] = mesh.triangles[t as usize];
        }
        tris.copy_from_slice(&self.sorted);
        std::mem::swap(&mut self.keys, &mut self.sorted_keys);
    }

    /// Appends the distinct vertices of a leaf of the run's triangles
    /// `range` (in `gathered`), in order of first use, and the triangles'
    /// corners as offsets into them; returns the leaf's vertex span and
    /// where it ends in `range`: at its end, or before the first triangle
    /// that could list more than [`LEAF_VERTICES`]. `first` is the position
    /// of the leaf's first triangle in the order.
    fn leaf(&mut self, range: std::ops::Range<usize>, first: usize) -> (Span, usize) {
        let tag = first as u32 + 1;
        let start = self.leaf_vertices.len();
        let corners = &mut self.corners[first - self.base..];
        let vertices = |listed: &Vec<u32>| Span {
            start: start as u32,
            end: listed.len() as u32,
        };
        // A leaf of at most `LEAF_VERTICES / 3` triangles cannot list too
        // many vertices (marching cubes' leaves never do).
        let tris = &self.gathered[range.clone()];
        if 3 * tris.len() <= LEAF_VERTICES
            && self
                .seen
                .list_in_window(tag, tris, &mut self.leaf_vertices, corners)
        {
            return (vertices(&self.leaf_vertices), range.end);
        }
        let mut stop = range.end;
        for ((i, tri), out) in range.clone().zip(&self.gathered[range]).zip(corners) {
            let listed = &self.leaf_vertices[start..];
            if listed.len() + 3 > LEAF_VERTICES {
                stop = i;
                break;
            }
            self.seen.reserve(tag, listed);
            let mut corner = [0u16; 3];
            for (c, &v) in corner.iter_mut().zip(tri) {
                let next = (self.leaf_vertices.len() - start) as u32;
                let at = self.seen.get_or_insert(tag, v, next).unwrap_or_else(|| {
                    self.leaf_vertices.push(v);
                    next
                });
                *c = at as u16;
            }
            *out = corner;
        }
        (vertices(&self.leaf_vertices), stop)
    }
}

/// Triangle ids sorted by (group, layer, id), layer `cells[t] / layer`,
/// and the start of each group's ids (`n_groups + 1` entries): one stable
/// counting sort by group when the layers never decrease along the ids,
/// else a stable counting sort by layer first.
pub(super) fn order_by_group_and_layer(
    cells: &[u32],
    layer: usize,
    groups: &[u32],
    n_groups: usize,
) -> (Vec<u32>, Vec<u32>) {
    // Runs of one group along the ids (marching cubes emits long ones):
    // counted and placed a run at a time.
    let mut group_runs = Vec::new();
    let mut start = vec![0u32; n_groups + 1];
    let mut i = 0;
    while i < groups.len() {
        let g = groups[i];
        let end = i + groups[i..].iter().take_while(|&&h| h == g).count();
        group_runs.push((g, i as u32, end as u32));
        start[g as usize + 1] += (end - i) as u32;
        i = end;
    }
    // Keys `lo..hi` form the current layer.
    let (mut lo, mut hi, mut monotone) = (0usize, 0usize, true);
    for &c in cells {
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
    if monotone {
        for &(g, a, b) in &group_runs {
            let at = next[g as usize] as usize;
            next[g as usize] += b - a;
            (out[at..at + (b - a) as usize].iter_mut())
                .zip(a..b)
                .for_each(|(o, t)| *o = t);
        }
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
        // Slices, so that a group's cursor is read once per triangle, not
        // again after the store.
        let (next_at, placed) = (&mut next[..], &mut out[..]);
        for t in by_layer {
            let s = &mut next_at[groups[t as usize] as usize];
            let at = *s as usize;
            *s += 1;
            placed[at] = t;
        }
    }
    (out, start)
}

/// The (group, layer) runs of `order` (sorted by group, layer, id).
pub(super) fn layer_runs(
    order: &[u32],
    group_starts: &[u32],
    cells: &[u32],
    layer: usize,
) -> Vec<LayerRun> {
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
