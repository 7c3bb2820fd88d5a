//! `chisel polyhedrize VOLUME (--level T | --label L)`: the lossless
//! polyhedral representation of a digital object (seed 003 §4.4–4.5; SPEC
//! §4.4–4.5) as nested convex shells, written as a `.cells` file (compact
//! eq. 8.2 encoding) and/or readable JSON, with a triangle mesh of the
//! merged surface (§4.4.1; of the separate shells when siblings overlap,
//! reported as `"mesh": "shells"` with the reason in `merge_refused`), a
//! preview coloured face by face by depth, `--verify` (the written cell list is
//! read back and voxelized against S, by the nested shells and, when the
//! merged surface exists, by ray parity, §4.4.3) and a JSON report.
//! `--slice Z` gives the 2-D analogue (ch. 9): nested convex polygons for
//! one slice.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::hull::{HullArgs, SelectArgs, SelectionFigures};
use super::report::{Report, ReportArgs, Show};
use super::{BackendChoice, Global, ViewAxes};
use crate::gpu::Backend;
use crate::polyhedron::{
    PolyhedrizeOptions, Polyhedron, PolyhedronSummary, ZkhReport, polyhedrize,
};
use crate::render::RenderOptions;
use crate::voxel::{BoundaryTopology, DigitalObject, ObjectFigures, marching_cubes_integers};

/// The report of `chisel polyhedrize`.
#[derive(Debug, Serialize)]
pub struct PolyhedrizeReport<'a> {
    command: &'static str,
    volume: &'a Path,
    dims: [usize; 3],
    slice: Option<usize>,
    selection: SelectionFigures<'a>,
    object: ObjectFigures,
    topology: BoundaryTopology,
    backend: &'static str,
    adapter: Option<String>,
    options: PolyhedrizeOptions,
    polyhedron: PolyhedronSummary,
    sibling_merges: usize,
    marching_cubes: McFigures,
    zkh: Vec<ZkhReport>,
    /// `merged` (the merged surface) or `shells` (the separate shells).
    mesh: &'static str,
    merged_faces: Option<usize>,
    merged_faces_split: Option<usize>,
    merged_faces_with_holes: Option<usize>,
    merged_convex_faces: Option<usize>,
    merged_triangles: Option<usize>,
    merged_volume_voxels: Option<f64>,
    merged_area_voxels: Option<f64>,
    /// Why there is no merged surface.
    merge_refused: Option<String>,
    verified: Option<bool>,
    verify_ray_parity_mismatches: Option<u64>,
    outputs: PolyhedrizeOutputs<'a>,
    timings_s: PolyhedrizeTimings,
}

impl Report for PolyhedrizeReport<'_> {
    const SCHEMA: &'static str = "chisel.polyhedrize/1";
}

/// The marching-cubes surface of the same object, for comparison (eq. 8.1).
#[derive(Debug, Serialize)]
struct McFigures {
    triangles: u64,
    integers_eq_8_1: u64,
}

#[derive(Debug, Serialize)]
struct PolyhedrizeOutputs<'a> {
    cells: Option<&'a Path>,
    cells_json: Option<&'a Path>,
    mesh: Option<&'a Path>,
    preview: Option<&'a Path>,
}

/// Seconds per stage (`verify*` with `--verify` only).
#[derive(Debug, Default, Serialize)]
struct PolyhedrizeTimings {
    object: f64,
    topology: f64,
    polyhedrize: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    verify: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    verify_ray_parity: Option<f64>,
    merge: f64,
}

/// Arguments of `chisel polyhedrize`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Volume (any format `chisel stats` reads).
    volume: PathBuf,
    #[command(flatten)]
    select: SelectArgs,
    #[command(flatten)]
    hull: HullArgs,
    /// Decompose genus > 0 components into maximal digital balls (§4.5.4)
    /// instead of recursing into them like all others.
    #[arg(long)]
    balls: bool,
    /// Keep sibling shells whose interiors overlap apart instead of merging
    /// them into the hull of their union (then no merged surface).
    #[arg(long)]
    overlapping_siblings: bool,
    /// Pressing-in and cutting-out (Def. PR, Def. AU): the shell of each
    /// concavity or tunnel of CH(S) spans its marked faces (criteria
    /// (i)–(iii)) and the ZKH, instead of the ZKH alone.
    #[arg(long)]
    press_in: bool,
    /// Only slice Z of the volume: the 2-D analogue (seed 003 ch. 9),
    /// polygons for the pixel set of one CT slice or label image (no
    /// surface, so not with --mesh or --preview).
    #[arg(long, conflicts_with_all = ["mesh", "preview"])]
    slice: Option<usize>,
    /// Backend of the inside-shell scans.
    #[command(flatten)]
    backend: BackendChoice,
    /// Cell list, binary `.cells` (compact eq. 8.2 encoding), written atomically.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Cell list as readable JSON (vertices and face cycles per shell).
    #[arg(long)]
    cells_json: Option<PathBuf>,
    /// The merged surface (§4.4.1) as a triangle mesh (world units; scalar
    /// `depth`); the separate shells when it is unavailable (overlapping
    /// siblings), as the report's `mesh` field says.
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Preview PNG of the mesh of `--mesh`, flat, each face coloured by its
    /// depth.
    #[arg(long)]
    preview: Option<PathBuf>,
    #[command(flatten)]
    view: ViewAxes,
    /// Read the encoded cell list back and voxelize it: must reproduce S
    /// exactly, by the nested shells and (merged surface) by ray parity.
    #[arg(long)]
    verify: bool,
    #[command(flatten)]
    report: ReportArgs,
}

