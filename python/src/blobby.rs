//! Blobby models fitted to range scans (`chisel blobby fit`, seed 001
//! §3): primitives split and fitted by L-BFGS until there are enough; the
//! model as blobs and as a scene file the implicit room reads.

use chisel::Result;
use chisel::blobby::RangePoints;
use chisel::blobby::Weights;
use chisel::blobby::fit::{FitOptions, FitStage, fit};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2};
use pyo3::prelude::*;
use serde::Serialize;

use crate::arrays::mesh_from;
use crate::errors::IntoPy;
use crate::json::to_json;

/// What [`blobby_fit`] reports.
#[derive(Debug, Serialize)]
struct BlobbyFigures {
    options: FitOptions,
    normals_turned: bool,
    points: usize,
    stages: Vec<FitStage>,
}

/// Fits `primitives` blobs to the scan's vertices and normals (from its
/// triangles, turned outward): `(blobs float64[N, 5] as centre x, y, z,
/// decay a, strength b; the scene TOML; report JSON)`.
#[pyfunction]
#[pyo3(signature = (vertices, triangles, primitives = 32, alpha = 0.5, beta = 1e-4, iso = 0.5, pair_iterations = 40, global_iterations = 80, energy_target = None, backend = "cpu", adapter = None))]
#[allow(clippy::too_many_arguments)]
pub fn blobby_fit<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f32>,
    triangles: &Bound<'py, PyAny>,
    primitives: usize,
    alpha: f64,
    beta: f64,
    iso: f64,
    pair_iterations: u64,
    global_iterations: u64,
    energy_target: Option<f64>,
    backend: &str,
    adapter: Option<String>,
) -> PyResult<(Bound<'py, PyAny>, String, String)> {
    let scan = mesh_from(vertices, triangles)?;
    let options = FitOptions {
        primitives,
        weights: Weights { alpha, beta },
        iso,
        pair_iterations,
        global_iterations,
        energy_target,
    };
    let (model, figures) = py
        .detach(|| -> Result<_> {
            let mut points = RangePoints::from_mesh(&scan)?;
            let normals_turned = points.orient_outward();
            let result = crate::gpu::with_backend(backend, adapter.as_deref(), |b| {
                fit(&points, &options, b, |_| {})
            })?;
            let figures = BlobbyFigures {
                options,
                normals_turned,
                points: points.len(),
                stages: result.stages,
            };
            Ok((result.model, figures))
        })
        .py_err()?;
    let n = model.blobs.len();
    let flat: Vec<f64> = model
        .blobs
        .iter()
        .flat_map(|b| [b.centre.x, b.centre.y, b.centre.z, b.a, b.b])
        .collect();
    let blobs = PyArray1::from_vec(py, flat).reshape([n, 5])?.into_any();
    let toml = model.to_scene_toml(&format!(
        "chisel.blobby_fit: {n} primitives, alpha {alpha}, beta {beta}"
    ));
    Ok((blobs, toml, to_json("blobby fit", &figures)?))
}
