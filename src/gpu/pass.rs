//! The pass layer: every kernel is bound and dispatched here.
//!
//! ```text
//! gpu.kernel(Kernel::VertexNormals)?      pipeline with an explicit layout from its KernelSpec
//!     .uniform(&params)                   each binding checked against the spec's kind, in order
//!     .read(&positions) … .write(&normals)
//!     .bind()?                            one error scope around the bind group
//!     .record(&mut encoder, n, timer)     its own compute pass, labelled chisel.<kernel>
//! ```
//!
//! [`BoundKernel::dispatch`] records into a pass the caller holds, for
//! rooms that chain several dispatches in one pass (reductions, scans).

use std::sync::Arc;

use bytemuck::Pod;
use encase::{ShaderType, internal::WriteInto};

use super::spec::{BindKind, KernelSpec};
use super::{Gpu, GpuArray, Kernel, PassTimer, UniformBuffer};
use crate::error::{Error, Result};

/// A kernel's compiled pipeline and the bind-group layout built from its spec.
#[derive(Debug)]
pub(crate) struct Compiled {
    pub pipeline: wgpu::ComputePipeline,
    pub layout: wgpu::BindGroupLayout,
}

/// The bind-group layout entries of `spec` (compute stage, whole buffers).
pub(crate) fn layout_entries(spec: &KernelSpec) -> Vec<wgpu::BindGroupLayoutEntry> {
    (spec.bindings.iter().enumerate())
        .map(|(i, kind)| wgpu::BindGroupLayoutEntry {
            binding: i as u32,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: kind.binding_type(),
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        })
        .collect()
}

/// Bindings of one dispatch being gathered, checked one by one against the
/// kernel's spec ([`Gpu::kernel`]).
#[derive(Debug)]
pub struct Binder<'a> {
    gpu: &'a Gpu,
    spec: &'static KernelSpec,
    compiled: Arc<Compiled>,
    entries: Vec<wgpu::BindingResource<'a>>,
    /// The first binding that disagreed with the spec.
    mismatch: Option<String>,
}

impl<'a> Binder<'a> {
    pub(crate) fn new(gpu: &'a Gpu, spec: &'static KernelSpec, compiled: Arc<Compiled>) -> Self {
        Binder {
            gpu,
            spec,
            compiled,
            entries: Vec::with_capacity(spec.bindings.len()),
            mismatch: None,
        }
    }

    fn push(mut self, kind: BindKind, label: &str, resource: wgpu::BindingResource<'a>) -> Self {
        let i = self.entries.len();
        if self.mismatch.is_none() {
            match self.spec.bindings.get(i) {
                Some(&want) if want == kind => {}
                Some(want) => {
                    self.mismatch = Some(format!(
                        "binding {i} is {want:?} in the WGSL, bound as {kind:?} (`{label}`)"
                    ))
                }
                None => {
                    self.mismatch = Some(format!(
                        "the WGSL declares {} bindings, `{label}` would be binding {i}",
                        self.spec.bindings.len()
                    ))
                }
            }
        }
        self.entries.push(resource);
        self
    }

    /// The next binding: the kernel's uniform `Params`.
    pub fn uniform<T: ShaderType + WriteInto>(self, u: &'a UniformBuffer<T>) -> Self {
        self.push(BindKind::Uniform, u.label(), u.binding())
    }

    /// The next binding: a storage array the kernel only reads.
    pub fn read<T: Pod>(self, a: &'a GpuArray<T>) -> Self {
        self.push(BindKind::Read, a.label(), a.binding())
    }

    /// The next binding: a storage array the kernel writes.
    pub fn write<T: Pod>(self, a: &'a GpuArray<T>) -> Self {
        self.push(BindKind::ReadWrite, a.label(), a.binding())
    }

    /// The bind group, after checking that every declared binding was given
    /// with its kind (one error scope names the kernel on failure).
    pub fn bind(self) -> Result<BoundKernel> {
        let kernel = self.spec.kernel;
        let fail = |message: String| Error::Kernel {
            name: kernel.name().into(),
            message,
        };
        if let Some(m) = self.mismatch {
            return Err(fail(m));
        }
        if self.entries.len() != self.spec.bindings.len() {
            return Err(fail(format!(
                "{} of its {} bindings given",
                self.entries.len(),
                self.spec.bindings.len()
            )));
        }
        let label = kernel.label();
        let entries: Vec<wgpu::BindGroupEntry<'_>> = (self.entries.into_iter().enumerate())
            .map(|(i, resource)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource,
            })
            .collect();
        let bind_group = self.gpu.scoped(&label, || {
            (self.gpu.device).create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(&label),
                layout: &self.compiled.layout,
                entries: &entries,
            })
        })?;
        Ok(BoundKernel {
            kernel,
            wg_size: self.spec.wg_size,
            compiled: self.compiled,
            bind_group,
        })
    }
}

/// A kernel with its bindings, ready to be dispatched (any number of times).
#[derive(Debug)]
pub struct BoundKernel {
    kernel: Kernel,
    wg_size: u32,
    compiled: Arc<Compiled>,
    bind_group: wgpu::BindGroup,
}

impl BoundKernel {
    /// The kernel it dispatches.
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// Invocations per workgroup (`@workgroup_size` of the WGSL).
    pub fn wg_size(&self) -> u32 {
        self.wg_size
    }

    /// Records a dispatch of `n_invocations` into the open `pass` (nothing
    /// when zero; a 2-D grid past the per-dimension limit, see
    /// [`Gpu::workgroups`]).
    pub fn dispatch(&self, gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, n_invocations: u32) {
        if n_invocations == 0 {
            return;
        }
        let (x, y) = gpu.workgroups(n_invocations, self.wg_size);
        pass.set_pipeline(&self.compiled.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }

    /// Records the dispatch in a compute pass of its own, labelled
    /// `chisel.<kernel>`, with timestamps `timer`'s pair `at` when given.
    pub fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        n_invocations: u32,
        timer: Option<(&PassTimer, u32)>,
    ) {
        let label = self.kernel.label();
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&label),
            timestamp_writes: timer.map(|(t, at)| t.writes(at)),
        });
        self.dispatch(gpu, &mut pass, n_invocations);
    }
}
