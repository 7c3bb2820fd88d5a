//! Scalpels (`chisel cut`): planes, rectangles, spheres and triangulated
//! knives, applied in that order, each cutting every piece of the one
//! before; optionally capped so closed input gives closed pieces.

use chisel::cut::{CutOptions, Knife, cut_sequence};
use chisel::{Error, Result, TriMesh};
use glam::DVec3;
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;

use crate::arrays::{mesh_from, mesh_to};
use crate::errors::IntoPy;
use crate::json::to_json;

/// A plane: point, normal.
type Plane = ([f64; 3], [f64; 3]);
/// A rectangle: centre, normal, u axis, half extents along u and v.
type Rect = ([f64; 3], [f64; 3], [f64; 3], [f64; 2]);
/// A sphere: centre, radius.
type Sphere = ([f64; 3], f64);
/// A piece: `(vertices, triangles, side)`.
type Piece<'py> = (Bound<'py, PyAny>, Bound<'py, PyAny>, String);

/// The pieces of `mesh` after every knife: `[(vertices, triangles,
/// side)]` and the cut's statistics as JSON.
#[pyfunction]
#[pyo3(signature = (vertices, triangles, planes = Vec::new(), rects = Vec::new(), spheres = Vec::new(), knives = Vec::new(), cap = false))]
#[allow(clippy::too_many_arguments)]
pub fn cut<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f32>,
    triangles: &Bound<'py, PyAny>,
    planes: Vec<Plane>,
    rects: Vec<Rect>,
    spheres: Vec<Sphere>,
    knives: Vec<(PyReadonlyArray2<'py, f32>, Bound<'py, PyAny>)>,
    cap: bool,
) -> PyResult<(Vec<Piece<'py>>, String)> {
    let mesh = mesh_from(vertices, triangles)?;
    let v = DVec3::from_array;
    let mut all: Vec<Knife> = planes
        .into_iter()
        .map(|(point, normal)| Knife::Plane {
            point: v(point),
            normal: v(normal),
        })
        .collect();
    all.extend(
        rects
            .into_iter()
            .map(|(centre, normal, u_axis, half_extents)| Knife::Rect {
                centre: v(centre),
                normal: v(normal),
                u_axis: v(u_axis),
                half_extents,
            }),
    );
    all.extend(spheres.into_iter().map(|(centre, radius)| Knife::Sphere {
        centre: v(centre),
        radius,
    }));
    for (kv, kt) in knives {
        all.push(Knife::Mesh(mesh_from(kv, &kt)?));
    }
    if all.is_empty() {
        return Err(crate::errors::to_py(Error::empty(
            "knives (plane, rect, sphere or knife)",
        )));
    }
    let result = py
        .detach(|| -> Result<_> { cut_sequence(&mesh, &all, &CutOptions { cap }) })
        .py_err()?;
    let stats = to_json("cut statistics", &result.stats)?;
    let mut pieces = Vec::with_capacity(result.pieces.len());
    for (piece, side) in result.pieces.into_iter().zip(result.sides) {
        let TriMesh {
            positions,
            triangles,
            ..
        } = piece;
        let (pv, pt) = mesh_to(py, positions, triangles)?;
        let side = serde_json::to_value(side)
            .ok()
            .and_then(|s| s.as_str().map(str::to_string))
            .unwrap_or_default();
        pieces.push((pv, pt, side));
    }
    Ok((pieces, stats))
}
