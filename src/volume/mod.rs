//! Host-side scalar volumes (CT, MR, label images).
//!
//! A [`Volume`] holds `dims = [nx, ny, nz]` samples in file order (x fastest,
//! then y, then z; never flipped), the voxel `spacing`, the `origin` of
//! sample (0,0,0) and the world direction of each index axis (`axes`, an
//! orthonormal frame: a rotation, or a rotation and a reflection) in world
//! units (usually mm), and, when the file says, the anatomical [`Space`]
//! those world coordinates are in. Sample `(i, j, k)` lies at
//! `origin + i·spacing[0]·axes[0] + j·spacing[1]·axes[1] + k·spacing[2]·axes[2]`
//! ([`Volume::world`]). 2-D images have `nz = 1`.

pub mod analysis;

pub use analysis::{
    ComponentCount, LabelCount, Labelling, VolumeStats, label_6_connected, label_components,
    threshold_components,
};

/// Sample storage, one variant per element type a reader can produce.
#[derive(Debug, Clone, PartialEq)]
pub enum VolumeData {
    U8(Vec<u8>),
    I8(Vec<i8>),
    U16(Vec<u16>),
    I16(Vec<i16>),
    U32(Vec<u32>),
    I32(Vec<i32>),
    F32(Vec<f32>),
    F64(Vec<f64>),
}

/// Element type of a [`VolumeData`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ScalarType {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    F32,
    F64,
}

impl ScalarType {
    /// Bytes per sample.
    pub fn size(self) -> usize {
        match self {
            ScalarType::U8 | ScalarType::I8 => 1,
            ScalarType::U16 | ScalarType::I16 => 2,
            ScalarType::U32 | ScalarType::I32 | ScalarType::F32 => 4,
            ScalarType::F64 => 8,
        }
    }

    /// Lower-case name (`u8`, `i16`, `f32`, ...).
    pub fn name(self) -> &'static str {
        match self {
            ScalarType::U8 => "u8",
            ScalarType::I8 => "i8",
            ScalarType::U16 => "u16",
            ScalarType::I16 => "i16",
            ScalarType::U32 => "u32",
            ScalarType::I32 => "i32",
            ScalarType::F32 => "f32",
            ScalarType::F64 => "f64",
        }
    }

    /// Whether every sample converts to `f32` without rounding.
    pub fn exact_in_f32(self) -> bool {
        !matches!(self, ScalarType::U32 | ScalarType::I32 | ScalarType::F64)
    }
}

impl VolumeData {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.samples().len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The samples, borrowed.
    pub fn samples(&self) -> Samples<'_> {
        match self {
            VolumeData::U8(v) => Samples::U8(v),
            VolumeData::I8(v) => Samples::I8(v),
            VolumeData::U16(v) => Samples::U16(v),
            VolumeData::I16(v) => Samples::I16(v),
            VolumeData::U32(v) => Samples::U32(v),
            VolumeData::I32(v) => Samples::I32(v),
            VolumeData::F32(v) => Samples::F32(v),
            VolumeData::F64(v) => Samples::F64(v),
        }
    }

    /// Element type.
    pub fn scalar_type(&self) -> ScalarType {
        match self {
            VolumeData::U8(_) => ScalarType::U8,
            VolumeData::I8(_) => ScalarType::I8,
            VolumeData::U16(_) => ScalarType::U16,
            VolumeData::I16(_) => ScalarType::I16,
            VolumeData::U32(_) => ScalarType::U32,
            VolumeData::I32(_) => ScalarType::I32,
            VolumeData::F32(_) => ScalarType::F32,
            VolumeData::F64(_) => ScalarType::F64,
        }
    }

    /// Sample `i` as `f64` (exact for every element type).
    pub fn get_f64(&self, i: usize) -> f64 {
        match self {
            VolumeData::U8(v) => f64::from(v[i]),
            VolumeData::I8(v) => f64::from(v[i]),
            VolumeData::U16(v) => f64::from(v[i]),
            VolumeData::I16(v) => f64::from(v[i]),
            VolumeData::U32(v) => f64::from(v[i]),
            VolumeData::I32(v) => f64::from(v[i]),
            VolumeData::F32(v) => f64::from(v[i]),
            VolumeData::F64(v) => v[i],
        }
    }

    /// All samples converted to `f32` (the GPU's scalar type). Exact when
    /// [`ScalarType::exact_in_f32`] holds; otherwise rounded to nearest.
    pub fn to_f32(&self) -> Vec<f32> {
        match self {
            VolumeData::U8(v) => v.iter().map(|&x| f32::from(x)).collect(),
            VolumeData::I8(v) => v.iter().map(|&x| f32::from(x)).collect(),
            VolumeData::U16(v) => v.iter().map(|&x| f32::from(x)).collect(),
            VolumeData::I16(v) => v.iter().map(|&x| f32::from(x)).collect(),
            VolumeData::U32(v) => v.iter().map(|&x| x as f32).collect(),
            VolumeData::I32(v) => v.iter().map(|&x| x as f32).collect(),
            VolumeData::F32(v) => v.clone(),
            VolumeData::F64(v) => v.iter().map(|&x| x as f32).collect(),
        }
    }
}

