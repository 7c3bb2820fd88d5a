//! `chisel bench relax MESH`: iterations per second of the tissue step
//! kernels on the CPU mirror and the GPU in the same run, the bytes one
//! iteration must move and the effective bandwidth, and the time to
//! equilibrium after one surgery increment per solver (issue 3 §8; the
//! criterion bench `benches/relax.rs` measures the same on fran_cut).

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::report::{Report, ReportArgs, Show};
use super::{Global, vec3_arg};
use crate::gpu::Backend;
use crate::tissue::bench::{
    Equilibrium, Machine, Rate, Settled, approach_equilibrium, export_network, increment_bone,
    iteration_rate, time_to_equilibrium,
};
use crate::tissue::chebyshev::{Spectrum, estimate_spectrum};
use crate::tissue::phantom::refine_grid;
use crate::tissue::{Fragments, NetworkParams, Plan, ResolvedPlan, Solver, SpringNetwork};

/// The report of `chisel bench relax`.
#[derive(Debug, Serialize)]
pub struct BenchRelaxReport<'a> {
    command: &'static str,
    mesh: &'a Path,
    bone_mesh: Option<&'a Path>,
    grid: Option<[usize; 2]>,
    plan: Option<&'a Path>,
    scale_increment: bool,
    machine: Machine,
    adapter: Option<String>,
    networks: Vec<NetworkRun>,
}

impl Report for BenchRelaxReport<'_> {
    const SCHEMA: &'static str = "chisel.bench-relax/1";
}

/// One refinement of the network and what was measured on it.
#[derive(Debug, Serialize)]
struct NetworkRun {
    refine: usize,
    nodes: usize,
    free_nodes: usize,
    csr_entries: usize,
    springs: usize,
    build_seconds: f64,
    spectrum: Option<Spectrum>,
    spectrum_seconds: Option<f64>,
    bytes_per_iteration: u64,
    rates: Vec<Rate>,
    /// With `--plan`: each run's time to equilibrium after one increment.
    time_to_equilibrium: Option<Vec<Settled>>,
    /// With `--approach`: iterations to within 1 % of equilibrium.
    approach: Option<Equilibrium>,
}

/// Arguments of `chisel bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    what: What,
}

#[derive(Debug, clap::Subcommand)]
enum What {
    /// Tissue relaxation: step kernel rates (CPU and GPU, same run), memory
    /// traffic, time to equilibrium after one surgery increment.
    Relax(RelaxArgs),
}

/// Which backends a benchmark runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Backends {
    Cpu,
    Gpu,
    Both,
}

/// Arguments of `chisel bench relax`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct RelaxArgs {
    /// Epidermis mesh (any format `chisel stats` reads).
    mesh: PathBuf,
    /// Bone mesh (default: the skin scaled by 0.7 about the origin).
    #[arg(long)]
    bone_mesh: Option<PathBuf>,
    /// Origin O of the layer construction `x,y,z` (default: SPEC §1.1 rule).
    #[arg(long, value_delimiter = ',')]
    origin: Option<Vec<f32>>,
    /// The mesh is a structured scan grid of `COLS,ROWS` vertices (vertex i
    /// at column i / ROWS, row i % ROWS; fran_cut.vtk: 45,49), which
    /// `--refine` subdivides.
    #[arg(long, value_delimiter = ',')]
    grid: Option<Vec<usize>>,
    /// Refinement factors of the grid, one network each (fran_cut: 1,8,13
    /// give 6.6k, 408k and 1.07M nodes); needs `--grid` unless just 1.
    #[arg(long, value_delimiter = ',', default_value = "1")]
    refine: Vec<usize>,
    /// Solvers whose step kernel is timed (and relaxed with `--plan`).
    #[arg(long, value_delimiter = ',', default_value = "explicit,chebyshev")]
    solver: Vec<Solver>,
    /// Where the kernels run.
    #[arg(long, value_enum, default_value = "both")]
    backend: Backends,
    /// Timed seconds per rate (after a warm-up batch).
    #[arg(long, default_value_t = 3.0)]
    seconds: f64,
    /// Surgery plan: the bone is moved by its first increment for the
    /// rates, and each solver relaxes that increment to its stop test
    /// (time to equilibrium). Without a plan the bone stays at rest.
    #[arg(long)]
    plan: Option<PathBuf>,
    /// With `--plan`: also the iterations and time until every free node
    /// is within 1 % of the largest displacement of the equilibrium itself
    /// (a reference from Chebyshev at ε = 10⁻⁷ · diagonal), each run
    /// capped at `--max-iterations`.
    #[arg(long, requires = "plan")]
    approach: bool,
    /// Divide the increment by the refinement factor (keeps the bone's step
    /// below the spacing of refined networks).
    #[arg(long, requires = "plan")]
    scale_increment: bool,
    /// Iteration cap of each relaxation.
    #[arg(long, default_value_t = 40_000)]
    max_iterations: u32,
    /// Also write each network (with the bone as the rates see it) into
    /// `DIR/x<factor>/` as raw little-endian arrays, for timing other
    /// tools on the same network (`scripts/reference_spring_step.py`).
    #[arg(long, value_name = "DIR")]
    export: Option<PathBuf>,
    #[command(flatten)]
    report: ReportArgs,
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    match &args.what {
        What::Relax(a) => relax(global, a),
    }
}

