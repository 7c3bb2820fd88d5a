//! One GPU context per process and adapter choice, opened on first use
//! and reused by every later call (`backend="gpu"`), as the command line's
//! `--backend` and `--adapter` choose.

use std::str::FromStr;
use std::sync::{Arc, Mutex};

use chisel::gpu::{AdapterChoice, Backend, Gpu, GpuOptions};
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

/// Software adapters found by `auto`, by adapter choice: probed once.
static PROBED: Mutex<Vec<(String, bool)>> = Mutex::new(Vec::new());

/// Whether `adapter` names a software adapter (or none opens: `auto`
/// then runs on the CPU, as the command line's `--backend auto`).
fn software(adapter: Option<&str>) -> Result<bool> {
    let choice = choice(adapter)?;
    let key = choice.to_string();
    let mut probed = PROBED
        .lock()
        .map_err(|_| Error::Internal("the adapter probe lock is poisoned".into()))?;
    if let Some((_, s)) = probed.iter().find(|(k, _)| *k == key) {
        return Ok(*s);
    }
    let s = chisel::gpu::probe_adapter(&choice).map_or(true, |(_, software)| software);
    probed.push((key, s));
    Ok(s)
}

/// The device `backend` asks for: `"cpu"` none, `"gpu"` the adapter's,
/// `"auto"` the adapter's unless it is a software one.
pub fn device_for(backend: &str, adapter: Option<&str>) -> Result<Option<Arc<Gpu>>> {
    match backend {
        "cpu" => Ok(None),
        "gpu" => device(adapter).map(Some),
        "auto" if software(adapter)? => Ok(None),
        "auto" => device(adapter).map(Some),
        other => Err(Error::unknown("backend", other, ["cpu", "gpu", "auto"])),
    }
}

/// Runs `f` on the backend `backend` and `adapter` ask for.
pub fn with_backend<T>(
    backend: &str,
    adapter: Option<&str>,
    f: impl FnOnce(Backend<'_>) -> Result<T>,
) -> Result<T> {
    let gpu = device_for(backend, adapter)?;
    f(gpu.as_deref().map_or(Backend::Cpu, Backend::Gpu))
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
