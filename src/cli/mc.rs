//! `chisel mc VOLUME --level L | --label N`: marching cubes with one-pass
//! grouping (seed 004 §1), per-group figures, optional per-group meshes.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::report::{Report, ReportArgs, Show};
use super::{BackendChoice, Global, ViewAxes};
use crate::gpu::Backend;
use crate::mc::{Group, IsoSpec, McOptions, marching_cubes};

/// The report of `chisel mc`.
#[derive(Debug, Serialize)]
pub struct McReport<'a> {
    command: &'static str,
    volume: &'a Path,
    dims: [usize; 3],
    spacing: [f64; 3],
    iso: Iso,
    backend: &'static str,
    adapter: Option<String>,
    vertices: usize,
    triangles: usize,
    /// `None` with `--no-groups`.
    group_count: Option<usize>,
    groups: &'a [Group],
    timings_s: McTimings,
    outputs: McOutputs<'a>,
}

impl Report for McReport<'_> {
    const SCHEMA: &'static str = "chisel.mc/1";
}

/// `{"level": L}` or `{"label": N}`.
#[derive(Debug, Serialize)]
#[serde(rename_all = "snake_case")]
enum Iso {
    Level(f32),
    Label(f64),
}

#[derive(Debug, Serialize)]
struct McTimings {
    read: f64,
    marching_cubes: f64,
}

#[derive(Debug, Serialize)]
struct McOutputs<'a> {
    mesh: &'a Path,
    groups_dir: Option<&'a Path>,
    preview: Option<&'a Path>,
}

