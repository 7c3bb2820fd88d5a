//! One GPU context per process and adapter choice, opened on first use
//! and reused by every later call (`backend="gpu"`), as the command line's
//! `--backend` and `--adapter` choose.

use std::str::FromStr;
use std::sync::{Arc, Mutex};

use chisel::gpu::{AdapterChoice, Gpu, GpuOptions};
use chisel::{Error, Result};
use pyo3::prelude::*;

use crate::errors::IntoPy;

/// The devices opened so far, by adapter choice.
static DEVICES: Mutex<Vec<(String, Arc<Gpu>)>> = Mutex::new(Vec::new());

/// `adapter` as given, else `CHISEL_ADAPTER`, else `auto`.
fn choice(adapter: Option<&str>) -> Result<AdapterChoice> {
    match adapter {
        Some(a) => AdapterChoice::from_str(a),
        None => AdapterChoice::from_env(),
    }
}

/// The process's device for `adapter`, opened on first use.
pub fn device(adapter: Option<&str>) -> Result<Arc<Gpu>> {
    let choice = choice(adapter)?;
    let key = choice.to_string();
    let mut devices = DEVICES
        .lock()
        .map_err(|_| Error::Internal("the device cache lock is poisoned".into()))?;
    if let Some((_, gpu)) = devices.iter().find(|(k, _)| *k == key) {
        return Ok(gpu.clone());
    }
    let gpu = Arc::new(Gpu::with_options(GpuOptions {
        adapter: Some(choice),
        ..Default::default()
    })?);
    devices.push((key, gpu.clone()));
    Ok(gpu)
}

/// The device `backend` asks for: `"cpu"` none, `"gpu"` the adapter's,
/// `"auto"` the adapter's unless it is a software one (as the command
/// line's `--backend auto`).
pub fn backend(backend: &str, adapter: Option<&str>) -> Result<Option<Arc<Gpu>>> {
    match backend {
        "cpu" => Ok(None),
        "gpu" => device(adapter).map(Some),
        "auto" => match chisel::gpu::probe_adapter(&choice(adapter)?) {
            Ok((_, false)) => device(adapter).map(Some),
            Ok((_, true)) | Err(_) => Ok(None),
        },
        other => Err(Error::unknown("backend", other, ["cpu", "gpu", "auto"])),
    }
}

/// The adapters and the one `adapter` opens, as `chisel info --json`.
#[pyfunction]
#[pyo3(signature = (adapter = None))]
pub fn gpu_info(py: Python<'_>, adapter: Option<String>) -> PyResult<String> {
    py.detach(|| {
        let (report, _) = chisel::gpu::info(choice(adapter.as_deref())?);
        chisel::foundation::report::to_json(&report)
    })
    .py_err()
}
