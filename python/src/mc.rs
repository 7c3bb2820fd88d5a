//! Marching cubes of a numpy volume (`chisel mc`), with the seed's
//! grouping: the mesh, each triangle's group and the groups' figures.

use chisel::gpu::Backend;
use chisel::mc::{IsoSpec, McOptions};
use chisel::{Error, Result};
use numpy::PyArray1;
use pyo3::prelude::*;

use crate::arrays::{Frame, HeldVolume, mesh_to};
use crate::errors::IntoPy;

/// `(vertices, triangles, triangle_groups or None, groups as JSON)`.
type McResult<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Option<Bound<'py, PyAny>>,
    String,
);

/// The iso-surface at `level` (samples ≥ level inside) or the boundary of
/// the voxels equal to `label`, in world units: `(vertices, triangles,
/// triangle_groups or None, groups as JSON)`.
#[pyfunction]
#[pyo3(signature = (array, frame, level = None, label = None, close_border = false, groups = true, backend = "cpu", adapter = None))]
#[allow(clippy::too_many_arguments)]
pub fn marching_cubes<'py>(
    py: Python<'py>,
    array: &Bound<'py, PyAny>,
    frame: Frame,
    level: Option<f64>,
    label: Option<f64>,
    close_border: bool,
    groups: bool,
    backend: &str,
    adapter: Option<String>,
) -> PyResult<McResult<'py>> {
    let iso = match (level, label) {
        (Some(l), None) => Ok(IsoSpec::Level(l as f32)),
        (None, Some(l)) => Ok(IsoSpec::Label(l)),
        _ => Err(Error::param(
            "level, label",
            format!("{level:?}, {label:?}"),
            "give exactly one of them",
        )),
    }
    .py_err()?;
    // A C-ordered array is read in place, not copied.
    let held = HeldVolume::of(array, frame)?;
    let volume = held.view()?;
    let surface = py
        .detach(|| -> Result<_> {
            let gpu = crate::gpu::backend(backend, adapter.as_deref())?;
            let backend = gpu.as_deref().map_or(Backend::Cpu, Backend::Gpu);
            let options = McOptions {
                close_border,
                mesh_only: !groups,
            };
            chisel::mc::marching_cubes(volume, iso, &options, backend)
        })
        .py_err()?;
    let figures = serde_json::to_string(&surface.groups)
        .map_err(|e| crate::errors::to_py(Error::Internal(format!("groups to JSON: {e}"))))?;
    let triangle_groups =
        groups.then(|| PyArray1::from_vec(py, surface.triangle_groups).into_any());
    let (v, t) = mesh_to(py, surface.mesh.positions, surface.mesh.triangles)?;
    Ok((v, t, triangle_groups, figures))
}
