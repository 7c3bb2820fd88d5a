// mesh: shaded triangles for headless previews (render::pipeline).
//
// Draw: indexed triangle list, one vertex invocation per index; the vertex
// stage reads its attributes from storage buffers by `vertex_index`, so the
// normals written by kernels/vertex_normals.wgsl feed it without a readback.
// No back-face culling: the fragment stage lights both sides.
// Buffers:
//   camera:    view_proj (world → clip, orthographic, depth 0..1),
//              to_eye / to_light (unit world vectors toward the camera and
//              the key light), use_scalars (0 = grey, 1 = colour map),
//              n_colors (stops in `colormap`, ≥ 2)
//   vertices:  #V vec4<f32>, xyz = position, w = colour-map coordinate in
//              [0, 1], or < 0 where the scalar is not finite (drawn grey)
//   normals:   #V vec4<f32>, xyz = unit area-weighted vertex normal (0 for
//              isolated vertices), w unused — the vertex_normals output
//   colormap:  n_colors vec4<f32>, linear RGB stops at t = k / (n_colors − 1)
// Lighting: Lambert + Blinn–Phong in linear RGB; the target is an sRGB
// texture, so the hardware encodes. Two-sided: the interpolated normal is
// turned toward the side of the triangle the camera sees (`front_facing`
// flips with the winding exactly as the normal does, so a mesh and its
// flip_winding() copy shade identically).
// Mirror: render::colormap::Colormap::sample (the legend's CPU lookup).

struct Camera {
    view_proj: mat4x4<f32>,
    to_eye: vec4<f32>,
    to_light: vec4<f32>,
    depth_pull: f32,
    use_scalars: u32,
    n_colors: u32,
}

// Material (linear RGB). The peak (base·(AMBIENT + DIFFUSE) + SPECULAR)
// stays below the white background.
const BASE_GREY: vec3<f32> = vec3<f32>(0.50, 0.50, 0.52);
const NO_VALUE_GREY: vec3<f32> = vec3<f32>(0.30, 0.30, 0.30);
const AMBIENT: f32 = 0.22;
const DIFFUSE: f32 = 0.78;
const SPECULAR: f32 = 0.12;
const SHININESS: f32 = 32.0;

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<storage, read> vertices: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> normals: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> colormap: array<vec4<f32>>;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) t: f32,
}

@vertex
fn vs_main(@builtin(vertex_index) v_ix: u32) -> VertexOut {
    let v = vertices[v_ix];
    var out: VertexOut;
    out.clip = camera.view_proj * vec4<f32>(v.xyz, 1.0);
    out.normal = normals[v_ix].xyz;
    out.t = v.w;
    return out;
}

// Piecewise-linear lookup of `colormap` at t ∈ [0, 1].
fn colormap_at(t: f32) -> vec3<f32> {
    let x = clamp(t, 0.0, 1.0) * f32(camera.n_colors - 1u);
    let lo_ix = min(u32(floor(x)), camera.n_colors - 2u);
    let f = x - f32(lo_ix);
    return mix(colormap[lo_ix].rgb, colormap[lo_ix + 1u].rgb, f);
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let e = camera.to_eye.xyz;
    // A zero normal (isolated or zero-area fan) faces the camera.
    var n = e;
    let len = length(in.normal);
    if len > 1e-20 {
        n = in.normal / len;
        if !front {
            n = -n;
        }
    }
    var base = BASE_GREY;
    if camera.use_scalars != 0u {
        // Valid coordinates are in [0, 1], "no value" is −1; compare against
        // −0.5 because interpolating exact zeros can round to −1e-10.
        if in.t >= -0.5 {
            base = colormap_at(in.t);
        } else {
            base = NO_VALUE_GREY;
        }
    }
    let l = camera.to_light.xyz;
    let diffuse = max(dot(n, l), 0.0);
    let h = normalize(l + e);
    let specular = SPECULAR * pow(max(dot(n, h), 0.0), SHININESS);
    let color = base * (AMBIENT + DIFFUSE * diffuse) + vec3<f32>(specular);
    return vec4<f32>(min(color, vec3<f32>(0.95)), 1.0);
}
