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

use std::time::Instant;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::chebyshev::{self, ChebyshevCoefficients, Spectrum};
use super::cpu::{self, StepParams};
use super::explicit;
use super::gpu::GpuStepper;
use super::network::SpringNetwork;
use super::plan::{Iterations, ResolvedPlan};
use crate::mesh::{ScalarField, TriMesh};
use crate::parity::Backend;
use crate::{Error, Result};

/// A window ends the relaxation as stalled only if max |v| stayed above
/// this fraction of its value at the window start.
pub const STALL_DECAY: f32 = 0.5;

/// Which iteration relaxes the network.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Solver {
    /// The seed's damped semi-implicit Euler (eq. 4.4–4.7): faithful dynamics.
    #[default]
    Explicit,
    /// Stationary Chebyshev acceleration of block-Jacobi relaxation: the same
    /// static equilibrium in far fewer passes (see `chebyshev.rs`).
    Chebyshev,
}

impl Solver {
    /// `explicit` or `chebyshev`.
    pub fn name(self) -> &'static str {
        match self {
            Solver::Explicit => "explicit",
            Solver::Chebyshev => "chebyshev",
        }
    }
}

impl std::str::FromStr for Solver {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "explicit" => Ok(Solver::Explicit),
            "chebyshev" => Ok(Solver::Chebyshev),
            _ => Err(Error::InvalidInput(format!(
                "unknown solver `{s}` (expected `explicit` or `chebyshev`)"
            ))),
        }
    }
}

/// Numerical options of a relaxation.
#[derive(Debug, Clone, PartialEq)]
pub struct RelaxOptions {
    /// Solver (default explicit).
    pub solver: Solver,
    /// Explicit Δt (also the Chebyshev pseudo-step h); `None` = 0.9 × the
    /// stability limit.
    pub dt: Option<f32>,
    /// Accept a Δt at or above the stability limit.
    pub force_dt: bool,
    /// ε: converged when max |v| < ε (mesh units per time unit);
    /// `None` = 1e-5 × the network's bounding-box diagonal.
    pub epsilon: Option<f32>,
    /// δ: stalled when positions moved less than δ over the window;
    /// `None` = 10 · ε · Δt (a tenth of what a steady drift at speed ε
    /// would cover in 100 iterations).
    pub delta: Option<f32>,
    /// Stall window in iterations (seed: 100).
    pub window: u32,
    /// Iteration cap of a `converge` increment.
    pub max_iterations: u32,
    /// K: iterations between convergence checks (GPU readbacks).
    pub check_every: u32,
    /// External forces f_i, one per free node (epidermis then subcutis);
    /// `None` = 0 (the seed's normal case).
    pub external_forces: Option<Vec<Vec3>>,
    /// The Chebyshev solver's spectral bounds of this network; `None` =
    /// estimated for this relaxation ([`chebyshev::estimate_spectrum`]).
    /// Callers that relax one network several times estimate once and pass
    /// it: the same coefficients every time, and the estimate paid once.
    pub spectrum: Option<Spectrum>,
}

impl Default for RelaxOptions {
    fn default() -> Self {
        RelaxOptions {
            solver: Solver::Explicit,
            dt: None,
            force_dt: false,
            epsilon: None,
            delta: None,
            window: 100,
            max_iterations: 100_000,
            check_every: 25,
            external_forces: None,
            spectrum: None,
        }
    }
}

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
    pub dt: f32,
    pub dt_limit: f32,
    pub epsilon: f32,
    pub delta: f32,
    pub check_every: u32,
    pub window: u32,
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

/// The result of one convergence probe: bit keys of max |v|² and of the
/// max squared window change (see `cpu::tissue_reduce_max`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Probe {
    pub keys: [u32; 2],
}

/// A solver state on one backend.
pub(crate) trait Stepper {
    /// Writes the bone layer (#bone `[x, y, z, _]`) into the state.
    fn set_bone(&mut self, bone: &[[f32; 4]]) -> Result<()>;
    /// Zeroes all velocities.
    fn reset_velocities(&mut self) -> Result<()>;
    /// Takes the stall-window snapshot of the current positions.
    fn snapshot(&mut self) -> Result<()>;
    /// Runs `n` iterations, then probes max |v|² and, with `window`, the
    /// max squared change since the snapshot and re-snapshots.
    fn advance(&mut self, n: u32, window: bool) -> Result<Probe>;
    /// All node positions.
    fn positions(&mut self) -> Result<Vec<[f32; 4]>>;
}

