//! The `chisel` command line (SPEC §0.7): one module per command.
//!
//! Conventions shared by every command: `--adapter` picks the GPU (same
//! values as `CHISEL_ADAPTER`), `--backend auto|cpu|gpu` picks where
//! data-parallel work runs (one default, `auto`, printed when chosen), `--quiet` hides progress bars (they also hide when stderr is
//! not a terminal), `--json` prints the report on stdout, `--report FILE`
//! writes it atomically.

mod bench;
mod blobby;
mod convert;
mod cut;
mod demo;
mod fuse;
mod hull;
mod implicit;
mod info;
mod mc;
mod morph;
mod phantom;
mod polyhedrize;
mod relax;
mod render;
mod report;
mod scan;
mod spline;
mod stats;

use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

use crate::gpu::{AdapterChoice, Gpu, GpuOptions};

/// chisel: GPU compute for surgical-planning geometry.
#[derive(Debug, Parser)]
#[command(name = "chisel", version, about, long_about = None)]
pub struct Cli {
    #[command(flatten)]
    global: Global,
    #[command(subcommand)]
    command: Command,
}

/// Options every command accepts.
#[derive(Debug, Clone, clap::Args)]
pub struct Global {
    /// GPU adapter: auto, cpu (lavapipe), an index from `chisel info`, or a
    /// name substring [default: `CHISEL_ADAPTER`, else `WGPU_ADAPTER_NAME`,
    /// else auto].
    #[arg(long, global = true)]
    adapter: Option<String>,
    /// Hide progress bars and informational messages.
    #[arg(long, short, global = true)]
    quiet: bool,
    /// DICOM directories holding several series: the SeriesInstanceUID to
    /// read (`chisel stats DIR` lists them).
    #[arg(long, global = true, value_name = "UID")]
    series: Option<String>,
}

/// Preview axes: which world directions are up and front in the views
/// (default: +y up, front chosen by [`crate::render::Facing::Auto`]).
#[derive(Debug, Clone, Default, clap::Args)]
pub struct ViewAxes {
    /// World direction that is up in the previews `x,y,z` (headsq: 0,0,-1).
    #[arg(
        long,
        value_delimiter = ',',
        num_args = 1,
        allow_hyphen_values = true,
        requires = "view_front"
    )]
    view_up: Option<Vec<f32>>,
    /// World direction the front view looks from `x,y,z` (headsq: 0,-1,0).
    #[arg(
        long,
        value_delimiter = ',',
        num_args = 1,
        allow_hyphen_values = true,
        requires = "view_up"
    )]
    view_front: Option<Vec<f32>>,
}

impl ViewAxes {
    /// The facing rule these options ask for.
    pub fn facing(&self) -> anyhow::Result<crate::render::Facing> {
        let v = |name: &str, a: &Option<Vec<f32>>| -> anyhow::Result<Option<glam::Vec3>> {
            let v = vec3_arg(name, a.as_deref())?;
            anyhow::ensure!(
                v.is_none_or(|v| v.length() > 0.0),
                "--{name} takes a non-zero x,y,z"
            );
            Ok(v)
        };
        Ok(
            match (
                v("view-up", &self.view_up)?,
                v("view-front", &self.view_front)?,
            ) {
                (Some(up), Some(front)) => {
                    anyhow::ensure!(
                        up.normalize().cross(front.normalize()).length() > 1e-3,
                        "--view-up and --view-front must not be parallel"
                    );
                    crate::render::Facing::Anatomical { up, front }
                }
                _ => crate::render::Facing::Auto,
            },
        )
    }
}

/// A `x,y,z` option as a vector; `name` (without `--`) for the error.
pub(super) fn vec3_arg(name: &str, v: Option<&[f32]>) -> anyhow::Result<Option<glam::Vec3>> {
    match v {
        None => Ok(None),
        Some(&[x, y, z]) => Ok(Some(glam::Vec3::new(x, y, z))),
        Some(o) => anyhow::bail!("--{name} takes x,y,z; got {} numbers", o.len()),
    }
}

