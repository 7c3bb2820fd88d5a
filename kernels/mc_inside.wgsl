// mc_inside: marching-cubes inside flags — one bit per point of `n_layers`
// point layers from global layer `z_begin`, 1 where the sample is ≥ level
// (or equals the label; shared/mc_grid.wgsl decodes it), packed in the bit
// rows of shared/mc_bits.wgsl (`inside_bits`). mc_classify, mc_vertices
// and mc_triangles read these flags instead of decoding the samples of
// every corner again: each sample is decoded once here (a padding point
// decodes the inner sample it mirrors), 32 consecutive samples an
// invocation, and again only at the ends of crossing edges, by
// mc_vertices.
//
// Dispatch: one invocation per output word (the 32 flags of one row's
// points 32j ..< 32j + 32), 2-D grid past the per-dimension limit
// (shared/dispatch.wgsl).
// Buffers:
//   params:   grid (dims, sample words, level), slab position, row_words
//   samples:  the volume's samples in their own type, packed in u32 words
//             (shared/mc_grid.wgsl, params.grid); must hold the inner
//             layers of layers z_begin ..< z_begin + n_layers
//   inside_bits: n_layers · ny · row_words words out, row y + ny · layer
// Mirror: mc::mirror::mc_inside.

#import dispatch
#import mc_grid

struct Params {
    grid: SampleGrid,
    z_begin: u32,
    n_layers: u32,
    row_words: u32,
}

const WG_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: Params;
// binding 1: samples (shared/mc_grid.wgsl)
@group(0) @binding(2) var<storage, read_write> inside_bits: array<u32>;

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(local_invocation_id) lid: vec3<u32>,
        @builtin(workgroup_id) wid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let word = workgroup_index(wid, n_groups) * WG_SIZE + lid.x;
    if word >= params.n_layers * params.grid.ny * params.row_words {
        return;
    }
    let row = word / params.row_words;
    let x0 = (word % params.row_words) * 32u;
    let y = row % params.grid.ny;
    let z = params.z_begin + row / params.grid.ny;
    var flags = 0u;
    for (var b = 0u; b < min(32u, params.grid.nx - x0); b++) {
        if grid_sample(params.grid, x0 + b, y, z) >= params.grid.level {
            flags |= 1u << b;
        }
    }
    inside_bits[word] = flags;
}
