//! `chisel scan VOLUME (--level T | --labels)`: the large-volume hull
//! scan of every structure of a volume, [`crate::volume_scan`] (SPEC §4.3);
//! the report is its [`ScanReport`].

use std::path::PathBuf;
use std::time::Instant;

use super::hull::HullArgs;
use super::report::{ReportArgs, Show};
use super::{BackendChoice, Global};
use crate::volume_scan::{MANY_LABELS, ScanInput, ScanOptions, ScanReport};

/// Arguments of `chisel scan`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Volume (any format `chisel stats` reads).
    volume: PathBuf,
    /// Structures = 6-connected components of the samples ≥ T.
    #[arg(
        long,
        conflicts_with = "labels",
        required_unless_present = "labels",
        allow_hyphen_values = true,
        value_parser = super::level_f64
    )]
    level: Option<f64>,
    /// Structures = the non-zero label values (all voxels of each label).
    #[arg(long)]
    labels: bool,
    /// Skip (and count) structures with fewer voxels.
    #[arg(long, default_value_t = 1)]
    min_voxels: u64,
    /// Where the inside-hull scan runs (`hull_rows` kernel or its CPU mirror).
    #[command(flatten)]
    backend: BackendChoice,
    #[command(flatten)]
    hull: HullArgs,
    #[command(flatten)]
    report: ReportArgs,
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    args.report.check()?;
    let t = Instant::now();
    let volume = global.read_volume(&args.volume)?;
    let read_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let gpu = global.backend(&args.backend)?;
    let adapter_s = gpu.as_ref().map(|_| t.elapsed().as_secs_f64());
    let options = ScanOptions {
        level: args.level,
        min_voxels: args.min_voxels,
        candidates: args.hull.kind(),
        hull: args.hull.options(),
    };
    let input = ScanInput {
        path: &args.volume,
        read_s,
        gpu: gpu.as_ref(),
        adapter_s,
    };
    let bar = global.progress(0, "structures");
    let report: ScanReport =
        crate::volume_scan::scan(&volume, input, &options, &mut |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
            Ok(())
        })?;
    bar.finish_and_clear();
    if args.level.is_none() && report.structures > MANY_LABELS {
        eprintln!(
            "warning: {}: {} distinct labels; an intensity volume (a CT) is scanned \
             per threshold (--level T), not per label",
            args.volume.display(),
            report.structures
        );
    }
    let zkh = &report.zkh;
    global.note(format!(
        "{} structures ({} scanned, {} skipped below {} voxels, {} degenerate); {} ZKHs \
         ({} cavities, {} concavities, {} tunnels, {} branched) in {:.3} s on {}",
        report.structures,
        report.scanned,
        report.skipped.count,
        args.min_voxels,
        report.degenerate,
        zkh.count,
        zkh.cavities.count,
        zkh.concavities.count,
        zkh.tunnels.count,
        zkh.branched_tunnels.count,
        report.timings_s.total,
        report.backend,
    ));
    args.report.emit(&report, Show::WithJson)
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        vec![self.volume.as_path()]
    }
}
