//! The sample grid marching cubes walks: the volume's samples as `f32`
//! (labels as 0/1), optionally padded by one outside sample per side.
//!
//! [`Field::layer`] defines that grid in `f32`; nothing converts whole
//! layers in production. The CPU reads the inside flags a row at a time as
//! bits straight from the volume's native type ([`Field::inside_row`]) and
//! converts a sample to `f32` only where an edge crosses
//! ([`Field::sample`]); the GPU uploads the samples in their own type and
//! decodes and pads them in the kernels ([`super::grid`]). All give exactly
//! `layer(z)[x + nx·y]` and `layer(z)[x + nx·y] >= level` (tested in
//! `tests/mc.rs`), so the CPU mirror and the GPU kernels see bit-identical
//! inputs.

use super::IsoSpec;
use crate::volume::{Samples, VolumeView};
use crate::{Error, Result};

/// Most samples per axis of the (padded) grid: `2¹⁴`, below which f32
/// grid coordinates resolve [`super::cpu::T_MIN`].
pub const MAX_AXIS_SAMPLES: usize = 1 << 14;

/// A volume prepared for marching cubes.
#[derive(Debug)]
pub struct Field<'a> {
    volume: VolumeView<'a>,
    iso: IsoSpec,
    /// 1 when the border is closed (one outside sample added per side), else 0.
    pub pad: usize,
    /// Sample counts per axis of the (padded) grid.
    pub dims: [usize; 3],
    /// Iso level in sample units (0.5 for labels).
    pub level: f32,
}

impl<'a> Field<'a> {
    /// Checks the iso specification and the grid size. The samples'
    /// finiteness is checked where they are read: by the CPU path's bit
    /// load, row by row as it packs them ([`Field::check_finite_row`]), and
    /// by [`Field::check_finite`] (a pass of its own) before the GPU path
    /// converts them.
    pub fn new(
        volume: impl Into<VolumeView<'a>>,
        iso: IsoSpec,
        close_border: bool,
    ) -> Result<Self> {
        let volume = volume.into();
        let level = match iso {
            IsoSpec::Level(l) if l.is_finite() => l,
            IsoSpec::Level(l) => {
                return Err(Error::param("level", l, "must be finite"));
            }
            IsoSpec::Label(_) => 0.5,
        };
        let pad = usize::from(close_border);
        let dims = volume.dims.map(|d| d + 2 * pad);
        if dims.iter().any(|&d| d > MAX_AXIS_SAMPLES) {
            return Err(Error::limit(
                format!(
                    "marching cubes: samples per axis of volume {:?} (border padding included; \
                     f32 grid positions must keep vertices apart)",
                    volume.dims
                ),
                dims.into_iter().max().unwrap_or(0),
                MAX_AXIS_SAMPLES,
            ));
        }
        let n_points = dims.iter().product::<usize>();
        if n_points
            .checked_mul(3)
            .is_none_or(|n| n > u32::MAX as usize * 3)
        {
            return Err(Error::limit(
                format!(
                    "marching cubes: grid points of volume {:?} (32-bit vertex numbering)",
                    volume.dims
                ),
                n_points,
                u32::MAX,
            ));
        }
        Ok(Field {
            volume,
            iso,
            pad,
            dims,
            level,
        })
    }

    /// Errors at the first sample that is not finite (level mode; labels
    /// are compared, never interpolated). Marching cubes needs finite
    /// samples: a NaN is neither inside nor outside.
    pub fn check_finite(&self) -> Result<()> {
        let [_, vy, vz] = self.volume.dims;
        (0..vz).try_for_each(|k| (0..vy).try_for_each(|j| self.check_inner_row(j, k)))
    }

    /// [`Field::check_finite`] for row `y` of layer `z` of the padded grid
    /// (padding rows hold no samples of their own: nothing to check).
    pub fn check_finite_row(&self, y: usize, z: usize) -> Result<()> {
        let p = self.pad;
        let [_, vy, vz] = self.volume.dims;
        match (y.checked_sub(p), z.checked_sub(p)) {
            (Some(j), Some(k)) if j < vy && k < vz => self.check_inner_row(j, k),
            _ => Ok(()),
        }
    }

