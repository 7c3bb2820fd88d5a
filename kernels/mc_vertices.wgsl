// mc_vertices: marching-cubes vertices — one vertex per crossing grid edge,
// numbered in point order (axes x < y < z within a point), welded by
// construction: the vertex of edge (point p, axis a) is
// vert_base[p] + (number of crossing edges of p with axis < a).
//
// Dispatch: one invocation per point of `n_layers` point layers from global
// layer `z_begin`, blocks of WG_SIZE points per layer as in mc_classify
// (same block numbering, so block_offsets lines up with its counts).
// Buffers:
//   params:        grid (dims, sample words, level), bit rows, slab
//                  position, v_start (see Params)
//   samples:       the volume's samples in their own type, packed in u32
//                  words (shared/mc_grid.wgsl, params.grid), read only at
//                  the ends of crossing edges
//   inside_bits:   mc_inside's flags (shared/mc_bits.wgsl, params.rows),
//                  which find the crossing edges; must hold layers
//                  z_begin ..= z_begin + n_layers (the last one clipped at
//                  nz − 1)
//   block_offsets: per block and one more, exclusive scan of mc_classify's
//                  vertex counts over the whole grid (host scan), so block
//                  w holds block_offsets[w + 1] − block_offsets[w] vertices
//   vert_base:     n_layers·nx·ny u32 out, first vertex id of each point
//   positions:     vec4<f32> out for the first `n_owned` layers:
//                  xyz = position in grid index space, w = bitcast edge id
//                  3·point + axis; element = vertex id − v_start
// Interpolation (same f32 expression as the mirror), the only sample reads:
//   t = clamp((level − a) / (b − a), T_MIN, 1 − T_MIN), a at p, b at
//   p + e_axis; u[axis] = f32(p[axis]) + t. T_MIN = 2⁻¹⁰ keeps vertices
//   inside their edges (no zero-area triangles; mc::cpu::T_MIN).
// Mirror: mc::mirror::mc_vertices.

#import block_scan
#import dispatch
#import mc_grid
#import mc_bits

struct Params {
    grid: SampleGrid,
    rows: BitRows,
    z_begin: u32,
    n_layers: u32,
    n_owned: u32,
    blocks_per_layer: u32,
    v_start: u32,
}

const WG_SIZE: u32 = SCAN_WG;
const T_MIN: f32 = 0.0009765625;

@group(0) @binding(0) var<uniform> params: Params;
// binding 1: samples (shared/mc_grid.wgsl)
// binding 2: inside_bits (shared/mc_bits.wgsl)
@group(0) @binding(3) var<storage, read> block_offsets: array<u32>;
@group(0) @binding(4) var<storage, read_write> vert_base: array<u32>;
@group(0) @binding(5) var<storage, read_write> positions: array<vec4<f32>>;

// The block's count (from block_offsets), read by all as a uniform value.
var<workgroup> sh_count: u32;

fn sample(x: u32, y: u32, z: u32) -> f32 {
    return grid_sample(params.grid, x, y, z);
}

fn flag(x: u32, y: u32, z: u32) -> u32 {
    return inside(params.rows, x, y, z);
}

// Vertex k + v_start: on the edge (at, axis) whose ends hold samples a, b.
fn write_vertex(k: u32, at: vec3<u32>, axis: u32, a: f32, b: f32) {
    let t = clamp((params.grid.level - a) / (b - a), T_MIN, 1.0 - T_MIN);
    var u = vec3<f32>(at);
    u[axis] += t;
    let point = at.x + params.grid.nx * (at.y + params.grid.ny * at.z);
    positions[k] = vec4<f32>(u, bitcast<f32>(3u * point + axis));
}

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(local_invocation_id) lid: vec3<u32>,
        @builtin(workgroup_id) wid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let w = workgroup_index(wid, n_groups);
    let layer = w / params.blocks_per_layer;
    let q = (w % params.blocks_per_layer) * WG_SIZE + lid.x;
    // A block without a vertex writes nothing (no triangle refers to a
    // point without a crossing edge, so its vert_base is never read).
    if lid.x == 0u && layer < params.n_layers {
        sh_count = block_offsets[w + 1u] - block_offsets[w];
    }
    if workgroupUniformLoad(&sh_count) == 0u {
        return;
    }
    let n_layer = params.grid.nx * params.grid.ny;
    let in_range = layer < params.n_layers && q < n_layer;
    let x = q % params.grid.nx;
    let y = q / params.grid.nx;
    let z = params.z_begin + layer;
    // `crossing` bit a set for a crossing edge along axis a.
    var crossing = 0u;
    if in_range {
        let m = flag(x, y, z);
        if x + 1u < params.grid.nx && flag(x + 1u, y, z) != m { crossing |= 1u; }
        if y + 1u < params.grid.ny && flag(x, y + 1u, z) != m { crossing |= 2u; }
        if z + 1u < params.grid.nz && flag(x, y, z + 1u) != m { crossing |= 4u; }
    }
    let nv = countOneBits(crossing);
    let inclusive = block_scan(lid.x, nv);
    if !in_range {
        return;
    }
    let base = block_offsets[w] + inclusive - nv;
    vert_base[layer * n_layer + q] = base;
    if layer >= params.n_owned || crossing == 0u {
        return;
    }
    let at = vec3<u32>(x, y, z);
    let a = sample(x, y, z);
    var k = base - params.v_start;
    if (crossing & 1u) != 0u {
        write_vertex(k, at, 0u, a, sample(x + 1u, y, z));
        k += 1u;
    }
    if (crossing & 2u) != 0u {
        write_vertex(k, at, 1u, a, sample(x, y + 1u, z));
        k += 1u;
    }
    if (crossing & 4u) != 0u {
        write_vertex(k, at, 2u, a, sample(x, y, z + 1u));
    }
}
