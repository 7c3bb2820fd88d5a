// exclusive_scan_blocks: exclusive prefix sum of #N u32 within blocks of
// WG_SIZE elements (the shared workgroup scan, shared/block_scan.wgsl),
// plus each block's total. The host scans the totals with this same kernel (recursively, until
// one block is left, whose total is the grand total) and adds them back with
// exclusive_scan_add.
//
// Dispatch: one invocation per element, WG_SIZE per workgroup, 2-D grid past
// the per-dimension limit (shared/dispatch.wgsl); workgroup w = block w.
// Buffers:
//   params:   n (elements at this level)
//   values:   #N u32 in
//   scanned:  #N u32 out, scanned[i] = Σ_{block start ≤ j < i} values[j]
//   totals:   ceil(#N / WG_SIZE) u32 out, totals[w] = Σ of block w
// Arithmetic: u32 addition wraps (mod 2³², WGSL's rule for runtime integer
// overflow); addition mod 2³² is associative, so any summation order, the
// mirror's included, gives the same bits.
// Mirror: exclusive_scan::cpu::scan_blocks (whole scan: exclusive_scan::cpu::exclusive_scan).

#import dispatch
#import block_scan

struct Params {
    n: u32,
}

// The workgroup is one block_scan group (SCAN_WG invocations).
const WG_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> values: array<u32>;
@group(0) @binding(2) var<storage, read_write> scanned: array<u32>;
@group(0) @binding(3) var<storage, read_write> totals: array<u32>;

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(workgroup_id) wid: vec3<u32>,
        @builtin(local_invocation_index) lid: u32,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let w = workgroup_index(wid, n_groups);
    let first_ix = w * WG_SIZE;
    // Surplus workgroups of a 2-D grid: the whole group leaves (uniform).
    if first_ix >= params.n {
        return;
    }
    let ix = first_ix + lid;
    var v = 0u;
    if ix < params.n {
        v = values[ix];
    }
    // Inclusive sum of the block up to this element (wrapping, so the
    // exclusive sum is the inclusive one less this element, mod 2³²).
    let inclusive = block_scan(lid, v);
    if ix < params.n {
        scanned[ix] = inclusive - v;
    }
    if lid == WG_SIZE - 1u {
        totals[w] = inclusive;
    }
}
