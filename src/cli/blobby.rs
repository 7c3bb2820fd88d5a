//! `chisel blobby fit SCAN -o MODEL.toml`: a blobby model fitted to a range
//! scan (seed 001 §3.3–3.5): energy minimisation with primitives split one
//! at a time; the model is a scene file `chisel implicit` reads.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::report::{Report, ReportArgs, Show};
use super::{BackendChoice, Global, ViewAxes};
use crate::blobby::fit::{FitOptions, FitStage, fit};
use crate::blobby::{RangePoints, Weights};
use crate::gpu::Backend;
use crate::implicit::{Scene, grid};
use crate::mesh::ScalarField;
use crate::mesh::distance::DistanceGrid;
use crate::render::{Panel, RenderOptions, View};

/// Arguments of `chisel blobby`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    what: What,
}

#[derive(Debug, clap::Subcommand)]
enum What {
    /// Fit a blobby model to a range scan (its vertices with their normals).
    Fit(FitArgs),
}

/// Arguments of `chisel blobby fit`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct FitArgs {
    /// The scan: a triangle mesh (any format `chisel stats` reads); its
    /// vertices and area-weighted normals are the range points, turned
    /// outward when most point towards their centroid.
    scan: PathBuf,
    /// Primitives of the final model.
    #[arg(long, default_value_t = 32)]
    primitives: usize,
    /// Weight α of the normal term.
    #[arg(long, default_value_t = 0.5)]
    alpha: f64,
    /// Weight β of the shrink term.
    #[arg(long, default_value_t = 1e-4)]
    beta: f64,
    /// The iso value T.
    #[arg(long, default_value_t = 0.5)]
    iso: f64,
    #[command(flatten)]
    backend: BackendChoice,
    /// The model: a scene file of the implicit room (written atomically).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the marching-cubes surface of the model, with `distance`
    /// to the scan per vertex.
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Preview PNG: the scan beside the fitted surface coloured by its
    /// distance to the scan.
    #[arg(long)]
    preview: Option<PathBuf>,
    #[command(flatten)]
    view: ViewAxes,
    #[command(flatten)]
    report: ReportArgs,
}

/// The report of `chisel blobby fit`.
#[derive(Debug, Serialize)]
pub struct BlobbyFitReport<'a> {
    command: &'static str,
    scan: &'a Path,
    points: usize,
    /// Whether the scan's normals pointed mostly towards its centroid and
    /// were turned outward.
    normals_turned: bool,
    options: FitOptions,
    /// E, E_value/M, E_normal/M, E_shrink per N.
    stages: &'a [FitStage],
    /// From each range point to the fitted surface (its marching-cubes mesh).
    distance: Distance,
    surface: Counts,
    backend: &'static str,
    adapter: Option<String>,
    timings_s: Timings,
    outputs: Outputs<'a>,
}

impl Report for BlobbyFitReport<'_> {
    const SCHEMA: &'static str = "chisel.blobby-fit/1";
}

#[derive(Debug, Serialize)]
struct Distance {
    rms: f64,
    max: f64,
    /// The same, over the scan's bounding-box diagonal.
    rms_relative: f64,
    max_relative: f64,
}

#[derive(Debug, Serialize)]
struct Counts {
    vertices: usize,
    triangles: usize,
    /// Lattice spacing of the marching cubes.
    spacing: f64,
}

#[derive(Debug, Serialize)]
struct Timings {
    read: f64,
    fit: f64,
    surface: f64,
    total: f64,
}

#[derive(Debug, Serialize)]
struct Outputs<'a> {
    model: &'a Path,
    mesh: Option<&'a Path>,
    preview: Option<&'a Path>,
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    match &args.what {
        What::Fit(a) => run_fit(global, a),
    }
}

