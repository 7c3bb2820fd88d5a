// exclusive_scan_blocks: exclusive prefix sum of #N u32 within blocks of
// WG_SIZE elements (Hillis–Steele in workgroup memory), plus each block's
// total. The host scans the totals with this same kernel (recursively, until
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
// Mirror: scan::cpu::scan_blocks (whole scan: scan::cpu::exclusive_scan).

#import dispatch

struct Params {
    n: u32,
}

const WG_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> values: array<u32>;
@group(0) @binding(2) var<storage, read_write> scanned: array<u32>;
@group(0) @binding(3) var<storage, read_write> totals: array<u32>;

var<workgroup> sh_sum: array<u32, WG_SIZE>;

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
    // Inclusive Hillis–Steele scan: after the step with offset d, sh_sum[l]
    // holds the sum of the 2d elements ending at l (fewer at the block start).
    sh_sum[lid] = v;
    for (var offset = 1u; offset < WG_SIZE; offset <<= 1u) {
        workgroupBarrier();
        var t = sh_sum[lid];
        if lid >= offset {
            t += sh_sum[lid - offset];
        }
        workgroupBarrier();
        sh_sum[lid] = t;
    }
    workgroupBarrier();
    if ix < params.n {
        var exclusive = 0u;
        if lid > 0u {
            exclusive = sh_sum[lid - 1u];
        }
        scanned[ix] = exclusive;
    }
    if lid == WG_SIZE - 1u {
        totals[w] = sh_sum[lid];
    }
}
