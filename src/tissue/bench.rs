//! Measurements of `chisel bench relax` and `benches/relax.rs` (issue 3
//! §8): iteration rates of the step kernels resident on a backend with the
//! memory traffic they imply, and the time to equilibrium after one
//! surgery increment, per solver and backend.

use std::time::Instant;

use serde::Serialize;

use super::chebyshev::{self, Spectrum};
use super::cpu::fast::Lanes;
use super::network::SpringNetwork;
use super::plan::ResolvedPlan;
use super::relax::{Simulation, Status, relax};
use super::stepper::{RelaxOptions, Solver, bone_displacements};
use crate::Result;
use crate::gpu::Backend;

/// CPU seconds (user + system, all threads) this process has used, from
/// `/proc/self/stat` (clock ticks of 1/100 s); `None` off Linux. Next to a
/// wall-clock rate it tells how much of the machine the run really had.
pub fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = stat.rsplit_once(')')?.1;
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// The machine a measurement ran on, for reports.
#[derive(Debug, Clone, Serialize)]
pub struct Machine {
    /// `model name` of `/proc/cpuinfo` (`None` where unknown).
    pub cpu: Option<String>,
    /// Logical CPUs the OS reports.
    pub cpus: usize,
    /// Threads of the rayon pool the CPU mirrors run on.
    pub threads: usize,
    /// Nodes the CPU mirrors gather side by side ([`Lanes::best`]).
    pub cpu_lanes: Lanes,
    /// `/proc/loadavg`'s 1, 5 and 15 minute averages when the run started
    /// (a shared machine's figures are pessimistic when these exceed `cpus`).
    pub load_average: Option<[f64; 3]>,
}

impl Machine {
    /// This machine, now.
    pub fn now() -> Machine {
        let cpu = std::fs::read_to_string("/proc/cpuinfo").ok().and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, name)| name.trim().to_string())
        });
        let load_average = std::fs::read_to_string("/proc/loadavg").ok().and_then(|s| {
            let v: Vec<f64> = s
                .split_whitespace()
                .take(3)
                .filter_map(|x| x.parse().ok())
                .collect();
            <[f64; 3]>::try_from(v).ok()
        });
        Machine {
            cpu,
            cpus: std::thread::available_parallelism().map_or(1, |n| n.get()),
            threads: rayon::current_num_threads(),
            cpu_lanes: Lanes::best(),
            load_average,
        }
    }

    /// The load averages as `"1.47 1.40 1.36"`, or `unknown`.
    pub fn load_text(&self) -> String {
        self.load_average
            .map_or("unknown".into(), |l| format!("{} {} {}", l[0], l[1], l[2]))
    }
}

/// Iteration rate of one solver's step kernel on one backend.
#[derive(Debug, Clone, Serialize)]
pub struct Rate {
    pub solver: Solver,
    /// `cpu` or `gpu`.
    pub backend: &'static str,
    /// Timed iterations and their wall time (warm-up excluded).
    pub iterations: u64,
    pub seconds: f64,
    pub iterations_per_second: f64,
    /// Process CPU time per timed iteration, all threads (Linux only).
    pub cpu_seconds_per_iteration: Option<f64>,
    /// [`SpringNetwork::bytes_per_iteration`]: the compulsory traffic.
    pub bytes_per_iteration: u64,
    /// `iterations_per_second · bytes_per_iteration`, GB/s (10⁹ bytes).
    pub effective_gb_per_second: f64,
}