/// The anatomical frame of world coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Space {
    /// x towards the patient's left, y posterior, z superior (DICOM, ITK
    /// and MetaImage, NRRD from 3D Slicer).
    #[serde(rename = "LPS")]
    Lps,
    /// x towards the patient's right, y anterior, z superior (NIfTI).
    #[serde(rename = "RAS")]
    Ras,
}

impl Space {
    /// Per-axis signs that take coordinates in `self` to `to`: LPS and RAS
    /// differ in the signs of x and y.
    pub fn signs_to(self, to: Space) -> [f64; 3] {
        if self == to {
            [1.0; 3]
        } else {
            [-1.0, -1.0, 1.0]
        }
    }

    /// `LPS` or `RAS`.
    pub fn name(self) -> &'static str {
        match self {
            Space::Lps => "LPS",
            Space::Ras => "RAS",
        }
    }
}

/// The axes of a volume whose index axes are the world axes.
pub const IDENTITY_AXES: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// How far a volume's axes may be from orthonormal (dot products), for
/// directions written as decimal text by other tools.
pub const AXES_TOLERANCE: f64 = 1e-5;

/// Whether `axes` include a reflection (their determinant is negative).
pub fn reflects(axes: &[[f64; 3]; 3]) -> bool {
    let [a, b, c] = axes;
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
        < 0.0
}

/// Completes the first `given` orthonormal axes to a right-handed frame
/// (an image of fewer than three spatial axes): the cross product for the
/// third, the world axis least along the first for the second.
pub fn complete_axes(axes: &mut [[f64; 3]; 3], given: usize) {
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    if given == 1 {
        let a = axes[0];
        let k = (0..3)
            .min_by(|&i, &j| a[i].abs().total_cmp(&a[j].abs()))
            .unwrap_or(0);
        let mut e = [0.0; 3];
        e[k] = 1.0;
        let b = cross(cross(a, e), a);
        let len = b.iter().map(|c| c * c).sum::<f64>().sqrt();
        axes[1] = b.map(|c| c / len);
    }
    if (1..=2).contains(&given) {
        axes[2] = cross(axes[0], axes[1]);
    }
}

/// A 3-D (or 2-D, `nz = 1`) scalar volume.
#[derive(Debug, Clone, PartialEq)]
pub struct Volume {
    /// Samples per axis `[nx, ny, nz]`.
    pub dims: [usize; 3],
    /// Distance between sample centres per axis (world units, usually mm).
    pub spacing: [f64; 3],
    /// World position of sample (0,0,0).
    pub origin: [f64; 3],
    /// World direction of each index axis: unit vectors, mutually
    /// orthogonal ([`IDENTITY_AXES`] for an axis-aligned volume).
    pub axes: [[f64; 3]; 3],
    /// The anatomical frame of the world coordinates, when the file names
    /// one.
    pub space: Option<Space>,
    /// `nx·ny·nz` samples, x fastest.
    pub data: VolumeData,
}

