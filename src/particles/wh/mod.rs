//! Witkin–Heckbert particles on a skeletal implicit surface (SPEC §3.2,
//! seed 002 eq. 3–11; WH94 for the adaptive radii, fission and death).
//!
//! One iteration: the host keeps the cell list ([`CellList`]), the kernel
//! `particle_update` moves every particle (repulsion, constraint velocity
//! with feedback, Euler step, σ adaptation), then the host applies
//! **fission and death** (WH94's rule, decided per particle from the step's
//! outputs; `docs/design/particles.md` §2):
//!
//! - near equilibrium: |Δp|/Δt < γ σ_i;
//! - fission: near equilibrium AND (σ_i > σ_max OR (D_i > ν Ê AND σ_i > σ̂)):
//!   a child at a tangent offset uniform in [−σ_i/2, σ_i/2]², both with σ_i/√2;
//! - death: near equilibrium AND σ_i < δ σ̂ AND u > σ_i/(δ σ̂), u uniform
//!   in [0, 1) from a hash of (seed, iteration, particle id);
//! - lost: |F − I|/|∇F| > 4 σ̂ after the step (a particle off the surface).
//!
//! Both backends decide from identical inputs with the same f32 rule; the
//! hash is exact, so runs are deterministic.

pub mod cpu;
pub mod gpu;

use glam::Vec3;

use super::StepOutput;
use super::cells::CellList;
use crate::gpu::Backend;
use crate::implicit::Pose;
use crate::implicit::field::FieldInput;
use crate::implicit::field::cpu::skeletal_field;
use crate::{Error, Result};

/// Uniform parameters of `particle_update`.
#[derive(Debug, Clone, Copy, PartialEq, encase::ShaderType)]
pub struct UpdateParams {
    /// Cell-list cells per axis.
    pub nx: u32,
    pub ny: u32,
    pub nz: u32,
    pub n_particles: u32,
    pub n_cells: u32,
    /// Relaxation step Δt.
    pub dt: f32,
    /// Scene-time advance δ of this iteration (0 while relaxing).
    pub delta: f32,
    /// Feedback κ = φΔt.
    pub kappa: f32,
    /// Repulsion amplitude α.
    pub alpha: f32,
    /// Desired energy Ê.
    pub e_hat: f32,
    /// σ feedback rate ρ_σ.
    pub rho_sigma: f32,
    /// σ denominator guard β_σ.
    pub beta_sigma: f32,
    /// σ bounds.
    pub sigma_lo: f32,
    pub sigma_hi: f32,
    /// Squared gradient guard g_min² of eq. 8.
    pub g_min2: f32,
    /// 1 to adapt σ, 0 to keep it.
    pub adapt: u32,
}

/// One step's inputs besides the field.
#[derive(Debug, Clone, Copy)]
pub struct StepInput<'a> {
    pub params: UpdateParams,
    /// [`CellList::flat`].
    pub cells: &'a [u32],
    /// (position, σ) per particle.
    pub positions: &'a [[f32; 4]],
}

/// One `particle_update` step on `backend`: new (position, σ) and
/// (D_i, |Δp|/Δt, (F − I)/|∇F|, |∇F|) per particle.
pub fn particle_update(
    field: &FieldInput,
    input: &StepInput<'_>,
    backend: Backend<'_>,
) -> Result<StepOutput> {
    match backend {
        Backend::Cpu => Ok(cpu::particle_update(field, input)),
        Backend::Gpu(g) => gpu::particle_update(g, field, input),
    }
}

