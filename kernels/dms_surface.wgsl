// dms_surface: points and normals of a DMS spline surface by gather over
// the basis rows (seed 000 eq. 2.11): F = Σ w·x, F_u = Σ ∂w/∂u·x,
// F_v = Σ ∂w/∂v·x, normal = normalize(F_u × F_v).
//
// Dispatch: one invocation per point, WG_SIZE per workgroup, 2-D grid past
// the per-dimension limit (see shared/dispatch.wgsl).
// Buffers:
//   params:    n_points
//   row_off:   #P + 1 u32, CSR starts into row_src / weights
//   row_src:   source id per row entry (a control, or a vertex under point
//              identification)
//   weights:   vec4<f32> per row entry: (w, ∂w/∂u, ∂w/∂v, 0)
//   base:      #P vec4<f32>, xyz added to F (zero for a plain gather; the
//              controls of the rest state when the sources are a
//              relaxation's displacements from rest)
//   sources:   vec4<f32> per source, xyz = position (any buffer another
//              pass keeps, e.g. a relaxation's state)
//   positions: #P vec4<f32> out, xyz = base + F, w = 0
//   normals:   #P vec4<f32> out, xyz = unit F_u × F_v (0 where it
//              vanishes), w = 0
// Mirror: dms::surface::cpu::dms_surface.

#import dispatch

struct Params {
    n_points: u32,
}

const WG_SIZE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> row_off: array<u32>;
@group(0) @binding(2) var<storage, read> row_src: array<u32>;
@group(0) @binding(3) var<storage, read> weights: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> base: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> sources: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> positions: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> normals: array<vec4<f32>>;

@compute @workgroup_size(WG_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(num_workgroups) n_groups: vec3<u32>) {
    let ix = linear_index(gid, n_groups, WG_SIZE);
    if ix >= params.n_points {
        return;
    }
    var f = base[ix].xyz;
    var fu = vec3<f32>(0.0);
    var fv = vec3<f32>(0.0);
    for (var e = row_off[ix]; e < row_off[ix + 1u]; e++) {
        let x = sources[row_src[e]].xyz;
        let w = weights[e];
        f += w.x * x;
        fu += w.y * x;
        fv += w.z * x;
    }
    let n = cross(fu, fv);
    let len = length(n);
    var unit = vec3<f32>(0.0);
    if len > 0.0 {
        unit = n / len;
    }
    positions[ix] = vec4<f32>(f, 0.0);
    normals[ix] = vec4<f32>(unit, 0.0);
}