/// Arguments of `chisel mc`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Scalar or label volume.
    volume: PathBuf,
    /// Iso level: samples ≥ level are inside.
    #[arg(long, conflicts_with = "label", required_unless_present = "label", allow_hyphen_values = true, value_parser = super::level_f32)]
    level: Option<f32>,
    /// Extract the boundary of the voxels equal to this label.
    #[arg(long, allow_hyphen_values = true, value_parser = super::level_f64)]
    label: Option<f64>,
    /// Close surfaces at the volume border: half a voxel outside it next to
    /// samples above the level; at a border sample equal to the level the
    /// closing surface touches the sample (2⁻¹⁰ of a voxel beyond it).
    #[arg(long)]
    close_border: bool,
    /// Where marching cubes runs (the GPU finishes grouping on the host).
    #[command(flatten)]
    backend: BackendChoice,
    /// Output surface mesh (written atomically).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write one mesh per group (connected component) into this folder.
    #[arg(long)]
    groups_dir: Option<PathBuf>,
    /// Only the mesh: no grouping, per-group figures or forest (the report's
    /// `group_count` is null and `groups` empty).
    #[arg(long, conflicts_with = "groups_dir")]
    no_groups: bool,
    /// Preview PNG.
    #[arg(long)]
    preview: Option<PathBuf>,
    #[command(flatten)]
    view: ViewAxes,
    #[command(flatten)]
    report: ReportArgs,
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    // The preview axes are checked before the work, as the output paths are.
    let facing = args.view.facing()?;
    let t = Instant::now();
    crate::io::check_mesh_output(&args.output)?;
    if let Some(path) = &args.preview {
        crate::foundation::fs::check_png_output(path)?;
    }
    args.report.check()?;
    if let Some(dir) = &args.groups_dir {
        super::check_output_dir(dir)?;
    }
    if let Some(l) = args.label
        && l.fract() != 0.0
    {
        anyhow::bail!("--label takes a whole number (a voxel value); got {l}");
    }
    let volume = global.read_volume(&args.volume)?;
    if volume.dims.iter().any(|&d| d < 2) {
        anyhow::bail!(
            "{}: a volume of {:?} samples has no cells: marching cubes needs at least 2 samples along each axis",
            args.volume.display(),
            volume.dims
        );
    }
    let read_s = t.elapsed().as_secs_f64();
    let iso = match (args.level, args.label) {
        (Some(l), None) => IsoSpec::Level(l),
        (None, Some(l)) => IsoSpec::Label(l),
        _ => anyhow::bail!("give exactly one of --level and --label"),
    };
    let gpu = global.backend(&args.backend)?;
    let backend = gpu.as_ref().map_or(Backend::Cpu, Backend::Gpu);
    let t = Instant::now();
    let surface = marching_cubes(
        &volume,
        iso,
        &McOptions {
            close_border: args.close_border,
            mesh_only: args.no_groups,
        },
        backend,
    )?;
    let mc_s = t.elapsed().as_secs_f64();
    if surface.mesh.n_triangles() == 0 {
        let values = || (0..volume.data.len()).map(|i| volume.data.get_f64(i));
        let (lo, hi) = crate::reduce::volume_range(&volume, Backend::Cpu)?
            .map_or((f32::NAN, f32::NAN), |r| (r.min, r.max));
        let border = if args.close_border {
            ""
        } else {
            " (try --close-border: it closes surfaces at the volume border)"
        };
        let why = match iso {
            IsoSpec::Level(l) if !(lo..=hi).contains(&l) => {
                format!("level {l} lies outside the data range {lo} to {hi}")
            }
            IsoSpec::Label(l) if !values().any(|x| x == l) => {
                format!("label {l} occurs in no voxel (values {lo} to {hi})")
            }
            IsoSpec::Level(l) => {
                format!("no cell has samples on both sides of level {l}{border}")
            }
            IsoSpec::Label(l) => format!("no cell has samples in and out of label {l}{border}"),
        };
        anyhow::bail!("{}: {why}; nothing written", args.volume.display());
    }
    crate::io::write_mesh(&args.output, &surface.mesh)?;
    if let Some(dir) = &args.groups_dir {
        super::clear_numbered_outputs(global, dir, "group_")?;
        let bar = global.progress(surface.groups.len() as u64, "groups");
        for (g, mesh) in crate::mesh::split_by_label(&surface.mesh, &surface.triangle_groups)
            .iter()
            .enumerate()
        {
            crate::io::write_mesh(&dir.join(format!("group_{g:04}.ply")), mesh)?;
            bar.inc(1);
        }
        bar.finish_and_clear();
    }
    if let Some(path) = &args.preview {
        let mut opened = None;
        let g = global.preview_gpu(&gpu, &mut opened)?;
        let opts = super::preview_options(
            format!(
                "chisel mc: {} at {}",
                super::file_name(&args.volume),
                match iso {
                    IsoSpec::Level(l) => format!("level {l}"),
                    IsoSpec::Label(l) => format!("label {l}"),
                }
            ),
            facing,
        );
        crate::render::render_png(g, &surface.mesh, &opts, path)?;
    }
    let report = McReport {
        command: "mc",
        volume: &args.volume,
        dims: volume.dims,
        spacing: volume.spacing,
        iso: match iso {
            IsoSpec::Level(l) => Iso::Level(l),
            IsoSpec::Label(l) => Iso::Label(l),
        },
        backend: backend.name(),
        adapter: gpu.as_ref().map(|g| g.describe()),
        vertices: surface.mesh.n_vertices(),
        triangles: surface.mesh.n_triangles(),
        group_count: (!args.no_groups).then_some(surface.groups.len()),
        groups: &surface.groups,
        timings_s: McTimings {
            read: read_s,
            marching_cubes: mc_s,
        },
        outputs: McOutputs {
            mesh: &args.output,
            groups_dir: args.groups_dir.as_deref(),
            preview: args.preview.as_deref(),
        },
    };
    let groups = if args.no_groups {
        String::new()
    } else {
        format!(" in {} groups", surface.groups.len())
    };
    global.note(format!(
        "{} triangles{groups} ({:.3} s on {}); wrote {}",
        surface.mesh.n_triangles(),
        mc_s,
        backend.name(),
        args.output.display()
    ));
    args.report.emit(&report, Show::WithJson)
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        vec![self.volume.as_path()]
    }
}
