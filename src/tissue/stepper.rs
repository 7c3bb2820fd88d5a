//! What the relaxation driver ([`super::relax()`]) asks of a backend: the
//! solver, the numerical options, the state both backends start from
//! (`Setup`), and the `Stepper` trait that the CPU mirror (`CpuStepper`)
//! and the GPU ([`super::gpu::GpuStepper`]) implement.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::chebyshev::{self, ChebyshevCoefficients, Spectrum};
use super::cpu::{SpringChebyshevParams, SpringStepParams};
use super::explicit;
use super::network::SpringNetwork;
use crate::{Error, Result};

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
            _ => Err(Error::unknown("solver", s, ["explicit", "chebyshev"])),
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
    /// The node states `x − x_rest` on the device, when the state lives
    /// there.
    fn device_state(&self) -> Option<&crate::gpu::GpuArray<[f32; 4]>> {
        None
    }
}

/// The kernel one iteration of a solver runs, with its parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum StepKernel {
    /// [`Solver::Explicit`]: `spring_step`.
    SpringStep(SpringStepParams),
    /// [`Solver::Chebyshev`]: `spring_chebyshev`.
    SpringChebyshev(SpringChebyshevParams),
}

impl StepKernel {
    /// The dispatch size.
    pub fn n_free(&self) -> u32 {
        match self {
            StepKernel::SpringStep(p) => p.n_free,
            StepKernel::SpringChebyshev(p) => p.n_free,
        }
    }

    /// The material table rows.
    pub fn materials(&self) -> &[[f32; 4]; 16] {
        match self {
            StepKernel::SpringStep(p) => &p.materials,
            StepKernel::SpringChebyshev(p) => &p.materials,
        }
    }
}

/// Everything both backends share: kernel parameters and initial state.
#[derive(Debug, Clone)]
pub(crate) struct Setup {
    pub solver: Solver,
    pub kernel: StepKernel,
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
        for (name, v) in [
            ("check_every", opts.check_every),
            ("window", opts.window),
            ("max_iterations", opts.max_iterations),
        ] {
            if v == 0 {
                return Err(Error::param(name, v, "must be ≥ 1"));
            }
        }
        let dt_limit = explicit::stability_limit(net);
        let dt = explicit::choose_dt(net, opts.dt, opts.force_dt)?;
        let diag = net.diagonal().max(f32::MIN_POSITIVE);
        let epsilon = opts.epsilon.unwrap_or(1e-5 * diag);
        if !(epsilon.is_finite() && epsilon > 0.0) {
            return Err(Error::param("epsilon", epsilon, "must be finite and > 0"));
        }
        let delta = opts.delta.unwrap_or(10.0 * epsilon * dt);
        if !(delta.is_finite() && delta >= 0.0) {
            return Err(Error::param("delta", delta, "must be finite and ≥ 0"));
        }
        let n_free = u32::try_from(net.n_free)
            .map_err(|_| Error::limit("free nodes", net.n_free, u32::MAX))?;
        let forces: Vec<[f32; 4]> = match &opts.external_forces {
            None => vec![[0.0; 4]; net.n_free],
            Some(f) if f.len() == net.n_free && f.iter().all(|v| v.is_finite()) => {
                f.iter().map(|v| [v.x, v.y, v.z, 0.0]).collect()
            }
            Some(f) if f.len() != net.n_free => {
                return Err(Error::mismatch(
                    "external forces (one per free node)",
                    net.n_free,
                    f.len(),
                ));
            }
            Some(f) => {
                let i = f.iter().position(|v| !v.is_finite()).unwrap_or(0);
                return Err(Error::data(
                    "external forces",
                    "free node",
                    i,
                    format!("force {} is not finite", f[i]),
                ));
            }
        };
        let materials = net.material_table();
        let mut positions = vec![[0.0f32; 4]; net.n_nodes()];
        let use_forces = opts.external_forces.is_some();
        let (kernel, chebyshev) = match opts.solver {
            Solver::Explicit => {
                let w = 1.0 / net.params.mass;
                for p in &mut positions[..net.n_free] {
                    p[3] = w;
                }
                (
                    StepKernel::SpringStep(SpringStepParams {
                        n_free,
                        use_forces,
                        dt,
                        damping: net.params.damping,
                        materials,
                    }),
                    None,
                )
            }
            Solver::Chebyshev => {
                let spectrum = opts
                    .spectrum
                    .unwrap_or_else(|| chebyshev::estimate_spectrum(net));
                let coef = ChebyshevCoefficients::new(spectrum);
                (
                    StepKernel::SpringChebyshev(SpringChebyshevParams {
                        n_free,
                        use_forces,
                        h: dt,
                        momentum: coef.momentum as f32,
                        gain: (coef.step / dt as f64) as f32,
                        isotropy: chebyshev::BLOCK_ISOTROPY,
                        materials,
                    }),
                    Some(coef),
                )
            }
        };
        Ok(Setup {
            solver: opts.solver,
            kernel,
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

/// The kernels' bone state: `u = target − x_rest` per bone node (#bone
/// `[ux, uy, uz, 0]`) for `bone` (#bone absolute targets) and the bone
/// layer at rest `bone_rest` ([`SpringNetwork::bone_rest`]).
pub(crate) fn bone_displacements(
    bone_rest: &[[f32; 4]],
    bone: &[[f32; 4]],
) -> Result<Vec<[f32; 4]>> {
    if bone.len() != bone_rest.len() {
        return Err(Error::mismatch(
            "bone positions (one per bone node)",
            bone_rest.len(),
            bone.len(),
        ));
    }
    Ok(bone
        .iter()
        .zip(bone_rest)
        .map(|(b, r)| [b[0] - r[0], b[1] - r[1], b[2] - r[2], 0.0])
        .collect())
}

/// Absolute positions `x = x_rest + u` (w lane kept) of a kernel state
/// over the rest positions `rest`.
pub(crate) fn absolute(rest: &[[f32; 4]], state: &[[f32; 4]]) -> Vec<[f32; 4]> {
    state
        .iter()
        .zip(rest)
        .map(|(u, r)| [r[0] + u[0], r[1] + u[1], r[2] + u[2], u[3]])
        .collect()
}
