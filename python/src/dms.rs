//! DMS spline surfaces (`chisel spline`, seed 000 ch. 2): a mesh's
//! parametrisation, knot clouds, the quadratic basis and a fit, evaluated
//! on a lattice.

use chisel::dms::fit::FitReport;
use chisel::dms::param::Projection;
use chisel::dms::spline::{Fit, SplineOptions, SplineTimings, spline as run_spline};
use chisel::{Error, Result};
use glam::{DVec2, Vec3};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use serde::Serialize;

use crate::arrays::{mesh_from, mesh_to, scalars_to};
use crate::errors::IntoPy;
use crate::json::to_json;

/// The figures [`spline`] returns.
#[derive(Debug, Serialize)]
struct SplineFigures {
    fit: FitReport,
    knot_quality: f64,
    timings_s: SplineTimings,
}

/// A mesh as `(vertices, triangles, scalars)`.
type MeshWithScalars<'py> = (Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>);
/// `(surface, controls float64[C, 3], control net, figures JSON)`.
type SplineResult<'py> = (
    MeshWithScalars<'py>,
    Bound<'py, PyAny>,
    (Bound<'py, PyAny>, Bound<'py, PyAny>),
    String,
);

/// The spline of a mesh evaluated at `n` points per parameter edge.
#[pyfunction]
#[pyo3(signature = (vertices, triangles, n, param = "cylinder", uv = None, fit = "quasi", data = None, fairing = 0.0, backend = "cpu", adapter = None))]
#[allow(clippy::too_many_arguments)]
pub fn spline<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f32>,
    triangles: &Bound<'py, PyAny>,
    n: u32,
    param: &str,
    uv: Option<PyReadonlyArray2<'py, f64>>,
    fit: &str,
    data: Option<PyReadonlyArray2<'py, f32>>,
    fairing: f64,
    backend: &str,
    adapter: Option<String>,
) -> PyResult<SplineResult<'py>> {
    let mesh = mesh_from(vertices, triangles)?;
    let columns = |name: &str, shape: &[usize], n: usize| {
        if shape[1] == n {
            Ok(())
        } else {
            Err(crate::errors::to_py(Error::param(
                name,
                format!("shape {shape:?}"),
                format!("{n} columns"),
            )))
        }
    };
    if let Some(uv) = &uv {
        columns("uv", uv.shape(), 2)?;
    }
    if let Some(d) = &data {
        columns("data", d.shape(), 3)?;
    }
    let projection = match (param, uv) {
        ("given", Some(uv)) => Projection::Given(
            uv.as_array()
                .rows()
                .into_iter()
                .map(|r| DVec2::new(r[0], r[1]))
                .collect(),
        ),
        ("cylinder", None) => Projection::Cylinder,
        ("planar", None) => Projection::Planar,
        (p, uv) => {
            return Err(crate::errors::to_py(Error::param(
                "param",
                format!("{p} (uv {})", if uv.is_some() { "given" } else { "none" }),
                "\"cylinder\" or \"planar\" without uv, \"given\" with uv float64[N, 2]",
            )));
        }
    };
    let fit = match fit {
        "identify" => Fit::Identify,
        "quasi" => Fit::Quasi,
        "lsq" => Fit::LeastSquares { fairing },
        other => {
            return Err(crate::errors::to_py(Error::unknown(
                "fit",
                other,
                ["identify", "quasi", "lsq"],
            )));
        }
    };
    let data: Option<Vec<Vec3>> = data.map(|d| {
        d.as_array()
            .rows()
            .into_iter()
            .map(|r| Vec3::new(r[0], r[1], r[2]))
            .collect()
    });
    let options = SplineOptions {
        projection,
        fit,
        data,
        n,
    };
    let (figures, surface, net) = py
        .detach(|| -> Result<_> {
            let (domain, surface) = crate::gpu::with_backend(backend, adapter.as_deref(), |b| {
                run_spline(&mesh, &options, b)
            })?;
            let net = domain.control_mesh(&surface.controls);
            let figures = SplineFigures {
                fit: surface.fit.clone(),
                knot_quality: domain.knot_quality,
                timings_s: domain.timings.clone(),
            };
            Ok((figures, surface, net))
        })
        .py_err()?;
    let n_controls = surface.controls.len();
    let flat: Vec<f64> = surface.controls.iter().flat_map(|c| c.to_array()).collect();
    let controls = PyArray1::from_vec(py, flat)
        .reshape([n_controls, 3])?
        .into_any();
    let scalars = scalars_to(py, surface.mesh.scalars)?.into_any();
    let (v, t) = mesh_to(py, surface.mesh.positions, surface.mesh.triangles)?;
    Ok((
        (v, t, scalars),
        controls,
        mesh_to(py, net.positions, net.triangles)?,
        to_json("spline", &figures)?,
    ))
}