impl Volume {
    /// A volume with checked sample count, positive finite spacing and finite origin.
    pub fn new(
        dims: [usize; 3],
        spacing: [f64; 3],
        origin: [f64; 3],
        data: VolumeData,
    ) -> crate::Result<Self> {
        check_grid(dims, data.len(), spacing, origin)?;
        Ok(Volume {
            dims,
            spacing,
            origin,
            axes: IDENTITY_AXES,
            space: None,
            data,
        })
    }

    /// The volume with index axes along `axes` in anatomical frame `space`.
    ///
    /// Errors: axes that are not finite unit vectors, mutually orthogonal
    /// within [`AXES_TOLERANCE`] (sheared grids are not represented).
    pub fn with_frame(mut self, axes: [[f64; 3]; 3], space: Option<Space>) -> crate::Result<Self> {
        check_axes(&axes)?;
        self.axes = axes;
        self.space = space;
        Ok(self)
    }

    /// World position of fractional index `(i, j, k)`.
    pub fn world(&self, index: [f64; 3]) -> [f64; 3] {
        self.view().world(index)
    }

    /// The volume with its samples borrowed.
    pub fn view(&self) -> VolumeView<'_> {
        VolumeView {
            dims: self.dims,
            spacing: self.spacing,
            origin: self.origin,
            axes: self.axes,
            space: self.space,
            data: self.data.samples(),
        }
    }

    /// Whether the axes include a reflection (determinant −1): surfaces
    /// built in index space then turn inside out in the world unless their
    /// winding is reversed.
    pub fn reflects(&self) -> bool {
        reflects(&self.axes)
    }

    /// Origin and axes expressed in anatomical frame `to` (unchanged when
    /// the volume names no frame or the same one).
    pub fn frame_in(&self, to: Space) -> ([f64; 3], [[f64; 3]; 3]) {
        let signs = self.space.map_or([1.0; 3], |s| s.signs_to(to));
        (
            std::array::from_fn(|c| self.origin[c] * signs[c]),
            self.axes.map(|a| std::array::from_fn(|c| a[c] * signs[c])),
        )
    }

    /// Number of samples `nx·ny·nz`.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// Whether the volume has no samples.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Linear index of sample `(x, y, z)`.
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        self.view().index(x, y, z)
    }

    /// Slice `z` as a volume of one sample in z (same type, spacing; origin
    /// moved to the slice), for the 2-D analogue of the voxel algorithms.
    ///
    /// Errors: [`crate::Error::InvalidParameter`] when `z` is out of range.
    pub fn slice_z(&self, z: usize) -> crate::Result<Volume> {
        if z >= self.dims[2] {
            return Err(crate::Error::param(
                "slice",
                z,
                format!("does not exist: the volume has {} slices", self.dims[2]),
            ));
        }
        let n = self.dims[0] * self.dims[1];
        let r = n * z..n * (z + 1);
        let data = match &self.data {
            VolumeData::U8(v) => VolumeData::U8(v[r].to_vec()),
            VolumeData::I8(v) => VolumeData::I8(v[r].to_vec()),
            VolumeData::U16(v) => VolumeData::U16(v[r].to_vec()),
            VolumeData::I16(v) => VolumeData::I16(v[r].to_vec()),
            VolumeData::U32(v) => VolumeData::U32(v[r].to_vec()),
            VolumeData::I32(v) => VolumeData::I32(v[r].to_vec()),
            VolumeData::F32(v) => VolumeData::F32(v[r].to_vec()),
            VolumeData::F64(v) => VolumeData::F64(v[r].to_vec()),
        };
        Ok(Volume {
            dims: [self.dims[0], self.dims[1], 1],
            spacing: self.spacing,
            origin: self.world([0.0, 0.0, z as f64]),
            axes: self.axes,
            space: self.space,
            data,
        })
    }
}