/// Iterations per second of `solver` resident on `backend`, the bone layer
/// at `bone` (#bone `[x, y, z, _]`, e.g. [`increment_bone`]): one untimed
/// warm-up batch, then batches of doubling size (from 8 iterations) until
/// at least `min_seconds` have been timed. Each batch ends with the
/// solver's convergence readback, as a relaxation's batches do.
/// `spectrum`: see [`RelaxOptions::spectrum`].
pub fn iteration_rate(
    net: &SpringNetwork,
    solver: Solver,
    backend: Backend<'_>,
    bone: &[[f32; 4]],
    min_seconds: f64,
    spectrum: Option<Spectrum>,
) -> Result<Rate> {
    let opts = RelaxOptions {
        solver,
        spectrum,
        ..RelaxOptions::default()
    };
    let mut sim = Simulation::new(net, &opts, backend)?;
    sim.set_bone(bone)?;
    sim.step(8)?;
    let (mut iterations, mut seconds, mut batch) = (0u64, 0.0f64, 8u32);
    let cpu0 = process_cpu_seconds();
    while seconds < min_seconds {
        let t = Instant::now();
        sim.step(batch)?;
        seconds += t.elapsed().as_secs_f64();
        iterations += u64::from(batch);
        batch = batch.saturating_mul(2).min(1 << 16);
    }
    let cpu = match (cpu0, process_cpu_seconds()) {
        (Some(a), Some(b)) => Some((b - a) / iterations as f64),
        _ => None,
    };
    let rate = iterations as f64 / seconds.max(1e-12);
    let bytes = net.bytes_per_iteration();
    Ok(Rate {
        solver,
        backend: backend.name(),
        iterations,
        seconds,
        iterations_per_second: rate,
        cpu_seconds_per_iteration: cpu,
        bytes_per_iteration: bytes,
        effective_gb_per_second: rate * bytes as f64 / 1e9,
    })
}

/// The bone layer's positions after `increment` (a one-step, one-increment
/// plan such as [`ResolvedPlan::first_increment`] gives): #bone
/// `[x, y, z, _]`.
pub fn increment_bone(net: &SpringNetwork, increment: &ResolvedPlan) -> Vec<[f32; 4]> {
    let mut bone = net.bone_rest().to_vec();
    for s in &increment.steps {
        for (&k, t) in s.bone_vertices.iter().zip(s.targets(s.increments)) {
            bone[k as usize] = t;
        }
    }
    bone
}

/// Writes `net` with the bone at `bone` (#bone `[x, y, z, _]`) into the
/// folder `dir` (created if missing) as little-endian raw arrays, for
/// timing other tools on the very network the rates are measured on
/// (`scripts/reference_spring_step.py`): `rest.f32` (#nodes × 4: x_rest,
/// the w lane 0), `displacement.f32` (#nodes × 4: u = 0 and w = 1/m for
/// the free nodes, the bone's u and w = 0 for the rest), `offsets.u32`
/// (#free + 1 CSR row starts), `entries.u32` (neighbour in bits 0–27,
/// material in bits 28–31), `materials.f32` (16 rows `[c1, c2 − c1,
/// knee, c_max]`) and `network.json` (counts, Δt, damping, mass, the file
/// list). Each file is written atomically.
pub fn export_network(dir: &std::path::Path, net: &SpringNetwork, bone: &[[f32; 4]]) -> Result<()> {
    use crate::foundation::fs::write_atomic;
    let u_bone = bone_displacements(net.bone_rest(), bone)?;
    std::fs::create_dir_all(dir).map_err(|e| crate::Error::io(dir, e))?;
    let w = 1.0 / net.params.mass;
    let mut u = vec![[0.0, 0.0, 0.0, w]; net.n_free];
    u.extend(u_bone);
    let materials = net.material_table();
    let le = |words: &[u32]| -> Vec<u8> { words.iter().flat_map(|w| w.to_le_bytes()).collect() };
    let f32s = |rows: &[[f32; 4]]| {
        le(&rows
            .iter()
            .flatten()
            .map(|x| x.to_bits())
            .collect::<Vec<_>>())
    };
    write_atomic(&dir.join("rest.f32"), &f32s(&net.rest))?;
    write_atomic(&dir.join("displacement.f32"), &f32s(&u))?;
    write_atomic(&dir.join("offsets.u32"), &le(&net.csr.offsets))?;
    write_atomic(&dir.join("entries.u32"), &le(&net.csr.entries))?;
    write_atomic(&dir.join("materials.f32"), &f32s(&materials))?;
    let header = serde_json::json!({
        "format": "chisel spring network, little-endian raw arrays",
        "nodes": net.n_nodes(),
        "free": net.n_free,
        "entries": net.csr.entries.len(),
        "dt": super::explicit::choose_dt(net, None, false).ok(),
        "damping": net.params.damping,
        "mass": net.params.mass,
        "bytes_per_iteration": net.bytes_per_iteration(),
        "files": {
            "rest.f32": "nodes x [x, y, z, 0]",
            "displacement.f32": "nodes x [ux, uy, uz, w]; w = 1/m on free nodes, 0 on bone",
            "offsets.u32": "free + 1 CSR row starts",
            "entries.u32": "neighbour (bits 0-27) | material (bits 28-31) << 28",
            "materials.f32": "16 x [c1, c2 - c1, knee, c_max]",
        },
    });
    let text = serde_json::to_string_pretty(&header)
        .map_err(|e| crate::Error::Internal(format!("network.json: {e}")))?;
    write_atomic(&dir.join("network.json"), text.as_bytes())
}

