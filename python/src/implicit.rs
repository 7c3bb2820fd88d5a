//! Skeletal implicit surfaces (`chisel implicit`, seed 002): a scene's
//! frames sampled by Witkin–Heckbert particles or followed by the
//! particle spring network.

use chisel::implicit::Scene;
use chisel::particles::animate::{
    self, FrameReport, NetworkFrameReport, NetworkSteps, Setup, frame_times,
};
use chisel::particles::{NetworkOptions, WhOptions};
use std::path::PathBuf;

use chisel::{Error, Result, TriMesh};
use pyo3::prelude::*;
use serde::Serialize;

use crate::arrays::{mesh_to, scalars_to};
use crate::json::to_json;
use crate::progress::Progress;

/// What [`implicit`] reports: the setup and one report per frame.
#[derive(Debug, Serialize)]
struct Animation {
    method: &'static str,
    edge_length: f64,
    setup: Option<Setup>,
    options: Option<NetworkOptions>,
    particle_frames: Vec<FrameReport>,
    network_frames: Vec<NetworkFrameReport>,
    network_steps: Vec<NetworkSteps>,
}

/// A frame as `(vertices, triangles, scalars)`.
type Frame<'py> = (Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>);

/// The built-in example scenes: `[(name, TOML)]`.
#[pyfunction]
pub fn scene_examples() -> Vec<(&'static str, &'static str)> {
    chisel::implicit::scene::EXAMPLES.to_vec()
}

/// The scene (a file, or TOML text) over `frames`
/// evenly spaced times: `method="particles"` gives each frame's particles
/// (points with `nx, ny, nz, sigma` scalars), `"network"` the spring
/// network's closed mesh; with the report as JSON. `reports=False` skips
/// the network's per-frame quality figures (two extra marching cubes and
/// a Hausdorff distance each; particle frames always report, at no cost).
#[pyfunction]
#[pyo3(signature = (scene_path, scene_text, method = "particles", frames = 8, edge_length = None, reports = true, backend = "cpu", adapter = None, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn implicit<'py>(
    py: Python<'py>,
    scene_path: Option<PathBuf>,
    scene_text: Option<String>,
    method: &str,
    frames: u32,
    edge_length: Option<f64>,
    reports: bool,
    backend: &str,
    adapter: Option<String>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(Vec<Frame<'py>>, String)> {
    let origin = scene_path
        .as_ref()
        .map_or("<scene_toml>".to_string(), |p| p.display().to_string());
    let mut progress = Progress::new(progress, format!("{origin}: frames"));
    let result = py.detach(|| -> Result<(Vec<TriMesh>, Animation)> {
        if frames == 0 {
            return Err(Error::param("frames", 0, "at least 1"));
        }
        let scene = match (&scene_path, scene_text) {
            (Some(path), None) => chisel::io::read_text(path)?,
            (None, Some(text)) => text,
            _ => {
                return Err(Error::param(
                    "scene",
                    "both or neither",
                    "give a scene file or its TOML text",
                ));
            }
        };
        let parsed = Scene::from_toml_str(&scene, &origin)?;
        let times = frame_times(&parsed, frames);
        crate::gpu::with_backend(backend, adapter.as_deref(), |backend| {
            let total = times.len();
            let mut meshes = Vec::with_capacity(total);
            match method {
                "particles" => {
                    let opts = WhOptions::from_scene(&scene, &origin)?;
                    let r = animate::edge_length(&parsed, opts.edge_length, edge_length)?;
                    let mut reports_out = Vec::new();
                    let setup =
                        animate::sample(&parsed, &times, r, opts, backend, |p, field, report| {
                            meshes.push(animate::point_set(p, field));
                            reports_out.push(report.clone());
                            progress.tick(meshes.len(), total)
                        })?;
                    Ok((
                        meshes,
                        Animation {
                            method: "particles",
                            edge_length: r,
                            setup: Some(setup),
                            options: None,
                            particle_frames: reports_out,
                            network_frames: Vec::new(),
                            network_steps: Vec::new(),
                        },
                    ))
                }
                "network" => {
                    let opts = NetworkOptions::from_scene(&scene, &origin)?;
                    let r = animate::edge_length(&parsed, opts.edge_length, edge_length)?;
                    let net = animate::start_network(&parsed, r, opts, backend)?;
                    let (mut frame_reports, mut steps_out) = (Vec::new(), Vec::new());
                    animate::network(&parsed, &times, net, backend, |net, t, steps| {
                        let k = meshes.len() as u32;
                        meshes.push(net.mesh());
                        if reports {
                            frame_reports
                                .push(animate::network_report(net, &parsed, k, t, steps, backend)?);
                        }
                        steps_out.push(steps.clone());
                        progress.tick(meshes.len(), total)
                    })?;
                    Ok((
                        meshes,
                        Animation {
                            method: "network",
                            edge_length: r,
                            setup: None,
                            options: Some(opts),
                            particle_frames: Vec::new(),
                            network_frames: frame_reports,
                            network_steps: steps_out,
                        },
                    ))
                }
                other => Err(Error::unknown("method", other, ["particles", "network"])),
            }
        })
    });
    let (meshes, animation) = progress.finish(result)?;
    let mut out = Vec::with_capacity(meshes.len());
    for m in meshes {
        let scalars = scalars_to(py, m.scalars)?.into_any();
        let (v, t) = mesh_to(py, m.positions, m.triangles)?;
        out.push((v, t, scalars));
    }
    Ok((out, to_json("animation", &animation)?))
}
