//! GPU context: adapter choice, device, queue, kernel registry, typed buffers,
//! readback and timing (SPEC §0.3).
//!
//! One [`Gpu`] owns instance, adapter, device and queue. Adapter choice follows
//! [`AdapterChoice`] (env `CHISEL_ADAPTER`, CLI `--adapter`). Optional features
//! (`SHADER_INT64`, `TIMESTAMP_QUERY`, `SUBGROUP`) are requested when present
//! and reported in [`GpuFeatures`]; every kernel that can use them keeps a
//! portable path. Limits are raised to what the adapter allows. Device loss,
//! out-of-memory and validation failures come back as [`crate::Error`] values.

mod adapter;
mod backend;
mod buffer;
mod pass;
mod registry;
mod spec;
mod timing;

pub use adapter::{AdapterChoice, AdapterReport, Chosen, InfoReport, adapter_reports, info};
pub use backend::Backend;
pub use buffer::{GpuArray, Staged, UniformBuffer, chunk_ranges, row_chunks};
pub use pass::{Binder, BoundKernel};
pub use registry::{Kernel, Shader, preprocess};
pub use spec::{BindKind, KernelSpec};
pub use timing::{PassTimer, PassTimes};

use pass::Compiled;

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use crate::error::{Error, Result};

/// Optional adapter features the device was opened with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct GpuFeatures {
    /// `SHADER_INT64`: 64-bit integers in WGSL (exact hull predicates).
    pub int64: bool,
    /// `TIMESTAMP_QUERY`: kernel timing on the GPU clock.
    pub timestamps: bool,
    /// `SUBGROUP`: subgroup operations (never assumed by a kernel).
    pub subgroups: bool,
}

/// Options for opening a [`Gpu`].
#[derive(Debug, Clone, Default)]
pub struct GpuOptions {
    /// Which adapter to use; `None` reads `CHISEL_ADAPTER` (default `auto`).
    pub adapter: Option<AdapterChoice>,
    /// Cap on the bytes of one storage binding, below the adapter's own
    /// limit; lets tests exercise slab/chunk paths on small data.
    pub max_binding_bytes: Option<u64>,
    /// Open the device without optional features (tests the portable paths).
    pub portable: bool,
    /// Fill kernel outputs with sentinels (NaN, `u32::MAX`) before each
    /// dispatch and check after readback that none survived
    /// ([`GpuArray::output`]): tests and debugging (`CHISEL_GPU_SENTINELS=1`
    /// turns it on for any device). Off, outputs are cleared on the device.
    pub sentinels: bool,
}

/// Environment variable that turns output sentinels on ([`GpuOptions::sentinels`]).
pub const SENTINELS_ENV: &str = "CHISEL_GPU_SENTINELS";

/// The GPU context: instance, adapter, device, queue and cached pipelines.
#[derive(Debug)]
pub struct Gpu {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// What the adapter says about itself.
    pub info: wgpu::AdapterInfo,
    /// Optional features in use.
    pub features: GpuFeatures,
    max_binding_bytes: u64,
    sentinels: bool,
    /// Why the device was lost, once it was.
    lost: Arc<Mutex<Option<String>>>,
    /// The first error no error scope caught (an allocation out of memory,
    /// a validation error while recording), reported at the next check.
    uncaptured: Arc<Mutex<Option<Error>>>,
    pipelines: Mutex<HashMap<Kernel, Arc<Compiled>>>,
}

impl Gpu {
    /// Opens the adapter named by `CHISEL_ADAPTER` (default `auto`).
    pub fn new() -> Result<Self> {
        Self::with_options(GpuOptions::default())
    }

