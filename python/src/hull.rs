//! The exact convex hull of a digital object (`chisel hull`) and its
//! lossless polyhedrization (`chisel polyhedrize`): faces, cells and the
//! ZKH tables as JSON, surfaces as meshes.

use chisel::hull::{CellList, ConvexHull, HalfSpace, HullSummary};
use chisel::hull_scan::VoxelBox;
use chisel::polyhedron::{
    PolyhedrizeOptions, PolyhedronSummary, Zkh, ZkhReport, background_components,
    polyhedrize as run_polyhedrize,
};
use chisel::voxel::{BoundaryTopology, CandidateKind, DigitalObject, ObjectFigures};
use chisel::{Error, Result, TriMesh};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use serde::Serialize;

use crate::arrays::{Frame, MeshArrays, mesh_to, volume_from};
use crate::errors::IntoPy;
use crate::json::to_json;
use crate::options::{HullArgs, ObjectArgs};

/// `(figures JSON, hull vertices, faces, mesh)`.
type HullResult<'py> = (String, Bound<'py, PyAny>, Vec<Vec<u32>>, MeshArrays<'py>);

/// The figures [`hull`] returns.
#[derive(Debug, Serialize)]
struct HullFigures {
    object: ObjectFigures,
    candidates: Candidates,
    hull: HullSummary,
    cells: CellList,
    planes: Vec<HalfSpace>,
    zkh: Option<Vec<Zkh>>,
    zkh_skipped: Option<&'static str>,
}

#[derive(Debug, Serialize)]
struct Candidates {
    kind: CandidateKind,
    count: usize,
}

/// The figures [`polyhedrize`] returns.
#[derive(Debug, Serialize)]
struct PolyhedronFigures {
    object: ObjectFigures,
    topology: BoundaryTopology,
    options: PolyhedrizeOptions,
    polyhedron: PolyhedronSummary,
    sibling_merges: usize,
    zkh: Vec<ZkhReport>,
    cells: serde_json::Value,
    merge_refused: Option<String>,
}

/// The hull of the object: `(figures JSON, vertices int64[V, 3] in
/// combinatorial coordinates, faces as lists of vertex indices, the world
/// mesh of the fan-triangulated faces)`. The JSON holds `object`,
/// `candidates`, `hull` (the summary), `cells` (the cell list), `planes`
/// (outward normal and offset per face) and `zkh` (`null` with the reason
/// in `zkh_skipped`).
#[pyfunction]
#[pyo3(signature = (array, frame, level = None, label = None, component = "largest", zkh = true, corners = "local26", vertices = "voxels", coplanar = "merge", order = "furthest"))]
#[allow(clippy::too_many_arguments)]
pub fn hull<'py>(
    py: Python<'py>,
    array: &Bound<'py, PyAny>,
    frame: Frame,
    level: Option<f64>,
    label: Option<f64>,
    component: &str,
    zkh: bool,
    corners: &str,
    vertices: &str,
    coplanar: &str,
    order: &str,
) -> PyResult<HullResult<'py>> {
    let hull_args = HullArgs {
        corners,
        vertices,
        coplanar,
        order,
    };
    let args = ObjectArgs::parse(level, label, component, hull_args).py_err()?;
    let kind = args.candidates;
    let volume = volume_from(array, frame)?;
    let (figures, hull, mesh) = py
        .detach(|| -> Result<_> {
            let object = DigitalObject::from_volume(&volume, args.selection, args.component)?;
            let candidates = object.candidates(kind);
            let hull = ConvexHull::build(&candidates, args.hull)?;
            let frame = object.frame();
            let (zkhs, skipped) = if !zkh {
                (None, Some("zkh=False"))
            } else if hull.is_planar() {
                (None, Some("flat hull: no inside"))
            } else {
                (Some(background_components(&object, &hull)?), None)
            };
            let figures = HullFigures {
                object: object.figures(),
                candidates: Candidates {
                    kind,
                    count: candidates.len(),
                },
                hull: hull.summary(&frame),
                cells: hull.cell_list(),
                planes: hull.half_spaces(),
                zkh: zkhs,
                zkh_skipped: skipped,
            };
            let mesh = hull.to_mesh(&frame)?;
            Ok((figures, hull, mesh))
        })
        .py_err()?;
    let flat: Vec<i64> = hull.vertices().iter().flatten().copied().collect();
    let n = hull.vertices().len();
    let hull_vertices = PyArray1::from_vec(py, flat).reshape([n, 3])?.into_any();
    let faces = hull.faces().iter().map(|f| f.vertices.clone()).collect();
    Ok((
        to_json("hull", &figures)?,
        hull_vertices,
        faces,
        mesh_to(py, mesh.positions, mesh.triangles)?,
    ))
}

