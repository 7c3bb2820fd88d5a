// wireframe: the unique edges of a mesh as lines over the shaded surface
// (render::pipeline, drawn after shaders/mesh.wgsl in the same pass).
//
// Draw: indexed line list, 2 indices per undirected edge, depth test
// less-or-equal against the shaded mesh. Lines are pulled toward the camera
// by `depth_pull` (NDC depth, ≈ 3 pixels of world depth) so edges on the
// surface win the depth test while edges behind it stay hidden (WebGPU
// depth bias applies to triangles only, so the offset is done here).
// Buffers (same bind group layout as mesh.wgsl; bindings 2–3 unused here):
//   camera:    view_proj, depth_pull (see mesh.wgsl)
//   vertices:  #V vec4<f32>, xyz = position, w ignored

struct Camera {
    view_proj: mat4x4<f32>,
    to_eye: vec4<f32>,
    to_light: vec4<f32>,
    depth_pull: f32,
    use_scalars: u32,
    n_colors: u32,
}

// Line colour, linear RGB (≈ #303030 after sRGB encoding).
const LINE: vec3<f32> = vec3<f32>(0.03, 0.03, 0.03);

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<storage, read> vertices: array<vec4<f32>>;

@vertex
fn vs_main(@builtin(vertex_index) v_ix: u32) -> @builtin(position) vec4<f32> {
    var clip = camera.view_proj * vec4<f32>(vertices[v_ix].xyz, 1.0);
    clip.z = max(clip.z - camera.depth_pull * clip.w, 0.0);
    return clip;
}

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    return vec4<f32>(LINE, 1.0);
}