/// Witkin–Heckbert constants (the `[particles]` table of a scene file).
/// Lengths are relative to σ̂ = edge length / 2.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct WhOptions {
    /// Repulsion amplitude α (WH94: 6).
    pub alpha: f64,
    /// Desired energy Ê as a fraction of α (WH94: 0.8).
    pub energy: f64,
    /// σ feedback rate ρ_σ (WH94: 15).
    pub rho_sigma: f64,
    /// Surface feedback κ = φΔt per iteration (0.5).
    pub kappa: f64,
    /// β_σ = beta·α/σ̂ (WH94's fixed 10 is not scale-free).
    pub beta: f64,
    /// Near-equilibrium speed γ (WH94: 4).
    pub gamma: f64,
    /// Fission energy fraction ν (WH94: 0.2).
    pub nu: f64,
    /// Death radius fraction δ (WH94: 0.7).
    pub death: f64,
    /// σ_max / σ̂ (1.5).
    pub sigma_max: f64,
    /// Upper clamp of σ / σ̂ (2).
    pub sigma_clamp: f64,
    /// Lower clamp of σ / σ̂ (0.1).
    pub sigma_floor: f64,
    /// αΔt (0.25: the tapered kernel is stiffer than the Gaussian; 0.4 oscillates).
    pub alpha_dt: f64,
    /// Cell-list skin / σ̂ (0.5).
    pub skin: f64,
    /// Seed of the fission offsets and death tests.
    pub seed: u64,
    /// Target spacing (edge length); `--edge-length` overrides it, and
    /// without either it is the surface's bounding-box diagonal / 64.
    pub edge_length: Option<f64>,
    /// Iterations that carry the particles from one frame's time to the
    /// next (scene time advancing by 1/transport of the gap each).
    pub transport: u32,
    /// Iterations at each frame's time after the transport.
    pub relax: u32,
    /// Most iterations of the first frame's relaxation.
    pub start_iterations: u32,
}

impl Default for WhOptions {
    fn default() -> Self {
        WhOptions {
            alpha: 6.0,
            energy: 0.8,
            rho_sigma: 15.0,
            kappa: 0.5,
            beta: 1.0,
            gamma: 4.0,
            nu: 0.2,
            death: 0.7,
            sigma_max: 1.5,
            sigma_clamp: 2.0,
            sigma_floor: 0.1,
            alpha_dt: 0.25,
            skin: 0.5,
            seed: 1,
            edge_length: None,
            transport: 4,
            relax: 8,
            start_iterations: 1000,
        }
    }
}

impl WhOptions {
    /// The `[particles]` table of a scene file (defaults when absent);
    /// errors name the file, line and key.
    pub fn from_scene(text: &str, origin: &str) -> Result<WhOptions> {
        let o: WhOptions = super::scene_table(text, origin, "particles")?;
        let positive = [
            ("alpha", o.alpha),
            ("energy", o.energy),
            ("rho_sigma", o.rho_sigma),
            ("kappa", o.kappa),
            ("beta", o.beta),
            ("gamma", o.gamma),
            ("nu", o.nu),
            ("death", o.death),
            ("sigma_max", o.sigma_max),
            ("sigma_clamp", o.sigma_clamp),
            ("sigma_floor", o.sigma_floor),
            ("alpha_dt", o.alpha_dt),
            ("skin", o.skin),
            ("edge_length", o.edge_length.unwrap_or(1.0)),
        ];
        super::check_positive(origin, "particles", &positive)?;
        Ok(o)
    }
}

/// Particles with persistent ids (fission appends, death removes).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Particles {
    /// (position, σ).
    pub points: Vec<[f32; 4]>,
    pub ids: Vec<u32>,
    next_id: u32,
}

impl Particles {
    /// Particles at `positions` with radius `sigma`, ids 0, 1, ….
    pub fn new(positions: &[Vec3], sigma: f32) -> Particles {
        Particles {
            points: positions.iter().map(|p| [p.x, p.y, p.z, sigma]).collect(),
            ids: (0..positions.len() as u32).collect(),
            next_id: positions.len() as u32,
        }
    }

    /// Particles of radius σ̂ at the vertices of a marching-cubes mesh of
    /// `pose` at lattice spacing 2.8 σ̂ (1.4 edge lengths: about as many
    /// vertices as an equilibrium packing has particles).
    pub fn on_surface(pose: &Pose, sigma_hat: f64, backend: Backend<'_>) -> Result<Particles> {
        let surface = crate::implicit::grid::marching_cubes(pose, 2.8 * sigma_hat, backend)?;
        Ok(Particles::new(&surface.mesh.positions, sigma_hat as f32))
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Positions as vectors.
    pub fn positions(&self) -> Vec<Vec3> {
        self.points
            .iter()
            .map(|p| Vec3::new(p[0], p[1], p[2]))
            .collect()
    }
}

/// What one iteration did.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Iteration {
    /// Max |F − I|/|∇F| before the step.
    pub residual: f32,
    /// Σ D_i (f64).
    pub energy: f64,
    pub fissions: u32,
    pub deaths: u32,
    /// Particles removed because they left the surface.
    pub lost: u32,
    /// Whether the cell list was rebuilt.
    pub rebuilt: bool,
}

