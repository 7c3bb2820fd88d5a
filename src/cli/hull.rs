//! `chisel hull VOLUME (--level T | --label L)`: the exact convex hull of
//! a digital object (seed 003 §4.1; SPEC §4.2) with its cell list (App. C),
//! storage per eq. 8.2, volume, area and the background components inside it
//! (ZKH, §4.2.1) with their class (Def. CO/CA/TU).

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::ValueEnum;
use serde::Serialize;

use super::report::{Report, ReportArgs, Show};
use super::{Global, ViewAxes};
use crate::hull::{ConvexHull, CoplanarPolicy, HullOptions, HullSummary, Order};
use crate::polyhedron::{Zkh, background_components};
use crate::render::RenderOptions;
use crate::voxel::{CandidateKind, Component, DigitalObject, ObjectFigures, Selection};

/// Candidate voxels for hull vertices at voxel centres (§4.1.2–4.1.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CornersArg {
    /// Local corners over the 6-neighbourhood.
    Local6,
    /// Local corners over the 18-neighbourhood.
    Local18,
    /// Local corners over the 26-neighbourhood (fewest candidates).
    Local26,
    /// Convex 3-cells (Def. KX3).
    Convex,
}

/// Where hull vertices sit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum VerticesArg {
    /// At voxel centres (3-cells).
    Voxels,
    /// At cell corners (convex 0-cells, Def. KX0).
    Corners,
}

/// Coplanar policy (§4.1.6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CoplanarArg {
    /// Coplanar faces grow into convex n-gons (the facets of the hull).
    Merge,
    /// Coplanar faces count as visible (triangles).
    Visible,
    /// Coplanar faces count as invisible (triangles).
    Invisible,
}

/// Candidate order (§4.1.8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum OrderArg {
    /// Always the point furthest beyond some face (fewest insertions).
    Furthest,
    /// The eight extreme points first, then lexicographic.
    Extreme,
    /// Lexicographic, the seed's basic order.
    Lexicographic,
}

/// Which voxels form the object.
#[derive(Debug, Clone, clap::Args)]
pub struct SelectArgs {
    /// Object = samples ≥ T.
    #[arg(long, conflicts_with = "label", required_unless_present = "label", allow_hyphen_values = true, value_parser = super::level_f64)]
    level: Option<f64>,
    /// Object = samples equal to this label.
    #[arg(long, allow_hyphen_values = true, value_parser = super::level_f64)]
    label: Option<f64>,
    /// Which 6-connected component: `largest`, `all` or a 1-based index in file order.
    #[arg(long, default_value = "largest")]
    component: String,
}

impl SelectArgs {
    /// The selection and the component rule.
    pub fn parse(&self) -> anyhow::Result<(Selection, Component)> {
        let selection = match (self.level, self.label) {
            (Some(t), None) => Selection::Threshold(t),
            (None, Some(l)) => Selection::Label(l),
            _ => anyhow::bail!("give exactly one of --level and --label"),
        };
        let component = match self.component.as_str() {
            "largest" => Component::Largest,
            "all" => Component::All,
            n => Component::Index(n.parse().map_err(|_| {
                anyhow::anyhow!("--component takes largest, all or a 1-based index; got `{n}`")
            })?),
        };
        Ok((selection, component))
    }

    /// The selection as given, for reports.
    pub fn figures(&self) -> SelectionFigures<'_> {
        SelectionFigures {
            level: self.level,
            label: self.label,
            component: &self.component,
        }
    }
}

/// The report's `selection`: `--level`, `--label`, `--component` as given.
#[derive(Debug, Serialize)]
pub struct SelectionFigures<'a> {
    level: Option<f64>,
    label: Option<f64>,
    component: &'a str,
}

/// How the hull is built: candidates, vertex cells, coplanar policy and
/// insertion order (shared by `hull` and `scan`).
#[derive(Debug, Clone, clap::Args)]
pub(super) struct HullArgs {
    /// Candidates for vertices at voxel centres.
    #[arg(long, value_enum, default_value = "local26")]
    corners: CornersArg,
    /// Hull vertices at voxel centres or at cell corners.
    #[arg(long, value_enum, default_value = "voxels")]
    vertices: VerticesArg,
    /// Treatment of coplanar faces.
    #[arg(long, value_enum, default_value = "merge")]
    coplanar: CoplanarArg,
    /// Order in which candidates are inserted.
    #[arg(long, value_enum, default_value = "furthest")]
    order: OrderArg,
}

impl HullArgs {
    /// The candidate kind (§4.1.2–4.1.3) these options ask for.
    pub(super) fn kind(&self) -> CandidateKind {
        match (self.vertices, self.corners) {
            (VerticesArg::Corners, _) => CandidateKind::ConvexCorners,
            (VerticesArg::Voxels, CornersArg::Local6) => CandidateKind::Local6,
            (VerticesArg::Voxels, CornersArg::Local18) => CandidateKind::Local18,
            (VerticesArg::Voxels, CornersArg::Local26) => CandidateKind::Local26,
            (VerticesArg::Voxels, CornersArg::Convex) => CandidateKind::ConvexVoxels,
        }
    }