    fn check_inner_row(&self, j: usize, k: usize) -> Result<()> {
        if matches!(self.iso, IsoSpec::Label(_)) {
            return Ok(());
        }
        let nx = self.volume.dims[0];
        let start = self.volume.index(0, j, k);
        let bad = match self.volume.data {
            Samples::F32(v) => first_non_finite(&v[start..start + nx], |x| x.is_finite()),
            Samples::F64(v) => first_non_finite(&v[start..start + nx], |x| x.is_finite()),
            _ => None,
        };
        match bad {
            None => Ok(()),
            Some(i) => Err(Error::data(
                "volume",
                "sample",
                start + i,
                format!("at ({i}, {j}, {k}) is not finite; marching cubes needs finite samples"),
            )),
        }
    }

    /// The surface asked for (a level or a label).
    pub fn iso(&self) -> IsoSpec {
        self.iso
    }

    /// Number of sample points of the (padded) grid.
    pub fn n_points(&self) -> usize {
        self.dims.iter().product()
    }

    /// The volume behind the field.
    pub fn volume(&self) -> &VolumeView<'a> {
        &self.volume
    }

    /// Fills `out` (`dims[0]·dims[1]` values) with layer `z` of the padded
    /// grid. Level mode: samples as `f32`. Label mode: 1 where the sample
    /// equals the label, else 0. Padding samples are outside, placed so that
    /// the closing vertex lies half a sample beyond the border: `2·level − v`
    /// next to an inside sample `v > level`, `outside()` (`level − 1`)
    /// elsewhere.
    pub fn layer(&self, z: usize, out: &mut [f32]) {
        let [nx, ny, _] = self.dims;
        let p = self.pad;
        let [vx, vy, vz] = self.volume.dims;
        let inner_z = z.checked_sub(p).filter(|&k| k < vz);
        let outside = self.outside();
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
            (2.0 * self.level - v).min(self.outside())
        } else {
            self.outside()
        }
    }

    /// A value below the level: `level − 1`, or the next float down where
    /// the level is too large for `− 1` to change it (|level| ≥ 2²⁴).
    pub(crate) fn outside(&self) -> f32 {
        (self.level - 1.0).min(self.level.next_down())
    }

    /// Row `y` of inner layer `z` as f32 (labels mapped to 0/1).
    pub(crate) fn inner_row(&self, y: usize, z: usize, out: &mut [f32]) {
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
        match self.volume.data {
            Samples::U8(v) => convert!(v),
            Samples::I8(v) => convert!(v),
            Samples::U16(v) => convert!(v),
            Samples::I16(v) => convert!(v),
            Samples::U32(v) => convert!(v),
            Samples::I32(v) => convert!(v),
            Samples::F32(v) => convert!(v),
            Samples::F64(v) => convert!(v),
        }
    }

    /// Words of one row of [`Field::inside_row`]: `⌈dims[0] / 64⌉`.
    pub fn row_words(&self) -> usize {
        self.dims[0].div_ceil(64)
    }

    /// Inside flags of row `y` of layer `z` of the padded grid as bits
    /// (`x` is bit `x mod 64` of word `x / 64`; bits from `dims[0]` on are
    /// 0): exactly `layer(z)[x + nx·y] >= level`. `out`: [`Field::row_words`]
    /// words. Inner samples are compared in their native type, one row at a
    /// time, without conversion to `f32`.
    pub fn inside_row(&self, y: usize, z: usize, out: &mut [u64]) {
        let [nx, ny, nz] = self.dims;
        let p = self.pad;
        out.fill(0);
        let pad_y = p == 1 && (y == 0 || y == ny - 1);
        let pad_z = p == 1 && (z == 0 || z == nz - 1);
        let [vx, vy, vz] = self.volume.dims;
        if pad_y || pad_z {
            // The padding values of `layer`: `pad_value` of the inner row
            // next to it, `outside()` where two coordinates are padding.
            let mut row = vec![self.outside(); nx];
            if !(pad_y && pad_z) {
                let inner = |c: usize, d: usize| c.saturating_sub(1).min(d - 1);
                let mut inner_row = vec![0.0f32; vx];
                self.inner_row(inner(y, vy), inner(z, vz), &mut inner_row);
                for (d, &v) in row[1..=vx].iter_mut().zip(&inner_row) {
                    *d = self.pad_value(v);
                }
            }
            pack(&row, out, |v| v >= self.level);
            return;
        }
        let (j, k) = (y - p, z - p);
        self.pack_inner(j, k, out);
        if p == 1 {
            shift_up_one(out);
            let ends = [(0, 0), (vx - 1, nx - 1)];
            for (i, x) in ends {
                let v = self.inner_value(self.volume.index(i, j, k));
                if self.pad_value(v) >= self.level {
                    out[x / 64] |= 1 << (x % 64);
                }
            }
        }
    }

    /// Inside bits of inner row `j` of inner layer `k` (unpadded x).
    fn pack_inner(&self, j: usize, k: usize, out: &mut [u64]) {
        let nx = self.volume.dims[0];
        let start = self.volume.index(0, j, k);
        let range = start..start + nx;
        let level = self.level;
        // Integer types exact in f32: `f32(v) >= level` ⇔ `v >= ⌈level⌉`;
        // `f64(v) == label` ⇔ label integral and `v == label`.
        macro_rules! exact_int {
            ($v:expr, $t:ty) => {{
                let src = &$v[range];
                match self.iso {
                    IsoSpec::Level(_) => {
                        let t = level.ceil();
                        if t <= <$t>::MIN as f32 {
                            pack(src, out, |_| true);
                        } else if t <= <$t>::MAX as f32 {
                            let t = t as $t;
                            pack(src, out, |v| v >= t);
                        }
                    }
                    IsoSpec::Label(label) => {
                        if label.fract() == 0.0
                            && label >= <$t>::MIN as f64
                            && label <= <$t>::MAX as f64
                        {
                            let l = label as $t;
                            pack(src, out, |v| v == l);
                        }
                    }
                }
            }};
        }
        macro_rules! general {
            ($v:expr) => {{
                let src = &$v[range];
                match self.iso {
                    IsoSpec::Level(_) => pack(src, out, |v| v as f32 >= level),
                    IsoSpec::Label(label) => pack(src, out, |v| v as f64 == label),
                }
            }};
        }
        match self.volume.data {
            Samples::U8(v) => exact_int!(v, u8),
            Samples::I8(v) => exact_int!(v, i8),
            Samples::U16(v) => exact_int!(v, u16),
            Samples::I16(v) => exact_int!(v, i16),
            Samples::U32(v) => general!(v),
            Samples::I32(v) => general!(v),
            Samples::F32(v) => general!(v),
            Samples::F64(v) => general!(v),
        }
    }

    /// Sample `(x, y, z)` of the padded grid as `f32`: exactly
    /// `layer(z)[x + nx·y]`. A padding sample next to one inner sample `v`
    /// (one coordinate outside) is `pad_value(v)`; padding edges and
    /// corners are `outside()`.
    #[inline]
    pub fn sample(&self, x: usize, y: usize, z: usize) -> f32 {
        let p = self.pad;
        let d = self.volume.dims;
        let (i, j, k) = (x.wrapping_sub(p), y.wrapping_sub(p), z.wrapping_sub(p));
        if i < d[0] && j < d[1] && k < d[2] {
            return self.inner_value(i + d[0] * (j + d[1] * k));
        }
        let c = [x, y, z];
        let mut inner = [0usize; 3];
        let mut n_pad = 0;
        for a in 0..3 {
            match c[a].checked_sub(p).filter(|&i| i < d[a]) {
                Some(i) => inner[a] = i,
                None => {
                    n_pad += 1;
                    inner[a] = if c[a] == 0 { 0 } else { d[a] - 1 };
                }
            }
        }
        let v = || self.inner_value(self.volume.index(inner[0], inner[1], inner[2]));
        match n_pad {
            0 => v(),
            1 => self.pad_value(v()),
            _ => self.outside(),
        }
    }

    /// Calls `visitor` with [`NativeSamples`] of the volume's scalar type:
    /// one type dispatch for a whole pass instead of one per sample.
    pub fn visit_samples<V: SampleVisitor>(&self, visitor: V) -> V::Output {
        match self.volume.data {
            Samples::U8(v) => visitor.visit(NativeSamples::new(self, v)),
            Samples::I8(v) => visitor.visit(NativeSamples::new(self, v)),
            Samples::U16(v) => visitor.visit(NativeSamples::new(self, v)),
            Samples::I16(v) => visitor.visit(NativeSamples::new(self, v)),
            Samples::U32(v) => visitor.visit(NativeSamples::new(self, v)),
            Samples::I32(v) => visitor.visit(NativeSamples::new(self, v)),
            Samples::F32(v) => visitor.visit(NativeSamples::new(self, v)),
            Samples::F64(v) => visitor.visit(NativeSamples::new(self, v)),
        }
    }

    /// Inner sample `i` (linear index) as `f32`, labels as 0/1: the
    /// conversion of [`Field::inner_row`].
    #[inline]
    fn inner_value(&self, i: usize) -> f32 {
        macro_rules! convert {
            ($v:expr) => {
                match self.iso {
                    IsoSpec::Level(_) => $v[i] as f32,
                    IsoSpec::Label(label) => {
                        if $v[i] as f64 == label {
                            1.0
                        } else {
                            0.0
                        }
                    }
                }
            };
        }
        match self.volume.data {
            Samples::U8(v) => convert!(v),
            Samples::I8(v) => convert!(v),
            Samples::U16(v) => convert!(v),
            Samples::I16(v) => convert!(v),
            Samples::U32(v) => convert!(v),
            Samples::I32(v) => convert!(v),
            Samples::F32(v) => convert!(v),
            Samples::F64(v) => convert!(v),
        }
    }

    /// World position of index-space point `u` (padded grid):
    /// [`VolumeView::world`] of `u − pad`, evaluated in f64 and rounded to f32.
    pub fn to_world(&self, u: [f32; 3]) -> glam::Vec3 {
        let w = self.volume.world(u.map(|x| f64::from(x) - self.pad as f64));
        glam::Vec3::new(w[0] as f32, w[1] as f32, w[2] as f32)
    }
}