    /// Opens a device with explicit options.
    pub fn with_options(options: GpuOptions) -> Result<Self> {
        let choice = match options.adapter {
            Some(c) => c,
            None => AdapterChoice::from_env()?,
        };
        let instance = instance();
        let adapter = adapter::select(&instance, &choice)?;
        let info = adapter.get_info();
        let available = adapter.features();
        let mut wanted = wgpu::Features::empty();
        if !options.portable {
            wanted |= wgpu::Features::SHADER_INT64
                | wgpu::Features::TIMESTAMP_QUERY
                | wgpu::Features::SUBGROUP;
        }
        let required_features = available & wanted;
        let required_limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("chisel"),
            required_features,
            required_limits: required_limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| Error::RequestDevice {
            adapter: info.name.clone(),
            message: e.to_string(),
        })?;
        let lost = Arc::new(Mutex::new(None));
        let lost_cb = Arc::clone(&lost);
        device.set_device_lost_callback(move |reason, message| {
            if let Ok(mut slot) = lost_cb.lock() {
                *slot = Some(format!("{reason:?}: {message}"));
            }
        });
        let uncaptured = Arc::new(Mutex::new(None));
        let uncaptured_cb = Arc::clone(&uncaptured);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let error = match &e {
                wgpu::Error::OutOfMemory { .. } => Error::OutOfMemory {
                    label: "chisel".into(),
                    message: e.to_string(),
                },
                _ => Error::Validation {
                    label: "chisel".into(),
                    message: e.to_string(),
                },
            };
            if let Ok(mut slot) = uncaptured_cb.lock() {
                slot.get_or_insert(error);
            }
        }));
        let adapter_max = required_limits
            .max_storage_buffer_binding_size
            .min(required_limits.max_buffer_size);
        let max_binding_bytes = options
            .max_binding_bytes
            .map_or(adapter_max, |cap| cap.min(adapter_max))
            .max(256);
        let features = GpuFeatures {
            int64: required_features.contains(wgpu::Features::SHADER_INT64),
            timestamps: required_features.contains(wgpu::Features::TIMESTAMP_QUERY),
            subgroups: required_features.contains(wgpu::Features::SUBGROUP),
        };
        Ok(Gpu {
            instance,
            adapter,
            device,
            queue,
            info,
            features,
            max_binding_bytes,
            sentinels: options.sentinels
                || std::env::var(SENTINELS_ENV).is_ok_and(|v| v == "1" || v == "true"),
            lost,
            uncaptured,
            pipelines: Mutex::new(HashMap::new()),
        })
    }

    /// The same device seen with other options, without opening a second
    /// one: bindings capped at `max_binding_bytes` (below this device's
    /// cap), and with `portable` the optional features hidden, so kernels
    /// take their portable variants. Tests of the chunked, slabbed and
    /// fallback paths use it, keeping one device per process. Pipelines are
    /// cached per view.
    pub fn view(&self, max_binding_bytes: Option<u64>, portable: bool) -> Gpu {
        Gpu {
            instance: self.instance.clone(),
            adapter: self.adapter.clone(),
            device: self.device.clone(),
            queue: self.queue.clone(),
            info: self.info.clone(),
            features: if portable {
                GpuFeatures {
                    int64: false,
                    timestamps: false,
                    subgroups: false,
                }
            } else {
                self.features
            },
            max_binding_bytes: max_binding_bytes
                .map_or(self.max_binding_bytes, |cap| {
                    cap.min(self.max_binding_bytes)
                })
                .max(256),
            sentinels: self.sentinels,
            lost: Arc::clone(&self.lost),
            uncaptured: Arc::clone(&self.uncaptured),
            pipelines: Mutex::new(HashMap::new()),
        }
    }

    /// Whether the adapter is a software rasteriser on the CPU (lavapipe):
    /// correctly rounded division, no fused multiply-adds, slow kernels.
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// One line naming the adapter: `name (backend, type, driver)`.
    pub fn describe(&self) -> String {
        adapter::describe(&self.info)
    }

    /// Largest number of bytes one storage binding may hold on this device
    /// (after any [`GpuOptions::max_binding_bytes`] cap).
    pub fn max_binding_bytes(&self) -> u64 {
        self.max_binding_bytes
    }

    /// Largest number of `T` elements that fit one storage binding.
    pub fn max_binding_len<T>(&self) -> usize {
        let size = std::mem::size_of::<T>().max(1) as u64;
        usize::try_from(self.max_binding_bytes / size).unwrap_or(usize::MAX)
    }

    /// Whether kernel outputs start as sentinels ([`GpuOptions::sentinels`]).
    pub fn sentinels(&self) -> bool {
        self.sentinels
    }

    /// Fails with [`Error::DeviceLost`] if the device-lost callback fired,
    /// or with the first error no error scope caught (taken, so it is
    /// reported once).
    pub fn check_errors(&self) -> Result<()> {
        if let Some(msg) = self.lost.lock().ok().and_then(|s| s.clone()) {
            return Err(Error::DeviceLost(msg));
        }
        match self.uncaptured.lock().ok().and_then(|mut s| s.take()) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// The pass builder of `kernel` ([`Binder`]): its pipeline, built once
    /// with the bind-group layout its WGSL declares ([`Kernel::spec`]) and
    /// cached for the life of the device.
    pub fn kernel(&self, kernel: Kernel) -> Result<Binder<'_>> {
        let spec = kernel.spec()?;
        let cached = (self.pipelines.lock().ok()).and_then(|m| m.get(&kernel).cloned());
        let compiled = match cached {
            Some(c) => c,
            None => {
                let c = Arc::new(self.compile(kernel, spec)?);
                if let Ok(mut m) = self.pipelines.lock() {
                    m.insert(kernel, Arc::clone(&c));
                }
                c
            }
        };
        Ok(Binder::new(self, spec, compiled))
    }

    /// Compiles `kernel` inside validation and out-of-memory error scopes.
    fn compile(&self, kernel: Kernel, spec: &KernelSpec) -> Result<Compiled> {
        self.check_errors()?;
        let fail = |message: String| Error::Kernel {
            name: kernel.name().into(),
            message,
        };
        if !self.device.features().contains(kernel.requires()) {
            return Err(fail(format!(
                "needs device features {:?}, which this adapter lacks",
                kernel.requires()
            )));
        }
        let source = preprocess(kernel.source()).map_err(fail)?;
        let label = kernel.label();
        self.scoped(&label, || {
            let module = (self.device).create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(&label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
            let layout = (self.device).create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(&label),
                entries: &pass::layout_entries(spec),
            });
            let pipeline_layout =
                (self.device).create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(&label),
                    bind_group_layouts: &[Some(&layout)],
                    immediate_size: 0,
                });
            let pipeline =
                (self.device).create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(&label),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some("main"),
                    compilation_options: Default::default(),
                    cache: None,
                });
            Compiled { pipeline, layout }
        })
        .map_err(|e| match e {
            Error::Validation { message, .. } => fail(message),
            other => other,
        })
    }

    /// Runs `f` inside validation + out-of-memory error scopes and turns a
    /// captured error into [`Error::Validation`] / [`Error::OutOfMemory`].
    pub fn scoped<T>(&self, label: &str, f: impl FnOnce() -> T) -> Result<T> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = f();
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        self.check_errors()?;
        if let Some(e) = o {
            return Err(Error::OutOfMemory {
                label: label.into(),
                message: e.to_string(),
            });
        }
        if let Some(e) = v {
            return Err(Error::Validation {
                label: label.into(),
                message: e.to_string(),
            });
        }
        Ok(out)
    }

    /// Workgroup counts `(x, y)` covering `n_invocations` at `wg_size` per
    /// group, going 2-D past `max_compute_workgroups_per_dimension`. Kernels
    /// recover the linear index as `gid.x + gid.y * nwg.x * WG_SIZE`.
    pub fn workgroups(&self, n_invocations: u32, wg_size: u32) -> (u32, u32) {
        let groups = n_invocations.div_ceil(wg_size);
        let max = self
            .device
            .limits()
            .max_compute_workgroups_per_dimension
            .max(1);
        if groups <= max {
            (groups, 1)
        } else {
            let y = groups.div_ceil(max);
            (groups.div_ceil(y), y)
        }
    }

    /// Submits `encoder` and waits for the queue to drain.
    pub fn submit_and_wait(&self, encoder: wgpu::CommandEncoder) -> Result<()> {
        let index = self.queue.submit([encoder.finish()]);
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map_err(|e| Error::DeviceLost(e.to_string()))?;
        self.check_errors()
    }

    /// A fresh command encoder labelled `chisel.<label>`.
    pub fn encoder(&self, label: &str) -> wgpu::CommandEncoder {
        self.device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some(&format!("chisel.{label}")),
            })
    }
}