/// The hexagonal equilibrium spacing x* (in units of σ) of the tapered
/// kernel: Σ over the lattice's rings within 3σ of exp(−x²/2)(1 − x²/9)²
/// equals Ê/α (bisection in f64). With the default Ê = 0.8α, x* ≈ 1.63.
pub fn equilibrium_spacing(energy: f64) -> f64 {
    let lattice_sum = |x: f64| {
        let mut d = 0.0;
        for a in -4i32..=4 {
            for b in -4i32..=4 {
                if (a, b) == (0, 0) {
                    continue;
                }
                // Hexagonal lattice of unit spacing: |a e1 + b e2|².
                let r2 = x * x * f64::from(a * a + a * b + b * b);
                let q = r2 / 9.0;
                if q < 1.0 {
                    d += (-r2 / 2.0).exp() * (1.0 - q) * (1.0 - q);
                }
            }
        }
        d
    };
    let (mut lo, mut hi) = (0.1, 3.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if lattice_sum(mid) > energy {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// σ̂ for a target spacing (edge length) `r`: radii settle between δσ̂
/// (death) and σ̂ (fission), so σ̂ = r / (x*·(1 + δ)/2).
pub fn sigma_for_spacing(r: f64, opts: &WhOptions) -> f64 {
    r / (equilibrium_spacing(opts.energy) * 0.5 * (1.0 + opts.death))
}

/// How a relaxation ended.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Relaxation {
    /// Iterations with fission and death (the population phase).
    pub adapt_iterations: u32,
    /// Iterations with σ and the population fixed (the settling phase).
    pub settle_iterations: u32,
    /// Whether the stopping rule held (else the iteration cap ended it).
    pub converged: bool,
    /// The last iteration.
    pub last: Iteration,
    /// Relative energy change of the last iteration.
    pub energy_change: f64,
    /// The residual bound used: 1e-4 of the particles' bounding-box diagonal.
    pub residual_bound: f32,
    /// Fissions, deaths and lost particles over all iterations.
    pub fissions: u32,
    pub deaths: u32,
    pub lost: u32,
}

/// A 32-bit mix of (seed, iteration, id): exact integer hashing (PCG-style
/// output permutation of a multiply-xorshift).
fn hash(seed: u64, iteration: u64, id: u32) -> u32 {
    let mut x = seed
        ^ iteration.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ u64::from(id).wrapping_mul(0xD1B5_4A32_D192_ED03);
    x ^= x >> 33;
    x = x.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    x ^= x >> 33;
    x = x.wrapping_mul(0xC4CE_B9FE_1A85_EC53);
    x ^= x >> 33;
    x as u32
}

/// Uniform [0, 1) from a hash (24 bits, exact in f32).
fn unit(h: u32) -> f32 {
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// A Witkin–Heckbert sampler on one scene: the particles, the cell list and
/// the constants resolved for σ̂.
#[derive(Debug)]
pub struct Sampler {
    pub particles: Particles,
    pub opts: WhOptions,
    /// Desired radius σ̂.
    pub sigma_hat: f32,
    /// Gradient guard g_min.
    pub g_min: f32,
    cells: Option<CellList>,
    iteration: u64,
}

impl Sampler {
    /// A sampler of `particles` with desired radius `sigma_hat`; g_min is
    /// 1e-3 of the median |∇F| at the particles in `field`.
    ///
    /// Errors: a non-positive σ̂, no particles.
    pub fn new(
        particles: Particles,
        sigma_hat: f64,
        opts: WhOptions,
        field: &FieldInput,
    ) -> Result<Sampler> {
        if !(sigma_hat.is_finite() && sigma_hat > 0.0) {
            return Err(Error::param(
                "sigma",
                sigma_hat,
                "must be positive and finite",
            ));
        }
        if particles.is_empty() {
            return Err(Error::empty("particles"));
        }
        let mut g: Vec<f32> = (particles.points.iter())
            .map(|p| {
                let (s, _) = skeletal_field(field, [p[0], p[1], p[2]]);
                (s.grad[0] * s.grad[0] + s.grad[1] * s.grad[1] + s.grad[2] * s.grad[2]).sqrt()
            })
            .collect();
        g.sort_by(f32::total_cmp);
        Ok(Sampler {
            particles,
            opts,
            sigma_hat: sigma_hat as f32,
            g_min: 1e-3 * g[g.len() / 2],
            cells: None,
            iteration: 0,
        })
    }

    /// Δt = αΔt / α.
    pub fn dt(&self) -> f32 {
        (self.opts.alpha_dt / self.opts.alpha) as f32
    }

    /// The kernel's parameters for the current particles and cell list.
    fn params(&self, cells: &CellList, delta: f32, adapt: bool) -> UpdateParams {
        let o = &self.opts;
        let sh = f64::from(self.sigma_hat);
        let dt = self.dt();
        UpdateParams {
            nx: cells.dims.x,
            ny: cells.dims.y,
            nz: cells.dims.z,
            n_particles: self.particles.len() as u32,
            n_cells: (cells.starts.len() - 1) as u32,
            dt,
            delta,
            kappa: o.kappa as f32,
            alpha: o.alpha as f32,
            e_hat: (o.energy * o.alpha) as f32,
            rho_sigma: o.rho_sigma as f32,
            beta_sigma: (o.beta * o.alpha / sh) as f32,
            sigma_lo: (o.sigma_floor * sh) as f32,
            sigma_hi: (o.sigma_clamp * sh) as f32,
            g_min2: self.g_min * self.g_min,
            adapt: u32::from(adapt),
        }
    }

    /// The current cell list, rebuilt when the particles moved too far or
    /// a cutoff 3σ outgrew it (`rebuilt` says so).
    fn refresh_cells(&mut self) -> Result<bool> {
        let pos = self.particles.positions();
        let cutoff = 3.0
            * self
                .particles
                .points
                .iter()
                .fold(0.0f32, |m, p| m.max(p[3]));
        let valid = (self.cells.as_ref()).is_some_and(|c| c.still_valid(&pos, cutoff));
        if !valid {
            let skin = (self.opts.skin as f32) * self.sigma_hat;
            // 10 % headroom so that slowly growing radii do not rebuild every step.
            let cells = CellList::build(&pos, 1.1 * cutoff, skin)?;
            // Particles in cell order: the gathers then read neighbours
            // that lie close in memory.
            let order = &cells.items;
            self.particles.points = order
                .iter()
                .map(|&i| self.particles.points[i as usize])
                .collect();
            self.particles.ids = order
                .iter()
                .map(|&i| self.particles.ids[i as usize])
                .collect();
            self.cells = Some(CellList::build(
                &self.particles.positions(),
                1.1 * cutoff,
                skin,
            )?);
        }
        Ok(!valid)
    }

    /// One iteration: step every particle (scene time advancing by `delta`
    /// under `field`, the pose at the iteration's start), then fission,
    /// death and the removal of lost particles when `adapt`.
    pub fn iterate(
        &mut self,
        field: &FieldInput,
        delta: f32,
        adapt: bool,
        backend: Backend<'_>,
    ) -> Result<Iteration> {
        let rebuilt = self.refresh_cells()?;
        let cells = self.cells.as_ref().expect("refreshed above");
        let flat = cells.flat();
        let params = self.params(cells, delta, adapt);
        let input = StepInput {
            params,
            cells: &flat,
            positions: &self.particles.points,
        };
        let (next, state) = particle_update(field, &input, backend)?;
        let mut it = Iteration {
            residual: state.iter().fold(0.0f32, |m, s| m.max(s[2].abs())),
            energy: state.iter().map(|s| f64::from(s[0])).sum(),
            rebuilt,
            ..Iteration::default()
        };
        self.particles.points = next;
        self.iteration += 1;
        if adapt {
            self.population(field, &state, &params, &mut it);
        }
        Ok(it)
    }

    /// Relaxes on a still field: first with σ adaptation, fission and
    /// death until the population changes by less than 0.1 % per iteration
    /// for 5 iterations, then with σ and the population fixed until
    /// max |F − I|/|∇F| ≤ 1e-4 of the bounding-box diagonal and the energy
    /// changes by ≤ 1e-6 (relative) in one step; at most `max_iter`
    /// iterations in all.
    pub fn relax(
        &mut self,
        field: &FieldInput,
        max_iter: u32,
        backend: Backend<'_>,
    ) -> Result<Relaxation> {
        let mut out = Relaxation {
            adapt_iterations: 0,
            settle_iterations: 0,
            converged: false,
            last: Iteration::default(),
            energy_change: f64::INFINITY,
            residual_bound: 0.0,
            fissions: 0,
            deaths: 0,
            lost: 0,
        };
        let mut calm = 0;
        while out.adapt_iterations < max_iter && calm < 5 {
            let n = self.particles.len();
            out.last = self.iterate(field, 0.0, true, backend)?;
            out.adapt_iterations += 1;
            out.fissions += out.last.fissions;
            out.deaths += out.last.deaths;
            out.lost += out.last.lost;
            let changed = (out.last.fissions + out.last.deaths + out.last.lost) as usize;
            calm = if changed * 1000 <= n { calm + 1 } else { 0 };
        }
        let mut energy = f64::NAN;
        while out.adapt_iterations + out.settle_iterations < max_iter {
            out.last = self.iterate(field, 0.0, false, backend)?;
            out.settle_iterations += 1;
            out.energy_change = ((out.last.energy - energy) / out.last.energy).abs();
            energy = out.last.energy;
            let pos = self.particles.positions();
            let lo = pos.iter().fold(Vec3::INFINITY, |m, p| m.min(*p));
            let hi = pos.iter().fold(Vec3::NEG_INFINITY, |m, p| m.max(*p));
            out.residual_bound = 1e-4 * (hi - lo).length();
            if out.last.residual <= out.residual_bound && out.energy_change <= 1e-6 {
                out.converged = true;
                break;
            }
        }
        Ok(out)
    }

    /// Fission, death and lost particles (module docs), in particle order.
    fn population(
        &mut self,
        field: &FieldInput,
        state: &[[f32; 4]],
        u: &UpdateParams,
        it: &mut Iteration,
    ) {
        let o = &self.opts;
        let sh = self.sigma_hat;
        let (gamma, nu, death) = (o.gamma as f32, o.nu as f32, o.death as f32);
        let sigma_max = (o.sigma_max as f32) * sh;
        let old = std::mem::take(&mut self.particles);
        let mut kept = Particles {
            points: Vec::with_capacity(old.len()),
            ids: Vec::with_capacity(old.len()),
            next_id: old.next_id,
        };
        let mut children = Vec::new();
        for (i, (&p, s)) in old.points.iter().zip(state).enumerate() {
            let id = old.ids[i];
            let sigma = p[3];
            if s[2].abs() > 4.0 * sh {
                it.lost += 1;
                continue;
            }
            let near = s[1] < gamma * sigma;
            if near
                && sigma < death * sh
                && unit(hash(o.seed, self.iteration, id)) > sigma / (death * sh)
            {
                it.deaths += 1;
                continue;
            }
            if near && (sigma > sigma_max || (s[0] > nu * u.e_hat && sigma > sh)) {
                it.fissions += 1;
                let half = sigma * std::f32::consts::FRAC_1_SQRT_2;
                let (f, _) = skeletal_field(field, [p[0], p[1], p[2]]);
                let n = Vec3::from_array(f.grad).normalize_or(Vec3::Z);
                let t1 = n.any_orthonormal_vector();
                let t2 = n.cross(t1);
                let h = hash(o.seed ^ 0x5EED, self.iteration, id);
                let (a, b) = (unit(h) - 0.5, unit(h.rotate_left(16) ^ 0x9E37_79B9) - 0.5);
                let c = Vec3::new(p[0], p[1], p[2]) + sigma * (a * t1 + b * t2);
                kept.points.push([p[0], p[1], p[2], half]);
                kept.ids.push(id);
                children.push([c.x, c.y, c.z, half]);
                continue;
            }
            kept.points.push(p);
            kept.ids.push(id);
        }
        for c in children {
            kept.points.push(c);
            kept.ids.push(kept.next_id);
            kept.next_id += 1;
        }
        self.particles = kept;
    }
}