/// A scalar type a volume stores, converted with `as` exactly like
/// [`Field::layer`] does.
pub trait Scalar: Copy + Send + Sync {
    /// The sample as `f32` (level mode).
    fn to_f32(self) -> f32;
    /// The sample as `f64` (compared with a label).
    fn to_f64(self) -> f64;
}

macro_rules! scalar {
    ($($t:ty),*) => {$(
        impl Scalar for $t {
            #[inline]
            fn to_f32(self) -> f32 {
                self as f32
            }
            #[inline]
            fn to_f64(self) -> f64 {
                self as f64
            }
        }
    )*};
}
scalar!(u8, i8, u16, i16, u32, i32, f32, f64);

/// Something run with the samples in their native type
/// ([`Field::visit_samples`]).
pub trait SampleVisitor {
    type Output;
    fn visit<T: Scalar>(self, samples: NativeSamples<'_, '_, T>) -> Self::Output;
}

/// [`Field::sample`] with the volume's scalar type known at compile time:
/// inner samples are one index and one conversion; padding samples go
/// through [`Field::sample`]. Gives exactly [`Field::sample`].
#[derive(Debug, Clone, Copy)]
pub struct NativeSamples<'f, 'a, T> {
    field: &'f Field<'a>,
    data: &'a [T],
    dims: [usize; 3],
    pad: usize,
    /// `Some(label)` in label mode.
    label: Option<f64>,
}

