//! GPU passes of the tissue kernels: `spring_step` / `spring_chebyshev`
//! (one dispatch per iteration, double-buffered positions, many iterations
//! recorded per submission) and `tissue_reduce_max` (two-stage tree
//! reduction); [`spring_step`], [`spring_chebyshev`] and
//! [`tissue_reduce_max`] run one pass on explicit inputs for the parity
//! tests. Only the two convergence keys (8 bytes) are read back per
//! check; the state stays on the device until the end.

use bytemuck::Zeroable;
use glam::Vec4;

use super::cpu;
use super::network::{SpringCsr, SpringNetwork};
use super::stepper::{Probe, Setup, StepKernel, Stepper, absolute, bone_displacements};
use crate::gpu::{Binder, BoundKernel, Gpu, GpuArray, Kernel, Staged, UniformBuffer};
use crate::{Error, Result};

/// Workgroups of the first reduction stage (≤ `WG_SIZE` of
/// `tissue_reduce_max` so one workgroup finishes the second stage).
const REDUCE_GROUPS: u32 = 256;
/// Most iterations recorded into one command buffer.
const MAX_PER_SUBMIT: u32 = 512;

/// `Params` of `spring_step.wgsl` (`gain` and `isotropy` are not read).
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct SpringStepParams {
    pub n_free: u32,
    pub use_forces: u32,
    pub dt: f32,
    pub damping: f32,
    pub gain: f32,
    pub isotropy: f32,
}

/// `Params` of `spring_chebyshev.wgsl`.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct SpringChebyshevParams {
    pub n_free: u32,
    pub use_forces: u32,
    pub h: f32,
    pub momentum: f32,
    pub gain: f32,
    pub isotropy: f32,
}

/// `Materials` of the step kernels: one `(c1, c2 − c1, knee, c_max)` row per
/// material.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct Materials {
    pub rows: [Vec4; 16],
}

impl From<&cpu::SpringStepParams> for SpringStepParams {
    fn from(p: &cpu::SpringStepParams) -> Self {
        SpringStepParams {
            n_free: p.n_free,
            use_forces: u32::from(p.use_forces),
            dt: p.dt,
            damping: p.damping,
            gain: 0.0,
            isotropy: 0.0,
        }
    }
}

impl From<&cpu::SpringChebyshevParams> for SpringChebyshevParams {
    fn from(p: &cpu::SpringChebyshevParams) -> Self {
        SpringChebyshevParams {
            n_free: p.n_free,
            use_forces: u32::from(p.use_forces),
            h: p.h,
            momentum: p.momentum,
            gain: p.gain,
            isotropy: p.isotropy,
        }
    }
}

/// `Params` of `tissue_reduce_max.wgsl`.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct ReduceParams {
    pub n: u32,
    pub mode: u32,
}

/// The step kernel's `Params` uniform.
#[derive(Debug)]
enum StepUniform {
    SpringStep(UniformBuffer<SpringStepParams>),
    SpringChebyshev(UniformBuffer<SpringChebyshevParams>),
}

impl StepUniform {
    fn new(gpu: &Gpu, kernel: &StepKernel) -> Result<Self> {
        let label = format!("{}.params", kernel_of(kernel).name());
        Ok(match kernel {
            StepKernel::SpringStep(p) => {
                StepUniform::SpringStep(UniformBuffer::new(gpu, &label, &p.into())?)
            }
            StepKernel::SpringChebyshev(p) => {
                StepUniform::SpringChebyshev(UniformBuffer::new(gpu, &label, &p.into())?)
            }
        })
    }

    /// The next binding of `binder`: this uniform.
    fn bind_to<'a>(&'a self, binder: Binder<'a>) -> Binder<'a> {
        match self {
            StepUniform::SpringStep(u) => binder.uniform(u),
            StepUniform::SpringChebyshev(u) => binder.uniform(u),
        }
    }
}

fn kernel_of(kernel: &StepKernel) -> Kernel {
    match kernel {
        StepKernel::SpringStep(_) => Kernel::SpringStep,
        StepKernel::SpringChebyshev(_) => Kernel::SpringChebyshev,
    }
}

/// Buffers only the bind groups reference, kept alive with them.
#[derive(Debug)]
#[expect(dead_code, reason = "held for the bind groups, never read")]
struct KeepAlive {
    params: StepUniform,
    materials: UniformBuffer<Materials>,
    offsets: GpuArray<u32>,
    entries: GpuArray<u32>,
    rest: GpuArray<[f32; 4]>,
    forces: GpuArray<[f32; 4]>,
    partials: GpuArray<[u32; 2]>,
    reduce_params: [UniformBuffer<ReduceParams>; 2],
}

