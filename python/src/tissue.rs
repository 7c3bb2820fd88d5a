//! Soft-tissue relaxation (`chisel relax`): a plan's bone cuts and moves,
//! the spring network between skin and bone relaxed to equilibrium.

use std::path::PathBuf;

use chisel::tissue::network::{Material, Stiffness};
use chisel::tissue::{
    BoneCutFigures, Fragments, Job, NetworkParams, Plan, RelaxOptions, RelaxReport, Solver,
};
use chisel::{Error, Result};
use numpy::{PyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use serde::Serialize;

use crate::arrays::{MeshArrays, mesh_from, mesh_to};
use crate::errors::IntoPy;
use crate::json::to_json;

/// The report [`relax`] returns.
#[derive(Debug, Serialize)]
struct Relaxation {
    relax: RelaxReport,
    bone_cut: Option<BoneCutFigures>,
}

/// Relaxes `skin` over `bone` (`None`: the skin scaled by the network's
/// bone scale) as the plan (a file path, TOML or JSON, or a plan as JSON
/// text) moves the bone: `(relaxed skin, displacement float32[N], report
/// JSON)`. The report is the engine's relaxation report plus `bone_cut`.
#[pyfunction]
#[pyo3(signature = (skin_vertices, skin_triangles, bone = None, plan_path = None, plan_json = None, solver = "explicit", force_dt = false, bending = None, subcutis_depth = None, origin = None, backend = "cpu", adapter = None))]
#[allow(clippy::too_many_arguments)]
pub fn relax<'py>(
    py: Python<'py>,
    skin_vertices: PyReadonlyArray2<'py, f32>,
    skin_triangles: &Bound<'py, PyAny>,
    bone: Option<(PyReadonlyArray2<'py, f32>, Bound<'py, PyAny>)>,
    plan_path: Option<PathBuf>,
    plan_json: Option<String>,
    solver: &str,
    force_dt: bool,
    bending: Option<f32>,
    subcutis_depth: Option<f32>,
    origin: Option<[f32; 3]>,
    backend: &str,
    adapter: Option<String>,
) -> PyResult<(MeshArrays<'py>, Bound<'py, PyAny>, String)> {
    let skin = mesh_from(skin_vertices, skin_triangles)?;
    let bone = match bone {
        Some((v, t)) => Some(mesh_from(v, &t)?),
        None => None,
    };
    let solver: Solver = solver.parse().py_err()?;
    let (report, relaxed, displacement) = py
        .detach(|| -> Result<_> {
            let plan = match (&plan_path, &plan_json) {
                (Some(p), None) => Plan::from_path(p)?,
                (None, Some(text)) => Plan::from_json_str(text, "plan")?,
                _ => {
                    return Err(Error::param(
                        "plan",
                        "both or neither",
                        "give a plan file or a plan dict",
                    ));
                }
            };
            plan.check_fragments(&Fragments::new())?;
            let dynamics = plan.dynamics.clone();
            let mut params = NetworkParams {
                origin,
                subcutis_depth,
                stiffness: Stiffness {
                    bending: Material::linear(bending.unwrap_or(0.0)),
                    ..Default::default()
                },
                ..Default::default()
            };
            dynamics.apply_to_network(&mut params);
            let job = Job::build(skin, bone, plan, Fragments::new(), &params)?;
            let mut opts = RelaxOptions {
                solver,
                force_dt,
                ..Default::default()
            };
            dynamics.apply_to_options(&mut opts);
            let report =
                crate::gpu::with_backend(backend, adapter.as_deref(), |b| job.run(&opts, b))?;
            let relaxed = report.skin_mesh(&job.network);
            let displacement = report.displacement.clone();
            let value = Relaxation {
                relax: report,
                bone_cut: job.cut,
            };
            Ok((value, relaxed, displacement))
        })
        .py_err()?;
    Ok((
        mesh_to(py, relaxed.positions, relaxed.triangles)?,
        PyArray1::from_vec(py, displacement).into_any(),
        to_json("relaxation", &report)?,
    ))
}
