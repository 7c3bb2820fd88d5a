//! `chisel demo`: the main job on embedded generated data.
//!
//! A CT-like head phantom (soft tissue over a skull whose mandible is fused
//! to the skull base) → skin and bone surfaces by marching cubes on the GPU
//! (checked against the CPU: the same triangles) → the skin's short edges
//! collapsed → a plane osteotomy through both rami frees the jaw, capped →
//! layered spring network over the bone (seed 000 ch. 4) with bend springs
//! across the skin → the jaw advanced 6 mm and the tissue relaxed
//! on the GPU → the same plan on the CPU mirror as a parity check → relaxed
//! skin, its face as a smooth DMS spline surface (seed 000 ch. 2), moved
//! bone, the phantom CT, before/after previews and a JSON report in the
//! output folder.

use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;

use super::Global;
use super::relax::{
    Crossings, NetworkFigures, Overshoot, SkinSpline, before_mesh, bone_before_after, run_job,
    skin_spline, write_preview,
};
use super::report::{Report, Show};
use glam::Vec3;

use crate::gpu::Backend;
use crate::gpu::GpuFeatures;
use crate::mc::McOptions;
use crate::render::{Facing, View};
use crate::tissue::ct::CtFigures;
use crate::tissue::ct::{CT_BENDING, CT_SUBCUTIS_DEPTH};
use crate::tissue::network::{Material, Stiffness};
use crate::tissue::phantom::{ct_demo_plan, ct_head_phantom};
use crate::tissue::{BoneCutFigures, Job, RelaxReport};
use crate::tissue::{CtLayers, CtParams, Fragments, NetworkParams, RelaxOptions, Solver};

/// Arguments of `chisel demo`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output folder (created if missing).
    #[arg(short, long, default_value = "chisel-demo")]
    output: PathBuf,
    /// Voxel size of the CT phantom, mm (1–8; smaller = finer surfaces, more nodes).
    #[arg(long, default_value_t = 5.0)]
    voxel: f32,
    /// Solver for the GPU run.
    #[arg(long, default_value = "chebyshev")]
    solver: Solver,
    /// Print the report as JSON on stdout too.
    #[arg(long)]
    json: bool,
}

/// Accuracy of the relaxed skin's DMS spline (points per edge).
const DEMO_SPLINE_N: u32 = 5;

/// Skin and bone levels of the phantom (as for the VTK CT head).
const SKIN_LEVEL: f32 = 500.0;
const BONE_LEVEL: f32 = 1150.0;

/// The report of `chisel demo` (`report.json` in the output folder).
#[derive(Debug, Serialize)]
pub struct DemoReport<'a> {
    command: &'static str,
    adapter: String,
    features: GpuFeatures,
    phantom: PhantomFigures,
    ct: &'a CtFigures,
    marching_cubes_gpu_equals_cpu: bool,
    cut: Option<&'a BoneCutFigures>,
    network: NetworkFigures,
    relax_gpu: &'a RelaxReport,
    skin_self_intersecting_pairs: Crossings,
    skin_overshoot: Overshoot,
    /// The relaxed face as a smooth DMS spline (GPU basis and gathers).
    skin_spline: &'a SkinSpline,
    parity: DemoParity,
    outputs: DemoOutputs,
    timings_s: DemoTimings,
}

impl Report for DemoReport<'_> {
    const SCHEMA: &'static str = "chisel.demo/1";
}

#[derive(Debug, Serialize)]
struct PhantomFigures {
    dims: [usize; 3],
    voxel_mm: f32,
    levels: Levels,
}

#[derive(Debug, Serialize)]
struct Levels {
    skin: f32,
    bone: f32,
}

/// The CPU mirror's run of the same plan against the GPU's.
#[derive(Debug, Serialize)]
struct DemoParity {
    cpu_status: crate::tissue::Status,
    cpu_iterations: u64,
    same_status_and_iterations: bool,
    max_epidermis_distance: f32,
}

#[derive(Debug, Serialize)]
struct DemoOutputs {
    skin: PathBuf,
    skin_spline: PathBuf,
    bone: PathBuf,
    ct: PathBuf,
    preview: PathBuf,
    bone_preview: PathBuf,
}