/// Free-node positions and velocities after one step.
pub type StepOutput = (Vec<[f32; 4]>, Vec<[f32; 4]>);

/// A relaxation state resident on the GPU.
#[derive(Debug)]
pub struct GpuStepper<'g> {
    gpu: &'g Gpu,
    kernel: Kernel,
    n_free: u32,
    n_reduce_groups: u32,
    pos: [GpuArray<[f32; 4]>; 2],
    vel: GpuArray<[f32; 4]>,
    snap: GpuArray<[f32; 4]>,
    result: GpuArray<[u32; 2]>,
    /// Reused read-back of `result`.
    staging: Staged<[u32; 2]>,
    /// `[0]`: pos[0] → pos[1]; `[1]`: pos[1] → pos[0].
    step_bind: [BoundKernel; 2],
    /// First reduction stage reading pos[cur].
    reduce_bind: [BoundKernel; 2],
    reduce_final: BoundKernel,
    cur: usize,
    /// Host copy of the rest positions (state ↔ absolute positions).
    rest: Vec<[f32; 4]>,
    // Kept alive for the bind groups.
    _buffers: KeepAlive,
}

impl<'g> GpuStepper<'g> {
    /// Uploads the network and initial state of `setup`. The second
    /// position buffer's free part starts as NaN sentinels: the first
    /// iteration must overwrite every free node.
    pub(crate) fn new(gpu: &'g Gpu, net: &SpringNetwork, setup: &Setup) -> Result<Self> {
        Self::from_parts(
            gpu,
            &setup.kernel,
            &net.csr,
            &net.rest,
            &setup.forces,
            &setup.positions,
            &vec![[0.0; 4]; net.n_free],
        )
    }

    fn from_parts(
        gpu: &'g Gpu,
        step: &StepKernel,
        csr: &SpringCsr,
        rest: &[[f32; 4]],
        forces: &[[f32; 4]],
        positions: &[[f32; 4]],
        velocities: &[[f32; 4]],
    ) -> Result<Self> {
        let kernel = kernel_of(step);
        let n_free = step.n_free();
        let nf = n_free as usize;
        for (what, expected, found) in [
            ("tissue GPU state: CSR offsets", nf + 1, csr.offsets.len()),
            ("tissue GPU state: velocities", nf, velocities.len()),
            ("tissue GPU state: forces", nf, forces.len()),
            (
                "tissue GPU state: rest positions",
                positions.len(),
                rest.len(),
            ),
            (
                "tissue GPU state: positions",
                nf.max(positions.len()),
                positions.len(),
            ),
        ] {
            if expected != found {
                return Err(Error::mismatch(what, expected, found));
            }
        }
        // Buffer labels name the kernel: `spring_step.rest`, `spring_chebyshev.rest`.
        let label = |buffer: &str| format!("{}.{buffer}", kernel.name());
        let uniform = StepUniform::new(gpu, step)?;
        let materials = UniformBuffer::new(
            gpu,
            &label("materials"),
            &Materials {
                rows: step.materials().map(Vec4::from_array),
            },
        )?;
        let offsets = GpuArray::from_slice(gpu, &label("offsets"), &csr.offsets)?;
        let entries = GpuArray::from_slice(gpu, &label("entries"), &csr.entries)?;
        let rest_buf = GpuArray::from_slice(gpu, &label("rest"), rest)?;
        let forces = GpuArray::from_slice(gpu, &label("forces"), forces)?;
        let mut second = positions.to_vec();
        second[..nf].fill([f32::NAN; 4]);
        let pos = [
            GpuArray::from_slice(gpu, &label("pos_a"), positions)?,
            GpuArray::from_slice(gpu, &label("pos_b"), &second)?,
        ];
        let vel = GpuArray::from_slice(gpu, &label("vel"), velocities)?;
        let snap = GpuArray::from_slice(gpu, "tissue_reduce_max.snap", &positions[..nf])?;
        let reduce_wg = Kernel::TissueReduceMax.spec()?.wg_size;
        let n_reduce_groups = n_free
            .div_ceil(reduce_wg)
            .clamp(1, REDUCE_GROUPS.min(reduce_wg));
        let partials =
            GpuArray::zeroed(gpu, "tissue_reduce_max.partials", n_reduce_groups as usize)?;
        let result = GpuArray::output(gpu, "tissue_reduce_max.result", 1, [u32::MAX; 2])?;
        let reduce_params = [
            UniformBuffer::new(
                gpu,
                "tissue_reduce_max.params0",
                &ReduceParams { n: n_free, mode: 0 },
            )?,
            UniformBuffer::new(
                gpu,
                "tissue_reduce_max.params1",
                &ReduceParams {
                    n: n_reduce_groups,
                    mode: 1,
                },
            )?,
        ];
        let staging = result.staging(gpu);
        let step_bind_for = |src: usize| {
            (uniform.bind_to(gpu.kernel(kernel)?))
                .uniform(&materials)
                .read(&offsets)
                .read(&entries)
                .read(&rest_buf)
                .read(&forces)
                .read(&pos[src])
                .write(&pos[1 - src])
                .write(&vel)
                .bind()
        };
        let step_bind = [step_bind_for(0)?, step_bind_for(1)?];
        let reduce_bind_for = |cur: usize| {
            (gpu.kernel(Kernel::TissueReduceMax)?)
                .uniform(&reduce_params[0])
                .read(&vel)
                .read(&pos[cur])
                .read(&snap)
                .read(&result)
                .write(&partials)
                .bind()
        };
        let reduce_bind = [reduce_bind_for(0)?, reduce_bind_for(1)?];
        let reduce_final = (gpu.kernel(Kernel::TissueReduceMax)?)
            .uniform(&reduce_params[1])
            .read(&vel)
            .read(&pos[0])
            .read(&snap)
            .read(&partials)
            .write(&result)
            .bind()?;
        Ok(GpuStepper {
            gpu,
            kernel,
            n_free,
            n_reduce_groups,
            pos,
            vel,
            snap,
            result,
            staging,
            step_bind,
            reduce_bind,
            reduce_final,
            cur: 0,
            rest: rest.to_vec(),
            _buffers: KeepAlive {
                params: uniform,
                materials,
                offsets,
                entries,
                rest: rest_buf,
                forces,
                partials,
                reduce_params,
            },
        })
    }