fn run_fit(global: &Global, args: &FitArgs) -> anyhow::Result<()> {
    let facing = args.view.facing()?;
    let t0 = Instant::now();
    crate::foundation::fs::check_output_path(&args.output)?;
    if let Some(p) = &args.mesh {
        crate::io::check_mesh_output(p)?;
    }
    if let Some(p) = &args.preview {
        crate::foundation::fs::check_png_output(p)?;
    }
    args.report.check()?;
    let scan = crate::io::read_surface(&args.scan)?;
    let mut points = RangePoints::from_mesh(&scan)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.scan.display()))?;
    let normals_turned = points.orient_outward();
    let read_s = t0.elapsed().as_secs_f64();
    let opts = FitOptions {
        primitives: args.primitives,
        weights: Weights {
            alpha: args.alpha,
            beta: args.beta,
        },
        iso: args.iso,
        ..FitOptions::default()
    };
    let gpu = global.backend(&args.backend)?;
    let backend = gpu.as_ref().map_or(Backend::Cpu, Backend::Gpu);
    let bar = global.progress(args.primitives as u64, "blobby fit: primitives");
    let t1 = Instant::now();
    let result = fit(&points, &opts, backend, |s| {
        bar.set_position(s.primitives as u64)
    });
    bar.finish_and_clear();
    let result = result.map_err(|e| anyhow::anyhow!("{}: {e}", args.scan.display()))?;
    let fit_s = t1.elapsed().as_secs_f64();
    let last = result.stages.last().expect("at least one stage");
    let text = result.model.to_scene_toml(&format!(
        "chisel blobby fit {}: {} primitives, alpha {}, beta {}\nE {:.6e} (value {:.6e}, normal {:.6e}, shrink {:.6e})",
        super::file_name(&args.scan),
        result.model.blobs.len(),
        args.alpha,
        args.beta,
        last.terms.total,
        last.terms.value,
        last.terms.normal,
        last.terms.shrink,
    ));
    crate::foundation::fs::write_atomic(&args.output, text.as_bytes())?;
    // The fitted surface near the scan: marching cubes at 1/100 of the
    // scan's diagonal over the model's own bounds.
    let t2 = Instant::now();
    let scene = Scene::from_toml_str(&text, &args.output.display().to_string())?;
    let pose = scene.pose(0.0);
    let diagonal = points.diagonal();
    let spacing = diagonal / 100.0;
    let mut surface = grid::marching_cubes(&pose, spacing, backend)?.mesh;
    let to_surface = DistanceGrid::new(&surface);
    let d: Vec<f64> = (points.positions.iter())
        .map(|p| to_surface.distance(p.as_vec3()))
        .collect();
    let to_scan = DistanceGrid::new(&scan);
    let values = (surface.positions.iter())
        .map(|v| to_scan.distance(*v) as f32)
        .collect();
    surface.scalars.push(ScalarField {
        name: "distance".into(),
        values,
    });
    let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
    let max = d.iter().copied().fold(0.0, f64::max);
    if let Some(p) = &args.mesh {
        crate::io::write_mesh(p, &surface)?;
    }
    if let Some(path) = &args.preview {
        let mut opened = None;
        let g = global.preview_gpu(&gpu, &mut opened)?;
        let panels = [
            Panel {
                mesh: &scan,
                caption: "scan".into(),
                scalars: None,
            },
            Panel {
                mesh: &surface,
                caption: format!("{} blobs", result.model.blobs.len()),
                scalars: Some("distance".into()),
            },
        ];
        let image = crate::render::render_panels(
            g,
            &panels,
            &RenderOptions {
                width: 384,
                height: 384,
                views: vec![View::Front, View::Right, View::Iso],
                title: Some(format!(
                    "chisel blobby fit: {} ({} points; colour: distance to the scan; RMS {:.2} % of its diagonal)",
                    super::file_name(&args.scan),
                    points.len(),
                    100.0 * rms / diagonal
                )),
                facing,
                ..Default::default()
            },
        )?;
        image.save_png(path)?;
    }
    let surface_s = t2.elapsed().as_secs_f64();
    global.note(format!(
        "{} primitives, E {:.4e}, RMS distance {:.3e} ({:.2} % of the diagonal); wrote {}",
        result.model.blobs.len(),
        last.terms.total,
        rms,
        100.0 * rms / diagonal,
        args.output.display()
    ));
    let report = BlobbyFitReport {
        command: "blobby fit",
        scan: &args.scan,
        points: points.len(),
        normals_turned,
        options: opts,
        stages: &result.stages,
        distance: Distance {
            rms,
            max,
            rms_relative: rms / diagonal,
            max_relative: max / diagonal,
        },
        surface: Counts {
            vertices: surface.n_vertices(),
            triangles: surface.n_triangles(),
            spacing,
        },
        backend: backend.name(),
        adapter: gpu.as_ref().map(|g| g.describe()),
        timings_s: Timings {
            read: read_s,
            fit: fit_s,
            surface: surface_s,
            total: t0.elapsed().as_secs_f64(),
        },
        outputs: Outputs {
            model: &args.output,
            mesh: args.mesh.as_deref(),
            preview: args.preview.as_deref(),
        },
    };
    args.report.emit(&report, Show::WithJson)
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        match &self.what {
            What::Fit(f) => vec![f.scan.as_path()],
        }
    }
}
