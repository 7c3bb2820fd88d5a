//! `chisel implicit SCENE.toml -o DIR`: sample a skeletal implicit scene's
//! time span (SPEC §3.1–3.2): frames evenly spaced from t = 0 to the last
//! key, written as `DIR/frame_NNNN.ply`, a contact sheet, a JSON report.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::ValueEnum;
use serde::Serialize;

use super::report::{Report, ReportArgs, Show};
use super::{BackendChoice, Global, ViewAxes};
use crate::TriMesh;
use crate::gpu::Backend;
use crate::implicit::Scene;
use crate::particles::animate::{self, FrameReport, NetworkFrameReport, Setup};
use crate::particles::{NetworkOptions, WhOptions};
use crate::render::{Panel, RenderOptions, View};

/// How the surface is sampled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MethodArg {
    /// Witkin–Heckbert particles (point sets with normals).
    Particles,
    /// The particle spring network (closed triangle meshes through splits and merges).
    Network,
}

/// Arguments of `chisel implicit`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Scene file (TOML: iso, blend, primitives, keys; see docs/cli.md).
    scene: PathBuf,
    /// Frames, evenly spaced from t = 0 to the last key.
    #[arg(long, default_value_t = 8)]
    frames: u32,
    /// Sampling method.
    #[arg(long, value_enum, default_value = "particles")]
    method: MethodArg,
    /// Target spacing of the samples (default: the scene's
    /// `[particles] edge_length`, else the surface's diagonal / 64).
    #[arg(long)]
    edge_length: Option<f64>,
    #[command(flatten)]
    backend: BackendChoice,
    /// Output folder for `frame_NNNN.ply` (created; older frames removed).
    #[arg(short, long)]
    output: PathBuf,
    /// Contact sheet PNG: up to 6 frames side by side (front and iso views).
    #[arg(long)]
    preview: Option<PathBuf>,
    #[command(flatten)]
    view: ViewAxes,
    #[command(flatten)]
    report: ReportArgs,
}

/// The report of `chisel implicit`.
#[derive(Debug, Serialize)]
struct ImplicitReport<'a> {
    command: &'static str,
    scene: &'a Path,
    method: MethodArg,
    primitives: usize,
    duration: f64,
    setup: SetupReport,
    frames: Frames,
    backend: &'static str,
    adapter: Option<String>,
    seconds: f64,
    output: &'a Path,
    preview: Option<&'a Path>,
}

/// The sampler's setup, by method.
#[derive(Debug, Serialize)]
#[serde(untagged)]
enum SetupReport {
    Particles(Setup),
    Network {
        edge_length: f64,
        options: NetworkOptions,
    },
}

/// Per-frame figures, by method.
#[derive(Debug, Serialize)]
#[serde(untagged)]
enum Frames {
    Particles(Vec<FrameReport>),
    Network(Vec<NetworkFrameReport>),
}

