// Shared declarations of the hull-scan kernels (hull_scan, hull_rows and
// their _i32x2 twins): the uniform parameters and one face n·p ≤ d.
// Host side: hull_scan::gpu::{Params, GpuFace}.

struct Params {
    // Faces in `faces` (hull_scan*; hull_rows* read theirs from `layers`).
    n_faces: u32,
    // Items of this slab: voxels (hull_scan*) or rows (hull_rows*).
    n_items: u32,
    // Voxels per row and rows per z layer of the box.
    nx: u32,
    ny: u32,
    // First z layer (local) of this slab.
    z0: u32,
    // Voxel index of the box's first voxel; centres are 2·index + 1.
    origin_x: i32,
    origin_y: i32,
    origin_z: i32,
}

// normal.xyz: outward normal (|n_c| < 2^31), w unused; offset.xy: d as
// (low word, high word), two's complement, zw unused.
struct Face {
    normal: vec4<i32>,
    offset: vec4<u32>,
}

const WG_SIZE: u32 = 256u;

// hull_rows*: the start of a layer's face list when the polyhedron misses
// the layer.
const LAYER_MISSES: u32 = 0xffffffffu;