/// The adapter `choice` names, without opening a device: its one-line
/// description and whether it is a software rasteriser (lavapipe).
pub fn probe_adapter(choice: &AdapterChoice) -> Result<(String, bool)> {
    let info = adapter::select(&instance(), choice)?.get_info();
    Ok((
        adapter::describe(&info),
        info.device_type == wgpu::DeviceType::Cpu,
    ))
}

/// A wgpu instance over the primary backends (Vulkan, Metal, DX12); the GL
/// backend only when `WGPU_BACKEND` asks for it (its probing is slow and noisy
/// on headless machines, and it duplicates Vulkan adapters with fewer features).
pub fn instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    if std::env::var_os("WGPU_BACKEND").is_none() {
        desc.backends = wgpu::Backends::PRIMARY;
    }
    wgpu::Instance::new(desc)
}

/// The GPU in tests: the adapter from `CHISEL_ADAPTER`, or `None` with a note
/// on stderr when none exists. With `CI=true` a missing adapter is an error.
/// Its outputs start as sentinels ([`GpuOptions::sentinels`]).
pub fn gpu_for_tests() -> Result<Option<Gpu>> {
    let options = GpuOptions {
        sentinels: true,
        ..GpuOptions::default()
    };
    match Gpu::with_options(options) {
        Ok(g) => Ok(Some(g)),
        Err(e @ Error::NoAdapter { .. }) => {
            if std::env::var("CI").is_ok_and(|v| v == "true" || v == "1") {
                Err(e)
            } else {
                eprintln!("skipping GPU part: {e}");
                Ok(None)
            }
        }
        Err(e) => Err(e),
    }
}