/// The file name of `path` for preview titles (a long folder would push
/// the name and the figures out of the title).
pub(super) fn file_name(path: &std::path::Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// A level or label option: any number but NaN (`inf`, `-inf` and negative
/// numbers are values; the options that take one also accept a leading
/// hyphen).
pub(super) fn level_f64(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number"))?;
    if v.is_nan() {
        return Err("NaN compares false with every sample; give a number (±inf allowed)".into());
    }
    Ok(v)
}

/// [`level_f64`] for f32 options.
pub(super) fn level_f32(s: &str) -> Result<f32, String> {
    level_f64(s).map(|v| v as f32)
}

/// Checks an output folder before any work is done: not an existing file,
/// in a folder that exists (it is created when the outputs are written).
pub(super) fn check_output_dir(dir: &std::path::Path) -> anyhow::Result<()> {
    if dir.exists() && !dir.is_dir() {
        anyhow::bail!("{}: is a file; expected an output folder", dir.display());
    }
    Ok(crate::foundation::fs::check_parent_folder(dir)?)
}

/// Creates `dir` and removes the `{prefix}NNN.ply` files an earlier run
/// left there, so that the folder holds this run's numbered outputs only;
/// other files are left alone.
pub(super) fn clear_numbered_outputs(
    global: &Global,
    dir: &std::path::Path,
    prefix: &str,
) -> anyhow::Result<()> {
    let io = |e| crate::Error::io(dir, e);
    std::fs::create_dir_all(dir).map_err(io)?;
    let mut removed = 0;
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let entry = entry.map_err(io)?;
        let name = entry.file_name();
        let numbered = name
            .to_string_lossy()
            .strip_prefix(prefix)
            .and_then(|r| r.strip_suffix(".ply"))
            .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()));
        if numbered && entry.file_type().is_ok_and(|t| t.is_file()) {
            crate::foundation::fs::check_output_path(&entry.path())?;
            std::fs::remove_file(entry.path()).map_err(|e| crate::Error::io(entry.path(), e))?;
            removed += 1;
        }
    }
    if removed > 0 {
        global.note(format!(
            "removed {removed} {prefix}*.ply files of an earlier run from {}",
            dir.display()
        ));
    }
    Ok(())
}

/// The preview a mesh-making command writes with `--preview`: four views
/// (front, side, top, iso) of 384 px, titled, in the chosen facing.
fn preview_options(title: String, facing: crate::render::Facing) -> crate::render::RenderOptions {
    crate::render::RenderOptions {
        views: vec![
            crate::render::View::Front,
            crate::render::View::Right,
            crate::render::View::Top,
            crate::render::View::Iso,
        ],
        width: 384,
        height: 384,
        title: Some(title),
        facing,
        ..Default::default()
    }
}

/// Where data-parallel work runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BackendArg {
    /// The GPU when the chosen adapter is a hardware GPU, else the CPU
    /// (whose fast paths beat a software adapter such as lavapipe).
    Auto,
    /// The CPU paths of each kernel.
    Cpu,
    /// The WGSL kernels on the chosen adapter (a software one included).
    Gpu,
}

