//! numpy arrays in and out: volumes as `(nz, ny, nx)` arrays of any
//! sample type the engine reads, meshes as `float32[N, 3]` vertices and
//! `uint32[M, 3]` triangles. Outputs hand their buffers to numpy (no copy).

use chisel::mesh::ScalarField;
use chisel::volume::{Samples, Space, Volume, VolumeData, VolumeView};
use chisel::{Error, TriMesh};
use numpy::ndarray::Array3;
use numpy::{
    Element, IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray2,
    PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use crate::errors::IntoPy;

/// A volume's frame as Python passes it: spacing, origin, axes (rows:
/// the world direction of x, y, z) and the anatomical space (`"LPS"`,
/// `"RAS"` or `None`).
pub type Frame = ([f64; 3], [f64; 3], [[f64; 3]; 3], Option<String>);

/// The samples of a 3-D array in the engine's order (x fastest): the
/// array itself, read in place, when it is C-ordered, else one copy in C
/// order (F-ordered arrays, strided views).
#[derive(Debug)]
enum Buf<'py, T: Element> {
    InPlace(PyReadonlyArray3<'py, T>),
    Copied(Vec<T>),
}

impl<'py, T: Element + Copy> Buf<'py, T> {
    fn of(array: &Bound<'py, PyArray3<T>>) -> PyResult<Self> {
        let ro = array.try_readonly().map_err(|e| {
            crate::errors::to_py(Error::param(
                "array",
                "borrowed for writing",
                format!("the array must be readable: {e}"),
            ))
        })?;
        // `as_slice` also takes an F-ordered buffer (memory order, z
        // fastest): only a C-ordered one is the engine's order.
        Ok(if ro.is_c_contiguous() && ro.as_slice().is_ok() {
            Buf::InPlace(ro)
        } else {
            Buf::Copied(ro.as_array().iter().copied().collect())
        })
    }

    /// The samples; empty only if the array changed layout since (then
    /// the volume's sample count check fails, with an error).
    fn slice(&self) -> &[T] {
        match self {
            Buf::InPlace(a) => a.as_slice().unwrap_or(&[]),
            Buf::Copied(v) => v,
        }
    }

    fn into_vec(self) -> Vec<T> {
        match self {
            Buf::InPlace(a) => a.as_slice().map(<[T]>::to_vec).unwrap_or_default(),
            Buf::Copied(v) => v,
        }
    }
}

/// A numpy volume held for the length of a call: its samples (in place
/// where the layout allows), dims and frame.
#[derive(Debug)]
pub struct HeldVolume<'py> {
    dims: [usize; 3],
    frame: Frame,
    data: Held<'py>,
}