impl<'f, 'a, T: Scalar> NativeSamples<'f, 'a, T> {
    fn new(field: &'f Field<'a>, data: &'a [T]) -> Self {
        NativeSamples {
            field,
            data,
            dims: field.volume.dims,
            pad: field.pad,
            label: match field.iso {
                IsoSpec::Level(_) => None,
                IsoSpec::Label(l) => Some(l),
            },
        }
    }

    /// The iso level ([`Field::level`]).
    pub fn level(&self) -> f32 {
        self.field.level
    }

    /// Sample `(x, y, z)` of the padded grid: exactly [`Field::sample`].
    #[inline]
    pub fn sample(&self, x: usize, y: usize, z: usize) -> f32 {
        let p = self.pad;
        let d = self.dims;
        let (i, j, k) = (x.wrapping_sub(p), y.wrapping_sub(p), z.wrapping_sub(p));
        if i < d[0] && j < d[1] && k < d[2] {
            let v = self.data[i + d[0] * (j + d[1] * k)];
            match self.label {
                None => v.to_f32(),
                Some(l) => f32::from(u8::from(v.to_f64() == l)),
            }
        } else {
            self.field.sample(x, y, z)
        }
    }
}

/// The first `x` of `row` that is not `finite`: whole chunks are tested
/// without an early exit (a loop that vectorises), the position only
/// searched in a chunk that fails.
fn first_non_finite<T: Copy>(row: &[T], finite: impl Fn(T) -> bool) -> Option<usize> {
    row.chunks(64).enumerate().find_map(|(c, chunk)| {
        if chunk.iter().fold(true, |a, &x| a & finite(x)) {
            None
        } else {
            chunk.iter().position(|&x| !finite(x)).map(|i| 64 * c + i)
        }
    })
}