/// Largest distance between the xyz of two node lists.
fn max_distance(a: &[[f32; 4]], b: &[[f32; 4]]) -> f32 {
    let d = |p: &[f32; 4], q: &[f32; 4]| {
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
    };
    a.iter().zip(b).map(|(p, q)| d(p, q)).fold(0.0, f32::max)
}

/// One relaxation of a surgery increment to the solver's own stop test.
#[derive(Debug, Clone, Serialize)]
pub struct Settled {
    pub solver: Solver,
    pub backend: &'static str,
    pub status: Status,
    pub iterations: u64,
    /// Wall time of the relaxation (without the Chebyshev solver's
    /// one-time spectrum estimate, [`chebyshev::estimate_spectrum`], which
    /// is made before).
    pub seconds: f64,
    /// Largest distance of a free node from the first run's final state,
    /// in % of that run's largest free-node displacement.
    pub gap_percent: f64,
}

/// `spectrum`, or else [`chebyshev::estimate_spectrum`] of `net` when one
/// of `solvers` needs it (`None` when none does).
fn shared_spectrum(
    net: &SpringNetwork,
    spectrum: Option<Spectrum>,
    solvers: impl IntoIterator<Item = Solver>,
) -> Option<Spectrum> {
    spectrum.or_else(|| {
        (solvers.into_iter())
            .any(|s| s == Solver::Chebyshev)
            .then(|| chebyshev::estimate_spectrum(net))
    })
}

/// Relaxes `increment` to each solver's stop test, for each `(solver,
/// backend)` of `runs` in order; gaps are measured against the first run.
/// `each` sees every result as it comes. The Chebyshev runs share
/// `spectrum`, or one estimate made before the first run.
pub fn time_to_equilibrium(
    net: &SpringNetwork,
    increment: &ResolvedPlan,
    runs: &[(Solver, Backend<'_>)],
    max_iterations: u32,
    spectrum: Option<Spectrum>,
    mut each: impl FnMut(&Settled),
) -> Result<Vec<Settled>> {
    let free = net.n_free;
    let spectrum = shared_spectrum(net, spectrum, runs.iter().map(|r| r.0));
    let mut reference: Option<(Vec<[f32; 4]>, f32)> = None;
    let mut out = Vec::new();
    for &(solver, backend) in runs {
        let opts = RelaxOptions {
            solver,
            spectrum,
            max_iterations,
            ..RelaxOptions::default()
        };
        let r = relax(net, increment, &opts, backend)?;
        let (x_ref, scale) = reference.get_or_insert_with(|| {
            let scale = max_distance(&r.positions[..free], &net.rest[..free]);
            (r.positions[..free].to_vec(), scale)
        });
        let gap = max_distance(&r.positions[..free], x_ref);
        let settled = Settled {
            solver,
            backend: backend.name(),
            status: r.status,
            iterations: r.iterations,
            seconds: r.seconds,
            gap_percent: 100.0 * f64::from(gap) / f64::from(scale.max(f32::MIN_POSITIVE)),
        };
        each(&settled);
        out.push(settled);
    }
    Ok(out)
}

/// Iterations and time until every free node is within a share of the
/// largest displacement of the equilibrium itself.
#[derive(Debug, Clone, Serialize)]
pub struct Approach {
    pub solver: Solver,
    pub backend: &'static str,
    /// Whether the share was reached within the cap.
    pub reached: bool,
    /// Iterations run (checked every [`APPROACH_CHECK`]) and their wall
    /// time; the checks' readbacks are not timed.
    pub iterations: u32,
    pub seconds: f64,
    /// The last checked state's largest distance from the reference, in %
    /// of the reference's largest displacement.
    pub gap_percent: f64,
}

impl std::fmt::Display for Approach {
    /// `chebyshev cpu: reached after 400 iterations, 6.490 s`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:>9} {:>3}: {} after {} iterations, {:.3} s",
            self.solver.name(),
            self.backend,
            if self.reached {
                "reached"
            } else {
                "NOT reached"
            },
            self.iterations,
            self.seconds
        )
    }
}