/// The object's lossless polyhedron: `(figures JSON, mesh, mesh kind)`.
/// The JSON holds `object`, `topology` (of its boundary), `options`,
/// `polyhedron` (the summary), `zkh` (per ZKH: class, voxels, genus,
/// shells, pressed faces), `cells` (every shell's faces and cells),
/// `merge_refused`; the mesh is the merged surface (kind `"merged"`) or,
/// where it cannot be merged, the shells (`"shells"`).
#[pyfunction]
#[pyo3(signature = (array, frame, level = None, label = None, component = "largest", slice = None, overlapping_siblings = false, balls = false, press_in = false, corners = "local26", vertices = "voxels", coplanar = "merge", order = "furthest", backend = "cpu", adapter = None))]
#[allow(clippy::too_many_arguments)]
pub fn polyhedrize<'py>(
    py: Python<'py>,
    array: &Bound<'py, PyAny>,
    frame: Frame,
    level: Option<f64>,
    label: Option<f64>,
    component: &str,
    slice: Option<usize>,
    overlapping_siblings: bool,
    balls: bool,
    press_in: bool,
    corners: &str,
    vertices: &str,
    coplanar: &str,
    order: &str,
    backend: &str,
    adapter: Option<String>,
) -> PyResult<(String, MeshArrays<'py>, &'static str)> {
    let hull_args = HullArgs {
        corners,
        vertices,
        coplanar,
        order,
    };
    let args = ObjectArgs::parse(level, label, component, hull_args).py_err()?;
    let (selection, component) = (args.selection, args.component);
    let options = PolyhedrizeOptions {
        candidates: args.candidates,
        hull: args.hull,
        disjoint_siblings: !overlapping_siblings,
        balls,
        press_in,
    };
    let volume = volume_from(array, frame)?;
    let (figures, mesh, kind) = py
        .detach(|| -> Result<(PolyhedronFigures, TriMesh, &'static str)> {
            let volume = match slice {
                Some(z) => volume.slice_z(z)?,
                None => volume,
            };
            let object = DigitalObject::from_volume(&volume, selection, component)?;
            let topology = object.topology()?;
            let (poly, zkh) = crate::gpu::with_backend(backend, adapter.as_deref(), |b| {
                run_polyhedrize(&object, options, b, &|_| {})
            })?;
            let (mesh, kind, refused) = match poly.merged_surface() {
                Ok(m) if !m.triangles.is_empty() => (m.to_mesh(&poly.frame)?, "merged", None),
                Ok(_) => (poly.to_mesh()?, "shells", Some("no 3-D shell".to_string())),
                Err(e) => (poly.to_mesh()?, "shells", Some(e.to_string())),
            };
            let figures = PolyhedronFigures {
                object: object.figures(),
                topology,
                options,
                polyhedron: poly.summary(),
                sibling_merges: poly.merges,
                zkh,
                cells: poly.to_json(),
                merge_refused: refused,
            };
            Ok((figures, mesh, kind))
        })
        .map_err(|e: Error| crate::errors::to_py(e))?;
    Ok((
        to_json("polyhedron", &figures)?,
        mesh_to(py, mesh.positions, mesh.triangles)?,
        kind,
    ))
}

/// Every voxel of the object's hull box classified against its hull (the
/// `hull_rows` kernel on the GPU, its CPU mirror otherwise, exact either
/// way): `(sides uint8[nz, ny, nx]: 0 outside, 1 on, 2 inside; the voxel
/// index (x, y, z) of sides[0, 0, 0])`.
#[pyfunction]
#[pyo3(signature = (array, frame, level = None, label = None, component = "largest", corners = "local26", vertices = "voxels", coplanar = "merge", order = "furthest", backend = "cpu", adapter = None))]
#[allow(clippy::too_many_arguments)]
pub fn hull_scan<'py>(
    py: Python<'py>,
    array: &Bound<'py, PyAny>,
    frame: Frame,
    level: Option<f64>,
    label: Option<f64>,
    component: &str,
    corners: &str,
    vertices: &str,
    coplanar: &str,
    order: &str,
    backend: &str,
    adapter: Option<String>,
) -> PyResult<(Bound<'py, PyAny>, [i64; 3])> {
    let hull_args = HullArgs {
        corners,
        vertices,
        coplanar,
        order,
    };
    let args = ObjectArgs::parse(level, label, component, hull_args).py_err()?;
    let volume = volume_from(array, frame)?;
    let classification = py
        .detach(|| -> Result<_> {
            let object = DigitalObject::from_volume(&volume, args.selection, args.component)?;
            let hull = ConvexHull::of_object(&object, args.candidates, args.hull)?;
            let (lo, hi) = hull.voxel_bbox();
            let bbox = VoxelBox {
                origin: lo,
                dims: std::array::from_fn(|a| (hi[a] - lo[a] + 1).max(0) as usize),
            };
            crate::gpu::with_backend(backend, adapter.as_deref(), |b| {
                hull.row_spans(&bbox, b)?.to_classification()
            })
        })
        .py_err()?;
    let [nx, ny, nz] = classification.bbox.dims;
    let sides = PyArray1::from_vec(py, classification.sides)
        .reshape([nz, ny, nx])?
        .into_any();
    Ok((sides, classification.bbox.origin))
}