/// `--backend`: the same flag, default and behaviour in every command
/// with data-parallel work; the choice is printed (unless `--quiet`) and
/// named in the report.
#[derive(Debug, Clone, clap::Args)]
pub struct BackendChoice {
    /// Where data-parallel work runs: `auto` (the GPU when the adapter is a
    /// hardware GPU, else the CPU), `cpu` or `gpu`.
    #[arg(long, value_enum, default_value = "auto")]
    backend: BackendArg,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// List GPU adapters (backend, type, driver, limits, features) and the chosen one.
    Info(info::Args),
    /// Figures of a mesh (topology, orientation) or a volume (range, labels, components).
    Stats(stats::Args),
    /// Convert between mesh formats (vtk, ply, obj, stl, byu) or volume formats.
    Convert(convert::Args),
    /// Marching cubes with one-pass grouping: iso-surface or label boundary of a volume.
    Mc(mc::Args),
    /// Cut a mesh with plane / rectangle / sphere / mesh scalpels (optionally capped).
    Cut(cut::Args),
    /// Relax the soft tissue over the bone after a surgery plan (spring network, GPU or CPU).
    Relax(relax::Args),
    /// Smooth DMS spline surface of a disk mesh (knot clouds, GPU basis, control net, normals).
    Spline(spline::Args),
    /// Skeletal implicit scene sampled over its time span by Witkin–Heckbert particles.
    Implicit(implicit::Args),
    /// Blobby models: `blobby fit` fits one to a range scan (a scene `implicit` reads).
    Blobby(blobby::Args),
    /// Fuse two closed star-shaped meshes into one of their summed volume (or subtract B from A).
    Fuse(fuse::Args),
    /// Morph A into B (volume linear in t) as frames with one connectivity.
    Morph(morph::Args),
    /// Exact convex hull of a voxel object: cell list, eq. 8.2 storage, ZKH classes.
    Hull(hull::Args),
    /// Lossless polyhedron of a voxel object: nested convex shells, .cells, --verify.
    Polyhedrize(polyhedrize::Args),
    /// Large-volume hull scan: hull, inside-hull counts and ZKH classes of every component or label.
    Scan(scan::Args),
    /// Write a test object volume: the seed's balls, cylinders, tori, dented ellipsoids; the CT head.
    Phantom(phantom::Args),
    /// Render a mesh to a PNG preview (shaded, views, wireframe, scalar colour map).
    Render(render::Args),
    /// The main job on embedded generated data: phantom → GPU kernels → previews + report.
    Demo(demo::Args),
    /// Benchmarks with JSON reports: `bench relax` (tissue step kernels, CPU and GPU in one run).
    Bench(bench::Args),
}

impl Global {
    /// Opens the GPU this invocation asked for.
    fn gpu(&self) -> anyhow::Result<Gpu> {
        let gpu = self.open_gpu()?;
        if !self.quiet {
            eprintln!("adapter: {}", gpu.describe());
        }
        Ok(gpu)
    }

    /// The GPU that `--backend` asks for, `None` for the CPU; prints the
    /// choice (and, for `auto`, why).
    fn backend(&self, choice: &BackendChoice) -> anyhow::Result<Option<Gpu>> {
        let gpu = match choice.backend {
            BackendArg::Cpu => None,
            BackendArg::Gpu => Some(self.open_gpu()?),
            BackendArg::Auto => {
                let adapter = self.adapter_choice()?;
                match crate::gpu::probe_adapter(&adapter) {
                    Ok((_, false)) => Some(self.open_gpu()?),
                    Ok((name, true)) => {
                        self.note(format!(
                            "backend: cpu (auto: the adapter {name} is a software one; \
                             `--backend gpu` runs the kernels on it)"
                        ));
                        return Ok(None);
                    }
                    Err(e) => {
                        self.note(format!("backend: cpu (auto: {e})"));
                        return Ok(None);
                    }
                }
            }
        };
        match &gpu {
            Some(g) => self.note(format!("backend: gpu on {}", g.describe())),
            None => self.note("backend: cpu"),
        }
        Ok(gpu)
    }

    /// The adapter `--adapter` names, else the library's rule
    /// ([`AdapterChoice::from_env`]: `CHISEL_ADAPTER`, `WGPU_ADAPTER_NAME`, auto).
    fn adapter_choice(&self) -> crate::Result<AdapterChoice> {
        match &self.adapter {
            Some(a) => a.parse(),
            None => AdapterChoice::from_env(),
        }
    }

    /// Opens the GPU without printing it.
    fn open_gpu(&self) -> anyhow::Result<Gpu> {
        let adapter = self.adapter_choice()?;
        Ok(Gpu::with_options(GpuOptions {
            adapter: Some(adapter),
            ..Default::default()
        })?)
    }

