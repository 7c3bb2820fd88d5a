//! numpy arrays in and out: volumes as `(nz, ny, nx)` arrays of any
//! sample type the engine reads, meshes as `float32[N, 3]` vertices and
//! `uint32[M, 3]` triangles. Outputs hand their buffers to numpy (no copy).

use chisel::volume::{Space, Volume, VolumeData};
use chisel::{Error, TriMesh};
use numpy::ndarray::Array3;
use numpy::{
    Element, IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use crate::errors::IntoPy;

/// A volume's frame as Python passes it: spacing, origin, axes (rows:
/// the world direction of x, y, z) and the anatomical space (`"LPS"`,
/// `"RAS"` or `None`).
pub type Frame = ([f64; 3], [f64; 3], [[f64; 3]; 3], Option<String>);

/// The samples of a 3-D array in the engine's order (x fastest): the
/// buffer itself when the array is C-contiguous, else one copy in C order.
fn samples<T: Element + Copy>(array: &Bound<'_, PyArray3<T>>) -> (Vec<T>, [usize; 3]) {
    let ro = array.readonly();
    let shape = ro.shape();
    let dims = [shape[2], shape[1], shape[0]];
    // `as_slice` also takes an F-ordered buffer (memory order, z fastest):
    // only a C-ordered one is the engine's order.
    let data = match ro.as_slice() {
        Ok(slice) if ro.is_c_contiguous() => slice.to_vec(),
        _ => ro.as_array().iter().copied().collect(),
    };
    (data, dims)
}

/// The engine's volume of a numpy array of shape `(nz, ny, nx)`.
pub fn volume_from(array: &Bound<'_, PyAny>, frame: Frame) -> PyResult<Volume> {
    macro_rules! try_type {
        ($t:ty, $variant:ident) => {
            if let Ok(a) = array.cast::<PyArray3<$t>>() {
                let (data, dims) = samples(a);
                return build(dims, VolumeData::$variant(data), frame);
            }
        };
    }
    try_type!(u8, U8);
    try_type!(i8, I8);
    try_type!(u16, U16);
    try_type!(i16, I16);
    try_type!(u32, U32);
    try_type!(i32, I32);
    try_type!(f32, F32);
    try_type!(f64, F64);
    if let Ok(a) = array.cast::<PyArray3<bool>>() {
        let (data, dims) = samples(a);
        let data = data.into_iter().map(u8::from).collect();
        return build(dims, VolumeData::U8(data), frame);
    }
    let described = array
        .getattr("dtype")
        .map(|d| format!("an array of {d} with shape {}", shape_of(array)))
        .unwrap_or_else(|_| format!("a {}", array.get_type()));
    Err(crate::errors::to_py(Error::param(
        "array",
        described,
        "a volume is a 3-D numpy array (nz, ny, nx) of bool, uint8, int8, uint16, int16, \
         uint32, int32, float32 or float64",
    )))
}

fn shape_of(array: &Bound<'_, PyAny>) -> String {
    array
        .getattr("shape")
        .map(|s| s.to_string())
        .unwrap_or_else(|_| "?".into())
}

fn build(dims: [usize; 3], data: VolumeData, frame: Frame) -> PyResult<Volume> {
    let (spacing, origin, axes, space) = frame;
    let space = match space.as_deref() {
        None => None,
        Some("LPS") => Some(Space::Lps),
        Some("RAS") => Some(Space::Ras),
        Some(other) => {
            return Err(crate::errors::to_py(Error::unknown(
                "space",
                other,
                ["LPS", "RAS"],
            )));
        }
    };
    Volume::new(dims, spacing, origin, data)
        .and_then(|v| v.with_frame(axes, space))
        .py_err()
}

/// A volume as `(array, spacing, origin, axes, space)`; the array owns
/// the engine's buffer.
pub fn volume_to<'py>(py: Python<'py>, v: Volume) -> PyResult<(Bound<'py, PyAny>, Frame)> {
    let [nx, ny, nz] = v.dims;
    let shape = (nz, ny, nx);
    fn wrap<'py, T: Element>(
        py: Python<'py>,
        shape: (usize, usize, usize),
        data: Vec<T>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let array = Array3::from_shape_vec(shape, data)
            .map_err(|e| crate::errors::to_py(Error::Internal(format!("volume shape: {e}"))))?;
        Ok(array.into_pyarray(py).into_any())
    }
    let array = match v.data {
        VolumeData::U8(d) => wrap(py, shape, d)?,
        VolumeData::I8(d) => wrap(py, shape, d)?,
        VolumeData::U16(d) => wrap(py, shape, d)?,
        VolumeData::I16(d) => wrap(py, shape, d)?,
        VolumeData::U32(d) => wrap(py, shape, d)?,
        VolumeData::I32(d) => wrap(py, shape, d)?,
        VolumeData::F32(d) => wrap(py, shape, d)?,
        VolumeData::F64(d) => wrap(py, shape, d)?,
    };
    let space = v.space.map(|s| s.name().to_string());
    Ok((array, (v.spacing, v.origin, v.axes, space)))
}

/// Vertices `float32[N, 3]` and triangles `[M, 3]` (any integer dtype,
/// checked against N) as the engine's mesh.
pub fn mesh_from(
    vertices: PyReadonlyArray2<'_, f32>,
    triangles: &Bound<'_, PyAny>,
) -> PyResult<TriMesh> {
    let shape = vertices.shape();
    if shape[1] != 3 {
        return Err(crate::errors::to_py(Error::param(
            "vertices",
            format!("shape ({}, {})", shape[0], shape[1]),
            "vertices are float32[N, 3]",
        )));
    }
    let positions: Vec<glam::Vec3> = vertices
        .as_array()
        .rows()
        .into_iter()
        .map(|r| glam::Vec3::new(r[0], r[1], r[2]))
        .collect();
    let np = triangles.py().import("numpy")?;
    let tri = np.call_method1("asarray", (triangles, "int64"))?;
    let tri = tri.cast::<PyArray2<i64>>()?.readonly();
    let tshape = tri.shape();
    if tshape[1] != 3 {
        return Err(crate::errors::to_py(Error::param(
            "triangles",
            format!("shape ({}, {})", tshape[0], tshape[1]),
            "triangles are integer[M, 3] vertex indices",
        )));
    }
    let mut tris = Vec::with_capacity(tshape[0]);
    for (k, r) in tri.as_array().rows().into_iter().enumerate() {
        let mut t = [0u32; 3];
        for c in 0..3 {
            t[c] = u32::try_from(r[c]).map_err(|_| {
                crate::errors::to_py(Error::data(
                    "triangles",
                    "triangle",
                    k,
                    format!("index {} is not a vertex index", r[c]),
                ))
            })?;
        }
        tris.push(t);
    }
    TriMesh::new(positions, tris).py_err()
}

/// `(vertices float32[N, 3], triangles uint32[M, 3])` owning the mesh's buffers.
pub fn mesh_to<'py>(
    py: Python<'py>,
    positions: Vec<glam::Vec3>,
    triangles: Vec<[u32; 3]>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let (n, m) = (positions.len(), triangles.len());
    let flat: Vec<f32> = bytemuck::allocation::cast_vec(positions);
    let v = PyArray1::from_vec(py, flat).reshape([n, 3])?;
    let flat: Vec<u32> = bytemuck::allocation::cast_vec(triangles);
    let t = PyArray1::from_vec(py, flat).reshape([m, 3])?;
    Ok((v.into_any(), t.into_any()))
}
