//! The kernel registry: every `kernels/*.wgsl` and `shaders/*.wgsl` file,
//! embedded at build time, under one name used everywhere (WGSL file, CPU
//! mirror, GPU pass, parity test, bench id, wgpu label `chisel.<name>`).
//!
//! `tests/shaders.rs` walks both folders and checks that every file is here
//! and passes naga validation.

/// Declares the registry: one variant per file, with its source.
macro_rules! registry {
    (
        $(#[$meta:meta])* $ty:ident, $dir:literal, requires $req:ident:
        $($(#[$vmeta:meta])* $variant:ident => $file:literal $(needs $feat:ident)?),* $(,)?
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum $ty {
            $($(#[$vmeta])* $variant,)*
        }

        impl $ty {
            /// Every entry, in declaration order.
            pub const ALL: &'static [$ty] = &[$($ty::$variant,)*];

            /// The file stem, which is also the kernel's name.
            pub fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $file,)*
                }
            }

            /// Path relative to the crate root.
            pub fn path(self) -> String {
                format!("{}/{}.wgsl", $dir, self.name())
            }

            /// The embedded WGSL source (before `#import` expansion).
            pub fn source(self) -> &'static str {
                match self {
                    $($ty::$variant => include_str!(concat!("../../", $dir, "/", $file, ".wgsl")),)*
                }
            }

            /// Device features the file needs (empty = portable).
            pub fn $req(self) -> wgpu::Features {
                match self {
                    $($ty::$variant => wgpu::Features::empty() $(| wgpu::Features::$feat)?,)*
                }
            }

            /// The wgpu label `chisel.<name>`.
            pub fn label(self) -> String {
                format!("chisel.{}", self.name())
            }
        }
    };
}

registry! {
    /// Compute kernels in `kernels/`.
    Kernel, "kernels", requires requires:
    /// Area-weighted vertex normals by gather over CSR vertex→triangle adjacency.
    VertexNormals => "vertex_normals",
    /// Per-workgroup min/max of `vec4` positions (bounding box), as order keys.
    BoundsReduce => "bounds_reduce",
    /// Per-workgroup min/max of `f32` samples (volume intensity range), as order keys.
    RangeReduce => "range_reduce",
    /// Exclusive scan of `u32` within workgroup blocks, block totals out.
    ExclusiveScanBlocks => "exclusive_scan_blocks",
    /// Adds scanned block totals back to every element of its block.
    ExclusiveScanAdd => "exclusive_scan_add",
    /// One damped semi-implicit Euler step of the tissue spring network (eq. 4.4–4.7).
    SpringStep => "spring_step",
    /// One stationary Chebyshev step toward the tissue network's equilibrium.
    SpringChebyshev => "spring_chebyshev",
    /// Max |v|² and max window change of a relaxation, as u32 keys.
    TissueReduceMax => "tissue_reduce_max",
    /// Marching cubes: the inside flag of every point, one bit each in bit rows.
    McInside => "mc_inside",
    /// Marching cubes: per-point vertex and triangle counts, summed per block.
    McClassify => "mc_classify",
    /// Marching cubes: welded vertices at scanned offsets, per-point first vertex id.
    McVertices => "mc_vertices",
    /// Marching cubes: triangles of each cell at scanned offsets.
    McTriangles => "mc_triangles",
    /// Inside/on/outside of every voxel against every hull face, exact i64.
    HullScan => "hull_scan" needs SHADER_INT64,
    /// Inside/on/outside of every voxel, exact emulated 64-bit (portable).
    HullScanI32x2 => "hull_scan_i32x2",
    /// Per-row inside/on intervals of a convex polyhedron, exact i64 division.
    HullRows => "hull_rows" needs SHADER_INT64,
    /// Per-row intervals by binary search on emulated 64-bit products (portable).
    HullRowsI32x2 => "hull_rows_i32x2",
    /// DMS spline: B-spline weights and derivatives per evaluation point, summed per control.
    DmsBasis => "dms_basis",
    /// DMS spline: surface points and normals by gather over the basis rows.
    DmsSurface => "dms_surface",
    /// Skeletal implicit field: F − I, ∇F and ∂F/∂t at many points.
    ImplicitField => "implicit_field",
    /// Witkin–Heckbert particles: repulsion over the cell list, constraint velocity, Euler step.
    ParticleUpdate => "particle_update",
    /// Particle spring network: eq. 13 springs over CSR rows, projected by eq. 8, Euler step.
    NetworkUpdate => "network_update",
    /// Blobby fit: energy and gradient over range points × primitives, per workgroup.
    BlobbyEnergy => "blobby_energy",
    /// Rays from one origin through a linear BVH: nearest and farthest hit and the hit count.
    RayCast => "ray_cast",
    /// Rays from one origin through a linear BVH: every hit (parameter, triangle) at scanned offsets.
    RayHits => "ray_hits",
}

registry! {
    /// Render shaders in `shaders/`.
    Shader, "shaders", requires requires:
    /// Shaded triangles with optional scalar colour map.
    Mesh => "mesh",
    /// Wireframe lines drawn over the shaded mesh.
    Wireframe => "wireframe",
}

/// Files under `kernels/shared/`, available to `#import <name>`.
const SHARED: &[(&str, &str)] = &[
    (
        "dispatch",
        include_str!("../../kernels/shared/dispatch.wgsl"),
    ),
    (
        "spring_network",
        include_str!("../../kernels/shared/spring_network.wgsl"),
    ),
    (
        "order_key",
        include_str!("../../kernels/shared/order_key.wgsl"),
    ),
    (
        "hull_face",
        include_str!("../../kernels/shared/hull_face.wgsl"),
    ),
    ("i32x2", include_str!("../../kernels/shared/i32x2.wgsl")),
    (
        "skeletal_field",
        include_str!("../../kernels/shared/skeletal_field.wgsl"),
    ),
    (
        "block_scan",
        include_str!("../../kernels/shared/block_scan.wgsl"),
    ),
    ("bvh_ray", include_str!("../../kernels/shared/bvh_ray.wgsl")),
    ("mc_grid", include_str!("../../kernels/shared/mc_grid.wgsl")),
    ("mc_bits", include_str!("../../kernels/shared/mc_bits.wgsl")),
];

/// Expands `#import <name>` lines with `kernels/shared/<name>.wgsl`
/// (each imported once). Errors name the unknown import.
pub fn preprocess(source: &str) -> Result<String, String> {
    let mut out = String::with_capacity(source.len());
    let mut seen: Vec<&str> = Vec::new();
    for (n, line) in source.lines().enumerate() {
        if let Some(rest) = line.trim_start().strip_prefix("#import") {
            let name = rest.trim();
            let (key, body) = SHARED
                .iter()
                .find(|(k, _)| *k == name)
                .ok_or_else(|| format!("line {}: unknown `#import {name}`", n + 1))?;
            if !seen.contains(key) {
                seen.push(key);
                out.push_str(body);
                out.push('\n');
            }
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    Ok(out)
}