    fn record_steps(&mut self, encoder: &mut wgpu::CommandEncoder, n: u32) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.kernel.label()),
            timestamp_writes: None,
        });
        for _ in 0..n {
            self.step_bind[self.cur].dispatch(self.gpu, &mut pass, self.n_free);
            self.cur ^= 1;
        }
    }

    fn record_reduce(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("chisel.tissue_reduce_max"),
            timestamp_writes: None,
        });
        let first = &self.reduce_bind[self.cur];
        first.dispatch(self.gpu, &mut pass, self.n_reduce_groups * first.wg_size());
        let last = &self.reduce_final;
        last.dispatch(self.gpu, &mut pass, last.wg_size());
    }

    fn read_result(&self, mut encoder: wgpu::CommandEncoder) -> Result<[u32; 2]> {
        self.staging.copy_from(&mut encoder, &self.result);
        self.gpu.submit_and_wait(encoder)?;
        let keys = self.staging.finish(self.gpu)?;
        keys.first().copied().ok_or_else(|| Error::Readback {
            label: "chisel.tissue_reduce_max.result".into(),
            message: "empty readback".into(),
        })
    }

    fn copy_to_snapshot(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_buffer_to_buffer(
            &self.pos[self.cur].buffer,
            0,
            &self.snap.buffer,
            0,
            self.snap.byte_len(),
        );
    }
}

impl Stepper for GpuStepper<'_> {
    fn set_bone(&mut self, bone: &[[f32; 4]]) -> Result<()> {
        let bone_rest = &self.rest[(self.n_free as usize).min(self.rest.len())..];
        let data = bone_displacements(bone_rest, bone)?;
        if data.is_empty() {
            return Ok(());
        }
        let offset = self.n_free as u64 * 16;
        for p in &self.pos {
            if offset + data.len() as u64 * 16 > p.byte_len() {
                return Err(Error::mismatch(
                    "bone positions (one per bone node of the GPU state)",
                    ((p.byte_len() - offset) / 16) as usize,
                    data.len(),
                ));
            }
            self.gpu
                .queue
                .write_buffer(&p.buffer, offset, bytemuck::cast_slice(&data));
        }
        Ok(())
    }

    fn reset_velocities(&mut self) -> Result<()> {
        let mut encoder = self.gpu.encoder(&format!("{}.reset", self.kernel.name()));
        encoder.clear_buffer(&self.vel.buffer, 0, None);
        self.gpu.queue.submit([encoder.finish()]);
        Ok(())
    }

    fn snapshot(&mut self) -> Result<()> {
        let mut encoder = self.gpu.encoder("tissue_reduce_max.snapshot");
        self.copy_to_snapshot(&mut encoder);
        self.gpu.queue.submit([encoder.finish()]);
        Ok(())
    }

    fn advance(&mut self, n: u32, window: bool) -> Result<Probe> {
        let mut left = n;
        while left > MAX_PER_SUBMIT {
            let mut encoder = self.gpu.encoder(self.kernel.name());
            self.record_steps(&mut encoder, MAX_PER_SUBMIT);
            self.gpu.queue.submit([encoder.finish()]);
            left -= MAX_PER_SUBMIT;
        }
        let mut encoder = self.gpu.encoder(self.kernel.name());
        self.record_steps(&mut encoder, left);
        self.record_reduce(&mut encoder);
        if window {
            self.copy_to_snapshot(&mut encoder);
        }
        let keys = self.read_result(encoder)?;
        Ok(Probe { keys })
    }

    fn positions(&mut self) -> Result<Vec<[f32; 4]>> {
        let state = self.pos[self.cur].read(self.gpu)?;
        Ok(absolute(&self.rest, &state))
    }

    fn device_state(&self) -> Option<&GpuArray<[f32; 4]>> {
        Some(&self.pos[self.cur])
    }
}

