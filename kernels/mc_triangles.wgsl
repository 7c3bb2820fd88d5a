// mc_triangles: marching-cubes triangles — each cell writes its case's
// triangles (mc::tables, wound outward) at its scanned offset, so the
// output is in cell order and, within a cell, in table order.
//
// Dispatch: one invocation per point of `n_layers` cell layers from global
// layer `z_begin`; a point (x, y, z) stands for the cell whose lowest
// corner it is (none when x = nx − 1 or y = ny − 1). Blocks of WG_SIZE
// points per layer, numbered as in mc_classify.
// Buffers:
//   params:        bit rows (dims, first layer), slab position, t_start
//                  (see Params)
//   table:         257 case offsets, then 3 local edges per triangle
//   inside_bits:   mc_inside's flags (shared/mc_bits.wgsl, params.rows);
//                  must hold layers z_begin ..= z_begin + n_layers
//   block_offsets: per block and one more, exclusive scan of mc_classify's
//                  triangle counts (block w holds the difference of
//                  entries w + 1 and w)
//   vert_base:     first vertex id of each point of global layers
//                  vb_first.. (mc_vertices output)
//   triangles:     vec4<u32> out: xyz = vertex ids, w = linear cell index
//                  x + (nx−1)·(y + (ny−1)·z); element = triangle id − t_start
// Vertex of local edge e: owner point o (EDGE_OWNER[e] offset), axis e / 4,
// id = vert_base[o] + number of crossing edges of o with a smaller axis.
// Mirror: mc::mirror::mc_triangles.

#import block_scan
#import dispatch
#import mc_bits

struct Params {
    rows: BitRows,
    z_begin: u32,
    n_layers: u32,
    blocks_per_layer: u32,
    vb_first: u32,
    t_start: u32,
}

const WG_SIZE: u32 = SCAN_WG;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> table: array<u32>;
// binding 2: inside_bits (shared/mc_bits.wgsl)
@group(0) @binding(3) var<storage, read> block_offsets: array<u32>;
@group(0) @binding(4) var<storage, read> vert_base: array<u32>;
@group(0) @binding(5) var<storage, read_write> triangles: array<vec4<u32>>;

// The block's count (from block_offsets), read by all as a uniform value.
var<workgroup> sh_count: u32;

// The flag of point (x + dx, y + dy, z + dz) from the cell's
// neighbourhood `near`: bit dx + 3·(dy + 3·dz), dx, dy ≤ 2, dz ≤ 1 (five
// rows of three flags, inside_run; row y + 2 only in layer z, where the
// owners of z edges, the only ones that look past the cell's rows, lie).
fn flag(near: u32, dx: u32, dy: u32, dz: u32) -> u32 {
    return (near >> (dx + 3u * (dy + 3u * dz))) & 1u;
}

// Vertex id of the edge (owner corner d of cell (x, y, z), axis).
fn vertex(near: u32, x: u32, y: u32, z: u32, d: vec3<u32>, axis: u32) -> u32 {
    let o = vec3<u32>(x, y, z) + d;
    let m = flag(near, d.x, d.y, d.z);
    var rank = 0u;
    if axis > 0u && o.x + 1u < params.rows.nx && flag(near, d.x + 1u, d.y, d.z) != m {
        rank += 1u;
    }
    if axis > 1u && o.y + 1u < params.rows.ny && flag(near, d.x, d.y + 1u, d.z) != m {
        rank += 1u;
    }
    let n_layer = params.rows.nx * params.rows.ny;
    return vert_base[(o.z - params.vb_first) * n_layer + o.y * params.rows.nx + o.x] + rank;
}

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(local_invocation_id) lid: vec3<u32>,
        @builtin(workgroup_id) wid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    var edge_owner = array<u32, 12>(0u, 2u, 4u, 6u, 0u, 1u, 4u, 5u, 0u, 1u, 2u, 3u);
    let w = workgroup_index(wid, n_groups);
    let layer = w / params.blocks_per_layer;
    let q = (w % params.blocks_per_layer) * WG_SIZE + lid.x;
    // A block without a triangle writes nothing.
    if lid.x == 0u && layer < params.n_layers {
        sh_count = block_offsets[w + 1u] - block_offsets[w];
    }
    if workgroupUniformLoad(&sh_count) == 0u {
        return;
    }
    let n_layer = params.rows.nx * params.rows.ny;
    let x = q % params.rows.nx;
    let y = q / params.rows.nx;
    let z = params.z_begin + layer;
    let in_range = layer < params.n_layers && q < n_layer
        && x + 1u < params.rows.nx && y + 1u < params.rows.ny;
    var near = 0u;
    var case_ix = 0u;
    var nt = 0u;
    if in_range {
        let r = params.rows;
        near = inside_run(r, x, y, z) | (inside_run(r, x, y + 1u, z) << 3u)
            | (inside_run(r, x, y, z + 1u) << 9u) | (inside_run(r, x, y + 1u, z + 1u) << 12u);
        for (var c = 0u; c < 8u; c++) {
            case_ix |= flag(near, c & 1u, (c >> 1u) & 1u, c >> 2u) << c;
        }
        nt = table[case_ix + 1u] - table[case_ix];
    }
    let inclusive = block_scan(lid.x, nt);
    if nt == 0u {
        return;
    }
    near |= inside_run(params.rows, x, y + 2u, z) << 6u;
    let out0 = block_offsets[w] + inclusive - nt - params.t_start;
    let cell = x + (params.rows.nx - 1u) * (y + (params.rows.ny - 1u) * z);
    let first = table[case_ix];
    for (var k = 0u; k < nt; k++) {
        var v = vec3<u32>(0u);
        for (var j = 0u; j < 3u; j++) {
            let e = table[257u + 3u * (first + k) + j];
            let c = edge_owner[e];
            let d = vec3<u32>(c & 1u, (c >> 1u) & 1u, c >> 2u);
            v[j] = vertex(near, x, y, z, d, e / 4u);
        }
        triangles[out0 + k] = vec4<u32>(v, cell);
    }
}