/// Largest preview mesh drawn with its edges.
const WIREFRAME_MAX_TRIANGLES: usize = 20_000;

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    // The preview axes are checked before the work, as the output paths are.
    let facing = args.view.facing()?;
    for path in [&args.output, &args.cells_json, &args.report.file]
        .into_iter()
        .flatten()
    {
        crate::foundation::fs::check_output_path(path)?;
    }
    if let Some(path) = &args.mesh {
        crate::io::check_mesh_output(path)?;
    }
    if let Some(path) = &args.preview {
        crate::foundation::fs::check_png_output(path)?;
    }
    // `-o` is the binary cell list, not a mesh (`hull -o` is): a wrong
    // extension is caught before the work.
    for (path, ext, what) in [
        (
            &args.output,
            ".cells",
            "-o takes the binary cell list (--mesh writes the surface)",
        ),
        (&args.cells_json, ".json", "--cells-json writes JSON"),
    ] {
        if let Some(path) = path
            && !path.to_string_lossy().to_lowercase().ends_with(ext)
        {
            anyhow::bail!("{}: {what}; name the file {ext}", path.display());
        }
    }
    let (selection, component) = args.select.parse()?;
    let mut timings = PolyhedrizeTimings::default();
    let since = |t: Instant| t.elapsed().as_secs_f64();
    let t = Instant::now();
    let mut volume = global.read_volume(&args.volume)?;
    if let Some(z) = args.slice {
        volume = volume
            .slice_z(z)
            .map_err(|e| anyhow::anyhow!("{}: {e}", args.volume.display()))?;
    }
    let object = DigitalObject::from_volume(&volume, selection, component)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.volume.display()))?;
    timings.object = since(t);
    let t = Instant::now();
    let topology = object.topology()?;
    timings.topology = since(t);
    let gpu = global.backend(&args.backend)?;
    let backend = gpu.as_ref().map_or(Backend::Cpu, Backend::Gpu);
    let options = PolyhedrizeOptions {
        candidates: args.hull.kind(),
        hull: args.hull.options(),
        balls: args.balls,
        disjoint_siblings: !args.overlapping_siblings,
        press_in: args.press_in,
    };
    let t = Instant::now();
    let bar = if global.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new_spinner()
    };
    bar.set_message("shells");
    let (poly, zkh) = polyhedrize(&object, options, backend, &|n| bar.set_position(n as u64))
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.volume.display()))?;
    bar.finish_and_clear();
    timings.polyhedrize = since(t);
    let summary = poly.summary();
    // A mesh needs a 3-D shell; refused before anything is written.
    let needs_mesh = args.mesh.is_some() || args.preview.is_some();
    if needs_mesh && summary.shells_by_dimension[3] == 0 {
        anyhow::bail!(
            "{}: every shell is flat (2-D or lower), so --mesh / --preview have no \
             surface to draw; -o and --cells-json write the polygons",
            args.volume.display()
        );
    }
    let bytes = poly.to_bytes();
    if let Some(path) = &args.output {
        crate::foundation::fs::write_atomic(path, &bytes)?;
    }
    if let Some(path) = &args.cells_json {
        crate::foundation::fs::write_atomic(
            path,
            serde_json::to_string_pretty(&poly.to_json())?.as_bytes(),
        )?;
    }
    let (verified, ray_parity) = if args.verify {
        let t = Instant::now();
        let back = Polyhedron::from_bytes(&bytes, "encoded cell list", object.frame())?;
        let (n, first) = back.mismatches(&object, backend, 10)?;
        timings.verify = Some(since(t));
        if n > 0 {
            anyhow::bail!(
                "{}: the polyhedron differs from the object in {n} voxels (first: {first:?})",
                args.volume.display()
            );
        }
        // The same check by ray parity on the merged surface (§4.4.3),
        // when it exists (not for flat shells only, e.g. a slice: no
        // surface, no check); the stage includes merging the read-back shells.
        let t = Instant::now();
        let ray_parity = match back.merged_surface() {
            Ok(m) if !m.triangles.is_empty() => {
                Some(back.mismatches_ray_parity(&m, &object, backend, 10)?)
            }
            _ => None,
        };
        timings.verify_ray_parity = Some(since(t));
        (Some(true), ray_parity)
    } else {
        (None, None)
    };
    let t = Instant::now();
    let (merged, merge_refused) = match poly.merged_surface() {
        Ok(m) if m.triangles.is_empty() => (None, Some("no 3-D shell".to_string())),
        Ok(m) => (Some(m), None),
        Err(e) => (None, Some(e.to_string())),
    };
    timings.merge = since(t);
    let mesh = match (needs_mesh, &merged) {
        (false, _) => None,
        (true, Some(m)) => Some(m.to_mesh(&poly.frame)?),
        (true, None) => Some(poly.to_mesh()?),
    };
    let mesh_kind = if merged.is_some() { "merged" } else { "shells" };
    if needs_mesh && let Some(why) = &merge_refused {
        global.note(format!(
            "mesh: the separate shells (no merged surface: {why})"
        ));
    }
    if let (Some(path), Some(mesh)) = (&args.mesh, &mesh) {
        crate::io::write_mesh(path, mesh)?;
    }
    if let (Some(path), Some(mesh)) = (&args.preview, &mesh) {
        let owned;
        let gpu = match &gpu {
            Some(g) => g,
            None => {
                owned = global.gpu()?;
                &owned
            }
        };
        let opts = RenderOptions {
            // Edges show the faces of a small polyhedron; on tens of
            // thousands of triangles they only darken the picture.
            wireframe: mesh.triangles.len() <= WIREFRAME_MAX_TRIANGLES,
            scalars: Some("depth".into()),
            ..super::preview_options(
                match &merged {
                    Some(m) => format!(
                        "chisel polyhedrize: merged surface, {} faces ({} split)",
                        m.n_faces(),
                        m.n_faces_split()
                    ),
                    None => format!(
                        "chisel polyhedrize: {} shells, {} faces",
                        summary.shells, summary.faces
                    ),
                },
                facing,
            )
        };
        // The merged surface drawn face by face: flat, one depth per face.
        let faces = merged
            .as_ref()
            .map(|m| m.to_face_mesh(&poly.frame))
            .transpose()?;
        crate::render::render_png(gpu, faces.as_ref().unwrap_or(mesh), &opts, path)?;
    }
    let mc_triangles = 2 * object.n_boundary_facets();
    let report = PolyhedrizeReport {
        command: "polyhedrize",
        volume: &args.volume,
        dims: volume.dims,
        slice: args.slice,
        selection: args.select.figures(),
        object: object.figures(),
        topology,
        backend: backend.name(),
        adapter: gpu.as_ref().map(|g| g.describe()),
        options,
        polyhedron: summary.clone(),
        sibling_merges: poly.merges,
        marching_cubes: McFigures {
            triangles: mc_triangles,
            integers_eq_8_1: marching_cubes_integers(mc_triangles),
        },
        zkh,
        mesh: mesh_kind,
        merged_faces: merged.as_ref().map(|m| m.n_faces()),
        merged_faces_split: merged.as_ref().map(|m| m.n_faces_split()),
        merged_faces_with_holes: merged.as_ref().map(|m| m.n_faces_with_holes()),
        merged_convex_faces: merged.as_ref().map(|m| m.n_convex_faces()),
        merged_triangles: merged.as_ref().map(|m| m.triangles.len()),
        merged_volume_voxels: merged.as_ref().map(|m| m.volume_voxels()),
        merged_area_voxels: merged.as_ref().map(|m| m.area_voxels()),
        merge_refused,
        verified,
        verify_ray_parity_mismatches: ray_parity.as_ref().map(|r| r.0),
        outputs: PolyhedrizeOutputs {
            cells: args.output.as_deref(),
            cells_json: args.cells_json.as_deref(),
            mesh: args.mesh.as_deref(),
            preview: args.preview.as_deref(),
        },
        timings_s: timings,
    };
    global.note(format!(
        "polyhedron of {} voxels: {} shells, {} faces, {} integers (eq. 8.2) vs {} for marching cubes; G_nc {}{}",
        object.n_voxels(),
        summary.shells,
        summary.faces,
        summary.integers_eq_8_2,
        marching_cubes_integers(mc_triangles),
        summary.g_nc,
        if verified.is_some() { "; verified lossless" } else { "" }
    ));
    args.report.emit(&report, Show::WithJson)?;
    if let Some((n, first)) = ray_parity.filter(|r| r.0 > 0) {
        anyhow::bail!(
            "{}: ray parity on the merged surface differs from the object in {n} voxels \
             (first: {first:?})",
            args.volume.display()
        );
    }
    Ok(())
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        vec![self.volume.as_path()]
    }
}
