//! `chisel info`: every adapter with backend, type, driver, limits and
//! features, and the one chisel would choose.

use serde::Serialize;

use super::Global;
use super::report::{Report, ReportArgs, Show};
use crate::gpu::{AdapterReport, Gpu, GpuFeatures, GpuOptions, adapter_reports};

/// The report of `chisel info`.
#[derive(Debug, Serialize)]
pub struct InfoReport {
    /// chisel's version.
    chisel: &'static str,
    /// `--adapter` / `CHISEL_ADAPTER` as given.
    requested: String,
    adapters: Vec<AdapterReport>,
    chosen: Chosen,
}

impl Report for InfoReport {
    const SCHEMA: &'static str = "chisel.info/1";
}

/// The adapter chosen, or why none could be opened.
#[derive(Debug, Serialize)]
#[serde(untagged)]
enum Chosen {
    Opened {
        name: String,
        description: String,
        features: GpuFeatures,
        max_binding_bytes: u64,
    },
    Failed {
        error: String,
    },
}

/// Arguments of `chisel info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    report: ReportArgs,
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    args.report.check()?;
    let instance = crate::gpu::instance();
    let adapters = adapter_reports(&instance);
    let choice = global.adapter_choice()?;
    let chosen = Gpu::with_options(GpuOptions {
        adapter: Some(choice.clone()),
        ..Default::default()
    });
    let report = InfoReport {
        chisel: env!("CARGO_PKG_VERSION"),
        requested: choice.to_string(),
        adapters,
        chosen: match &chosen {
            Ok(gpu) => Chosen::Opened {
                name: gpu.info.name.clone(),
                description: gpu.describe(),
                features: gpu.features,
                max_binding_bytes: gpu.max_binding_bytes(),
            },
            Err(e) => Chosen::Failed {
                error: e.to_string(),
            },
        },
    };
    args.report.emit(&report, Show::Always)?;
    chosen?;
    Ok(())
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        Vec::new()
    }
}