/// Checks the arguments before any work: factors, grid, seconds, solvers.
fn check(args: &RelaxArgs) -> anyhow::Result<Option<(usize, usize)>> {
    anyhow::ensure!(
        args.seconds.is_finite() && args.seconds > 0.0,
        "--seconds takes a positive number of seconds; got {}",
        args.seconds
    );
    anyhow::ensure!(
        !args.refine.is_empty(),
        "--refine needs at least one factor"
    );
    if let Some(f) = args.refine.iter().find(|&&f| f == 0 || f > 64) {
        anyhow::bail!("--refine factors are 1..=64; got {f}");
    }
    anyhow::ensure!(
        !args.solver.is_empty(),
        "--solver needs at least one solver"
    );
    anyhow::ensure!(args.max_iterations > 0, "--max-iterations must be ≥ 1");
    let grid = match args.grid.as_deref() {
        None => None,
        Some(&[c, r]) if c >= 2 && r >= 2 => Some((c, r)),
        Some(g) => anyhow::bail!("--grid takes COLS,ROWS, each ≥ 2; got {g:?}"),
    };
    if grid.is_none() && args.refine.iter().any(|&f| f != 1) {
        anyhow::bail!("--refine above 1 subdivides a scan grid: give its --grid COLS,ROWS");
    }
    args.report.check()?;
    Ok(grid)
}

