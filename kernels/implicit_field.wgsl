// implicit_field: F − I, ∇F and ∂F/∂t of a skeletal implicit scene at many
// points (start meshes, dense references, topology probes).
//
// Dispatch: one invocation per point, WG_SIZE per workgroup, 2-D grid past
// the per-dimension limit (see shared/dispatch.wgsl).
// Buffers:
//   params:   n_points
//   field, skeleton, table: the scene (shared/skeletal_field.wgsl)
//   points:   #P vec4<f32>, xyz = position, w unused
//   samples:  #P vec4<f32> out, xyz = ∇F, w = F − I
//   rates:    #P f32 out, ∂F/∂t
// Mirror: implicit::field::cpu::implicit_field.

#import dispatch
#import skeletal_field

struct Params {
    n_points: u32,
}

const WG_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(4) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> samples: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> rates: array<f32>;

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let ix = linear_index(gid, n_groups, WG_SIZE);
    if ix >= params.n_points {
        return;
    }
    let f = skeletal_field(points[ix].xyz);
    samples[ix] = vec4<f32>(f.grad, f.value);
    rates[ix] = f.rate;
}
