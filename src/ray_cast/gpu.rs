//! GPU passes for `kernels/ray_cast.wgsl` and `kernels/ray_hits.wgsl`.

use glam::Vec3;

use super::bvh::Bvh;
use super::{Hit, RayHit};
use crate::gpu::{Gpu, GpuArray, Kernel, UniformBuffer};
use crate::{Error, Result};

/// Uniform parameters of `ray_cast` and `ray_hits`.
#[derive(Debug, Clone, Copy, PartialEq, encase::ShaderType)]
pub struct Params {
    pub n_rays: u32,
    pub n_nodes: u32,
    /// The rays' common origin.
    pub origin_x: f32,
    pub origin_y: f32,
    pub origin_z: f32,
}

impl Params {
    /// The parameters of `n_rays` rays from `origin` through `bvh`.
    pub fn new(n_rays: u32, bvh: &BvhBuffers, origin: Vec3) -> Params {
        Params {
            n_rays,
            n_nodes: bvh.n_nodes,
            origin_x: origin.x,
            origin_y: origin.y,
            origin_z: origin.z,
        }
    }
}

/// Most rays per dispatch (keeps the hit buffer at 80 MiB, under the
/// default 128 MiB storage binding).
pub const RAYS_PER_DISPATCH: usize = 1 << 22;

/// Most hits per `ray_hits` dispatch (64 MiB of output).
pub const HITS_PER_DISPATCH: usize = 1 << 23;

/// A hierarchy on the device.
#[derive(Debug)]
pub struct BvhBuffers {
    nodes: GpuArray<super::bvh::Node>,
    corners: GpuArray<[f32; 4]>,
    n_nodes: u32,
}

impl BvhBuffers {
    /// Uploads `bvh` (an empty one as one unreachable node).
    pub fn upload(gpu: &Gpu, bvh: &Bvh) -> Result<Self> {
        let empty = super::bvh::Node {
            lo: [1.0; 3],
            escape: 1,
            hi: [0.0; 3],
            leaf: 0,
        };
        let nodes: &[super::bvh::Node] = if bvh.nodes.is_empty() {
            std::slice::from_ref(&empty)
        } else {
            &bvh.nodes
        };
        let corners: &[[f32; 4]] = if bvh.corners.is_empty() {
            &[[0.0; 4]]
        } else {
            &bvh.corners
        };
        Ok(BvhBuffers {
            nodes: GpuArray::from_slice(gpu, "ray_cast.nodes", nodes)?,
            corners: GpuArray::from_slice(gpu, "ray_cast.corners", corners)?,
            n_nodes: bvh.nodes.len() as u32,
        })
    }

    /// Casts `dirs` from `origin`, in dispatches of at most
    /// [`RAYS_PER_DISPATCH`] rays.
    pub fn cast(&self, gpu: &Gpu, origin: Vec3, dirs: &[[f32; 4]]) -> Result<Vec<RayHit>> {
        let mut out = Vec::with_capacity(dirs.len());
        for chunk in dirs.chunks(RAYS_PER_DISPATCH) {
            let rays = RayBuffers::upload(gpu, self, origin, chunk)?;
            let mut encoder = gpu.encoder("ray_cast");
            rays.record(gpu, self, &mut encoder)?;
            gpu.submit_and_wait(encoder)?;
            out.extend(rays.hits.read(gpu)?);
        }
        Ok(out)
    }
}

impl BvhBuffers {
    /// Lists every hit of `dirs` from `origin` at `offsets` (the scanned
    /// counts of [`BvhBuffers::cast`]), in batches of at most
    /// [`RAYS_PER_DISPATCH`] rays and [`HITS_PER_DISPATCH`] hits; returns
    /// the hits and the counts the walks found.
    pub fn hits(
        &self,
        gpu: &Gpu,
        origin: Vec3,
        dirs: &[[f32; 4]],
        offsets: &[u32],
    ) -> Result<(Vec<Hit>, Vec<u32>)> {
        let mut hits = Vec::with_capacity(offsets[dirs.len()] as usize);
        let mut counts = Vec::with_capacity(dirs.len());
        let mut start = 0;
        while start < dirs.len() {
            let mut end = start + 1;
            while end < dirs.len()
                && end - start < RAYS_PER_DISPATCH
                && (offsets[end + 1] - offsets[start]) as usize <= HITS_PER_DISPATCH
            {
                end += 1;
            }
            let batch =
                HitBuffers::upload(gpu, self, origin, &dirs[start..end], &offsets[start..=end])?;
            let mut encoder = gpu.encoder("ray_hits");
            batch.record(gpu, self, &mut encoder)?;
            gpu.submit_and_wait(encoder)?;
            let got = batch.hits.read(gpu)?;
            hits.extend_from_slice(&got[..(offsets[end] - offsets[start]) as usize]);
            counts.extend(batch.counts.read(gpu)?);
            start = end;
        }
        Ok((hits, counts))
    }
}