#[derive(Debug)]
enum Held<'py> {
    U8(Buf<'py, u8>),
    I8(Buf<'py, i8>),
    U16(Buf<'py, u16>),
    I16(Buf<'py, i16>),
    U32(Buf<'py, u32>),
    I32(Buf<'py, i32>),
    F32(Buf<'py, f32>),
    F64(Buf<'py, f64>),
}

impl<'py> HeldVolume<'py> {
    /// Holds a numpy array of shape `(nz, ny, nx)` and its frame.
    pub fn of(array: &Bound<'py, PyAny>, frame: Frame) -> PyResult<Self> {
        macro_rules! try_type {
            ($t:ty, $variant:ident) => {
                if let Ok(a) = array.cast::<PyArray3<$t>>() {
                    let shape = a.shape();
                    return Ok(HeldVolume {
                        dims: [shape[2], shape[1], shape[0]],
                        frame,
                        data: Held::$variant(Buf::of(a)?),
                    });
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
            let shape = a.shape();
            let data = Buf::of(a)?.slice().iter().map(|&b| u8::from(b)).collect();
            return Ok(HeldVolume {
                dims: [shape[2], shape[1], shape[0]],
                frame,
                data: Held::U8(Buf::Copied(data)),
            });
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

    /// The samples as the engine's borrowed volume, checked as
    /// [`Volume::new`] and [`Volume::with_frame`] check.
    pub fn view(&self) -> PyResult<VolumeView<'_>> {
        let (spacing, origin, axes, space) = &self.frame;
        let samples = match &self.data {
            Held::U8(b) => Samples::U8(b.slice()),
            Held::I8(b) => Samples::I8(b.slice()),
            Held::U16(b) => Samples::U16(b.slice()),
            Held::I16(b) => Samples::I16(b.slice()),
            Held::U32(b) => Samples::U32(b.slice()),
            Held::I32(b) => Samples::I32(b.slice()),
            Held::F32(b) => Samples::F32(b.slice()),
            Held::F64(b) => Samples::F64(b.slice()),
        };
        VolumeView::new(
            self.dims,
            *spacing,
            *origin,
            *axes,
            space_of(space)?,
            samples,
        )
        .py_err()
    }

    /// The engine's owned volume (a copy of samples held in place).
    pub fn into_volume(self) -> PyResult<Volume> {
        let data = match self.data {
            Held::U8(b) => VolumeData::U8(b.into_vec()),
            Held::I8(b) => VolumeData::I8(b.into_vec()),
            Held::U16(b) => VolumeData::U16(b.into_vec()),
            Held::I16(b) => VolumeData::I16(b.into_vec()),
            Held::U32(b) => VolumeData::U32(b.into_vec()),
            Held::I32(b) => VolumeData::I32(b.into_vec()),
            Held::F32(b) => VolumeData::F32(b.into_vec()),
            Held::F64(b) => VolumeData::F64(b.into_vec()),
        };
        let (spacing, origin, axes, space) = self.frame;
        let space = space_of(&space)?;
        Volume::new(self.dims, spacing, origin, data)
            .and_then(|v| v.with_frame(axes, space))
            .py_err()
    }
}

/// The engine's owned volume of a numpy array of shape `(nz, ny, nx)`.
pub fn volume_from(array: &Bound<'_, PyAny>, frame: Frame) -> PyResult<Volume> {
    HeldVolume::of(array, frame)?.into_volume()
}

fn shape_of(array: &Bound<'_, PyAny>) -> String {
    array
        .getattr("shape")
        .map(|s| s.to_string())
        .unwrap_or_else(|_| "?".into())
}

fn space_of(space: &Option<String>) -> PyResult<Option<Space>> {
    match space.as_deref() {
        None => Ok(None),
        Some("LPS") => Ok(Some(Space::Lps)),
        Some("RAS") => Ok(Some(Space::Ras)),
        Some(other) => Err(crate::errors::to_py(Error::unknown(
            "space",
            other,
            ["LPS", "RAS"],
        ))),
    }
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

/// Per-vertex scalar fields from a dict of 1-D float32 arrays by name.
pub fn scalars_from(scalars: &Bound<'_, pyo3::types::PyDict>) -> PyResult<Vec<ScalarField>> {
    let mut out = Vec::with_capacity(scalars.len());
    for (name, values) in scalars.iter() {
        let values = values.cast::<PyArray1<f32>>().map_err(|_| {
            crate::errors::to_py(Error::param(
                "scalars",
                name.to_string(),
                "a scalar field is a float32[N] array",
            ))
        })?;
        out.push(ScalarField {
            name: name.extract()?,
            values: values.readonly().as_array().to_vec(),
        });
    }
    Ok(out)
}

/// A mesh as `(vertices, triangles)` arrays.
pub type MeshArrays<'py> = (Bound<'py, PyAny>, Bound<'py, PyAny>);

/// `(vertices float32[N, 3], triangles uint32[M, 3])` owning the mesh's buffers.
pub fn mesh_to<'py>(
    py: Python<'py>,
    positions: Vec<glam::Vec3>,
    triangles: Vec<[u32; 3]>,
) -> PyResult<MeshArrays<'py>> {
    let (n, m) = (positions.len(), triangles.len());
    let flat: Vec<f32> = bytemuck::allocation::cast_vec(positions);
    let v = PyArray1::from_vec(py, flat).reshape([n, 3])?;
    let flat: Vec<u32> = bytemuck::allocation::cast_vec(triangles);
    let t = PyArray1::from_vec(py, flat).reshape([m, 3])?;
    Ok((v.into_any(), t.into_any()))
}

/// Per-vertex scalar fields as a dict of float32 arrays by name.
pub fn scalars_to<'py>(
    py: Python<'py>,
    scalars: Vec<ScalarField>,
) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    let dict = pyo3::types::PyDict::new(py);
    for s in scalars {
        dict.set_item(s.name, PyArray1::from_vec(py, s.values))?;
    }
    Ok(dict)
}
