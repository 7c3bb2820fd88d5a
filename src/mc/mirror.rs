//! The marching-cubes kernels' mirrors: plain CPU loops over the same
//! workgroups and invocations as `kernels/mc_inside.wgsl`,
//! `kernels/mc_classify.wgsl`, `kernels/mc_vertices.wgsl` and
//! `kernels/mc_triangles.wgsl`, with the same names, buffers and f32
//! expressions, one function per kernel. They read beside their WGSL; the production CPU path is the bit-row
//! implementation in [`super::cpu`], tested equal to these mirrors chained
//! (`tests/mc.rs`), and each GPU kernel is tested against its mirror
//! on the same inputs (`tests/parity/mc_*.rs`), so a divergence names its
//! kernel.
//!
//! Tolerances ([`TOL_POSITION_ULPS`]): inside flags, block counts, vertex
//! ids, edge ids and triangles are integers and compare exactly; positions
//! are bit for bit on adapters with correctly rounded division (lavapipe),
//! else within
//! WGSL's 2.5-ulp division bound carried through `f32(p) + t`.

use super::cpu::T_MIN;
use super::exclusive_offsets;
use super::field::Field;
use super::gpu::{ClassifyParams, GpuRaw, InsideParams, TrianglesParams, VerticesParams};
use super::grid::{BitRows, grid_sample, inside_bit, inside_run, sample_grid, sample_words};
use super::tables;
use crate::Result;

/// Invocations per workgroup of the four kernels (`WG_SIZE`; checked
/// against the WGSL by `tests/shaders.rs`).
pub const WG_SIZE: u32 = 256;

/// Units in the last place a GPU position may differ from the mirror's on
/// hardware whose f32 division is not correctly rounded: WGSL allows 2.5
/// ulp for `x / y`, carried through `clamp` and `f32(p) + t` into at most
/// one more rounding (3 ulp of the coordinate's magnitude, rounded up).
pub const TOL_POSITION_ULPS: u32 = 3;

/// `edge_owner` of `mc_triangles.wgsl`: the corner owning each local edge.
const EDGE_OWNER: [u32; 12] = [0, 2, 4, 6, 0, 1, 4, 5, 0, 1, 2, 3];

/// `mc_inside`: the inside flag of every point of `n_layers` layers from
/// `z_begin`, as bit rows ([`BitRows`]): `inside_bits` holds `n_layers · ny ·
/// row_words` words, one invocation each.
pub fn mc_inside(params: &InsideParams, samples: &[u32], inside_bits: &mut [u32]) {
    let p = params;
    let n_words = p.n_layers * p.grid.ny * p.row_words;
    for word in 0..n_words {
        let row = word / p.row_words;
        let x0 = (word % p.row_words) * 32;
        let y = row % p.grid.ny;
        let z = p.z_begin + row / p.grid.ny;
        let mut flags = 0u32;
        for b in 0..32.min(p.grid.nx - x0) {
            if grid_sample(&p.grid, samples, x0 + b, y, z) >= p.grid.level {
                flags |= 1 << b;
            }
        }
        inside_bits[word as usize] = flags;
    }
}

/// `mc_classify`: per block of `WG_SIZE` points, (vertices, triangles).
/// `block_counts` holds `n_layers · blocks_per_layer` entries.
pub fn mc_classify(
    params: &ClassifyParams,
    inside_bits: &[u32],
    table: &[u32],
    block_counts: &mut [[u32; 2]],
) {
    let p = params;
    let flag = |x: u32, y: u32, z: u32| inside_bit(&p.rows, inside_bits, x, y, z);
    let n_layer = p.rows.nx * p.rows.ny;
    for w in 0..block_counts.len() as u32 {
        let layer = w / p.blocks_per_layer;
        let mut sh_sum = [0u32; 2];
        for lid in 0..WG_SIZE {
            let q = (w % p.blocks_per_layer) * WG_SIZE + lid;
            let mut nv = 0;
            let mut nt = 0;
            if layer < p.n_layers && q < n_layer {
                let x = q % p.rows.nx;
                let y = q / p.rows.nx;
                let z = p.z_begin + layer;
                let m = flag(x, y, z);
                if x + 1 < p.rows.nx && flag(x + 1, y, z) != m {
                    nv += 1;
                }
                if y + 1 < p.rows.ny && flag(x, y + 1, z) != m {
                    nv += 1;
                }
                if z + 1 < p.rows.nz && flag(x, y, z + 1) != m {
                    nv += 1;
                }
                if x + 1 < p.rows.nx && y + 1 < p.rows.ny && z + 1 < p.rows.nz {
                    let mut case_ix = 0u32;
                    for c in 0..8u32 {
                        case_ix |= flag(x + (c & 1), y + ((c >> 1) & 1), z + (c >> 2)) << c;
                    }
                    nt = table[case_ix as usize + 1] - table[case_ix as usize];
                }
            }
            sh_sum[0] += nv;
            sh_sum[1] += nt;
        }
        if layer < p.n_layers {
            block_counts[w as usize] = sh_sum;
        }
    }
}

