//! `chisel relax MESH --plan PLAN`: builds the layered spring network over
//! the bone (seed 000 ch. 4), runs the surgery plan and writes the relaxed
//! skin with per-vertex displacement, a before/after preview and a report.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::json;

use super::{BackendArg, Global};
use crate::mesh::{ScalarField, TriMesh};
use crate::parity::Backend;
use crate::render::{Panel, RenderOptions, View};
use crate::tissue::{
    Fragments, NetworkParams, Plan, RelaxOptions, RelaxReport, Solver, SpringNetwork,
};

/// Arguments of `chisel relax`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Epidermis mesh (any format `chisel stats` reads).
    mesh: PathBuf,
    /// Surgery plan, TOML or JSON (see `src/tissue/plans/` for examples).
    #[arg(long)]
    plan: PathBuf,
    /// Bone mesh; without it the bone layer is the skin scaled by 0.7 about the origin.
    #[arg(long)]
    bone: Option<PathBuf>,
    /// Origin O of the layer construction `x,y,z` (default: SPEC §1.1 rule).
    #[arg(long, value_delimiter = ',')]
    origin: Option<Vec<f32>>,
    /// Solver: `explicit` (the seed's damped dynamics) or `chebyshev` (accelerated equilibrium).
    #[arg(long, default_value = "explicit")]
    solver: Solver,
    /// Where the relaxation runs.
    #[arg(long, value_enum, default_value = "gpu")]
    backend: BackendArg,
    /// Time step Δt (default: 0.9 × the stability limit).
    #[arg(long)]
    dt: Option<f32>,
    /// Accept a Δt at or above the stability limit.
    #[arg(long)]
    force_dt: bool,
    /// Iteration cap per `converge` increment.
    #[arg(long, default_value_t = 100_000)]
    max_iterations: u32,
    /// Relaxed skin (PLY/VTK keep the `displacement` field), written atomically.
    #[arg(short, long)]
    output: PathBuf,
    /// Before/after preview PNG with a displacement colour map.
    #[arg(long)]
    preview: Option<PathBuf>,
    /// JSON report.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Print the report on stdout.
    #[arg(long)]
    json: bool,
}

/// A relaxation's inputs, ready to run.
pub struct Job {
    pub skin: TriMesh,
    pub network: SpringNetwork,
    pub plan: Plan,
    pub fragments: Fragments,
}

/// Runs `job` on `backend`, with a spinner, returning the report.
pub fn run_job(
    global: &Global,
    job: &Job,
    opts: &RelaxOptions,
    backend: Backend<'_>,
) -> anyhow::Result<RelaxReport> {
    let resolved = job.plan.resolve(&job.network, &job.fragments)?;
    let spinner = if global.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new_spinner()
    };
    spinner.set_message(format!(
        "relaxing {} nodes on {}",
        job.network.n_nodes(),
        backend.name()
    ));
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    let report = crate::tissue::relax(&job.network, &resolved, opts, backend);
    spinner.finish_and_clear();
    Ok(report?)
}

/// The input skin with a zero `displacement` field (the "before" panel).
pub fn before_mesh(skin: &TriMesh) -> TriMesh {
    TriMesh {
        positions: skin.positions.clone(),
        triangles: skin.triangles.clone(),
        scalars: vec![ScalarField {
            name: "displacement".into(),
            values: vec![0.0; skin.n_vertices()],
        }],
    }
}

/// Writes the before/after preview (shared framing and colour range).
pub fn write_preview(
    gpu: &crate::Gpu,
    before: &TriMesh,
    after: &TriMesh,
    views: Vec<View>,
    title: String,
    path: &Path,
) -> anyhow::Result<()> {
    let panels = [
        Panel {
            mesh: before,
            caption: "before".into(),
            scalars: None,
        },
        Panel {
            mesh: after,
            caption: "after".into(),
            scalars: None,
        },
    ];
    let opts = RenderOptions {
        width: 384,
        height: 384,
        views,
        scalars: Some("displacement".into()),
        title: Some(title),
        ..Default::default()
    };
    crate::render::render_panels(gpu, &panels, &opts)?.save_png(path)?;
    Ok(())
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    let t = Instant::now();
    let skin = crate::io::read_mesh(&args.mesh)?;
    let bone = args.bone.as_deref().map(crate::io::read_mesh).transpose()?;
    let origin = match args.origin.as_deref() {
        None => None,
        Some(&[x, y, z]) => Some([x, y, z]),
        Some(o) => anyhow::bail!("--origin takes x,y,z; got {} numbers", o.len()),
    };
    let params = NetworkParams {
        origin,
        ..Default::default()
    };
    let network = SpringNetwork::build(&skin, bone.as_ref(), &params)?;
    let plan = Plan::from_path(&args.plan)?;
    let build_s = t.elapsed().as_secs_f64();
    global.note(format!(
        "network: {} nodes ({} free), {} springs; plan `{}` with {} steps",
        network.n_nodes(),
        network.n_free,
        network.springs.len(),
        args.plan.display(),
        plan.steps.len()
    ));
    let job = Job {
        skin,
        network,
        plan,
        fragments: Fragments::new(),
    };
    let opts = RelaxOptions {
        solver: args.solver,
        dt: args.dt,
        force_dt: args.force_dt,
        max_iterations: args.max_iterations,
        ..Default::default()
    };
    let gpu = match args.backend {
        BackendArg::Gpu => Some(global.gpu()?),
        BackendArg::Cpu => None,
    };
    let backend = gpu.as_ref().map_or(Backend::Cpu, Backend::Gpu);
    let report = run_job(global, &job, &opts, backend)?;
    let relaxed = report.skin_mesh(&job.network);
    crate::io::write_mesh(&args.output, &relaxed)?;
    if let Some(path) = &args.preview {
        let opened;
        let preview_gpu = match &gpu {
            Some(g) => g,
            None => {
                opened = global.gpu()?;
                &opened
            }
        };
        write_preview(
            preview_gpu,
            &before_mesh(&job.skin),
            &relaxed,
            vec![View::Front, View::Right],
            format!(
                "chisel relax: {}",
                job.plan.name.clone().unwrap_or_default()
            ),
            path,
        )?;
    }
    let value = json!({
        "command": "relax",
        "mesh": args.mesh,
        "bone": args.bone,
        "plan": args.plan,
        "network": {
            "nodes": job.network.n_nodes(),
            "free_nodes": job.network.n_free,
            "springs": job.network.springs.len(),
            "springs_per_class": job.network.class_counts(),
            "origin": job.network.origin,
            "build_seconds": build_s,
        },
        "relax": report,
        "outputs": { "mesh": args.output, "preview": args.preview },
    });
    global.note(format!(
        "{:?} after {} iterations ({:.2} s, {:.0} it/s); max displacement {:.4}; wrote {}",
        report.status,
        report.iterations,
        report.seconds,
        report.iterations_per_second,
        report.max_displacement,
        args.output.display()
    ));
    if args.json {
        println!("{}", serde_json::to_string_pretty(&value)?);
    }
    if let Some(path) = &args.report {
        super::report::write_json(path, &value)?;
    }
    Ok(())
}
