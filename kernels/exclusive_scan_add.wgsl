// exclusive_scan_add: adds the scanned block totals back, turning per-block
// exclusive scans into one scan over all #N elements.
//
// Dispatch: one invocation per element, WG_SIZE per workgroup, 2-D grid past
// the per-dimension limit (shared/dispatch.wgsl). Blocks are WG_SIZE wide,
// the same as in exclusive_scan_blocks.
// Buffers:
//   params:   n (elements at this level)
//   offsets:  ceil(#N / WG_SIZE) u32, exclusive scan of the block totals
//   scanned:  #N u32 in/out, scanned[i] += offsets[i / WG_SIZE] (wrapping)
// Mirror: exclusive_scan::cpu::add_offsets (whole scan: exclusive_scan::cpu::exclusive_scan).

#import dispatch

struct Params {
    n: u32,
}

const WG_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> offsets: array<u32>;
@group(0) @binding(2) var<storage, read_write> scanned: array<u32>;

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let ix = linear_index(gid, n_groups, WG_SIZE);
    if ix >= params.n {
        return;
    }
    scanned[ix] += offsets[ix / WG_SIZE];
}