/// The reference equilibrium and every run's approach to it.
#[derive(Debug, Clone, Serialize)]
pub struct Equilibrium {
    /// The reference: Chebyshev at ε = 10⁻⁷ × the network diagonal (on
    /// the CPU), its status, iterations and wall time.
    pub reference_status: Status,
    pub reference_iterations: u64,
    pub reference_seconds: f64,
    /// The reference's largest free-node displacement (mesh units).
    pub largest_displacement: f32,
    /// Share of `largest_displacement` counted as arrived (0.01 = 1 %).
    pub share: f32,
    pub runs: Vec<Approach>,
}

/// Iterations between two checks of [`approach_equilibrium`].
pub const APPROACH_CHECK: u32 = 50;

/// Time to equilibrium measured against the equilibrium itself, not
/// against each solver's stop test (which the explicit scheme passes while
/// still far away: its velocities are small long before its displacements
/// are right). A reference state from Chebyshev at ε = 10⁻⁷ · diagonal,
/// then for each `(solver, backend)` of `runs` the iterations and seconds
/// until every free node is within `share` of the reference's largest
/// displacement, or `cap` iterations. `each` sees every result as it comes.
/// The reference and the Chebyshev runs share `spectrum`, or one estimate
/// made before the reference.
pub fn approach_equilibrium(
    net: &SpringNetwork,
    increment: &ResolvedPlan,
    runs: &[(Solver, Backend<'_>)],
    share: f32,
    cap: u32,
    spectrum: Option<Spectrum>,
    mut each: impl FnMut(&Approach),
) -> Result<Equilibrium> {
    let free = net.n_free;
    let spectrum = shared_spectrum(net, spectrum, [Solver::Chebyshev]);
    let tight = RelaxOptions {
        solver: Solver::Chebyshev,
        spectrum,
        epsilon: Some(1e-7 * net.diagonal()),
        max_iterations: 40_000,
        ..RelaxOptions::default()
    };
    let reference = relax(net, increment, &tight, Backend::Cpu)?;
    let x_ref = &reference.positions[..free];
    let scale = max_distance(x_ref, &net.rest[..free]);
    let bone = increment_bone(net, increment);
    let mut out = Vec::new();
    for &(solver, backend) in runs {
        let opts = RelaxOptions {
            solver,
            spectrum,
            ..RelaxOptions::default()
        };
        let mut sim = Simulation::new(net, &opts, backend)?;
        sim.set_bone(&bone)?;
        let (mut iterations, mut seconds, mut gap) = (0u32, 0.0f64, f32::INFINITY);
        while iterations < cap && gap > share * scale {
            let t = Instant::now();
            sim.step(APPROACH_CHECK)?;
            seconds += t.elapsed().as_secs_f64();
            iterations += APPROACH_CHECK;
            gap = max_distance(&sim.positions()?[..free], x_ref);
        }
        let approach = Approach {
            solver,
            backend: backend.name(),
            reached: gap <= share * scale,
            iterations,
            seconds,
            gap_percent: 100.0 * f64::from(gap) / f64::from(scale.max(f32::MIN_POSITIVE)),
        };
        each(&approach);
        out.push(approach);
    }
    Ok(Equilibrium {
        reference_status: reference.status,
        reference_iterations: reference.iterations,
        reference_seconds: reference.seconds,
        largest_displacement: scale,
        share,
        runs: out,
    })
}
