//! The large-volume hull scan (`chisel scan`) of a numpy volume or of a
//! file: the report as JSON, equal to `chisel scan --json` but for
//! `timings_s`. `progress(done, total)` runs after each structure, with
//! the GIL held; an exception it raises, or Ctrl-C, stops the scan.

use std::path::{Path, PathBuf};
use std::time::Instant;

use chisel::foundation::report::to_json;
use chisel::io::ReadOptions;
use chisel::volume::Volume;
use chisel::volume_scan::{ScanInput, ScanOptions};
use chisel::{Error, Result};
use pyo3::prelude::*;

use crate::arrays::{Frame, volume_from};
use crate::errors::IntoPy;
use crate::options::HullArgs;
use crate::progress::Progress;

/// The options as the command line names them.
fn options(
    level: Option<f64>,
    labels: bool,
    min_voxels: u64,
    hull: HullArgs<'_>,
) -> Result<ScanOptions> {
    let level = match (crate::options::level(level)?, labels) {
        (Some(t), false) => Some(t),
        (None, true) => None,
        _ => {
            return Err(Error::param(
                "level, labels",
                format!("{level:?}, {labels}"),
                "give a level or labels=True: one of them",
            ));
        }
    };
    let (candidates, hull) = hull.parse()?;
    Ok(ScanOptions {
        level,
        min_voxels,
        candidates,
        hull,
    })
}

/// Runs the scan with the GIL released, calling `progress` (and checking
/// for Ctrl-C) with the GIL after each structure.
fn run(
    py: Python<'_>,
    path: &Path,
    volume: Result<(Volume, f64)>,
    options: ScanOptions,
    backend: &str,
    adapter: Option<&str>,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    let mut progress = Progress::new(progress, format!("{}: scan", path.display()));
    let result = py.detach(|| -> Result<String> {
        let (volume, read_s) = volume?;
        let t = Instant::now();
        let gpu = crate::gpu::device_for(backend, adapter)?;
        let adapter_s = gpu.as_ref().map(|_| t.elapsed().as_secs_f64());
        let input = ScanInput {
            path,
            read_s,
            gpu: gpu.as_deref(),
            adapter_s,
        };
        let report = chisel::volume_scan::scan(&volume, input, &options, &mut |done, total| {
            progress.tick(done, total)
        })?;
        to_json(&report)
    });
    progress.finish(result)
}

/// Scans a numpy volume; `name` stands for its path in the report.
#[pyfunction]
#[pyo3(signature = (array, frame, name, level = None, labels = false, min_voxels = 1, corners = "local26", vertices = "voxels", coplanar = "merge", order = "furthest", backend = "cpu", adapter = None, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn scan(
    py: Python<'_>,
    array: &Bound<'_, PyAny>,
    frame: Frame,
    name: PathBuf,
    level: Option<f64>,
    labels: bool,
    min_voxels: u64,
    corners: &str,
    vertices: &str,
    coplanar: &str,
    order: &str,
    backend: &str,
    adapter: Option<String>,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    let hull = HullArgs {
        corners,
        vertices,
        coplanar,
        order,
    };
    let options = options(level, labels, min_voxels, hull).py_err()?;
    let volume = volume_from(array, frame)?;
    run(
        py,
        &name,
        Ok((volume, 0.0)),
        options,
        backend,
        adapter.as_deref(),
        progress,
    )
}

/// Reads and scans a volume file (a DICOM directory with `series`): the
/// report of `chisel scan PATH --json` with these options.
#[pyfunction]
#[pyo3(signature = (path, level = None, labels = false, min_voxels = 1, corners = "local26", vertices = "voxels", coplanar = "merge", order = "furthest", backend = "cpu", adapter = None, series = None, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn scan_file(
    py: Python<'_>,
    path: PathBuf,
    level: Option<f64>,
    labels: bool,
    min_voxels: u64,
    corners: &str,
    vertices: &str,
    coplanar: &str,
    order: &str,
    backend: &str,
    adapter: Option<String>,
    series: Option<String>,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    let hull = HullArgs {
        corners,
        vertices,
        coplanar,
        order,
    };
    let options = options(level, labels, min_voxels, hull).py_err()?;
    let volume = py.detach(|| {
        let t = Instant::now();
        chisel::io::read_volume_with(&path, &ReadOptions { series })
            .map(|(v, _)| (v, t.elapsed().as_secs_f64()))
    });
    run(
        py,
        &path,
        volume,
        options,
        backend,
        adapter.as_deref(),
        progress,
    )
}