impl Report for ImplicitReport<'_> {
    const SCHEMA: &'static str = "chisel.implicit/1";
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    let facing = args.view.facing()?;
    let t0 = Instant::now();
    super::check_output_dir(&args.output)?;
    if let Some(p) = &args.preview {
        crate::foundation::fs::check_png_output(p)?;
    }
    args.report.check()?;
    if args.frames == 0 {
        anyhow::bail!("--frames 0: at least one frame");
    }
    let text = crate::io::config::read_text(&args.scene)?;
    let origin = args.scene.display().to_string();
    let scene = Scene::from_toml_str(&text, &origin)?;
    let times = animate::frame_times(&scene, args.frames);
    let gpu = global.backend(&args.backend)?;
    let backend = gpu.as_ref().map_or(Backend::Cpu, Backend::Gpu);
    super::clear_numbered_outputs(global, &args.output, "frame_")?;
    let bar = global.progress(times.len() as u64, "frames");
    let shown = sheet_frames(times.len(), 6);
    let mut sheet: Vec<(TriMesh, f64)> = Vec::new();
    let frame_path = |k: u32| args.output.join(format!("frame_{k:04}.ply"));
    let (r, setup, frames) = match args.method {
        MethodArg::Particles => {
            let opts = WhOptions::from_scene(&text, &origin)?;
            let r = animate::edge_length(&scene, opts.edge_length, args.edge_length)?;
            let mut frames = Vec::new();
            let setup = animate::sample(&scene, &times, r, opts, backend, |p, field, report| {
                let points = animate::point_set(p, field);
                crate::io::write_mesh(&frame_path(report.frame), &points)?;
                if args.preview.is_some() && shown.contains(&(report.frame as usize)) {
                    sheet.push((animate::splats(&points, 0.8), report.time));
                }
                frames.push(report.clone());
                bar.inc(1);
                Ok(())
            })?;
            (r, SetupReport::Particles(setup), Frames::Particles(frames))
        }
        MethodArg::Network => {
            let opts = NetworkOptions::from_scene(&text, &origin)?;
            let r = animate::edge_length(&scene, opts.edge_length, args.edge_length)?;
            let net = animate::start_network(&scene, r, opts, backend)?;
            let mut frames = Vec::new();
            animate::network(&scene, &times, net, backend, |net, t, steps| {
                let k = frames.len() as u32;
                let mesh = net.mesh();
                crate::io::write_mesh(&frame_path(k), &mesh)?;
                if args.preview.is_some() && shown.contains(&(k as usize)) {
                    sheet.push((mesh, t));
                }
                frames.push(animate::network_report(net, &scene, k, t, steps, backend)?);
                bar.inc(1);
                Ok(())
            })?;
            (
                r,
                SetupReport::Network {
                    edge_length: r,
                    options: opts,
                },
                Frames::Network(frames),
            )
        }
    };
    bar.finish_and_clear();
    if let Some(path) = &args.preview {
        let mut opened = None;
        let g = global.preview_gpu(&gpu, &mut opened)?;
        let panels: Vec<Panel<'_>> = (sheet.iter())
            .map(|(mesh, t)| Panel {
                mesh,
                caption: format!("t = {t:.3}"),
                scalars: None,
            })
            .collect();
        let opts = RenderOptions {
            width: 320,
            height: 320,
            views: vec![View::Front, View::Iso],
            title: Some(format!(
                "chisel implicit: {} ({}, spacing {r:.3})",
                super::file_name(&args.scene),
                match args.method {
                    MethodArg::Particles => "Witkin-Heckbert particles",
                    MethodArg::Network => "spring network",
                }
            )),
            facing,
            ..Default::default()
        };
        crate::render::render_panels(g, &panels, &opts)?.save_png(path)?;
    }
    global.note(match &frames {
        Frames::Particles(f) => {
            let last = f.last().expect("at least one frame");
            format!(
                "{} frames, {} particles in the last ({} clusters, residual max {:.2e}); wrote {}",
                f.len(),
                last.particles,
                last.clusters,
                last.residual_max,
                args.output.display()
            )
        }
        Frames::Network(f) => {
            let last = f.last().expect("at least one frame");
            let events: usize = f.iter().map(|x| x.steps.events.len()).sum();
            let reseeds = (f.iter().flat_map(|x| &x.steps.events))
                .filter(|e| e.reseed)
                .count();
            format!(
                "{} frames, {} triangles in the last ({} components, genus {:?}, {} topology events of which {} reseeds, Hausdorff {:.2e}); wrote {}",
                f.len(),
                last.triangles,
                last.components,
                last.genus,
                events,
                reseeds,
                last.hausdorff,
                args.output.display()
            )
        }
    });
    let report = ImplicitReport {
        command: "implicit",
        scene: &args.scene,
        method: args.method,
        primitives: scene.primitives.len(),
        duration: scene.duration(),
        setup,
        backend: backend.name(),
        adapter: gpu.as_ref().map(|g| g.describe()),
        seconds: t0.elapsed().as_secs_f64(),
        output: &args.output,
        preview: args.preview.as_deref(),
        frames,
    };
    args.report.emit(&report, Show::WithJson)
}

/// Up to `k` frame indices out of `n`, evenly spread, first and last included.
fn sheet_frames(n: usize, k: usize) -> Vec<usize> {
    if n <= k {
        return (0..n).collect();
    }
    (0..k).map(|i| i * (n - 1) / (k - 1)).collect()
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        vec![self.scene.as_path()]
    }
}
