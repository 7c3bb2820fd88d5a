//! GPU passes for `kernels/bounds_reduce.wgsl` and `kernels/range_reduce.wgsl`.
//!
//! [`ReduceBuffers`] holds one problem: the input (f32 bit patterns) and one
//! output buffer per pass, 2·ceil(n / BLOCK) keys each, down to a single
//! (min, max) pair. Every pass has its own uniform, so all passes record
//! into one command buffer.

use bytemuck::Pod;

use super::cpu::from_key;
use crate::gpu::{Gpu, GpuArray, Kernel, UniformBuffer, chunk_ranges};
use crate::{Error, Result};

/// Items one workgroup reduces to one pair (`BLOCK` in both kernels:
/// `WG_SIZE · ITEMS_PER_INVOCATION`).
pub const BLOCK: u32 = super::cpu::BLOCK as u32;

/// Uniform parameters of `bounds_reduce` and `range_reduce`.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct Params {
    /// Items this pass reduces.
    pub n_items: u32,
    /// 0: `src` holds raw f32 bit patterns; 1: (lo, hi) key pairs.
    pub pairs: u32,
}

/// One pass: its parameters and its 2·ceil(n_items / BLOCK) output keys.
#[derive(Debug)]
struct Pass<T: Pod> {
    params: UniformBuffer<Params>,
    n_items: u32,
    dst: GpuArray<T>,
}

/// Device buffers of one reduction, kept for resident reruns. `T` is the
/// key type: `[u32; 4]` for `bounds_reduce`, `u32` for `range_reduce`.
#[derive(Debug)]
pub struct ReduceBuffers<T: Pod> {
    kernel: Kernel,
    input: GpuArray<T>,
    passes: Vec<Pass<T>>,
}

/// Buffers of a `bounds_reduce` problem.
pub type BoundsBuffers = ReduceBuffers<[u32; 4]>;
/// Buffers of a `range_reduce` problem (one chunk).
pub type RangeBuffers = ReduceBuffers<u32>;

impl<T: Pod> ReduceBuffers<T> {
    /// Uploads `input` (bit patterns, ≥ 1 item, one storage binding) and
    /// allocates the passes; outputs are kernel outputs ([`GpuArray::output`]).
    fn upload(gpu: &Gpu, kernel: Kernel, input: &[T], sentinel: T) -> Result<Self> {
        let name = kernel.name();
        if input.is_empty() {
            return Err(Error::empty(format!("{name}: items")));
        }
        let n = u32::try_from(input.len())
            .map_err(|_| Error::limit(format!("{name}: items"), input.len(), u32::MAX))?;
        let input = GpuArray::from_slice(gpu, &format!("{name}.input"), input)?;
        let mut passes = Vec::new();
        let mut n_items = n;
        loop {
            let pairs = u32::from(!passes.is_empty());
            let n_out = n_items.div_ceil(BLOCK);
            passes.push(Pass {
                params: UniformBuffer::new(
                    gpu,
                    &format!("{name}.params{}", passes.len()),
                    &Params { n_items, pairs },
                )?,
                n_items,
                dst: GpuArray::output(
                    gpu,
                    &format!("{name}.pass{}", passes.len()),
                    2 * n_out as usize,
                    sentinel,
                )?,
            });
            if n_out == 1 {
                break;
            }
            n_items = n_out;
        }
        Ok(ReduceBuffers {
            kernel,
            input,
            passes,
        })
    }

    /// Number of passes (⌈log₄₀₉₆ n⌉, at least 1).
    pub fn n_passes(&self) -> usize {
        self.passes.len()
    }