/// The checks of [`Volume::new`]: `n` samples for `dims`, positive finite
/// spacing, finite origin.
fn check_grid(
    dims: [usize; 3],
    n_samples: usize,
    spacing: [f64; 3],
    origin: [f64; 3],
) -> crate::Result<()> {
    let n = dims
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .ok_or_else(|| {
            crate::Error::param(
                "dims",
                format!("{dims:?}"),
                "the sample count overflows usize",
            )
        })?;
    if n != n_samples {
        return Err(crate::Error::mismatch(
            format!("samples of a {dims:?} volume"),
            n,
            n_samples,
        ));
    }
    if spacing.iter().any(|s| !s.is_finite() || *s <= 0.0) {
        return Err(crate::Error::param(
            "spacing",
            format!("{spacing:?}"),
            "must be positive and finite",
        ));
    }
    if origin.iter().any(|o| !o.is_finite()) {
        return Err(crate::Error::param(
            "origin",
            format!("{origin:?}"),
            "must be finite",
        ));
    }
    Ok(())
}

/// The check of [`Volume::with_frame`]: orthonormal axes.
fn check_axes(axes: &[[f64; 3]; 3]) -> crate::Result<()> {
    for i in 0..3 {
        for j in 0..3 {
            let dot: f64 = (0..3).map(|c| axes[i][c] * axes[j][c]).sum();
            let want = if i == j { 1.0 } else { 0.0 };
            if !dot.is_finite() || (dot - want).abs() > AXES_TOLERANCE {
                return Err(crate::Error::param(
                    "axes",
                    format!("{axes:?}"),
                    "must be orthonormal (unit directions at right angles; sheared grids \
                         are not represented)",
                ));
            }
        }
    }
    Ok(())
}

/// A volume's samples, borrowed: one slice of the sample type.
#[derive(Debug, Clone, Copy)]
pub enum Samples<'a> {
    U8(&'a [u8]),
    I8(&'a [i8]),
    U16(&'a [u16]),
    I16(&'a [i16]),
    U32(&'a [u32]),
    I32(&'a [i32]),
    F32(&'a [f32]),
    F64(&'a [f64]),
}

impl Samples<'_> {
    /// Number of samples.
    pub fn len(&self) -> usize {
        match self {
            Samples::U8(v) => v.len(),
            Samples::I8(v) => v.len(),
            Samples::U16(v) => v.len(),
            Samples::I16(v) => v.len(),
            Samples::U32(v) => v.len(),
            Samples::I32(v) => v.len(),
            Samples::F32(v) => v.len(),
            Samples::F64(v) => v.len(),
        }
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A volume whose samples are borrowed — from a [`Volume`]
/// ([`Volume::view`]) or read in place from a caller's buffer (a numpy
/// array in Python) — for the operations that only read samples
/// (marching cubes).
#[derive(Debug, Clone, Copy)]
pub struct VolumeView<'a> {
    /// Samples per axis `[nx, ny, nz]`.
    pub dims: [usize; 3],
    /// Distance between sample centres per axis.
    pub spacing: [f64; 3],
    /// World position of sample (0,0,0).
    pub origin: [f64; 3],
    /// World direction of each index axis.
    pub axes: [[f64; 3]; 3],
    /// The anatomical frame of the world coordinates.
    pub space: Option<Space>,
    /// `nx·ny·nz` samples, x fastest.
    pub data: Samples<'a>,
}

impl<'a> VolumeView<'a> {
    /// A view with the checks of [`Volume::new`] and [`Volume::with_frame`].
    pub fn new(
        dims: [usize; 3],
        spacing: [f64; 3],
        origin: [f64; 3],
        axes: [[f64; 3]; 3],
        space: Option<Space>,
        data: Samples<'a>,
    ) -> crate::Result<Self> {
        check_grid(dims, data.len(), spacing, origin)?;
        check_axes(&axes)?;
        Ok(VolumeView {
            dims,
            spacing,
            origin,
            axes,
            space,
            data,
        })
    }

    /// Linear index of sample `(x, y, z)`.
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// World position of fractional index `(i, j, k)`.
    pub fn world(&self, index: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|c| {
            self.origin[c]
                + (0..3)
                    .map(|k| index[k] * self.spacing[k] * self.axes[k][c])
                    .sum::<f64>()
        })
    }

    /// Whether the axes include a reflection ([`Volume::reflects`]).
    pub fn reflects(&self) -> bool {
        reflects(&self.axes)
    }
}

impl<'a> From<&'a Volume> for VolumeView<'a> {
    fn from(volume: &'a Volume) -> Self {
        volume.view()
    }
}
