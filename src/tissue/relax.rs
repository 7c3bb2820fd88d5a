//! The relaxation driver: applies a resolved plan increment by increment and
//! iterates a solver on the CPU mirror or the GPU until a stop criterion
//! (SPEC §1.2, seed §4.2).
//!
//! Stop criteria, checked every `check_every` (K) iterations on both
//! backends alike (so they stop at the same iteration):
//! - **converged**: max_i |v_i| < ε;
//! - **stalled**: over a window of at least `window` (100) iterations the
//!   positions changed by less than δ (max_i |x_i − x_i(window start)|)
//!   while some |v_i| ≥ ε — the seed's oscillation case — and max |v| did
//!   not fall below [`STALL_DECAY`] × its value at the window start (a
//!   state whose speed still decays is converging, however slowly its
//!   positions move: declaring it stalled would stop above the noise
//!   floor, as it did for the momentum solver on soft 10⁵-node networks);
//! - **diverged**: a non-finite speed, or runaway growth: max |v|·Δt above
//!   half the network's size (a node crossing half the model in one step;
//!   the seed reads divergence as tearing);
//! - **iteration limit**: `max_iterations` for `converge` increments, or the
//!   plan's fixed count.
//!
//! A diverged increment ends the plan (the later steps are not run).
//!
//! The driver only: the backends (`CpuStepper`,
//! [`super::gpu::GpuStepper`]) implement the `Stepper` trait of
//! [`super::stepper`].

use std::time::Instant;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::chebyshev::ChebyshevCoefficients;
use super::cpu_stepper::CpuStepper;
use super::gpu::GpuStepper;
use super::network::SpringNetwork;
use super::plan::{Iterations, ResolvedPlan};
use super::stepper::{RelaxOptions, Setup, Solver, Stepper};
use crate::gpu::Backend;
use crate::mesh::{ScalarField, TriMesh};
use crate::{Error, Result};

/// A window ends the relaxation as stalled only if max |v| stayed above
/// this fraction of its value at the window start.
pub const STALL_DECAY: f32 = 0.5;

/// How a relaxation (one increment) ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Converged,
    Stalled,
    Diverged,
    IterationLimit,
}

impl Status {
    /// The name used in reports (`converged`, `stalled`, `diverged`,
    /// `iteration_limit`).
    pub fn name(self) -> &'static str {
        match self {
            Status::Converged => "converged",
            Status::Stalled => "stalled",
            Status::Diverged => "diverged",
            Status::IterationLimit => "iteration_limit",
        }
    }
}

impl std::fmt::Display for Status {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One increment of one step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IncrementReport {
    /// 1-based increment number within its step.
    pub increment: u32,
    pub status: Status,
    pub iterations: u64,
    /// max_i |v_i| at the last check.
    pub max_speed: f32,
    /// max_i |x_i − x_i(window start)| of the last full stall window.
    pub window_change: Option<f32>,
    pub seconds: f64,
}

/// One plan step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepReport {
    pub name: String,
    /// Bone vertices moved.
    pub selected: usize,
    /// Status of the last increment run (diverged if any diverged).
    pub status: Status,
    pub iterations: u64,
    pub seconds: f64,
    pub increments: Vec<IncrementReport>,
}

/// Everything a relaxation produced. The per-vertex arrays are not
/// serialised (reports stay small); use [`RelaxReport::skin_mesh`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RelaxReport {
    pub plan: Option<String>,
    pub backend: &'static str,
    pub adapter: Option<String>,
    pub solver: Solver,
    pub nodes: usize,
    pub free_nodes: usize,
    pub springs: usize,
    /// The dynamics used (SPEC §1.3): node mass m, damping γ, Δt and its
    /// stability limit, ε, δ, check interval K, stall window, iteration cap.
    pub mass: f32,
    pub damping: f32,
    pub dt: f32,
    pub dt_limit: f32,
    pub epsilon: f32,
    pub delta: f32,
    pub check_every: u32,
    pub window: u32,
    pub max_iterations: u32,
    pub chebyshev: Option<ChebyshevCoefficients>,
    /// Overall: diverged if any increment diverged, else the last step's.
    pub status: Status,
    pub iterations: u64,
    pub seconds: f64,
    pub iterations_per_second: f64,
    /// max over epidermis vertices of |x − x_rest|.
    pub max_displacement: f32,
    pub steps: Vec<StepReport>,
    /// Relaxed epidermis positions (#surface vertices).
    #[serde(skip)]
    pub epidermis: Vec<Vec3>,
    /// |x − x_rest| per epidermis vertex.
    #[serde(skip)]
    pub displacement: Vec<f32>,
    /// All node positions `[x, y, z, w]` at the end (w: solver scaling).
    #[serde(skip)]
    pub positions: Vec<[f32; 4]>,
}

impl RelaxReport {
    /// The relaxed epidermis with a `displacement` scalar field.
    pub fn skin_mesh(&self, network: &SpringNetwork) -> TriMesh {
        TriMesh {
            positions: self.epidermis.clone(),
            triangles: network.surface_triangles.clone(),
            scalars: vec![ScalarField {
                name: "displacement".into(),
                values: self.displacement.clone(),
            }],
        }
    }
}