    /// The hull options (§4.1.6, §4.1.8) these options ask for.
    pub(super) fn options(&self) -> HullOptions {
        HullOptions {
            coplanar: match self.coplanar {
                CoplanarArg::Merge => CoplanarPolicy::Merge,
                CoplanarArg::Visible => CoplanarPolicy::Visible,
                CoplanarArg::Invisible => CoplanarPolicy::Invisible,
            },
            order: match self.order {
                OrderArg::Furthest => Order::Furthest,
                OrderArg::Extreme => Order::ExtremeFirst,
                OrderArg::Lexicographic => Order::Lexicographic,
            },
        }
    }
}

/// The report of `chisel hull`.
#[derive(Debug, Serialize)]
pub struct HullReport<'a> {
    command: &'static str,
    volume: &'a Path,
    dims: [usize; 3],
    selection: SelectionFigures<'a>,
    object: ObjectFigures,
    candidates: Candidates,
    hull: HullSummary,
    /// The ZKHs (`null` when skipped).
    zkh: Option<Vec<Zkh>>,
    /// Why the ZKHs were not looked for (`--no-zkh`, a flat hull).
    zkh_skipped: Option<&'static str>,
    outputs: HullOutputs<'a>,
    timings_s: HullTimings,
}

impl Report for HullReport<'_> {
    const SCHEMA: &'static str = "chisel.hull/1";
}

#[derive(Debug, Serialize)]
struct Candidates {
    kind: CandidateKind,
    count: usize,
}

#[derive(Debug, Serialize)]
struct HullOutputs<'a> {
    mesh: Option<&'a Path>,
    preview: Option<&'a Path>,
}

/// Seconds per stage.
#[derive(Debug, Default, Serialize)]
struct HullTimings {
    object: f64,
    candidates: f64,
    hull: f64,
    zkh: f64,
}

/// Arguments of `chisel hull`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Volume (any format `chisel stats` reads).
    volume: PathBuf,
    #[command(flatten)]
    select: SelectArgs,
    #[command(flatten)]
    hull: HullArgs,
    /// Hull as a triangle mesh (fan-triangulated faces, world units), written atomically.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Preview PNG of the hull.
    #[arg(long)]
    preview: Option<PathBuf>,
    #[command(flatten)]
    view: ViewAxes,
    /// Skip the background components inside the hull (ZKH).
    #[arg(long)]
    no_zkh: bool,
    #[command(flatten)]
    report: ReportArgs,
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    // The preview axes are checked before the work, as the output paths are.
    let facing = args.view.facing()?;
    if let Some(path) = &args.output {
        crate::io::check_mesh_output(path)?;
    }
    if let Some(path) = &args.preview {
        crate::foundation::fs::check_png_output(path)?;
    }
    args.report.check()?;
    let (selection, component) = args.select.parse()?;
    let mut timings = HullTimings::default();
    let t = Instant::now();
    let volume = global.read_volume(&args.volume)?;
    let object = DigitalObject::from_volume(&volume, selection, component)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.volume.display()))?;
    timings.object = t.elapsed().as_secs_f64();
    let kind = args.hull.kind();
    let options = args.hull.options();
    let t = Instant::now();
    let candidates = object.candidates(kind);
    timings.candidates = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let hull = ConvexHull::build(&candidates, options)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.volume.display()))?;
    timings.hull = t.elapsed().as_secs_f64();
    let frame = object.frame();
    let t = Instant::now();
    // A flat hull has no inside, so no ZKH (reported as skipped, not as 0).
    let zkh_skipped = if args.no_zkh {
        Some("--no-zkh")
    } else if hull.is_planar() {
        Some("flat hull: no inside")
    } else {
        None
    };
    let zkh = match zkh_skipped {
        Some(_) => Vec::new(),
        None => background_components(&object, &hull)?,
    };
    timings.zkh = t.elapsed().as_secs_f64();
    let mesh = hull.to_mesh(&frame)?;
    if let Some(path) = &args.output {
        crate::io::write_mesh(path, &mesh)?;
    }
    if let Some(path) = &args.preview {
        let gpu = global.gpu()?;
        let opts = RenderOptions {
            wireframe: true,
            ..super::preview_options(
                format!(
                    "chisel hull: {} ({} faces)",
                    super::file_name(&args.volume),
                    hull.n_faces()
                ),
                facing,
            )
        };
        crate::render::render_png(&gpu, &mesh, &opts, path)?;
    }
    let n_zkh = zkh.len();
    let report = HullReport {
        command: "hull",
        volume: &args.volume,
        dims: volume.dims,
        selection: args.select.figures(),
        object: object.figures(),
        candidates: Candidates {
            kind,
            count: candidates.len(),
        },
        hull: hull.summary(&frame),
        zkh: zkh_skipped.is_none().then_some(zkh),
        zkh_skipped,
        outputs: HullOutputs {
            mesh: args.output.as_deref(),
            preview: args.preview.as_deref(),
        },
        timings_s: timings,
    };
    global.note(format!(
        "hull of {} voxels: {} faces, {} vertices, {} integers (eq. 8.2); {}",
        object.n_voxels(),
        hull.n_faces(),
        hull.n_vertices(),
        hull.cell_list().integers_eq_8_2(),
        match zkh_skipped {
            Some(why) => format!("ZKH skipped ({why})"),
            None => format!("{n_zkh} ZKH"),
        }
    ));
    args.report.emit(&report, Show::WithJson)
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        vec![self.volume.as_path()]
    }
}
