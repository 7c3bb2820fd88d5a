//! `chisel info`: every adapter with backend, type, driver, limits and
//! features, and the one chisel would choose.

use serde_json::json;

use super::Global;
use crate::gpu::{AdapterChoice, Gpu, GpuOptions, adapter_reports};

/// Arguments of `chisel info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
    /// Also write the JSON report to this file.
    #[arg(long)]
    report: Option<std::path::PathBuf>,
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    if let Some(path) = &args.report {
        crate::foundation::fs::check_output_path(path)?;
    }
    let instance = crate::gpu::instance();
    let adapters = adapter_reports(&instance);
    let choice: AdapterChoice = global.adapter.parse()?;
    let chosen = Gpu::with_options(GpuOptions {
        adapter: Some(choice.clone()),
        ..Default::default()
    });
    let chosen_json = match &chosen {
        Ok(gpu) => json!({
            "name": gpu.info.name,
            "description": gpu.describe(),
            "features": gpu.features,
            "max_binding_bytes": gpu.max_binding_bytes(),
        }),
        Err(e) => json!({ "error": e.to_string() }),
    };
    let value = json!({
        "chisel": env!("CARGO_PKG_VERSION"),
        "requested": choice.to_string(),
        "adapters": adapters,
        "chosen": chosen_json,
    });
    super::report::emit(&value, args.json, args.report.as_deref())?;
    chosen?;
    Ok(())
}
