//! Marching cubes of a numpy volume (`chisel mc`), with the seed's
//! grouping: the mesh, each triangle's group and the groups' figures.

use chisel::Result;
use chisel::mc::{IsoSpec, McOptions};
use numpy::PyArray1;
use pyo3::prelude::*;

use crate::arrays::{Frame, HeldVolume, mesh_to};
use crate::errors::IntoPy;
use crate::json::to_json;
use crate::options::Iso;

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
    let iso = match Iso::of(level, label).py_err()? {
        Iso::Level(l) => IsoSpec::Level(l as f32),
        Iso::Label(l) => IsoSpec::Label(l),
    };
    // A C-ordered array is read in place, not copied.
    let held = HeldVolume::of(array, frame)?;
    let volume = held.view()?;
    let surface = py
        .detach(|| -> Result<_> {
            let options = McOptions {
                close_border,
                mesh_only: !groups,
            };
            crate::gpu::with_backend(backend, adapter.as_deref(), |b| {
                chisel::mc::marching_cubes(volume, iso, &options, b)
            })
        })
        .py_err()?;
    let figures = to_json("groups", &surface.groups)?;
    let triangle_groups =
        groups.then(|| PyArray1::from_vec(py, surface.triangle_groups).into_any());
    let (v, t) = mesh_to(py, surface.mesh.positions, surface.mesh.triangles)?;
    Ok((v, t, triangle_groups, figures))
}
