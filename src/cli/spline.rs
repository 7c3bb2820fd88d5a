//! `chisel spline MESH --n N -o OUT`: the mesh's quadratic DMS spline
//! surface (seed 000 ch. 2): parametrisation, knot clouds, basis on the
//! lattice of accuracy n, control net by point identification or least
//! squares, output mesh with normals and the distance to the input.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::ValueEnum;
use glam::DVec2;
use serde::Serialize;

use super::report::{Report, ReportArgs, Show};
use super::{BackendChoice, Global, ViewAxes};
use crate::TriMesh;
use crate::dms::fit::FitReport;
use crate::dms::param::ParamMap;
use crate::dms::spline::SplineTimings;
use crate::dms::{Fit, Projection, SplineOptions, lattice_counts, spline};
use crate::gpu::Backend;
use crate::render::{Panel, RenderOptions, View};

/// How the mesh is parametrised.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ParamArg {
    /// About a vertical (y) axis fitted to the vertices, seam opposite the face.
    Cylinder,
    /// Onto the plane of the two largest principal axes.
    Planar,
    /// The mesh's texture coordinates (the fields `u`, `v`).
    Uv,
}

/// How the control net is made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FitArg {
    /// Point identification (seed eq. 2.13): vertices and edge midpoints.
    Identify,
    /// Quasi-interpolation: blossoms of local quadratic fits (exact for
    /// quadratics; follows the shape, not the facets).
    Quasi,
    /// Least squares with shared controls against the mesh or `--data`.
    Lsq,
}

/// Arguments of `chisel spline`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Triangle mesh, a disk (any format `chisel stats` reads).
    mesh: PathBuf,
    /// Parametrisation.
    #[arg(long, value_enum, default_value = "cylinder")]
    param: ParamArg,
    /// Control net.
    #[arg(long, value_enum, default_value = "quasi")]
    fit: FitArg,
    /// Points to fit instead of the mesh (any mesh format; its vertices),
    /// projected by the same parametrisation (`--fit lsq`).
    #[arg(long)]
    data: Option<PathBuf>,
    /// Fairing weight W ≥ 0 of least squares, relative (0 = none).
    #[arg(long, default_value_t = 0.0)]
    fairing: f64,
    /// Accuracy: points per parameter edge (2 = the input's connectivity).
    #[arg(long)]
    n: u32,
    #[command(flatten)]
    backend: BackendChoice,
    /// Output spline mesh with normals `nx ny nz`, `distance` and `curvature` (written atomically).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the control net (six controls per triangle as four triangles).
    #[arg(long)]
    control_net: Option<PathBuf>,
    /// Preview PNG: the input, the spline, the spline coloured by their
    /// distance, and below it coloured by curvature.
    #[arg(long)]
    preview: Option<PathBuf>,
    #[command(flatten)]
    view: ViewAxes,
    #[command(flatten)]
    report: ReportArgs,
}

/// The report of `chisel spline`.
#[derive(Debug, Serialize)]
pub struct SplineReport<'a> {
    command: &'static str,
    mesh: &'a Path,
    input: Counts,
    param: ParamFigures,
    knots: KnotFigures,
    n: u32,
    output: Counts,
    /// `points(n) = p + E(n − 2) + t(n − 2)(n − 3)/2`, `t(n − 1)²` (seed Table 3).
    predicted: Counts,
    fit: &'a FitReport,
    /// `|F(u) − M(u)|` over the output points (M the input at the same u).
    distance: Distance,
    backend: &'static str,
    adapter: Option<String>,
    timings_s: Timings,
    outputs: Outputs<'a>,
}

impl Report for SplineReport<'_> {
    const SCHEMA: &'static str = "chisel.spline/1";
}

#[derive(Debug, Serialize)]
struct Counts {
    points: usize,
    triangles: usize,
}

#[derive(Debug, Serialize)]
struct ParamFigures {
    projection: ParamArg,
    mirrored: bool,
    repaired_triangles: Vec<u32>,
    /// Cylinder: the axis `(x, z)` and radius.
    axis: Option<[f64; 3]>,
}

