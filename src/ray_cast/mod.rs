//! Ray casting against triangle meshes: for each direction, every hit of
//! the half-line from one origin on a mesh, as the nearest hit, the
//! farthest hit and their count (kernel `ray_cast`), or as the list of
//! hits (kernel `ray_hits`, after `ray_cast`'s counts are scanned).
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
//! Parity: the mirror ([`cpu`]) of both kernels performs the same f32 operations in the
//! same order, so triangle ids and counts agree exactly and the distances
//! to the last bit unless a device contracts `a·b + c` into a fused
//! multiply–add; the stated bound for distances is [`DISTANCE_ULPS`].

pub mod bvh;
pub mod cpu;
pub mod gpu;

use glam::Vec3;

use crate::gpu::{Backend, Gpu};
use crate::{Error, Result};
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

/// One hit of a ray (8 bytes, `struct Hit` in `kernels/ray_hits.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Hit {
    /// Ray parameter (> 0).
    pub t: f32,
    /// Mesh triangle id.
    pub tri: u32,
}

/// Every hit of many rays: ray `i`'s are `hits[offsets[i]..offsets[i + 1]]`,
/// in the walk's order (sort them by `t` for the order along the ray).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Hits {
    /// Exclusive scan of the hit counts, with the total appended.
    pub offsets: Vec<u32>,
    pub hits: Vec<Hit>,
}

impl Hits {
    /// The hits of ray `i`.
    pub fn of(&self, i: usize) -> &[Hit] {
        &self.hits[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// Offsets from hit counts (the first pass's), as `u32`.
    ///
    /// Errors: a total of `u32::MAX` or more.
    pub fn offsets_of(counts: impl IntoIterator<Item = u32>) -> Result<Vec<u32>> {
        let mut out = vec![0u32];
        let mut sum = 0u64;
        for c in counts {
            sum += u64::from(c);
            out.push(
                u32::try_from(sum)
                    .ok()
                    .filter(|&s| s < u32::MAX)
                    .ok_or_else(|| Error::limit("ray_hits: hits", sum, u32::MAX - 1))?,
            );
        }
        Ok(out)
    }
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

    /// The backend it casts on.
    pub fn backend(&self) -> Backend<'a> {
        self.device
            .as_ref()
            .map_or(Backend::Cpu, |(g, _)| Backend::Gpu(g))
    }

    /// Casts every direction of `dirs` (`[x, y, z, _]`) from `origin`.
    pub fn cast(&self, origin: Vec3, dirs: &[[f32; 4]]) -> Result<Vec<RayHit>> {
        match &self.device {
            None => Ok(cpu::ray_cast(self.bvh, origin.to_array(), dirs)),
            Some((g, buffers)) => buffers.cast(g, origin, dirs),
        }
    }
}

impl RayCaster<'_> {
    /// Every hit of every direction of `dirs` from `origin`: kernel
    /// `ray_cast` counts them, the host scans the counts, kernel `ray_hits`
    /// lists them.
    ///
    /// Errors: the GPU's, a total of `u32::MAX` hits or more, or a second
    /// walk that found other counts than the first (an internal error).
    pub fn hits(&self, origin: Vec3, dirs: &[[f32; 4]]) -> Result<Hits> {
        let counts = self.cast(origin, dirs)?;
        let offsets = Hits::offsets_of(counts.iter().map(|h| h.count))?;
        let (hits, again) = match &self.device {
            None => cpu::ray_hits(self.bvh, origin.to_array(), dirs, &offsets),
            Some((g, buffers)) => buffers.hits(g, origin, dirs, &offsets)?,
        };
        if let Some(i) = (0..dirs.len()).find(|&i| again[i] != counts[i].count) {
            return Err(Error::Internal(format!(
                "ray_hits: ray {i} found {} hits, ray_cast {}",
                again[i], counts[i].count
            )));
        }
        Ok(Hits { offsets, hits })
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
