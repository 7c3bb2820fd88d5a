//! The sample grid marching cubes walks: the volume's samples as `f32`
//! (labels as 0/1), optionally padded by one outside sample per side.
//!
//! Both backends read samples only through [`Field::layer`], so the CPU
//! mirror and the GPU kernels see bit-identical inputs.

use super::IsoSpec;
use crate::volume::VolumeData;
use crate::{Error, Result, Volume};

/// A volume prepared for marching cubes.
#[derive(Debug)]
pub struct Field<'a> {
    volume: &'a Volume,
    iso: IsoSpec,
    /// 1 when the border is closed (one outside sample added per side), else 0.
    pub pad: usize,
    /// Sample counts per axis of the (padded) grid.
    pub dims: [usize; 3],
    /// Iso level in sample units (0.5 for labels).
    pub level: f32,
}

impl<'a> Field<'a> {
    /// Checks the iso specification and the sample values (all finite).
    pub fn new(volume: &'a Volume, iso: IsoSpec, close_border: bool) -> Result<Self> {
        let level = match iso {
            IsoSpec::Level(l) if l.is_finite() => l,
            IsoSpec::Level(l) => {
                return Err(Error::InvalidInput(format!("iso level {l} is not finite")));
            }
            IsoSpec::Label(_) => 0.5,
        };
        if matches!(iso, IsoSpec::Level(_)) {
            let bad = match &volume.data {
                VolumeData::F32(v) => v.iter().position(|x| !x.is_finite()),
                VolumeData::F64(v) => v.iter().position(|x| !x.is_finite()),
                _ => None,
            };
            if let Some(i) = bad {
                let (nx, ny) = (volume.dims[0], volume.dims[1]);
                return Err(Error::InvalidInput(format!(
                    "sample ({}, {}, {}) is not finite; marching cubes needs finite samples",
                    i % nx,
                    (i / nx) % ny,
                    i / (nx * ny)
                )));
            }
        }
        let pad = usize::from(close_border);
        let dims = volume.dims.map(|d| d + 2 * pad);
        let n_points = dims.iter().product::<usize>();
        if n_points
            .checked_mul(3)
            .is_none_or(|n| n > u32::MAX as usize * 3)
        {
            return Err(Error::InvalidInput(format!(
                "volume {:?} is too large for 32-bit vertex numbering",
                volume.dims
            )));
        }
        Ok(Field {
            volume,
            iso,
            pad,
            dims,
            level,
        })
    }

    /// Number of sample points of the (padded) grid.
    pub fn n_points(&self) -> usize {
        self.dims.iter().product()
    }

    /// The volume behind the field.
    pub fn volume(&self) -> &Volume {
        self.volume
    }

    /// Fills `out` (`dims[0]·dims[1]` values) with layer `z` of the padded
    /// grid. Level mode: samples as `f32`. Label mode: 1 where the sample
    /// equals the label, else 0. Padding samples are outside, placed so that
    /// the closing vertex lies half a sample beyond the border: `2·level − v`
    /// next to an inside sample `v > level`, `level − 1` elsewhere.
    pub fn layer(&self, z: usize, out: &mut [f32]) {
        let [nx, ny, _] = self.dims;
        let p = self.pad;
        let [vx, vy, vz] = self.volume.dims;
        let inner_z = z.checked_sub(p).filter(|&k| k < vz);
        let outside = self.level - 1.0;
        match inner_z {
            None => {
                // A padding layer: mirror the adjacent inner layer.
                let k = if z == 0 { 0 } else { vz - 1 };
                let mut row = vec![0.0f32; vx];
                out.fill(outside);
                for y in 0..vy {
                    self.inner_row(y, k, &mut row);
                    let dst = &mut out[(y + p) * nx + p..(y + p) * nx + p + vx];
                    for (d, &v) in dst.iter_mut().zip(&row) {
                        *d = self.pad_value(v);
                    }
                }
            }
            Some(k) => {
                let mut row = vec![0.0f32; vx];
                for y in 0..ny {
                    let dst = &mut out[y * nx..(y + 1) * nx];
                    let inner_y = y.checked_sub(p).filter(|&j| j < vy);
                    match inner_y {
                        None => {
                            let j = if y == 0 { 0 } else { vy - 1 };
                            self.inner_row(j, k, &mut row);
                            dst.fill(outside);
                            for (d, &v) in dst[p..p + vx].iter_mut().zip(&row) {
                                *d = self.pad_value(v);
                            }
                        }
                        Some(j) => {
                            self.inner_row(j, k, &mut dst[p..p + vx]);
                            if p == 1 {
                                dst[0] = self.pad_value(dst[1]);
                                dst[nx - 1] = self.pad_value(dst[nx - 2]);
                            }
                        }
                    }
                }
            }
        }
    }

    /// The padding sample next to an inner sample of value `v`.
    fn pad_value(&self, v: f32) -> f32 {
        if v > self.level {
            2.0 * self.level - v
        } else {
            self.level - 1.0
        }
    }

    /// Row `y` of inner layer `z` as f32 (labels mapped to 0/1).
    fn inner_row(&self, y: usize, z: usize, out: &mut [f32]) {
        let nx = self.volume.dims[0];
        let start = self.volume.index(0, y, z);
        let range = start..start + nx;
        macro_rules! convert {
            ($v:expr) => {
                match self.iso {
                    IsoSpec::Level(_) => {
                        for (o, &x) in out.iter_mut().zip(&$v[range]) {
                            *o = x as f32;
                        }
                    }
                    IsoSpec::Label(label) => {
                        for (o, &x) in out.iter_mut().zip(&$v[range]) {
                            *o = if x as f64 == label { 1.0 } else { 0.0 };
                        }
                    }
                }
            };
        }
        match &self.volume.data {
            VolumeData::U8(v) => convert!(v),
            VolumeData::I8(v) => convert!(v),
            VolumeData::U16(v) => convert!(v),
            VolumeData::I16(v) => convert!(v),
            VolumeData::U32(v) => convert!(v),
            VolumeData::I32(v) => convert!(v),
            VolumeData::F32(v) => convert!(v),
            VolumeData::F64(v) => convert!(v),
        }
    }

    /// World position of index-space point `u` (padded grid): `origin +
    /// spacing·(u − pad)` per axis, evaluated in f64 and rounded to f32.
    pub fn to_world(&self, u: [f32; 3]) -> glam::Vec3 {
        let o = self.volume.origin;
        let s = self.volume.spacing;
        let w = |a: usize| (o[a] + s[a] * (f64::from(u[a]) - self.pad as f64)) as f32;
        glam::Vec3::new(w(0), w(1), w(2))
    }
}
