//! Volume-preserving fusion, subtraction and morphing of meshes by ray
//! casting from a common centre (`chisel fuse`, `chisel morph`, seed 001).

use chisel::fusion::{
    FuseOptions, FusionReport, MorphOptions, MorphReport, RefineOptions, fuse as run_fuse,
    morph as run_morph,
};
use chisel::{Error, Result};
use glam::Vec3;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2};
use pyo3::prelude::*;

use crate::arrays::{MeshArrays, mesh_from, mesh_to};
use crate::errors::IntoPy;
use crate::json::to_json;

/// Two input meshes.
type Pair<'py> = (
    PyReadonlyArray2<'py, f32>,
    Bound<'py, PyAny>,
    PyReadonlyArray2<'py, f32>,
    Bound<'py, PyAny>,
);

fn refine(
    tolerance: Option<f64>,
    start_level: Option<u32>,
    max_triangles: Option<usize>,
) -> RefineOptions {
    let d = RefineOptions::default();
    RefineOptions {
        tolerance,
        start_level: start_level.unwrap_or(d.start_level),
        max_triangles: max_triangles.unwrap_or(d.max_triangles),
    }
}

/// The fusion of `a` and `b` (their volumes add; `subtract`: b's is
/// taken away): `(mesh, report JSON)`.
#[pyfunction]
#[pyo3(signature = (meshes, subtract = false, center = None, tolerance = None, start_level = None, max_triangles = None, cells = None, backend = "cpu", adapter = None))]
#[allow(clippy::too_many_arguments)]
pub fn fuse<'py>(
    py: Python<'py>,
    meshes: Pair<'py>,
    subtract: bool,
    center: Option<[f32; 3]>,
    tolerance: Option<f64>,
    start_level: Option<u32>,
    max_triangles: Option<usize>,
    cells: Option<usize>,
    backend: &str,
    adapter: Option<String>,
) -> PyResult<(MeshArrays<'py>, String)> {
    let (av, at, bv, bt) = meshes;
    let (a, b) = (mesh_from(av, &at)?, mesh_from(bv, &bt)?);
    let defaults = FuseOptions::default();
    let options = FuseOptions {
        center: center.map(Vec3::from_array),
        subtract,
        refine: refine(tolerance, start_level, max_triangles),
        cells: cells.unwrap_or(defaults.cells),
    };
    let fused = py
        .detach(|| -> Result<_> {
            crate::gpu::with_backend(backend, adapter.as_deref(), |on| {
                run_fuse(&a, &b, &options, on, |_| {})
            })
        })
        .py_err()?;
    let report: FusionReport = fused.report;
    Ok((
        mesh_to(py, fused.mesh.positions, fused.mesh.triangles)?,
        to_json("fusion", &report)?,
    ))
}

/// `a` morphed into `b` over `frames` frames of one connectivity:
/// `(vertices float32[frames, V, 3], triangles, report JSON)`.
#[pyfunction]
#[pyo3(signature = (meshes, frames = 9, center = None, center_end = None, tolerance = None, start_level = None, max_triangles = None, backend = "cpu", adapter = None))]
#[allow(clippy::too_many_arguments)]
pub fn morph<'py>(
    py: Python<'py>,
    meshes: Pair<'py>,
    frames: usize,
    center: Option<[f32; 3]>,
    center_end: Option<[f32; 3]>,
    tolerance: Option<f64>,
    start_level: Option<u32>,
    max_triangles: Option<usize>,
    backend: &str,
    adapter: Option<String>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, String)> {
    let (av, at, bv, bt) = meshes;
    let (a, b) = (mesh_from(av, &at)?, mesh_from(bv, &bt)?);
    let options = MorphOptions {
        center: center.map(Vec3::from_array),
        center_end: center_end.map(Vec3::from_array),
        frames,
        refine: refine(tolerance, start_level, max_triangles),
    };
    let morph = py
        .detach(|| -> Result<_> {
            crate::gpu::with_backend(backend, adapter.as_deref(), |on| {
                run_morph(&a, &b, &options, on, |_| {})
            })
        })
        .py_err()?;
    let report: MorphReport = morph.report;
    let mut frames_out = morph.frames.into_iter();
    let first = frames_out
        .next()
        .ok_or_else(|| crate::errors::to_py(Error::Internal("a morph without frames".into())))?;
    let n_vertices = first.positions.len();
    let mut flat: Vec<f32> = first.positions.iter().flat_map(|p| p.to_array()).collect();
    let mut n_frames = 1;
    for f in frames_out {
        flat.extend(f.positions.iter().flat_map(|p| p.to_array()));
        n_frames += 1;
    }
    let vertices = PyArray1::from_vec(py, flat)
        .reshape([n_frames, n_vertices, 3])?
        .into_any();
    let (_, triangles) = mesh_to(py, Vec::new(), first.triangles)?;
    Ok((vertices, triangles, to_json("morph", &report)?))
}