/// `mc_vertices`: per point its first vertex id (`vert_base`, `n_layers ·
/// nx · ny`) and, for the first `n_owned` layers, the vertices of its
/// crossing edges (`positions`, element = vertex id − `v_start`, `w` = the
/// edge id's bits). `block_offsets`: the exclusive scan of the vertex
/// counts with the total appended. Blocks without a vertex write nothing.
pub fn mc_vertices(
    params: &VerticesParams,
    samples: &[u32],
    inside_bits: &[u32],
    block_offsets: &[u32],
    vert_base: &mut [u32],
    positions: &mut [[f32; 4]],
) {
    let p = params;
    let sample = |x: u32, y: u32, z: u32| grid_sample(&p.grid, samples, x, y, z);
    let flag = |x: u32, y: u32, z: u32| inside_bit(&p.rows, inside_bits, x, y, z);
    // Vertex k + v_start: on the edge (at, axis) whose ends hold samples a, b.
    let write_vertex =
        |positions: &mut [[f32; 4]], k: u32, at: [u32; 3], axis: usize, a: f32, b: f32| {
            let t = ((p.grid.level - a) / (b - a)).clamp(T_MIN, 1.0 - T_MIN);
            let mut u = at.map(|c| c as f32);
            u[axis] += t;
            let point = at[0] + p.grid.nx * (at[1] + p.grid.ny * at[2]);
            positions[k as usize] = [u[0], u[1], u[2], f32::from_bits(3 * point + axis as u32)];
        };
    let n_layer = p.grid.nx * p.grid.ny;
    let n_blocks = p.n_layers * p.blocks_per_layer;
    for w in 0..n_blocks {
        let layer = w / p.blocks_per_layer;
        let sh_count = block_offsets[w as usize + 1] - block_offsets[w as usize];
        if sh_count == 0 {
            continue;
        }
        let mut inclusive = 0u32;
        for lid in 0..WG_SIZE {
            let q = (w % p.blocks_per_layer) * WG_SIZE + lid;
            let in_range = layer < p.n_layers && q < n_layer;
            let x = q % p.grid.nx;
            let y = q / p.grid.nx;
            let z = p.z_begin + layer;
            let mut crossing = 0u32;
            if in_range {
                let m = flag(x, y, z);
                if x + 1 < p.grid.nx && flag(x + 1, y, z) != m {
                    crossing |= 1;
                }
                if y + 1 < p.grid.ny && flag(x, y + 1, z) != m {
                    crossing |= 2;
                }
                if z + 1 < p.grid.nz && flag(x, y, z + 1) != m {
                    crossing |= 4;
                }
            }
            let nv = crossing.count_ones();
            inclusive += nv;
            if !in_range {
                continue;
            }
            let base = block_offsets[w as usize] + inclusive - nv;
            vert_base[(layer * n_layer + q) as usize] = base;
            if layer >= p.n_owned || crossing == 0 {
                continue;
            }
            let at = [x, y, z];
            let a = sample(x, y, z);
            let mut k = base - p.v_start;
            if crossing & 1 != 0 {
                write_vertex(positions, k, at, 0, a, sample(x + 1, y, z));
                k += 1;
            }
            if crossing & 2 != 0 {
                write_vertex(positions, k, at, 1, a, sample(x, y + 1, z));
                k += 1;
            }
            if crossing & 4 != 0 {
                write_vertex(positions, k, at, 2, a, sample(x, y, z + 1));
            }
        }
    }
}