/// Everything both backends share: kernel parameters and initial state.
#[derive(Debug, Clone)]
pub(crate) struct Setup {
    pub solver: Solver,
    pub params: StepParams,
    /// Initial state: #nodes displacements from rest (zero) with the
    /// solver's w lane (the kernels' `pos_in`).
    pub positions: Vec<[f32; 4]>,
    /// #free external forces (zeros when unused).
    pub forces: Vec<[f32; 4]>,
    pub dt: f32,
    pub dt_limit: f32,
    pub epsilon: f32,
    pub delta: f32,
    pub runaway_speed: f32,
    pub chebyshev: Option<ChebyshevCoefficients>,
}

impl Setup {
    pub fn new(net: &SpringNetwork, opts: &RelaxOptions) -> Result<Setup> {
        if opts.check_every == 0 || opts.window == 0 || opts.max_iterations == 0 {
            return Err(Error::InvalidInput(
                "check_every, window and max_iterations must be ≥ 1".into(),
            ));
        }
        let dt_limit = explicit::stability_limit(net);
        let dt = explicit::choose_dt(net, opts.dt, opts.force_dt)?;
        let diag = net.diagonal().max(f32::MIN_POSITIVE);
        let epsilon = opts.epsilon.unwrap_or(1e-5 * diag);
        if !(epsilon.is_finite() && epsilon > 0.0) {
            return Err(Error::InvalidInput(format!(
                "ε must be finite and > 0, got {epsilon}"
            )));
        }
        let delta = opts.delta.unwrap_or(10.0 * epsilon * dt);
        if !(delta.is_finite() && delta >= 0.0) {
            return Err(Error::InvalidInput(format!(
                "δ must be finite and ≥ 0, got {delta}"
            )));
        }
        let n_free = u32::try_from(net.n_free)
            .map_err(|_| Error::InvalidInput("more than 2^32 free nodes".into()))?;
        let forces: Vec<[f32; 4]> = match &opts.external_forces {
            None => vec![[0.0; 4]; net.n_free],
            Some(f) if f.len() == net.n_free && f.iter().all(|v| v.is_finite()) => {
                f.iter().map(|v| [v.x, v.y, v.z, 0.0]).collect()
            }
            Some(f) => {
                return Err(Error::InvalidInput(format!(
                    "external forces: need {} finite vectors (one per free node), got {}",
                    net.n_free,
                    f.len()
                )));
            }
        };
        let materials = net.material_table();
        let mut positions = vec![[0.0f32; 4]; net.n_nodes()];
        let (params, chebyshev) = match opts.solver {
            Solver::Explicit => {
                let w = 1.0 / net.params.mass;
                for p in &mut positions[..net.n_free] {
                    p[3] = w;
                }
                (
                    StepParams {
                        n_free,
                        use_forces: opts.external_forces.is_some(),
                        dt,
                        damping: net.params.damping,
                        gain: 0.0,
                        isotropy: 0.0,
                        materials,
                    },
                    None,
                )
            }
            Solver::Chebyshev => {
                let spectrum = opts
                    .spectrum
                    .unwrap_or_else(|| chebyshev::estimate_spectrum(net));
                let coef = ChebyshevCoefficients::new(spectrum);
                (
                    StepParams {
                        n_free,
                        use_forces: opts.external_forces.is_some(),
                        dt,
                        damping: coef.momentum as f32,
                        gain: (coef.step / dt as f64) as f32,
                        isotropy: chebyshev::BLOCK_ISOTROPY,
                        materials,
                    },
                    Some(coef),
                )
            }
        };
        Ok(Setup {
            solver: opts.solver,
            params,
            positions,
            forces,
            dt,
            dt_limit,
            epsilon,
            delta,
            runaway_speed: 0.5 * diag / dt,
            chebyshev,
        })
    }
}

/// The CPU mirror as a [`Stepper`].
#[derive(Debug)]
pub(crate) struct CpuStepper<'a> {
    net: &'a SpringNetwork,
    gather: cpu::SpringGather<'a>,
    setup: Setup,
    pos: [Vec<[f32; 4]>; 2],
    cur: usize,
    vel: Vec<[f32; 4]>,
    snap: Vec<[f32; 4]>,
}