/// One dispatch of `spring_step` on explicit inputs (the buffers of
/// [`cpu::spring_step`]; `pos_in` holds displacements from `rest`), for
/// parity tests: returns the free part of `pos_out` (NaN where the kernel
/// did not write) and the updated velocities.
pub fn spring_step(
    gpu: &Gpu,
    params: &cpu::SpringStepParams,
    csr: &SpringCsr,
    rest: &[[f32; 4]],
    forces: &[[f32; 4]],
    pos_in: &[[f32; 4]],
    vel: &[[f32; 4]],
) -> Result<StepOutput> {
    let step = StepKernel::SpringStep(*params);
    dispatch_once(gpu, &step, csr, rest, forces, pos_in, vel)
}

/// One dispatch of `spring_chebyshev` on explicit inputs (the buffers of
/// [`cpu::spring_chebyshev`]), as [`spring_step`].
pub fn spring_chebyshev(
    gpu: &Gpu,
    params: &cpu::SpringChebyshevParams,
    csr: &SpringCsr,
    rest: &[[f32; 4]],
    forces: &[[f32; 4]],
    pos_in: &[[f32; 4]],
    vel: &[[f32; 4]],
) -> Result<StepOutput> {
    let step = StepKernel::SpringChebyshev(*params);
    dispatch_once(gpu, &step, csr, rest, forces, pos_in, vel)
}

/// One dispatch of `step`'s kernel: free positions and velocities after it.
fn dispatch_once(
    gpu: &Gpu,
    step: &StepKernel,
    csr: &SpringCsr,
    rest: &[[f32; 4]],
    forces: &[[f32; 4]],
    pos_in: &[[f32; 4]],
    vel: &[[f32; 4]],
) -> Result<StepOutput> {
    let mut s = GpuStepper::from_parts(gpu, step, csr, rest, forces, pos_in, vel)?;
    let mut encoder = gpu.encoder(s.kernel.name());
    s.record_steps(&mut encoder, 1);
    gpu.submit_and_wait(encoder)?;
    let pos = s.pos[s.cur].read(gpu)?;
    Ok((pos[..s.n_free as usize].to_vec(), s.vel.read(gpu)?))
}

/// `tissue_reduce_max` on explicit inputs (#n each), for parity tests.
pub fn tissue_reduce_max(
    gpu: &Gpu,
    vel: &[[f32; 4]],
    pos: &[[f32; 4]],
    snapshot: &[[f32; 4]],
) -> Result<[u32; 2]> {
    let n = vel.len();
    if pos.len() != n || snapshot.len() != n {
        let found = if pos.len() != n {
            pos.len()
        } else {
            snapshot.len()
        };
        return Err(Error::mismatch(
            "tissue_reduce_max: pos and snapshot (one per velocity)",
            n,
            found,
        ));
    }
    let step = StepKernel::SpringStep(cpu::SpringStepParams {
        n_free: u32::try_from(n)
            .map_err(|_| Error::limit("tissue_reduce_max: nodes", n, u32::MAX))?,
        use_forces: false,
        dt: 0.0,
        damping: 0.0,
        materials: [[0.0; 4]; 16],
    });
    let csr = SpringCsr {
        offsets: vec![0; n + 1],
        entries: Vec::new(),
    };
    let s = GpuStepper::from_parts(
        gpu,
        &step,
        &csr,
        &vec![<[f32; 4]>::zeroed(); n],
        &vec![<[f32; 4]>::zeroed(); n],
        pos,
        vel,
    )?;
    s.snap.write(gpu, snapshot)?;
    let mut encoder = gpu.encoder("tissue_reduce_max");
    s.record_reduce(&mut encoder);
    s.read_result(encoder)
}