/// One batch of `ray_hits` on the device.
#[derive(Debug)]
pub struct HitBuffers {
    params: UniformBuffer<Params>,
    dirs: GpuArray<[f32; 4]>,
    offsets: GpuArray<u32>,
    /// Output hits (NaN / `u32::MAX` sentinels until written).
    pub hits: GpuArray<Hit>,
    /// Output counts (`u32::MAX` sentinels until written).
    pub counts: GpuArray<u32>,
    n_rays: u32,
}

impl HitBuffers {
    /// Uploads one batch: `dirs` (at most [`RAYS_PER_DISPATCH`]) with their
    /// `dirs.len() + 1` offsets, whose span is at most
    /// [`HITS_PER_DISPATCH`].
    pub fn upload(
        gpu: &Gpu,
        bvh: &BvhBuffers,
        origin: Vec3,
        dirs: &[[f32; 4]],
        offsets: &[u32],
    ) -> Result<Self> {
        if dirs.len() > RAYS_PER_DISPATCH {
            return Err(Error::limit(
                "ray_hits: rays per dispatch",
                dirs.len(),
                RAYS_PER_DISPATCH,
            ));
        }
        if offsets.len() != dirs.len() + 1 {
            return Err(Error::Internal(format!(
                "ray_hits: {} offsets for {} rays",
                offsets.len(),
                dirs.len()
            )));
        }
        let span = (offsets[dirs.len()] - offsets[0]) as usize;
        if span > HITS_PER_DISPATCH {
            return Err(Error::limit(
                "ray_hits: hits per dispatch",
                span,
                HITS_PER_DISPATCH,
            ));
        }
        let n_rays = dirs.len() as u32;
        let params = Params::new(n_rays, bvh, origin);
        let dirs: &[[f32; 4]] = if dirs.is_empty() { &[[0.0; 4]] } else { dirs };
        let sentinel = Hit {
            t: f32::NAN,
            tri: u32::MAX,
        };
        Ok(HitBuffers {
            params: UniformBuffer::new(gpu, "ray_hits.params", &params)?,
            dirs: GpuArray::from_slice(gpu, "ray_hits.dirs", dirs)?,
            offsets: GpuArray::from_slice(gpu, "ray_hits.offsets", offsets)?,
            hits: GpuArray::output(gpu, "ray_hits.hits", span.max(1), sentinel)?,
            counts: GpuArray::output(gpu, "ray_hits.counts", dirs.len(), u32::MAX)?,
            n_rays,
        })
    }

    /// Records the kernel into `encoder`.
    pub fn record(
        &self,
        gpu: &Gpu,
        bvh: &BvhBuffers,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<()> {
        gpu.kernel(Kernel::RayHits)?
            .uniform(&self.params)
            .read(&bvh.nodes)
            .read(&bvh.corners)
            .read(&self.dirs)
            .read(&self.offsets)
            .write(&self.hits)
            .write(&self.counts)
            .bind()?
            .record(gpu, encoder, self.n_rays, None);
        Ok(())
    }
}

/// One batch of rays on the device.
#[derive(Debug)]
pub struct RayBuffers {
    params: UniformBuffer<Params>,
    dirs: GpuArray<[f32; 4]>,
    /// Output hits (NaN / `u32::MAX` sentinels until written).
    pub hits: GpuArray<RayHit>,
    n_rays: u32,
}

impl RayBuffers {
    /// Uploads one batch (at most [`RAYS_PER_DISPATCH`] rays).
    pub fn upload(gpu: &Gpu, bvh: &BvhBuffers, origin: Vec3, dirs: &[[f32; 4]]) -> Result<Self> {
        if dirs.len() > RAYS_PER_DISPATCH {
            return Err(Error::limit(
                "ray_cast: rays per dispatch",
                dirs.len(),
                RAYS_PER_DISPATCH,
            ));
        }
        let n_rays = dirs.len() as u32;
        let params = Params::new(n_rays, bvh, origin);
        let sentinel = RayHit {
            near: f32::NAN,
            far: f32::NAN,
            near_tri: u32::MAX,
            far_tri: u32::MAX,
            count: u32::MAX,
        };
        let dirs: &[[f32; 4]] = if dirs.is_empty() { &[[0.0; 4]] } else { dirs };
        Ok(RayBuffers {
            params: UniformBuffer::new(gpu, "ray_cast.params", &params)?,
            dirs: GpuArray::from_slice(gpu, "ray_cast.dirs", dirs)?,
            hits: GpuArray::output(gpu, "ray_cast.hits", n_rays.max(1) as usize, sentinel)?,
            n_rays,
        })
    }

    /// Records the kernel into `encoder`.
    pub fn record(
        &self,
        gpu: &Gpu,
        bvh: &BvhBuffers,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<()> {
        gpu.kernel(Kernel::RayCast)?
            .uniform(&self.params)
            .read(&bvh.nodes)
            .read(&bvh.corners)
            .read(&self.dirs)
            .write(&self.hits)
            .bind()?
            .record(gpu, encoder, self.n_rays, None);
        Ok(())
    }
}
