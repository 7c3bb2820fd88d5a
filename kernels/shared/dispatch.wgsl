// Shared dispatch helper: the linear invocation index of a 1-D problem that
// the host may dispatch as a 2-D grid of workgroups (past
// max_compute_workgroups_per_dimension); see `Gpu::workgroups`.
fn linear_index(gid: vec3<u32>, n_groups: vec3<u32>, wg_size: u32) -> u32 {
    return gid.x + gid.y * n_groups.x * wg_size;
}

// The linear index of this workgroup in the same (possibly 2-D) grid; it is
// workgroup-uniform, so a whole group may return on it before a barrier.
fn workgroup_index(wid: vec3<u32>, n_groups: vec3<u32>) -> u32 {
    return wid.x + wid.y * n_groups.x;
}