fn relax(global: &Global, args: &RelaxArgs) -> anyhow::Result<()> {
    let grid = check(args)?;
    let machine = Machine::now();
    let skin = crate::io::read_surface(&args.mesh)?;
    if let Some((c, r)) = grid
        && skin.n_vertices() != c * r
    {
        anyhow::bail!(
            "{}: --grid {c},{r} needs {} vertices; the mesh has {}",
            args.mesh.display(),
            c * r,
            skin.n_vertices()
        );
    }
    let bone = (args.bone_mesh.as_deref())
        .map(crate::io::read_surface)
        .transpose()?;
    let plan = args.plan.as_deref().map(Plan::from_path).transpose()?;
    if let Some(p) = &plan {
        anyhow::ensure!(
            p.cuts.is_empty(),
            "{}: the plan cuts the bone; `bench relax` takes plans of steps only",
            args.plan.as_deref().map_or(Path::new("-"), |p| p).display()
        );
    }
    let gpu = match args.backend {
        Backends::Cpu => None,
        Backends::Gpu | Backends::Both => Some(global.gpu()?),
    };
    let mut backends: Vec<Backend<'_>> = Vec::new();
    if args.backend != Backends::Gpu {
        backends.push(Backend::Cpu);
    }
    if let Some(g) = &gpu {
        backends.push(Backend::Gpu(g));
    }
    let params = NetworkParams {
        origin: vec3_arg("origin", args.origin.as_deref())?.map(|o| o.to_array()),
        ..Default::default()
    };
    global.note(format!(
        "machine: {} ({} CPUs, {} threads, CPU gather {}), load {}",
        machine.cpu.as_deref().unwrap_or("unknown CPU"),
        machine.cpus,
        machine.threads,
        machine.cpu_lanes.name(),
        machine.load_text()
    ));
    let mut networks = Vec::new();
    for &factor in &args.refine {
        let t = Instant::now();
        let mesh = match grid {
            Some((c, r)) => refine_grid(&skin, c, r, factor)?,
            None => skin.clone(),
        };
        let net = SpringNetwork::build(&mesh, bone.as_ref(), &params)?;
        let build_seconds = t.elapsed().as_secs_f64();
        // The Chebyshev solver's one-time spectrum estimate, timed apart.
        let t = Instant::now();
        let spectrum = args
            .solver
            .contains(&Solver::Chebyshev)
            .then(|| estimate_spectrum(&net));
        let spectrum_seconds = spectrum.map(|_| t.elapsed().as_secs_f64());
        global.note(format!(
            "network ×{factor}: {} nodes ({} free), {} CSR entries, {:.2} MB per iteration, built in {build_seconds:.2} s",
            net.n_nodes(),
            net.n_free,
            net.csr.entries.len(),
            net.bytes_per_iteration() as f64 / 1e6
        ));
        let increment = plan
            .as_ref()
            .map(|p| -> anyhow::Result<ResolvedPlan> {
                let resolved = p.resolve(&net, &Fragments::new())?;
                let divide = if args.scale_increment { factor } else { 1 };
                resolved
                    .first_increment(divide as u32)
                    .ok_or_else(|| anyhow::anyhow!("the plan has no steps"))
            })
            .transpose()?;
        let bone_now = increment
            .as_ref()
            .map_or_else(|| net.bone_rest().to_vec(), |i| increment_bone(&net, i));
        if let Some(dir) = &args.export {
            let dir = dir.join(format!("x{factor}"));
            export_network(&dir, &net, &bone_now)?;
            global.note(format!("  network written to {}", dir.display()));
        }
        let runs: Vec<(Solver, Backend<'_>)> = (args.solver.iter())
            .flat_map(|&s| backends.iter().map(move |&b| (s, b)))
            .collect();
        let bar = global.progress(runs.len() as u64, "rates");
        let mut rates = Vec::new();
        for &(solver, backend) in &runs {
            bar.set_message(format!("{} {}", solver.name(), backend.name()));
            let r = iteration_rate(&net, solver, backend, &bone_now, args.seconds, spectrum)?;
            bar.suspend(|| {
                global.note(format!(
                    "  {:>9} {:>3}: {:>9.1} it/s, {:>6.2} GB/s effective{}",
                    solver.name(),
                    r.backend,
                    r.iterations_per_second,
                    r.effective_gb_per_second,
                    r.cpu_seconds_per_iteration
                        .map(|c| format!(", {:.1} ms CPU per iteration", c * 1e3))
                        .unwrap_or_default()
                ))
            });
            rates.push(r);
            bar.inc(1);
        }
        bar.finish_and_clear();
        let mut equilibrium = None;
        let mut approach = None;
        if let Some(increment) = &increment {
            let bar = global.progress(runs.len() as u64, "equilibrium");
            let settled = time_to_equilibrium(
                &net,
                increment,
                &runs,
                args.max_iterations,
                spectrum,
                |s| {
                    bar.suspend(|| {
                    global.note(format!(
                        "  {:>9} {:>3}: {} after {} iterations, {:.3} s, {:.3} % from the first run",
                        s.solver.name(),
                        s.backend,
                        s.status,
                        s.iterations,
                        s.seconds,
                        s.gap_percent
                    ))
                });
                    bar.inc(1);
                },
            )?;
            bar.finish_and_clear();
            equilibrium = Some(settled);
            if args.approach {
                let bar = global.progress(runs.len() as u64, "approach");
                let eq = approach_equilibrium(
                    &net,
                    increment,
                    &runs,
                    0.01,
                    args.max_iterations,
                    spectrum,
                    |a| {
                        bar.suspend(|| global.note(format!("  within 1 % of equilibrium: {a}")));
                        bar.inc(1);
                    },
                )?;
                bar.finish_and_clear();
                approach = Some(eq);
            }
        }
        networks.push(NetworkRun {
            refine: factor,
            nodes: net.n_nodes(),
            free_nodes: net.n_free,
            csr_entries: net.csr.entries.len(),
            springs: net.springs.len(),
            build_seconds,
            spectrum,
            spectrum_seconds,
            bytes_per_iteration: net.bytes_per_iteration(),
            rates,
            time_to_equilibrium: equilibrium,
            approach,
        });
    }
    let report = BenchRelaxReport {
        command: "bench relax",
        mesh: &args.mesh,
        bone_mesh: args.bone_mesh.as_deref(),
        grid: grid.map(|(c, r)| [c, r]),
        plan: args.plan.as_deref(),
        scale_increment: args.scale_increment,
        machine,
        adapter: gpu.as_ref().map(|g| g.describe()),
        networks,
    };
    args.report.emit(&report, Show::WithJson)
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        match &self.what {
            What::Relax(r) => [
                Some(r.mesh.as_path()),
                r.bone_mesh.as_deref(),
                r.plan.as_deref(),
            ]
            .into_iter()
            .flatten()
            .collect(),
        }
    }
}