/// Seconds per stage.
#[derive(Debug, Default, Serialize)]
struct DemoTimings {
    phantom: f64,
    gpu_open: f64,
    marching_cubes_gpu: f64,
    marching_cubes_cpu_check: f64,
    cut_and_network: f64,
    relax_gpu: f64,
    relax_cpu_mirror: f64,
    write_outputs: f64,
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.output).map_err(|e| crate::Error::io(&args.output, e))?;
    let bar = global.progress(7, "demo");
    let mut timings = DemoTimings::default();
    let since = |t: Instant| t.elapsed().as_secs_f64();

    let t = Instant::now();
    let volume = ct_head_phantom(args.voxel)?;
    let plan = ct_demo_plan()?;
    timings.phantom = since(t);
    bar.inc(1);

    let t = Instant::now();
    let gpu = global.gpu()?;
    timings.gpu_open = since(t);
    bar.inc(1);

    let t = Instant::now();
    let mc = |level: f32, backend| {
        let iso = crate::mc::IsoSpec::Level(level);
        crate::mc::marching_cubes(&volume, iso, &McOptions::default(), backend)
    };
    let (skin_gpu, bone_gpu) = (
        mc(SKIN_LEVEL, Backend::Gpu(&gpu))?,
        mc(BONE_LEVEL, Backend::Gpu(&gpu))?,
    );
    let ct_params = CtParams::for_volume(&volume, SKIN_LEVEL, BONE_LEVEL);
    let layers = CtLayers::from_surfaces(&skin_gpu, &bone_gpu, &ct_params)?;
    timings.marching_cubes_gpu = since(t);
    let t = Instant::now();
    let mc_same = skin_gpu.canonical_triangles()
        == mc(SKIN_LEVEL, Backend::Cpu)?.canonical_triangles()
        && bone_gpu.canonical_triangles() == mc(BONE_LEVEL, Backend::Cpu)?.canonical_triangles();
    timings.marching_cubes_cpu_check = since(t);
    bar.inc(1);

    let t = Instant::now();
    let params = NetworkParams {
        subcutis_depth: Some(CT_SUBCUTIS_DEPTH),
        stiffness: Stiffness {
            bending: Material::linear(CT_BENDING),
            ..Default::default()
        },
        ..Default::default()
    };
    let job = Job::build(
        layers.skin.clone(),
        Some(layers.bone.clone()),
        plan,
        Fragments::new(),
        &params,
    )?;
    timings.cut_and_network = since(t);
    bar.inc(1);

    let opts = RelaxOptions {
        solver: args.solver,
        ..Default::default()
    };
    let t = Instant::now();
    let gpu_report = run_job(global, &job, &opts, Backend::Gpu(&gpu))?;
    timings.relax_gpu = since(t);
    bar.inc(1);
    let t = Instant::now();
    let cpu_report = run_job(global, &job, &opts, Backend::Cpu)?;
    timings.relax_cpu_mirror = since(t);
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
    let out = |name: &str| args.output.join(name);
    crate::io::write_mesh(&out("relaxed_skin.ply"), &relaxed)?;
    let crossings = super::relax::skin_crossings(&job.skin, &relaxed);
    let overshoot = super::relax::skin_overshoot(&job.network, &job.plan, &gpu_report)?;
    let (bone_before, bone_after) = bone_before_after(&job, &gpu_report)
        .ok_or_else(|| anyhow::anyhow!("the demo network has no bone mesh"))?;
    crate::io::write_mesh(&out("bone_moved.ply"), &bone_after)?;
    crate::io::write_volume(&out("head_ct.nrrd"), &volume)?;
    let facing = Facing::Axes;
    let views = vec![View::Front, View::Right];
    let title = "chisel demo: jaw osteotomy, 6 mm advance (mm)";
    let spline = skin_spline(
        &job.skin,
        &relaxed.positions,
        DEMO_SPLINE_N,
        (Vec3::Z, Vec3::Y),
        Backend::Gpu(&gpu),
    )?;
    crate::io::write_mesh(&out("relaxed_skin_spline.ply"), &spline.after)?;
    let before = before_mesh(&job.skin);
    write_preview(
        &gpu,
        &[
            (&before, "before"),
            (&relaxed, "after"),
            (&spline.after, "after, DMS spline"),
        ],
        views.clone(),
        facing,
        format!("{title} - skin"),
        &out("before_after.png"),
    )?;
    write_preview(
        &gpu,
        &[(&bone_before, "before"), (&bone_after, "after")],
        views,
        facing,
        format!("{title} - bone"),
        &out("bone_before_after.png"),
    )?;
    timings.write_outputs = since(t);
    bar.inc(1);
    bar.finish_and_clear();

    let report = DemoReport {
        command: "demo",
        adapter: gpu.describe(),
        features: gpu.features,
        phantom: PhantomFigures {
            dims: volume.dims,
            voxel_mm: args.voxel,
            levels: Levels {
                skin: SKIN_LEVEL,
                bone: BONE_LEVEL,
            },
        },
        ct: &layers.figures,
        marching_cubes_gpu_equals_cpu: mc_same,
        cut: job.cut.as_ref(),
        network: NetworkFigures::of(&job.network, params.subcutis_depth),
        relax_gpu: &gpu_report,
        skin_self_intersecting_pairs: crossings,
        skin_overshoot: overshoot,
        skin_spline: &spline,
        parity: DemoParity {
            cpu_status: cpu_report.status,
            cpu_iterations: cpu_report.iterations,
            same_status_and_iterations: same_status,
            max_epidermis_distance: max_gpu_cpu,
        },
        outputs: DemoOutputs {
            skin: out("relaxed_skin.ply"),
            skin_spline: out("relaxed_skin_spline.ply"),
            bone: out("bone_moved.ply"),
            ct: out("head_ct.nrrd"),
            preview: out("before_after.png"),
            bone_preview: out("bone_before_after.png"),
        },
        timings_s: timings,
    };
    super::report::emit(
        &report,
        Show::WithJson,
        args.json,
        Some(&out("report.json")),
    )?;
    global.note(format!(
        "demo: CT {}×{}×{} → skin {} / bone {} vertices (GPU marching cubes {}), jaw cut free; \
         {} nodes, GPU relaxation {} after {} iterations ({:.2} s), max skin displacement {:.2} mm; \
         CPU mirror {} (max |Δ| {:.2e} mm); wrote {}",
        volume.dims[0],
        volume.dims[1],
        volume.dims[2],
        layers.figures.skin_vertices,
        layers.figures.bone_vertices,
        if mc_same { "= CPU" } else { "DIFFERS from CPU" },
        job.network.n_nodes(),
        gpu_report.status,
        gpu_report.iterations,
        gpu_report.seconds,
        gpu_report.max_displacement,
        if same_status { "agrees" } else { "DIFFERS" },
        max_gpu_cpu,
        args.output.display()
    ));
    anyhow::ensure!(
        mc_same,
        "GPU and CPU marching cubes gave different triangles"
    );
    anyhow::ensure!(
        same_status,
        "GPU and CPU mirror ended differently: {} after {} vs {} after {} iterations",
        gpu_report.status,
        gpu_report.iterations,
        cpu_report.status,
        cpu_report.iterations
    );
    Ok(())
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        Vec::new()
    }
}