impl<'a> CpuStepper<'a> {
    pub fn new(net: &'a SpringNetwork, setup: Setup) -> Self {
        let pos = [setup.positions.clone(), setup.positions.clone()];
        CpuStepper {
            net,
            gather: cpu::SpringGather::best(&net.csr, net.n_free),
            vel: vec![[0.0; 4]; net.n_free],
            snap: setup.positions[..net.n_free].to_vec(),
            setup,
            pos,
            cur: 0,
        }
    }

    /// One iteration of the solver's mirror.
    pub fn iterate(&mut self) {
        let (a, b) = self.pos.split_at_mut(1);
        let (src, dst) = if self.cur == 0 {
            (&a[0], &mut b[0])
        } else {
            (&b[0], &mut a[0])
        };
        let kernel = match self.setup.solver {
            Solver::Explicit => cpu::SpringGather::spring_step,
            Solver::Chebyshev => cpu::SpringGather::spring_chebyshev,
        };
        kernel(
            &self.gather,
            &self.setup.params,
            &self.net.rest,
            &self.setup.forces,
            src,
            dst,
            &mut self.vel,
        );
        self.cur ^= 1;
    }
}

impl Stepper for CpuStepper<'_> {
    fn set_bone(&mut self, bone: &[[f32; 4]]) -> Result<()> {
        let u = bone_displacements(self.net, bone)?;
        let nf = self.net.n_free;
        for buf in &mut self.pos {
            buf[nf..].copy_from_slice(&u);
        }
        Ok(())
    }

    fn reset_velocities(&mut self) -> Result<()> {
        self.vel.fill([0.0; 4]);
        Ok(())
    }

    fn snapshot(&mut self) -> Result<()> {
        let nf = self.net.n_free;
        self.snap.copy_from_slice(&self.pos[self.cur][..nf]);
        Ok(())
    }

    fn advance(&mut self, n: u32, window: bool) -> Result<Probe> {
        // Iterate on a pool thread: each iteration's parallel loop is then
        // shared by work stealing among awake threads instead of waking the
        // pool and putting this thread to sleep once per iteration.
        rayon::scope(|_| {
            for _ in 0..n {
                self.iterate();
            }
        });
        let nf = self.net.n_free;
        let keys = cpu::tissue_reduce_max(nf, &self.vel, &self.pos[self.cur], &self.snap);
        if window {
            self.snapshot()?;
        }
        Ok(Probe { keys })
    }

    fn positions(&mut self) -> Result<Vec<[f32; 4]>> {
        Ok(absolute(self.net, &self.pos[self.cur]))
    }
}

/// The kernels' bone state: `u = target − x_rest` per bone node (#bone
/// `[ux, uy, uz, 0]`) for `bone` (#bone absolute targets).
pub(crate) fn bone_displacements(net: &SpringNetwork, bone: &[[f32; 4]]) -> Result<Vec<[f32; 4]>> {
    if bone.len() != net.n_bone() {
        return Err(Error::InvalidInput(format!(
            "{} bone positions for {} bone nodes",
            bone.len(),
            net.n_bone()
        )));
    }
    Ok(bone
        .iter()
        .zip(net.bone_rest())
        .map(|(b, r)| [b[0] - r[0], b[1] - r[1], b[2] - r[2], 0.0])
        .collect())
}

/// Absolute positions `x = x_rest + u` (w lane kept) of a kernel state.
pub(crate) fn absolute(net: &SpringNetwork, state: &[[f32; 4]]) -> Vec<[f32; 4]> {
    state
        .iter()
        .zip(&net.rest)
        .map(|(u, r)| [r[0] + u[0], r[1] + u[1], r[2] + u[2], u[3]])
        .collect()
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
        dt: setup.dt,
        dt_limit: setup.dt_limit,
        epsilon: setup.epsilon,
        delta: setup.delta,
        check_every: opts.check_every,
        window: opts.window,
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
        return Err(Error::InvalidInput(format!(
            "{} bone positions for {} bone nodes",
            bone.len(),
            network.n_bone()
        )));
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