fn sqrt_key(key: u32) -> f32 {
    f32::from_bits(key).sqrt()
}

struct Outcome {
    status: Status,
    iterations: u64,
    max_speed: f32,
    window_change: Option<f32>,
}

fn run_increment(
    stepper: &mut dyn Stepper,
    setup: &Setup,
    opts: &RelaxOptions,
    iterations: Iterations,
) -> Result<Outcome> {
    let diverged = |speed: f32| !speed.is_finite() || speed > setup.runaway_speed;
    match iterations {
        Iterations::Fixed(n) => {
            let probe = stepper.advance(n, false)?;
            let speed = sqrt_key(probe.keys[0]);
            let status = if diverged(speed) {
                Status::Diverged
            } else if speed < setup.epsilon {
                Status::Converged
            } else {
                Status::IterationLimit
            };
            Ok(Outcome {
                status,
                iterations: n as u64,
                max_speed: speed,
                window_change: None,
            })
        }
        Iterations::Converge => {
            stepper.snapshot()?;
            let (mut it, mut since) = (0u32, 0u32);
            let mut window_change = None;
            // max |v| at the start of the current window (None: the first).
            let mut window_speed: Option<f32> = None;
            loop {
                let n = opts.check_every.min(opts.max_iterations - it);
                let window = it + n - since >= opts.window;
                let probe = stepper.advance(n, window)?;
                it += n;
                let speed = sqrt_key(probe.keys[0]);
                let mut still = false;
                if window {
                    let change = sqrt_key(probe.keys[1]);
                    window_change = Some(change);
                    since = it;
                    // Stalled only without progress: a converging state's
                    // speed falls geometrically, an oscillation's or a noise
                    // floor's does not.
                    still = change < setup.delta
                        && window_speed.is_none_or(|s0| speed > STALL_DECAY * s0);
                    window_speed = Some(speed);
                }
                let status = if diverged(speed) {
                    Some(Status::Diverged)
                } else if speed < setup.epsilon {
                    Some(Status::Converged)
                } else if still {
                    Some(Status::Stalled)
                } else if it >= opts.max_iterations {
                    Some(Status::IterationLimit)
                } else {
                    None
                };
                if let Some(status) = status {
                    return Ok(Outcome {
                        status,
                        iterations: it as u64,
                        max_speed: speed,
                        window_change,
                    });
                }
            }
        }
    }
}

/// A relaxation state resident on one backend, for callers that drive the
/// iterations themselves (interactive previews, benchmarks). On the GPU the
/// state stays on the device; only the convergence keys come back per
/// [`Simulation::step`].
pub struct Simulation<'a> {
    stepper: Box<dyn Stepper + 'a>,
    setup: Setup,
}

impl std::fmt::Debug for Simulation<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("solver", &self.setup.solver)
            .field("dt", &self.setup.dt)
            .finish_non_exhaustive()
    }
}

/// Convergence figures after [`Simulation::step`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StepProbe {
    /// max_i |v_i| over the free nodes.
    pub max_speed: f32,
    /// max_i |x_i − x_i(snapshot)| (the window change), then re-snapshotted.
    pub window_change: f32,
}

impl<'a> Simulation<'a> {
    /// The rest state of `network` with `opts`' solver on `backend`.
    pub fn new(
        network: &'a SpringNetwork,
        opts: &RelaxOptions,
        backend: Backend<'a>,
    ) -> Result<Self> {
        let setup = Setup::new(network, opts)?;
        let stepper: Box<dyn Stepper + 'a> = match backend {
            Backend::Cpu => Box::new(CpuStepper::new(network, setup.clone())),
            Backend::Gpu(gpu) => Box::new(GpuStepper::new(gpu, network, &setup)?),
        };
        Ok(Simulation { stepper, setup })
    }

    /// Δt (explicit) or h (Chebyshev) in use.
    pub fn dt(&self) -> f32 {
        self.setup.dt
    }

    /// Moves the bone layer to `bone` (#bone positions).
    pub fn set_bone(&mut self, bone: &[[f32; 4]]) -> Result<()> {
        self.stepper.set_bone(bone)
    }

    /// Zeroes the velocities.
    pub fn reset_velocities(&mut self) -> Result<()> {
        self.stepper.reset_velocities()
    }

    /// Runs `n` iterations (recorded into few submissions on the GPU) and
    /// probes the convergence figures.
    pub fn step(&mut self, n: u32) -> Result<StepProbe> {
        let probe = self.stepper.advance(n, true)?;
        Ok(StepProbe {
            max_speed: sqrt_key(probe.keys[0]),
            window_change: sqrt_key(probe.keys[1]),
        })
    }

    /// All node positions `[x, y, z, w]`.
    pub fn positions(&mut self) -> Result<Vec<[f32; 4]>> {
        self.stepper.positions()
    }

    /// On the GPU: the buffer holding every node's `x − x_rest` after the
    /// last [`Simulation::step`] (node order as the network's: the
    /// epidermis vertices first), for passes that read the state without a
    /// read-back (the smooth skin of `dms::LiveSkin`); `None` on the CPU.
    pub fn device_state(&self) -> Option<&crate::gpu::GpuArray<[f32; 4]>> {
        self.stepper.device_state()
    }
}