#[derive(Debug, Serialize)]
struct KnotFigures {
    theta_deg: f64,
    radius_fraction: f64,
    /// The smallest normalised determinant over every scored knot triple.
    min_quality: f64,
}

#[derive(Debug, Serialize)]
struct Distance {
    max: f32,
    rms: f32,
}

#[derive(Debug, Serialize)]
struct Timings {
    read: f64,
    #[serde(flatten)]
    spline: SplineTimings,
    total: f64,
}

#[derive(Debug, Serialize)]
struct Outputs<'a> {
    mesh: &'a Path,
    control_net: Option<&'a Path>,
    preview: Option<&'a Path>,
}

/// The UVs of `mesh` from its fields `u`, `v` (or `s`, `t`, or
/// `texture_u`, `texture_v`).
fn given_uv(mesh: &TriMesh, path: &Path) -> anyhow::Result<Vec<DVec2>> {
    let field = |name: &str| mesh.scalars.iter().find(|s| s.name == name);
    for (a, b) in [("u", "v"), ("s", "t"), ("texture_u", "texture_v")] {
        if let (Some(u), Some(v)) = (field(a), field(b)) {
            return Ok(u
                .values
                .iter()
                .zip(&v.values)
                .map(|(&x, &y)| DVec2::new(x as f64, y as f64))
                .collect());
        }
    }
    let names: Vec<&str> = mesh.scalars.iter().map(|s| s.name.as_str()).collect();
    anyhow::bail!(
        "{}: --param uv needs texture coordinates (fields u and v); the mesh has {:?}",
        path.display(),
        names
    )
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    let facing = args.view.facing()?;
    let t0 = Instant::now();
    crate::io::check_mesh_output(&args.output)?;
    if let Some(p) = &args.control_net {
        crate::io::check_mesh_output(p)?;
    }
    if let Some(p) = &args.preview {
        crate::foundation::fs::check_png_output(p)?;
    }
    args.report.check()?;
    if args.data.is_some() && args.fit != FitArg::Lsq {
        anyhow::bail!("--data needs --fit lsq (identify and quasi use the mesh itself)");
    }
    if args.fairing != 0.0 && args.fit != FitArg::Lsq {
        anyhow::bail!("--fairing weighs least squares: give --fit lsq");
    }
    let mesh = crate::io::read_surface(&args.mesh)?;
    let data = match &args.data {
        Some(p) => Some(crate::io::read_mesh(p)?.positions),
        None => None,
    };
    let read_s = t0.elapsed().as_secs_f64();
    let projection = match args.param {
        ParamArg::Cylinder => Projection::Cylinder,
        ParamArg::Planar => Projection::Planar,
        ParamArg::Uv => Projection::Given(given_uv(&mesh, &args.mesh)?),
    };
    let opts = SplineOptions {
        projection,
        fit: match args.fit {
            FitArg::Identify => Fit::Identify,
            FitArg::Quasi => Fit::Quasi,
            FitArg::Lsq => Fit::LeastSquares {
                fairing: args.fairing,
            },
        },
        data,
        n: args.n,
    };
    let gpu = global.backend(&args.backend)?;
    let backend = gpu.as_ref().map_or(Backend::Cpu, Backend::Gpu);
    let spinner = global.progress(0, "spline");
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    let result = spline(&mesh, &opts, backend);
    spinner.finish_and_clear();
    let (sd, s) = result.map_err(|e| anyhow::anyhow!("{}: {e}", args.mesh.display()))?;
    crate::io::write_mesh(&args.output, &s.mesh)?;
    if let Some(p) = &args.control_net {
        crate::io::write_mesh(p, &sd.control_mesh(&s.controls))?;
    }
    let dist = &s
        .mesh
        .scalars
        .iter()
        .find(|f| f.name == "distance")
        .expect("distance field")
        .values;
    let distance = Distance {
        max: dist.iter().copied().fold(0.0, f32::max),
        rms: (dist.iter().map(|d| d * d).sum::<f32>() / dist.len().max(1) as f32).sqrt(),
    };
    if let Some(path) = &args.preview {
        let opened;
        let g = match &gpu {
            Some(g) => g,
            None => {
                opened = global.gpu()?;
                &opened
            }
        };
        let panels = [
            Panel {
                mesh: &mesh,
                caption: "input".into(),
                scalars: None,
            },
            Panel {
                mesh: &s.mesh,
                caption: format!("spline n={}", args.n),
                scalars: None,
            },
            Panel {
                mesh: &s.mesh,
                caption: "distance".into(),
                scalars: Some("distance".into()),
            },
        ];
        let opts = RenderOptions {
            width: 384,
            height: 384,
            views: vec![View::Front, View::Right, View::Iso],
            title: Some(format!(
                "chisel spline: {} (DMS, {} control net; colour = distance to the input)",
                super::file_name(&args.mesh),
                s.fit.method
            )),
            facing,
            ..Default::default()
        };
        let top = crate::render::render_panels(g, &panels, &opts)?;
        // Curvature on its own colour scale, where faceting shows.
        let curvature = Panel {
            mesh: &s.mesh,
            caption: "curvature".into(),
            scalars: Some("curvature".into()),
        };
        let bottom = crate::render::render_panels(
            g,
            &[curvature],
            &RenderOptions {
                views: vec![View::Front, View::Iso],
                title: Some(
                    "curvature: normal turning rate |dn|/|dp| (where the input's facets show)"
                        .into(),
                ),
                ..opts
            },
        )?;
        crate::render::Image::stack(&[top, bottom]).save_png(path)?;
    }
    let (p, e, t) = (
        sd.domain
            .triangles
            .iter()
            .flatten()
            .collect::<std::collections::BTreeSet<_>>()
            .len() as u64,
        sd.domain.edges.len() as u64,
        sd.domain.triangles.len() as u64,
    );
    let (pp, pt) = lattice_counts(p, e, t, u64::from(args.n));
    let report = SplineReport {
        command: "spline",
        mesh: &args.mesh,
        input: Counts {
            points: mesh.n_vertices(),
            triangles: mesh.n_triangles(),
        },
        param: ParamFigures {
            projection: args.param,
            mirrored: sd.param.mirrored,
            repaired_triangles: sd.param.repaired.clone(),
            axis: match sd.param.map {
                ParamMap::Cylinder { centre, radius, .. } => Some([centre.x, centre.y, radius]),
                _ => None,
            },
        },
        knots: KnotFigures {
            theta_deg: crate::dms::knots::THETA_DEG,
            radius_fraction: crate::dms::knots::RADIUS_FRACTION,
            min_quality: sd.knot_quality,
        },
        n: args.n,
        output: Counts {
            points: s.mesh.n_vertices(),
            triangles: s.mesh.n_triangles(),
        },
        predicted: Counts {
            points: pp as usize,
            triangles: pt as usize,
        },
        fit: &s.fit,
        distance,
        backend: backend.name(),
        adapter: gpu.as_ref().map(|g| g.describe()),
        timings_s: Timings {
            read: read_s,
            spline: sd.timings.clone(),
            total: t0.elapsed().as_secs_f64(),
        },
        outputs: Outputs {
            mesh: &args.output,
            control_net: args.control_net.as_deref(),
            preview: args.preview.as_deref(),
        },
    };
    global.note(format!(
        "{} points, {} triangles (n = {}, {} fit: rms {:.3e}, max {:.3e}); wrote {}",
        s.mesh.n_vertices(),
        s.mesh.n_triangles(),
        args.n,
        s.fit.method,
        s.fit.rms,
        s.fit.max,
        args.output.display()
    ));
    args.report.emit(&report, Show::WithJson)
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        std::iter::once(self.mesh.as_path())
            .chain(self.data.as_deref())
            .collect()
    }
}