    /// Records every pass into `encoder` (no submission).
    pub fn record(&self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        let mut binds = Vec::with_capacity(self.passes.len());
        let mut src = &self.input;
        for pass in &self.passes {
            let bound = (gpu.kernel(self.kernel)?)
                .uniform(&pass.params)
                .read(src)
                .write(&pass.dst)
                .bind()?;
            binds.push(bound);
            src = &pass.dst;
        }
        let mut cpass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.kernel.label()),
            timestamp_writes: None,
        });
        for (pass, bound) in self.passes.iter().zip(&binds) {
            let n_invocations = pass.n_items.div_ceil(BLOCK) * bound.wg_size();
            bound.dispatch(gpu, &mut cpass, n_invocations);
        }
        Ok(())
    }

    /// The output keys of every pass, first pass first (for parity tests of
    /// the individual dispatches).
    pub fn pass_outputs(&self, gpu: &Gpu) -> Result<Vec<Vec<T>>> {
        self.passes.iter().map(|p| p.dst.read(gpu)).collect()
    }

    /// Records, submits, waits and reads the final (min, max) keys.
    pub fn run(&self, gpu: &Gpu) -> Result<[T; 2]> {
        let mut encoder = gpu.encoder(self.kernel.name());
        self.record(gpu, &mut encoder)?;
        let last = self.passes.last().ok_or_else(|| Error::Kernel {
            name: self.kernel.name().into(),
            message: "no passes".into(),
        })?;
        let staged = last.dst.stage(gpu, &mut encoder)?;
        gpu.submit_and_wait(encoder)?;
        let keys = staged.finish(gpu)?;
        match keys[..] {
            [lo, hi] => Ok([lo, hi]),
            _ => Err(Error::Readback {
                label: self.kernel.label(),
                message: format!("expected 2 keys, got {}", keys.len()),
            }),
        }
    }
}

impl BoundsBuffers {
    /// Uploads #N ≥ 1 positions `[x, y, z, w]`.
    pub fn new(gpu: &Gpu, positions: &[[f32; 4]]) -> Result<Self> {
        Self::upload(
            gpu,
            Kernel::BoundsReduce,
            bytemuck::cast_slice(positions),
            [u32::MAX; 4],
        )
    }
}

impl RangeBuffers {
    /// Uploads #N ≥ 1 samples (at most one storage binding).
    pub fn new(gpu: &Gpu, samples: &[f32]) -> Result<Self> {
        Self::upload(
            gpu,
            Kernel::RangeReduce,
            bytemuck::cast_slice(samples),
            u32::MAX,
        )
    }
}

/// Component-wise (min, max) of `positions` (all four lanes): uploads,
/// dispatches every pass and reads one pair back, one chunk of at most one
/// storage binding at a time, chunk results combined on the host by key.
/// `None` when empty.
pub fn bounds_reduce(gpu: &Gpu, positions: &[[f32; 4]]) -> Result<Option<([f32; 4], [f32; 4])>> {
    let mut acc: Option<[[u32; 4]; 2]> = None;
    for chunk in chunk_ranges(positions.len(), 16, gpu.max_binding_bytes()) {
        let [lo, hi] = BoundsBuffers::new(gpu, &positions[chunk])?.run(gpu)?;
        acc = Some(match acc {
            None => [lo, hi],
            Some([a, b]) => [
                std::array::from_fn(|i| a[i].min(lo[i])),
                std::array::from_fn(|i| b[i].max(hi[i])),
            ],
        });
    }
    Ok(acc.map(|[lo, hi]| (lo.map(from_key), hi.map(from_key))))
}

/// (min, max) of `samples`, one chunk of at most one storage binding at a
/// time (`chunk_ranges` over `gpu.max_binding_bytes()`), chunk results
/// combined on the host by key. `None` when empty.
pub fn range_reduce(gpu: &Gpu, samples: &[f32]) -> Result<Option<(f32, f32)>> {
    let mut acc: Option<[u32; 2]> = None;
    for chunk in chunk_ranges(samples.len(), 4, gpu.max_binding_bytes()) {
        let [lo, hi] = RangeBuffers::new(gpu, &samples[chunk])?.run(gpu)?;
        acc = Some(match acc {
            None => [lo, hi],
            Some([a, b]) => [a.min(lo), b.max(hi)],
        });
    }
    Ok(acc.map(|[lo, hi]| (from_key(lo), from_key(hi))))
}