/// Relaxes `network` through `plan` on `backend`.
///
/// Each step's motion is applied in its k increments (bone targets computed
/// from the step's start, so no drift); after each increment the solver
/// iterates as the plan says. Velocities carry over between increments and
/// steps unless a step sets `reset_velocities`.
pub fn relax(
    network: &SpringNetwork,
    plan: &ResolvedPlan,
    opts: &RelaxOptions,
    backend: Backend<'_>,
) -> Result<RelaxReport> {
    let setup = Setup::new(network, opts)?;
    let mut stepper: Box<dyn Stepper + '_> = match backend {
        Backend::Cpu => Box::new(CpuStepper::new(network, setup.clone())),
        Backend::Gpu(gpu) => Box::new(GpuStepper::new(gpu, network, &setup)?),
    };
    let start = Instant::now();
    let mut bone: Vec<[f32; 4]> = network.bone_rest().to_vec();
    let mut steps = Vec::with_capacity(plan.steps.len());
    let mut total = 0u64;
    let mut any_diverged = false;
    'plan: for step in &plan.steps {
        let step_start = Instant::now();
        let mut report = StepReport {
            name: step.name.clone(),
            selected: step.bone_vertices.len(),
            status: Status::Converged,
            iterations: 0,
            seconds: 0.0,
            increments: Vec::with_capacity(step.increments as usize),
        };
        for j in 1..=step.increments {
            let inc_start = Instant::now();
            if step.reset_velocities {
                stepper.reset_velocities()?;
            }
            for (&k, t) in step.bone_vertices.iter().zip(step.targets(j)) {
                bone[k as usize] = t;
            }
            stepper.set_bone(&bone)?;
            let out = run_increment(stepper.as_mut(), &setup, opts, step.iterations)?;
            report.iterations += out.iterations;
            report.status = out.status;
            report.increments.push(IncrementReport {
                increment: j,
                status: out.status,
                iterations: out.iterations,
                max_speed: out.max_speed,
                window_change: out.window_change,
                seconds: inc_start.elapsed().as_secs_f64(),
            });
            if out.status == Status::Diverged {
                any_diverged = true;
                total += report.iterations;
                report.seconds = step_start.elapsed().as_secs_f64();
                steps.push(report);
                break 'plan;
            }
        }
        total += report.iterations;
        report.seconds = step_start.elapsed().as_secs_f64();
        steps.push(report);
    }
    let positions = stepper.positions()?;
    let seconds = start.elapsed().as_secs_f64();
    let n = network.n_surface;
    let epidermis: Vec<Vec3> = positions[..n]
        .iter()
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    let displacement: Vec<f32> = epidermis
        .iter()
        .zip(&network.rest[..n])
        .map(|(p, r)| p.distance(Vec3::new(r[0], r[1], r[2])))
        .collect();
    let status = if any_diverged {
        Status::Diverged
    } else {
        steps.last().map_or(Status::Converged, |s| s.status)
    };
    Ok(RelaxReport {
        plan: plan.name.clone(),
        backend: backend.name(),
        adapter: match backend {
            Backend::Cpu => None,
            Backend::Gpu(g) => Some(g.describe()),
        },
        solver: opts.solver,
        nodes: network.n_nodes(),
        free_nodes: network.n_free,
        springs: network.springs.len(),
        mass: network.params.mass,
        damping: network.params.damping,
        dt: setup.dt,
        dt_limit: setup.dt_limit,
        epsilon: setup.epsilon,
        delta: setup.delta,
        check_every: opts.check_every,
        window: opts.window,
        max_iterations: opts.max_iterations,
        chebyshev: setup.chebyshev,
        status,
        iterations: total,
        seconds,
        iterations_per_second: if seconds > 0.0 {
            total as f64 / seconds
        } else {
            0.0
        },
        max_displacement: displacement.iter().copied().fold(0.0, f32::max),
        steps,
        epidermis,
        displacement,
        positions,
    })
}

/// Runs exactly `iterations` iterations of `solver` from the rest state with
/// the bone moved to `bone` (#bone positions) and returns all positions:
/// the kernel-level entry the parity tests and benches use.
pub fn iterate(
    network: &SpringNetwork,
    bone: &[[f32; 4]],
    opts: &RelaxOptions,
    iterations: u32,
    backend: Backend<'_>,
) -> Result<Vec<[f32; 4]>> {
    if bone.len() != network.n_bone() {
        return Err(Error::mismatch(
            "bone positions (one per bone node)",
            network.n_bone(),
            bone.len(),
        ));
    }
    let setup = Setup::new(network, opts)?;
    let mut stepper: Box<dyn Stepper + '_> = match backend {
        Backend::Cpu => Box::new(CpuStepper::new(network, setup.clone())),
        Backend::Gpu(gpu) => Box::new(GpuStepper::new(gpu, network, &setup)?),
    };
    stepper.set_bone(bone)?;
    stepper.advance(iterations, false)?;
    stepper.positions()
}
