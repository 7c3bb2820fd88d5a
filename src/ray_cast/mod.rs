//! Ray casting against triangle meshes (kernel `ray_cast`): for each
//! direction, every hit of the half-line from one origin on a mesh, as the
//! nearest hit, the farthest hit and their count.
//!
//! The mesh sits in a host-built linear BVH ([`bvh::Bvh`]); the kernel walks
//! it without a stack and tests triangles with a watertight test (Woop,
//! Benthin & Wald 2013: shear the ray onto an axis, three 2-D edge
//! functions, each a function of its edge alone). A ray through an edge or
//! a vertex of a closed, consistently oriented mesh hits exactly one of the
//! triangles there: an edge function of exactly 0 counts as inside only for
//! the triangle that walks the edge (counter-clockwise in the sheared plane)
//! in a direction of angle [0, π). So the hit count is the number of
//! crossings, which decides whether the mesh is star-shaped about the
//! origin along that direction (one hit) — the fusion room's question.
//!
//! Parity: the mirror ([`cpu`]) performs the same f32 operations in the
//! same order, so triangle ids and counts agree exactly and the distances
//! to the last bit unless a device contracts `a·b + c` into a fused
//! multiply–add; the stated bound for distances is [`DISTANCE_ULPS`].

pub mod bvh;
pub mod cpu;
pub mod gpu;

use glam::Vec3;

use crate::Result;
use crate::gpu::{Backend, Gpu};
pub use bvh::Bvh;

/// Triangle id of a miss.
pub const NO_TRIANGLE: u32 = u32::MAX;

/// Bound on the GPU–mirror difference of hit distances, in units in the
/// last place of the mirror's value (0 on a device that does not contract
/// multiply–adds; the bound covers one that does).
pub const DISTANCE_ULPS: u32 = 16;

/// What one ray met (20 bytes, `struct RayHit` in `kernels/ray_cast.wgsl`).
/// Distances are ray parameters: multiples of the direction's length.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RayHit {
    /// Nearest hit's parameter (−1 without a hit).
    pub near: f32,
    /// Farthest hit's parameter (−1 without a hit).
    pub far: f32,
    /// Triangle (mesh id) of the nearest hit, [`NO_TRIANGLE`] without one.
    pub near_tri: u32,
    /// Triangle of the farthest hit.
    pub far_tri: u32,
    /// Number of hits (crossings of the surface) at parameters > 0.
    pub count: u32,
}

/// A mesh's hierarchy ready to cast against on one backend (uploaded once
/// for the GPU; every [`RayCaster::cast`] uploads only its directions).
#[derive(Debug)]
pub struct RayCaster<'a> {
    bvh: &'a Bvh,
    device: Option<(&'a Gpu, gpu::BvhBuffers)>,
}

impl<'a> RayCaster<'a> {
    /// Prepares `bvh` for `backend`.
    pub fn new(bvh: &'a Bvh, backend: Backend<'a>) -> Result<Self> {
        let device = match backend {
            Backend::Cpu => None,
            Backend::Gpu(g) => Some((g, gpu::BvhBuffers::upload(g, bvh)?)),
        };
        Ok(RayCaster { bvh, device })
    }

    /// The hierarchy cast against.
    pub fn bvh(&self) -> &Bvh {
        self.bvh
    }

    /// Casts every direction of `dirs` (`[x, y, z, _]`) from `origin`.
    pub fn cast(&self, origin: Vec3, dirs: &[[f32; 4]]) -> Result<Vec<RayHit>> {
        match &self.device {
            None => Ok(cpu::ray_cast(self.bvh, origin.to_array(), dirs)),
            Some((g, buffers)) => buffers.cast(g, origin, dirs),
        }
    }
}

/// Casts `dirs` from `origin` against `bvh` on `backend` (one-off; keep a
/// [`RayCaster`] for repeated casts).
pub fn ray_cast(
    bvh: &Bvh,
    origin: Vec3,
    dirs: &[[f32; 4]],
    backend: Backend<'_>,
) -> Result<Vec<RayHit>> {
    RayCaster::new(bvh, backend)?.cast(origin, dirs)
}
