//! Statistics of a volume or a mesh (`chisel stats`): sample range, mean,
//! labels, components; mesh topology and self-intersections.

use chisel::mesh::{SelfIntersections, Topology, self_intersections};
use chisel::volume::analysis::{
    ComponentCount, VolumeStats, label_components, threshold_components,
};
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;
use serde::Serialize;

use crate::arrays::{Frame, mesh_from, volume_from};
use crate::errors::IntoPy;
use crate::json::to_json;

/// What [`volume_stats`] returns (typed, so that f32 figures print as
/// the command line prints them).
#[derive(Debug, Serialize)]
struct VolumeFigures {
    stats: VolumeStats,
    level: Option<ComponentCount>,
    label: Option<ComponentCount>,
}

/// What [`mesh_stats`] returns.
#[derive(Debug, Serialize)]
struct MeshFigures {
    topology: Topology,
    self_intersections: SelfIntersections,
}

/// `{stats, level?, label?}`: the volume's statistics and, with `level`
/// or `label`, its 6-connected components of samples ≥ level / == label.
#[pyfunction]
#[pyo3(signature = (array, frame, level = None, label = None))]
pub fn volume_stats(
    py: Python<'_>,
    array: &Bound<'_, PyAny>,
    frame: Frame,
    level: Option<f64>,
    label: Option<f64>,
) -> PyResult<String> {
    let level = crate::options::level(level).py_err()?;
    let label = crate::options::level(label).py_err()?;
    let volume = volume_from(array, frame)?;
    let value = py.detach(|| VolumeFigures {
        stats: VolumeStats::of(&volume),
        level: level.map(|t| threshold_components(&volume, t)),
        label: label.map(|l| label_components(&volume, l)),
    });
    to_json("volume statistics", &value)
}

/// `{topology, self_intersections}`: counts, edges, boundary loops,
/// components, Euler characteristic, orientation, area, signed volume;
/// intersecting triangle pairs and zero-area triangles.
#[pyfunction]
pub fn mesh_stats(
    py: Python<'_>,
    vertices: PyReadonlyArray2<'_, f32>,
    triangles: &Bound<'_, PyAny>,
) -> PyResult<String> {
    let mesh = mesh_from(vertices, triangles)?;
    let value = py.detach(|| MeshFigures {
        topology: Topology::of(&mesh),
        self_intersections: self_intersections(&mesh),
    });
    to_json("mesh statistics", &value)
}
