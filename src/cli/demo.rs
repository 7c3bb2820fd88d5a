//! `chisel demo`: the main job on embedded generated data.
//!
//! A head phantom (skin over a skull whose mandible is a separate
//! fragment) → layered spring network (seed 000 ch. 4) → the jaw-advance
//! plan relaxed on the GPU → the same plan on the CPU mirror for a parity
//! check → relaxed skin with per-vertex displacement, before/after preview
//! and a JSON report in the output folder.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;

use super::Global;
use super::relax::{Job, before_mesh, run_job, write_preview};
use crate::parity::Backend;
use crate::render::View;
use crate::tissue::phantom::{HeadPhantom, head_phantom};
use crate::tissue::{NetworkParams, RelaxOptions, Solver, SpringNetwork};

/// Arguments of `chisel demo`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output folder (created if missing).
    #[arg(short, long, default_value = "chisel-demo")]
    out: PathBuf,
    /// Phantom resolution (latitude bands of the skin, ≥ 8).
    #[arg(long, default_value_t = 24)]
    resolution: usize,
    /// Solver for the GPU run.
    #[arg(long, default_value = "explicit")]
    solver: Solver,
    /// Print the report as JSON on stdout too.
    #[arg(long)]
    json: bool,
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out).map_err(|e| crate::Error::io(&args.out, e))?;
    let bar = global.progress(5, "demo");
    let mut timings = serde_json::Map::new();
    let mut stage = |name: &str, t: Instant| {
        timings.insert(name.into(), json!(t.elapsed().as_secs_f64()));
    };

    let t = Instant::now();
    let phantom = head_phantom(args.resolution)?;
    let params = NetworkParams {
        origin: Some(phantom.origin.to_array()),
        ..Default::default()
    };
    let network = SpringNetwork::build(&phantom.skin, Some(&phantom.skull), &params)?;
    let job = Job {
        skin: phantom.skin.clone(),
        network,
        plan: HeadPhantom::demo_plan()?,
        fragments: phantom.fragments(),
    };
    stage("build", t);
    bar.inc(1);

    let t = Instant::now();
    let gpu = global.gpu()?;
    stage("gpu_open", t);
    bar.inc(1);

    let opts = RelaxOptions {
        solver: args.solver,
        ..Default::default()
    };
    let t = Instant::now();
    let gpu_report = run_job(global, &job, &opts, Backend::Gpu(&gpu))?;
    stage("relax_gpu", t);
    bar.inc(1);
    let t = Instant::now();
    let cpu_report = run_job(global, &job, &opts, Backend::Cpu)?;
    stage("relax_cpu_mirror", t);
    bar.inc(1);
    let max_gpu_cpu = gpu_report
        .epidermis
        .iter()
        .zip(&cpu_report.epidermis)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0f32, f32::max);
    let same_status =
        gpu_report.status == cpu_report.status && gpu_report.iterations == cpu_report.iterations;

    let t = Instant::now();
    let relaxed = gpu_report.skin_mesh(&job.network);
    let mesh_path = args.out.join("relaxed_skin.ply");
    crate::io::write_mesh(&mesh_path, &relaxed)?;
    let skull_path = args.out.join("skull.ply");
    crate::io::write_mesh(&skull_path, &phantom.skull)?;
    let preview_path = args.out.join("before_after.png");
    write_preview(
        &gpu,
        &before_mesh(&job.skin),
        &relaxed,
        vec![View::Front, View::Right],
        "chisel demo: jaw advance 6 mm, tissue relaxed on the GPU (mm)".into(),
        &preview_path,
    )?;
    stage("write_outputs", t);
    bar.inc(1);
    bar.finish_and_clear();

    let report = json!({
        "command": "demo",
        "adapter": gpu.describe(),
        "features": gpu.features,
        "phantom": {
            "resolution": args.resolution,
            "skin_vertices": phantom.skin.n_vertices(),
            "skin_triangles": phantom.skin.n_triangles(),
            "skull_vertices": phantom.skull.n_vertices(),
            "jaw_vertices": phantom.jaw_vertices.len(),
        },
        "network": {
            "nodes": job.network.n_nodes(),
            "free_nodes": job.network.n_free,
            "springs": job.network.springs.len(),
            "springs_per_class": job.network.class_counts(),
        },
        "relax_gpu": gpu_report,
        "parity": {
            "cpu_status": cpu_report.status,
            "cpu_iterations": cpu_report.iterations,
            "same_status_and_iterations": same_status,
            "max_epidermis_distance": max_gpu_cpu,
        },
        "outputs": { "mesh": mesh_path, "skull": skull_path, "preview": preview_path },
        "timings_s": timings,
    });
    let report_path = args.out.join("report.json");
    super::report::write_json(&report_path, &report)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    }
    global.note(format!(
        "demo: {} nodes, GPU {:?} after {} iterations ({:.2} s), max skin displacement {:.2} mm; \
         CPU mirror {} (max |Δ| {:.2e} mm); wrote {}",
        job.network.n_nodes(),
        gpu_report.status,
        gpu_report.iterations,
        gpu_report.seconds,
        gpu_report.max_displacement,
        if same_status { "agrees" } else { "DIFFERS" },
        max_gpu_cpu,
        args.out.display()
    ));
    anyhow::ensure!(
        same_status,
        "GPU and CPU mirror ended differently: {:?}/{} vs {:?}/{}",
        gpu_report.status,
        gpu_report.iterations,
        cpu_report.status,
        cpu_report.iterations
    );
    Ok(())
}
