//! `chisel morph A B --frames N -o DIR`: a morph from A to B (eq. 8,
//! ρ_t³ = (1 − t)·ρ_A³ + t·ρ_B³) as N meshes with one connectivity
//! (seed 001 §2.7.3, SPEC §3.4).

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::fuse::{RefineProgress, ShapeArgs, read_pair};
use super::report::{Report, ReportArgs, Show};
use super::{BackendChoice, Global, ViewAxes};
use crate::fusion::{MorphOptions, MorphReport, morph};
use crate::gpu::Backend;
use crate::render::{Panel, RenderOptions, View};

/// Arguments of `chisel morph`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Mesh A, the frame at t = 0 (closed).
    a: PathBuf,
    /// Mesh B, the frame at t = 1 (closed).
    b: PathBuf,
    /// Number of frames (t = k/(N − 1)).
    #[arg(long, default_value_t = 9)]
    frames: usize,
    #[command(flatten)]
    shape: ShapeArgs,
    /// The centre at t = 1 `x,y,z` (H moves linearly from `--center`).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        requires = "center"
    )]
    center_end: Option<Vec<f32>>,
    #[command(flatten)]
    backend: BackendChoice,
    /// Output folder: frame000.ply, frame001.ply, … (one connectivity).
    #[arg(short, long)]
    output: PathBuf,
    /// Preview PNG: a contact sheet of (at most 8) frames.
    #[arg(long)]
    preview: Option<PathBuf>,
    #[command(flatten)]
    view: ViewAxes,
    #[command(flatten)]
    report: ReportArgs,
}

/// The report of `chisel morph`.
#[derive(Debug, Serialize)]
pub struct MorphCliReport<'a> {
    command: &'static str,
    a: &'a Path,
    b: &'a Path,
    #[serde(flatten)]
    morph: &'a MorphReport,
    backend: &'static str,
    adapter: Option<String>,
    timings_s: Timings,
    outputs: Outputs<'a>,
}

impl Report for MorphCliReport<'_> {
    const SCHEMA: &'static str = "chisel.morph/1";
}

#[derive(Debug, Serialize)]
struct Timings {
    read: f64,
    morph: f64,
    total: f64,
}

#[derive(Debug, Serialize)]
struct Outputs<'a> {
    folder: &'a Path,
    frames: Vec<String>,
    preview: Option<&'a Path>,
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    let facing = args.view.facing()?;
    let t0 = Instant::now();
    super::check_output_dir(&args.output)?;
    if let Some(p) = &args.preview {
        crate::foundation::fs::check_png_output(p)?;
    }
    args.report.check()?;
    let options = MorphOptions {
        center: args.shape.center()?,
        center_end: super::vec3_arg("center-end", args.center_end.as_deref())?,
        frames: args.frames,
        refine: args.shape.refine(),
    };
    let (a, b) = read_pair(&args.a, &args.b)?;
    let read_s = t0.elapsed().as_secs_f64();
    let gpu = global.backend(&args.backend)?;
    let backend = gpu.as_ref().map_or(Backend::Cpu, Backend::Gpu);
    let mut progress = RefineProgress::new(
        global,
        "morph: refine",
        args.shape.refine().tolerance_for(&a, &b)?,
    );
    let t1 = Instant::now();
    let result = morph(&a, &b, &options, backend, |p| progress.pass(p));
    progress.bar.finish_and_clear();
    let m = result?;
    let morph_s = t1.elapsed().as_secs_f64();
    super::clear_numbered_outputs(global, &args.output, "frame")?;
    let mut names = Vec::with_capacity(m.frames.len());
    for (k, frame) in m.frames.iter().enumerate() {
        let name = format!("frame{k:03}.ply");
        crate::io::write_mesh(&args.output.join(&name), frame)?;
        names.push(name);
    }
    let r = &m.report;
    if let Some(path) = &args.preview {
        let n = m.frames.len();
        let shown: Vec<usize> = if n <= 8 {
            (0..n).collect()
        } else {
            (0..8).map(|i| (i * (n - 1) + 3) / 7).collect()
        };
        let panels: Vec<Panel> = shown
            .iter()
            .map(|&k| Panel {
                mesh: &m.frames[k],
                caption: format!("t = {:.3}", r.frames[k].t),
                scalars: None,
            })
            .collect();
        let mut opened = None;
        let g = global.preview_gpu(&gpu, &mut opened)?;
        let image = crate::render::render_panels(
            g,
            &panels,
            &RenderOptions {
                width: 256,
                height: 256,
                views: vec![View::Iso],
                title: Some(format!(
                    "chisel morph: {} to {} ({} frames, {} triangles each)",
                    super::file_name(&args.a),
                    super::file_name(&args.b),
                    n,
                    r.triangles
                )),
                facing,
                ..Default::default()
            },
        )?;
        image.save_png(path)?;
    }
    let worst = r
        .frames
        .iter()
        .map(|f| f.volumes.relative_error)
        .fold(0.0, f64::max);
    global.note(format!(
        "morph: {} frames of {} triangles, largest volume error {:.2e}, {} rays; wrote {}",
        m.frames.len(),
        r.triangles,
        worst,
        r.rays,
        args.output.display()
    ));
    let report = MorphCliReport {
        command: "morph",
        a: &args.a,
        b: &args.b,
        morph: r,
        backend: backend.name(),
        adapter: gpu.as_ref().map(|g| g.describe()),
        timings_s: Timings {
            read: read_s,
            morph: morph_s,
            total: t0.elapsed().as_secs_f64(),
        },
        outputs: Outputs {
            folder: &args.output,
            frames: names,
            preview: args.preview.as_deref(),
        },
    };
    args.report.emit(&report, Show::WithJson)
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        vec![self.a.as_path(), self.b.as_path()]
    }
}
