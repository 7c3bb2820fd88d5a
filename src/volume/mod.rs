//! Host-side scalar volumes (CT, MR, label images).
//!
//! A [`Volume`] holds `dims = [nx, ny, nz]` samples in file order (x fastest,
//! then y, then z; never flipped), the voxel `spacing` and the `origin` of
//! sample (0,0,0) in world units (usually mm). 2-D images have `nz = 1`.

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
        match self {
            VolumeData::U8(v) => v.len(),
            VolumeData::I8(v) => v.len(),
            VolumeData::U16(v) => v.len(),
            VolumeData::I16(v) => v.len(),
            VolumeData::U32(v) => v.len(),
            VolumeData::I32(v) => v.len(),
            VolumeData::F32(v) => v.len(),
            VolumeData::F64(v) => v.len(),
        }
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
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

/// A 3-D (or 2-D, `nz = 1`) scalar volume.
#[derive(Debug, Clone, PartialEq)]
pub struct Volume {
    /// Samples per axis `[nx, ny, nz]`.
    pub dims: [usize; 3],
    /// Distance between sample centres per axis (world units, usually mm).
    pub spacing: [f64; 3],
    /// World position of sample (0,0,0).
    pub origin: [f64; 3],
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
        if n != data.len() {
            return Err(crate::Error::mismatch(
                format!("samples of a {dims:?} volume"),
                n,
                data.len(),
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
        Ok(Volume {
            dims,
            spacing,
            origin,
            data,
        })
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
        x + self.dims[0] * (y + self.dims[1] * z)
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
        let mut origin = self.origin;
        origin[2] += self.spacing[2] * z as f64;
        Ok(Volume {
            dims: [self.dims[0], self.dims[1], 1],
            spacing: self.spacing,
            origin,
            data,
        })
    }
}