    /// The GPU a preview renders on: the backend's (`gpu`) when the command
    /// runs on one, else one opened into `opened` (the renderer needs a
    /// device even for a CPU run).
    fn preview_gpu<'g>(
        &self,
        gpu: &'g Option<Gpu>,
        opened: &'g mut Option<Gpu>,
    ) -> anyhow::Result<&'g Gpu> {
        Ok(match gpu {
            Some(g) => g,
            None => opened.insert(self.gpu()?),
        })
    }

    /// A progress bar on stderr (hidden with `--quiet` or without a terminal).
    fn progress(&self, len: u64, what: &str) -> indicatif::ProgressBar {
        if self.quiet {
            return indicatif::ProgressBar::hidden();
        }
        let bar = indicatif::ProgressBar::new(len);
        bar.set_style(
            indicatif::ProgressStyle::with_template("{msg:>12} [{bar:30}] {pos}/{len} {elapsed}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar.set_message(what.to_string());
        bar
    }

    /// Reads a volume (a file or a DICOM directory, `--series` choosing
    /// among several series) and prints the reader's notes.
    fn read_volume(&self, path: &std::path::Path) -> anyhow::Result<crate::Volume> {
        let options = crate::io::ReadOptions {
            series: self.series.clone(),
        };
        let (volume, notes) = crate::io::read_volume_with(path, &options)?;
        for note in notes {
            self.note(format!("{}: {note}", path.display()));
        }
        Ok(volume)
    }

    /// Prints an informational line unless `--quiet`.
    fn note(&self, msg: impl std::fmt::Display) {
        if !self.quiet {
            eprintln!("{msg}");
        }
    }
}

/// The files a command reads, as its command line names them: the input
/// guard ([`crate::foundation::fs::guard_inputs`]) starts from them before
/// any work, so no output of the command can overwrite one.
trait Inputs {
    fn inputs(&self) -> Vec<&std::path::Path>;
}

impl Command {
    fn inputs(&self) -> Vec<&std::path::Path> {
        match self {
            Command::Info(a) => a.inputs(),
            Command::Stats(a) => a.inputs(),
            Command::Convert(a) => a.inputs(),
            Command::Mc(a) => a.inputs(),
            Command::Cut(a) => a.inputs(),
            Command::Relax(a) => a.inputs(),
            Command::Spline(a) => a.inputs(),
            Command::Implicit(a) => a.inputs(),
            Command::Blobby(a) => a.inputs(),
            Command::Fuse(a) => a.inputs(),
            Command::Morph(a) => a.inputs(),
            Command::Hull(a) => a.inputs(),
            Command::Polyhedrize(a) => a.inputs(),
            Command::Scan(a) => a.inputs(),
            Command::Phantom(a) => a.inputs(),
            Command::Render(a) => a.inputs(),
            Command::Demo(a) => a.inputs(),
            Command::Bench(a) => a.inputs(),
        }
    }
}

/// Parses arguments, runs the command, maps errors to exit code 1 (2 for usage).
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    crate::foundation::fs::guard_inputs(&cli.command.inputs());
    let result = match &cli.command {
        Command::Info(a) => info::run(&cli.global, a),
        Command::Stats(a) => stats::run(&cli.global, a),
        Command::Convert(a) => convert::run(&cli.global, a),
        Command::Mc(a) => mc::run(&cli.global, a),
        Command::Cut(a) => cut::run(&cli.global, a),
        Command::Relax(a) => relax::run(&cli.global, a),
        Command::Spline(a) => spline::run(&cli.global, a),
        Command::Implicit(a) => implicit::run(&cli.global, a),
        Command::Blobby(a) => blobby::run(&cli.global, a),
        Command::Fuse(a) => fuse::run(&cli.global, a),
        Command::Morph(a) => morph::run(&cli.global, a),
        Command::Hull(a) => hull::run(&cli.global, a),
        Command::Polyhedrize(a) => polyhedrize::run(&cli.global, a),
        Command::Scan(a) => scan::run(&cli.global, a),
        Command::Phantom(a) => phantom::run(&cli.global, a),
        Command::Render(a) => render::run(&cli.global, a),
        Command::Demo(a) => demo::run(&cli.global, a),
        Command::Bench(a) => bench::run(&cli.global, a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    /// clap's own checks of every command's arguments (unique names,
    /// valid `requires`/`conflicts_with` targets), which otherwise fire only
    /// when that command runs.
    #[test]
    fn every_command_line_is_well_formed() {
        use clap::CommandFactory;
        super::Cli::command().debug_assert();
    }
}
