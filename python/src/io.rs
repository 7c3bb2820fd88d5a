//! Readers and writers of every format the engine supports, on numpy
//! arrays; the format follows the file's content (then its extension),
//! as on the command line.

use std::path::PathBuf;

use chisel::io::{self, ReadOptions};
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{Frame, mesh_from, mesh_to, scalars_from, scalars_to, volume_from, volume_to};
use crate::errors::IntoPy;

/// Reads a volume (a file, or a DICOM directory with `series` choosing
/// among several): `(array, (spacing, origin, axes, space), notes)`.
#[pyfunction]
#[pyo3(signature = (path, series = None))]
pub fn read_volume(
    py: Python<'_>,
    path: PathBuf,
    series: Option<String>,
) -> PyResult<(Bound<'_, PyAny>, Frame, Vec<String>)> {
    let (volume, notes) = py
        .detach(|| io::read_volume_with(&path, &ReadOptions { series }))
        .py_err()?;
    let (array, frame) = volume_to(py, volume)?;
    Ok((array, frame, notes))
}

/// Writes a volume, atomically; the format follows the extension.
#[pyfunction]
pub fn write_volume(
    py: Python<'_>,
    path: PathBuf,
    array: &Bound<'_, PyAny>,
    frame: Frame,
) -> PyResult<()> {
    let volume = volume_from(array, frame)?;
    py.detach(|| io::write_volume(&path, &volume)).py_err()
}

/// Reads a mesh: `(vertices, triangles, scalars)`, the scalars a dict of
/// per-vertex float32 arrays.
#[pyfunction]
pub fn read_mesh(
    py: Python<'_>,
    path: PathBuf,
) -> PyResult<(Bound<'_, PyAny>, Bound<'_, PyAny>, Bound<'_, PyDict>)> {
    let mesh = py.detach(|| io::read_mesh(&path)).py_err()?;
    let scalars = scalars_to(py, mesh.scalars)?;
    let (v, t) = mesh_to(py, mesh.positions, mesh.triangles)?;
    Ok((v, t, scalars))
}

/// Writes a mesh with its per-vertex scalars (where the format carries
/// them: PLY, VTK, VTP), atomically; the format follows the extension.
#[pyfunction]
#[pyo3(signature = (path, vertices, triangles, scalars = None))]
pub fn write_mesh(
    py: Python<'_>,
    path: PathBuf,
    vertices: PyReadonlyArray2<'_, f32>,
    triangles: &Bound<'_, PyAny>,
    scalars: Option<Bound<'_, PyDict>>,
) -> PyResult<()> {
    let mut mesh = mesh_from(vertices, triangles)?;
    if let Some(s) = scalars {
        mesh.scalars = scalars_from(&s)?;
    }
    py.detach(|| mesh.validate().and_then(|()| io::write_mesh(&path, &mesh)))
        .py_err()
}

/// The series of the DICOM image files under `dir` (up to four levels
/// down), as `chisel stats DIR` lists them: JSON.
#[pyfunction]
pub fn dicom_series(py: Python<'_>, dir: PathBuf) -> PyResult<String> {
    let series = py.detach(|| io::dicom_series(&dir)).py_err()?;
    crate::json::to_json("DICOM series", &series)
}
