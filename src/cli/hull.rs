//! `chisel hull VOLUME (--threshold T | --label L)`: the exact convex hull of
//! a digital object (seed 003 §4.1; SPEC §4.2) with its cell list (App. C),
//! storage per eq. 8.2, volume, area and the background components inside it
//! (ZKH, §4.2.1) with their class (Def. CO/CA/TU).

use std::path::PathBuf;
use std::time::Instant;

use clap::ValueEnum;
use serde_json::json;

use super::{Global, ViewAxes};
use crate::hull::{ConvexHull, CoplanarPolicy, HullOptions, Order};
use crate::polyhedron::background_components;
use crate::render::{RenderOptions, View};
use crate::voxel::{CandidateKind, Component, DigitalObject, Selection};

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
    #[arg(long, conflicts_with = "label", required_unless_present = "label")]
    threshold: Option<f64>,
    /// Object = samples equal to this label.
    #[arg(long)]
    label: Option<f64>,
    /// Which 6-connected component: `largest`, `all` or a 1-based index in file order.
    #[arg(long, default_value = "largest")]
    component: String,
}

impl SelectArgs {
    /// The selection and the component rule.
    pub fn parse(&self) -> anyhow::Result<(Selection, Component)> {
        let selection = match (self.threshold, self.label) {
            (Some(t), None) => Selection::Threshold(t),
            (None, Some(l)) => Selection::Label(l),
            _ => anyhow::bail!("give exactly one of --threshold and --label"),
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
    pub fn to_json(&self) -> serde_json::Value {
        json!({
            "threshold": self.threshold,
            "label": self.label,
            "component": self.component,
        })
    }
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

/// The report's `object` entry: voxels, boundary facets, inclusive voxel
/// bounding box (source indices).
pub(super) fn object_json(object: &DigitalObject) -> serde_json::Value {
    json!({
        "voxels": object.n_voxels(),
        "boundary_facets": object.n_boundary_facets(),
        "voxel_bbox": object.voxel_bbox(),
    })
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
    /// JSON report.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Print the report on stdout.
    #[arg(long)]
    json: bool,
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
    if let Some(path) = &args.report {
        crate::foundation::fs::check_output_path(path)?;
    }
    let (selection, component) = args.select.parse()?;
    let mut timings = serde_json::Map::new();
    let mut stage = |name: &str, t: Instant| {
        timings.insert(name.into(), json!(t.elapsed().as_secs_f64()));
    };
    let t = Instant::now();
    let volume = crate::io::read_volume(&args.volume)?;
    let object = DigitalObject::from_volume(&volume, selection, component)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.volume.display()))?;
    stage("object", t);
    let kind = args.hull.kind();
    let options = args.hull.options();
    let t = Instant::now();
    let candidates = object.candidates(kind);
    stage("candidates", t);
    let t = Instant::now();
    let hull = ConvexHull::build(&candidates, options)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.volume.display()))?;
    stage("hull", t);
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
    stage("zkh", t);
    let mesh = hull.to_mesh(&frame)?;
    if let Some(path) = &args.output {
        crate::io::write_mesh(path, &mesh)?;
    }
    if let Some(path) = &args.preview {
        let gpu = global.gpu()?;
        let opts = RenderOptions {
            views: vec![View::Front, View::Right, View::Top, View::Iso],
            width: 384,
            height: 384,
            wireframe: true,
            title: Some(format!(
                "chisel hull: {} ({} faces)",
                super::file_name(&args.volume),
                hull.n_faces()
            )),
            facing,
            ..Default::default()
        };
        crate::render::render_png(&gpu, &mesh, &opts, path)?;
    }
    let value = json!({
        "command": "hull",
        "volume": args.volume,
        "dims": volume.dims,
        "selection": args.select.to_json(),
        "object": object_json(&object),
        "candidates": { "kind": kind, "count": candidates.len() },
        "hull": hull.summary(&frame),
        "zkh": zkh_skipped.is_none().then_some(&zkh),
        "zkh_skipped": zkh_skipped,
        "outputs": { "mesh": args.output, "preview": args.preview },
        "timings_s": timings,
    });
    global.note(format!(
        "hull of {} voxels: {} faces, {} vertices, {} integers (eq. 8.2); {}",
        object.n_voxels(),
        hull.n_faces(),
        hull.n_vertices(),
        hull.cell_list().integers_eq_8_2(),
        match zkh_skipped {
            Some(why) => format!("ZKH skipped ({why})"),
            None => format!("{} ZKH", zkh.len()),
        }
    ));
    if args.json {
        println!("{}", serde_json::to_string_pretty(&value)?);
    }
    if let Some(path) = &args.report {
        super::report::write_json(path, &value)?;
    }
    Ok(())
}
