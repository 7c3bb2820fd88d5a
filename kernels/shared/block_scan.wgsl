// Shared workgroup scan of exclusive_scan_blocks and the marching-cubes
// emission kernels (mc_vertices, mc_triangles), whose workgroups hold
// SCAN_WG invocations.

const SCAN_WG: u32 = 256u;

var<workgroup> sh_scan: array<u32, 2u * SCAN_WG>;

// Inclusive scan of `value` over the workgroup, invocation `lid` of
// SCAN_WG: Hillis–Steele on two halves of `sh_scan`, each step reading one
// half and writing the other, so one barrier a step. Call from uniform
// control flow.
fn block_scan(lid: u32, value: u32) -> u32 {
    var src = 0u;
    sh_scan[lid] = value;
    workgroupBarrier();
    for (var stride = 1u; stride < SCAN_WG; stride <<= 1u) {
        var v = sh_scan[src + lid];
        if lid >= stride {
            v += sh_scan[src + lid - stride];
        }
        sh_scan[SCAN_WG - src + lid] = v;
        workgroupBarrier();
        src = SCAN_WG - src;
    }
    return sh_scan[src + lid];
}
