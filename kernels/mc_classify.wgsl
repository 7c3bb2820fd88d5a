// mc_classify: marching-cubes classification — per sample point, how many
// vertices (crossing +x/+y/+z grid edges) and triangles (table entry of the
// cell whose origin it is) it produces, from mc_inside's flags; one sum per
// workgroup block (added up by workgroup atomics from the few points that
// produce anything: one barrier, where a tree reduction takes eight).
//
// Dispatch: one invocation per point of `n_layers` point layers starting at
// global layer `z_begin`; each layer is cut into `blocks_per_layer` blocks
// of WG_SIZE points (a block never spans two layers), one workgroup per
// block, 2-D grid past the per-dimension limit (shared/dispatch.wgsl).
// Buffers:
//   params:        bit rows (dims, first layer), slab position (see Params)
//   table:         257 case offsets, then 3 local edges per triangle
//                  (mc::tables::CaseTable::flat)
//   inside_bits:   mc_inside's flags (shared/mc_bits.wgsl, params.rows);
//                  must hold layers z_begin ..= z_begin + n_layers (the
//                  last one clipped at nz − 1)
//   block_counts:  per block (vertices, triangles), out
// Inside: the point's flag is set (sample ≥ level, by mc_inside).
// Mirror: mc::mirror::mc_classify; the host
// scans block_counts (exclusive) for mc_vertices/mc_triangles.

#import dispatch
#import mc_bits

struct Params {
    rows: BitRows,
    z_begin: u32,
    n_layers: u32,
    blocks_per_layer: u32,
}

const WG_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> table: array<u32>;
// binding 2: inside_bits (shared/mc_bits.wgsl)
@group(0) @binding(3) var<storage, read_write> block_counts: array<vec2<u32>>;

// Block sums (vertices, triangles); workgroup memory starts zeroed.
var<workgroup> sh_sum: array<atomic<u32>, 2>;

fn flag(x: u32, y: u32, z: u32) -> u32 {
    return inside(params.rows, x, y, z);
}

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(local_invocation_id) lid: vec3<u32>,
        @builtin(workgroup_id) wid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let w = workgroup_index(wid, n_groups);
    let layer = w / params.blocks_per_layer;
    let q = (w % params.blocks_per_layer) * WG_SIZE + lid.x;
    let n_layer = params.rows.nx * params.rows.ny;
    var nv = 0u;
    var nt = 0u;
    if layer < params.n_layers && q < n_layer {
        let x = q % params.rows.nx;
        let y = q / params.rows.nx;
        let z = params.z_begin + layer;
        let m = flag(x, y, z);
        if x + 1u < params.rows.nx && flag(x + 1u, y, z) != m { nv += 1u; }
        if y + 1u < params.rows.ny && flag(x, y + 1u, z) != m { nv += 1u; }
        if z + 1u < params.rows.nz && flag(x, y, z + 1u) != m { nv += 1u; }
        if x + 1u < params.rows.nx && y + 1u < params.rows.ny && z + 1u < params.rows.nz {
            // Corner c = dx + 2·dy + 4·dz is bit c of the case index.
            var case_ix = 0u;
            for (var c = 0u; c < 8u; c++) {
                case_ix |= flag(x + (c & 1u), y + ((c >> 1u) & 1u), z + (c >> 2u)) << c;
            }
            nt = table[case_ix + 1u] - table[case_ix];
        }
    }
    if nv != 0u {
        atomicAdd(&sh_sum[0], nv);
    }
    if nt != 0u {
        atomicAdd(&sh_sum[1], nt);
    }
    workgroupBarrier();
    if lid.x == 0u && layer < params.n_layers {
        block_counts[w] = vec2<u32>(atomicLoad(&sh_sum[0]), atomicLoad(&sh_sum[1]));
    }
}
