// vertex_normals: area-weighted unit vertex normals by gather over the CSR
// vertex → triangle adjacency (no atomics, deterministic).
//
// Dispatch: one invocation per vertex, WG_SIZE per workgroup, 2-D grid past
// the per-dimension limit (see shared/dispatch.wgsl).
// Buffers:
//   params:     n_vertices
//   positions:  #V vec4<f32>, xyz = position, w unused
//   triangles:  3·#F u32, vertex indices, counter-clockwise = front
//   offsets:    #V + 1 u32, CSR row starts into tri_ids
//   tri_ids:    #adjacency u32, triangle ids incident to each vertex
//   normals:    #V vec4<f32> out, xyz = unit normal (0 when the incident
//               area is zero), w = 0
// Normal of triangle (a, b, c) = cross(b − a, c − a) (twice its area, along
// the right-hand-rule normal); summed in CSR order, then normalised.
// Mirror: vertex_normals::cpu::vertex_normals.

#import dispatch

struct Params {
    n_vertices: u32,
}

const WG_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> positions: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> triangles: array<u32>;
@group(0) @binding(3) var<storage, read> offsets: array<u32>;
@group(0) @binding(4) var<storage, read> tri_ids: array<u32>;
@group(0) @binding(5) var<storage, read_write> normals: array<vec4<f32>>;

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let ix = linear_index(gid, n_groups, WG_SIZE);
    if ix >= params.n_vertices {
        return;
    }
    var sum = vec3<f32>(0.0);
    for (var k = offsets[ix]; k < offsets[ix + 1u]; k++) {
        let t = tri_ids[k];
        let a = positions[triangles[3u * t]].xyz;
        let b = positions[triangles[3u * t + 1u]].xyz;
        let c = positions[triangles[3u * t + 2u]].xyz;
        sum += cross(b - a, c - a);
    }
    let len = length(sum);
    var n = vec3<f32>(0.0);
    if len > 0.0 {
        n = sum / len;
    }
    normals[ix] = vec4<f32>(n, 0.0);
}
