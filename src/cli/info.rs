//! `chisel info`: every adapter with backend, type, driver, limits and
//! features, and the one chisel would choose.

use super::Global;
use super::report::{ReportArgs, Show};

/// The report of `chisel info`.
/// Arguments of `chisel info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    report: ReportArgs,
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    args.report.check()?;
    let (report, chosen) = crate::gpu::info(global.adapter_choice()?);
    args.report.emit(&report, Show::Always)?;
    chosen?;
    Ok(())
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        Vec::new()
    }
}