/// `mc_triangles`: the triangles of every cell of `n_layers` cell layers
/// from `z_begin` at their scanned offsets (element = triangle id −
/// `t_start`), `[v0, v1, v2, cell]`, vertex ids from `vert_base` (whose
/// first layer is global layer `vb_first`). Blocks without a triangle write
/// nothing.
pub fn mc_triangles(
    params: &TrianglesParams,
    inside_bits: &[u32],
    table: &[u32],
    block_offsets: &[u32],
    vert_base: &[u32],
    triangles: &mut [[u32; 4]],
) {
    let p = params;
    let run = |x: u32, y: u32, z: u32| inside_run(&p.rows, inside_bits, x, y, z);
    // The flag of point (x + dx, y + dy, z + dz) from the neighbourhood
    // `near`: bit dx + 3·(dy + 3·dz).
    let flag = |near: u32, dx: u32, dy: u32, dz: u32| (near >> (dx + 3 * (dy + 3 * dz))) & 1;
    let n_layer = p.rows.nx * p.rows.ny;
    // Vertex id of the edge (owner corner d of cell (x, y, z), axis).
    let vertex = |near: u32, x: u32, y: u32, z: u32, d: [u32; 3], axis: u32| -> u32 {
        let o = [x + d[0], y + d[1], z + d[2]];
        let m = flag(near, d[0], d[1], d[2]);
        let mut rank = 0;
        if axis > 0 && o[0] + 1 < p.rows.nx && flag(near, d[0] + 1, d[1], d[2]) != m {
            rank += 1;
        }
        if axis > 1 && o[1] + 1 < p.rows.ny && flag(near, d[0], d[1] + 1, d[2]) != m {
            rank += 1;
        }
        vert_base[((o[2] - p.vb_first) * n_layer + o[1] * p.rows.nx + o[0]) as usize] + rank
    };
    let n_blocks = p.n_layers * p.blocks_per_layer;
    for w in 0..n_blocks {
        let layer = w / p.blocks_per_layer;
        let sh_count = block_offsets[w as usize + 1] - block_offsets[w as usize];
        if sh_count == 0 {
            continue;
        }
        let mut inclusive = 0u32;
        for lid in 0..WG_SIZE {
            let q = (w % p.blocks_per_layer) * WG_SIZE + lid;
            let x = q % p.rows.nx;
            let y = q / p.rows.nx;
            let z = p.z_begin + layer;
            let in_range =
                layer < p.n_layers && q < n_layer && x + 1 < p.rows.nx && y + 1 < p.rows.ny;
            let mut near = 0u32;
            let mut case_ix = 0u32;
            let mut nt = 0u32;
            if in_range {
                near = run(x, y, z)
                    | run(x, y + 1, z) << 3
                    | run(x, y, z + 1) << 9
                    | run(x, y + 1, z + 1) << 12;
                for c in 0..8u32 {
                    case_ix |= flag(near, c & 1, (c >> 1) & 1, c >> 2) << c;
                }
                nt = table[case_ix as usize + 1] - table[case_ix as usize];
            }
            inclusive += nt;
            if nt == 0 {
                continue;
            }
            near |= run(x, y + 2, z) << 6;
            let out0 = block_offsets[w as usize] + inclusive - nt - p.t_start;
            let cell = x + (p.rows.nx - 1) * (y + (p.rows.ny - 1) * z);
            let first = table[case_ix as usize];
            for k in 0..nt {
                let mut v = [0u32; 3];
                for j in 0..3 {
                    let e = table[(257 + 3 * (first + k)) as usize + j];
                    let c = EDGE_OWNER[e as usize];
                    let d = [c & 1, (c >> 1) & 1, c >> 2];
                    v[j] = vertex(near, x, y, z, d, e / 4);
                }
                triangles[(out0 + k) as usize] = [v[0], v[1], v[2], cell];
            }
        }
    }
}

/// The four mirrors chained over the whole grid of `field` in one slab,
/// as the GPU runs them (inside flags, classify, host scan, vertices,
/// triangles): the reference the bit-row CPU path is tested against.
pub fn marching_cubes(field: &Field<'_>) -> Result<GpuRaw> {
    let [nx, ny, nz] = field.dims;
    if field.dims.iter().any(|&d| d < 2) {
        return Ok(GpuRaw::default());
    }
    let layer = nx * ny;
    let samples = sample_words(field, 0, field.volume().dims[2])?;
    let grid = sample_grid(field, 0);
    let rows = BitRows::new(field, 0);
    let table = tables::table().flat();
    let bpl = layer.div_ceil(WG_SIZE as usize);
    let nz32 = nz as u32;
    let mut inside_bits = vec![0u32; rows.words(nz)];
    let inside = InsideParams {
        grid,
        z_begin: 0,
        n_layers: nz32,
        row_words: rows.row_words,
    };
    mc_inside(&inside, &samples, &mut inside_bits);
    let mut counts = vec![[0u32; 2]; nz * bpl];
    let classify = ClassifyParams {
        rows,
        z_begin: 0,
        n_layers: nz32,
        blocks_per_layer: bpl as u32,
    };
    mc_classify(&classify, &inside_bits, &table, &mut counts);
    let off_v = exclusive_offsets(counts.iter().map(|c| c[0].into()), "vertices")?;
    let off_t = exclusive_offsets(counts.iter().map(|c| c[1].into()), "triangles")?;
    let mut vert_base = vec![0u32; nz * layer];
    let mut positions = vec![[0.0f32; 4]; off_v[nz * bpl] as usize];
    let vertices = VerticesParams {
        grid,
        rows,
        z_begin: 0,
        n_layers: nz32,
        n_owned: nz32,
        blocks_per_layer: bpl as u32,
        v_start: 0,
    };
    mc_vertices(
        &vertices,
        &samples,
        &inside_bits,
        &off_v,
        &mut vert_base,
        &mut positions,
    );
    let mut triangles = vec![[0u32; 4]; off_t[nz * bpl] as usize];
    let cells = TrianglesParams {
        rows,
        z_begin: 0,
        n_layers: nz32 - 1,
        blocks_per_layer: bpl as u32,
        vb_first: 0,
        t_start: 0,
    };
    mc_triangles(
        &cells,
        &inside_bits,
        &table,
        &off_t,
        &vert_base,
        &mut triangles,
    );
    Ok(GpuRaw {
        positions,
        triangles,
        kernel_seconds: None,
    })
}