/// Sets bit `i` of `out` where `inside(src[i])`. `out`: ≥ ⌈len/64⌉ words,
/// zero. 64 samples at a time: the flags as bytes (a branch-free loop that
/// vectorises), then 8 bytes to 8 bits with one multiplication
/// ([`bytes_to_bits`]).
#[inline]
fn pack<T: Copy>(src: &[T], out: &mut [u64], inside: impl Fn(T) -> bool) {
    let mut chunks = src.chunks_exact(64);
    let mut flags = [0u8; 64];
    for (w, c) in out.iter_mut().zip(&mut chunks) {
        for (f, &v) in flags.iter_mut().zip(c) {
            *f = u8::from(inside(v));
        }
        *w = bytes_to_bits(&flags);
    }
    let rest = chunks.remainder();
    if !rest.is_empty() {
        flags.fill(0);
        for (f, &v) in flags.iter_mut().zip(rest) {
            *f = u8::from(inside(v));
        }
        out[src.len() / 64] = bytes_to_bits(&flags);
    }
}

/// 64 flags (bytes 0 or 1) as the bits of one word, flag `i` → bit `i`.
/// Per 8 bytes: `x · 0x0102040810204080` puts byte `i` at bit `56 + i`
/// (every other product lands on a distinct bit below 56 or past 63, so
/// nothing carries into the top byte).
#[inline]
fn bytes_to_bits(flags: &[u8; 64]) -> u64 {
    let mut w = 0u64;
    for (k, b) in flags.chunks_exact(8).enumerate() {
        let mut x = [0u8; 8];
        x.copy_from_slice(b);
        let x = u64::from_le_bytes(x);
        w |= (x.wrapping_mul(0x0102_0408_1020_4080) >> 56) << (8 * k);
    }
    w
}

/// Shifts a bit row up by one position (bit `x` moves to `x + 1`).
fn shift_up_one(row: &mut [u64]) {
    let mut carry = 0u64;
    for w in row.iter_mut() {
        let next = *w >> 63;
        *w = *w << 1 | carry;
        carry = next;
    }
}
