//! NIfTI-1 single-file images (`.nii`, `.nii.gz`).
//!
//! Read: the 348-byte header in either byte order (told apart by
//! `sizeof_hdr`), magic `n+1`, `dim[0]` 1–7 with axes beyond the third of
//! size 1, datatypes u8/i8/i16/u16/i32/u32/f32/f64 (`bitpix` must agree),
//! spacing from `pixdim[1..=3]` (positive), samples from `vox_offset`.
//! Placement: the `srow_*` affine when `sform_code > 0` (spacing and axes
//! from its columns, which must be orthogonal), else the qform when
//! `qform_code > 0` (quaternion, `qfac = pixdim[0]` for a reflection,
//! `qoffset`), both in RAS; else (method 1) the world axes, origin 0 and no
//! anatomical frame. Intensity scaling: when `scl_slope` is
//! finite, non-zero and `(scl_slope, scl_inter) ≠ (1, 0)`, samples become
//! `F32` values `slope·x + inter` (computed in `f64`, rounded once);
//! otherwise the stored type is kept.
//!
//! Write: little-endian, `vox_offset` 352 (no extensions), the frame in
//! RAS (an LPS volume's x and y negated) as qform and sform, both code 1,
//! `xyzt_units` mm, `scl_slope` 1. The format stores `f32`, so spacing,
//! origin and axes round-trip exactly only when they are `f32` values.
//! `.nii.gz` is gzip-compressed.

use std::io::{self, BufReader, Write};
use std::path::Path;

use flate2::Compression;
use flate2::write::GzEncoder;

use super::raw::{Encoding, Payload, Piece, Skip, read_samples, write_le};
use super::text::{Endian, Num};
use crate::foundation::fs::write_atomic_with;
use crate::volume::{ScalarType, Space, VolumeData};
use crate::{Error, Position, Result, Volume};

const HEADER_LEN: usize = 348;

struct Header<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    endian: Endian,
}

impl Header<'_> {
    fn i16(&self, at: usize) -> i16 {
        Num::I16.decode(&self.bytes[at..at + 2], self.endian) as i16
    }
    fn f32(&self, at: usize) -> f64 {
        Num::F32.decode(&self.bytes[at..at + 4], self.endian)
    }
    fn error(&self, at: usize, expected: impl Into<String>, found: impl Into<String>) -> Error {
        Error::format(self.path, Position::Byte(at as u64), expected, found)
    }
    fn unsupported(&self, at: usize, what: String) -> Error {
        Error::Unsupported {
            path: self.path.into(),
            what: format!("byte {at}: {what}"),
        }
    }
}

/// Reads a NIfTI-1 image (`gz` = the file is gzip-compressed).
pub(crate) fn read(path: &Path) -> Result<Volume> {
    let gz = path
        .file_name()
        .is_some_and(|n| n.to_string_lossy().to_ascii_lowercase().ends_with(".gz"));
    let (file, meta) = crate::foundation::fs::open_input(path)?;
    let mut bytes = vec![0u8; HEADER_LEN];
    let got = if gz {
        let mut dec = flate2::read::MultiGzDecoder::new(BufReader::new(file));
        read_up_to(&mut dec, &mut bytes).map_err(|e| {
            Error::format(
                path,
                Position::Byte(0),
                "a valid gzip stream",
                e.to_string(),
            )
        })?
    } else {
        read_up_to(&mut BufReader::new(file), &mut bytes).map_err(|e| Error::io(path, e))?
    };
    if got < HEADER_LEN {
        return Err(Error::Size {
            path: path.into(),
            at: Position::Byte(0),
            what: "the NIfTI-1 header".into(),
            needed: HEADER_LEN as u64,
            limit_kind: "the file",
            limit: got as u64,
        });
    }
    let endian = match (
        i32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
        i32::from_be_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
    ) {
        (348, _) => Endian::Little,
        (_, 348) => Endian::Big,
        (le, _) => {
            return Err(Error::format(
                path,
                Position::Byte(0),
                "sizeof_hdr = 348 (NIfTI-1, either byte order)",
                format!("{le}"),
            ));
        }
    };
    let h = Header {
        path,
        bytes: &bytes,
        endian,
    };
    match &bytes[344..348] {
        b"n+1\0" => {}
        b"ni1\0" => {
            return Err(h.unsupported(
                344,
                "a two-file NIfTI (`ni1`: header and .img); convert it to .nii".into(),
            ));
        }
        other => {
            return Err(h.error(344, "magic `n+1\\0`", format!("`{}`", other.escape_ascii())));
        }
    }
    let ndim = h.i16(40);
    if !(1..=7).contains(&ndim) {
        return Err(h.error(40, "dim[0] in 1..=7", format!("{ndim}")));
    }
    let ndim = ndim as usize;
    let mut dims = [1usize; 3];
    for i in 1..=ndim {
        let d = h.i16(40 + 2 * i);
        if d < 1 {
            return Err(h.error(40 + 2 * i, format!("dim[{i}] ≥ 1"), format!("{d}")));
        }
        if i > 3 && d != 1 {
            return Err(h.unsupported(40 + 2 * i, format!("dim[{i}] = {d}: more than 3 axes")));
        }
        if i <= 3 {
            dims[i - 1] = d as usize;
        }
    }
    let code = h.i16(70);
    let ty = match code {
        2 => ScalarType::U8,
        4 => ScalarType::I16,
        8 => ScalarType::I32,
        16 => ScalarType::F32,
        64 => ScalarType::F64,
        256 => ScalarType::I8,
        512 => ScalarType::U16,
        768 => ScalarType::U32,
        _ => {
            return Err(h.unsupported(
                70,
                format!("datatype {code} (supported: 2, 4, 8, 16, 64, 256, 512, 768)"),
            ));
        }
    };
    let bitpix = h.i16(72);
    if i64::from(bitpix) != 8 * ty.size() as i64 {
        return Err(h.error(
            72,
            format!("bitpix {} for datatype {code}", 8 * ty.size()),
            format!("{bitpix}"),
        ));
    }
    let mut spacing = [1.0f64; 3];
    for (i, s) in spacing.iter_mut().enumerate().take(ndim) {
        let at = 80 + 4 * i;
        let v = h.f32(at);
        if !(v.is_finite() && v > 0.0) {
            return Err(h.error(at, format!("pixdim[{}] > 0", i + 1), format!("{v}")));
        }
        *s = v;
    }
    let vox = h.f32(108);
    if !(vox.is_finite() && vox >= HEADER_LEN as f64 && vox.fract() == 0.0) {
        return Err(h.error(108, "an integral vox_offset ≥ 348", format!("{vox}")));
    }
    // The samples start inside the file (for a plain file; inside the
    // budget's worth of decompressed bytes for a gzip one).
    let within = if gz {
        crate::foundation::alloc::memory_budget() as f64
    } else {
        meta.len() as f64
    };
    if vox > within {
        return Err(h.error(
            108,
            format!("a vox_offset within the data (at most {within})"),
            format!("{vox}"),
        ));
    }
    let placement = orientation(&h, spacing)?;

    let piece = if gz {
        Piece::new(path.into(), 0, 0, Skip::Bytes(vox as u64))
    } else {
        Piece::new(path.into(), vox as u64, 0, Skip::Bytes(0))
    };
    let data = read_samples(&Payload {
        header: path,
        field: Position::Byte(40),
        ty,
        dims,
        endian,
        encoding: if gz { Encoding::Gzip } else { Encoding::Raw },
        pieces: vec![piece],
    })?;
    let (slope, inter) = (h.f32(112), h.f32(116));
    let data = if slope.is_finite() && slope != 0.0 && (slope != 1.0 || inter != 0.0) {
        if !inter.is_finite() {
            return Err(h.error(116, "a finite scl_inter", format!("{inter}")));
        }
        VolumeData::F32(
            (0..data.len())
                .map(|i| (slope * data.get_f64(i) + inter) as f32)
                .collect(),
        )
    } else {
        data
    };
    match placement {
        None => Volume::new(dims, spacing, [0.0; 3], data),
        Some(p) => Volume::new(dims, p.spacing, p.origin, data)?
            .with_frame(p.axes, Some(Space::Ras))
            .map_err(|_| {
                h.unsupported(
                    280,
                    format!(
                        "sform axes {:?} are not at right angles (a sheared grid is not \
                         represented)",
                        p.axes
                    ),
                )
            }),
    }
}

/// A NIfTI frame: origin, axes and spacing in RAS.
struct Placement {
    origin: [f64; 3],
    axes: [[f64; 3]; 3],
    spacing: [f64; 3],
}

/// The placement from sform (`sform_code > 0`, preferred as nibabel does),
/// else qform (`qform_code > 0`), else none (method 1: the pixdim spacing
/// along the world axes, origin 0, no anatomical frame).
fn orientation(h: &Header, spacing: [f64; 3]) -> Result<Option<Placement>> {
    let (qcode, scode) = (h.i16(252), h.i16(254));
    if scode > 0 {
        let mut m = [[0.0f64; 4]; 3];
        for (r, row) in m.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x = h.f32(280 + 16 * r + 4 * c);
                if !x.is_finite() {
                    return Err(h.error(
                        280 + 16 * r + 4 * c,
                        "a finite srow entry",
                        format!("{x}"),
                    ));
                }
            }
        }
        let mut p = Placement {
            origin: [m[0][3], m[1][3], m[2][3]],
            axes: [[0.0; 3]; 3],
            spacing: [0.0; 3],
        };
        for (k, (spacing, axis)) in p.spacing.iter_mut().zip(&mut p.axes).enumerate() {
            let col = [m[0][k], m[1][k], m[2][k]];
            let len = col.iter().map(|c| c * c).sum::<f64>().sqrt();
            if len <= 0.0 {
                return Err(h.error(
                    280 + 4 * k,
                    format!("a non-zero sform column {k}"),
                    format!("{col:?}"),
                ));
            }
            *spacing = len;
            *axis = col.map(|c| c / len);
        }
        return Ok(Some(p));
    }
    if qcode > 0 {
        let [b, c, d] = [h.f32(256), h.f32(260), h.f32(264)];
        let o = [h.f32(268), h.f32(272), h.f32(276)];
        if [b, c, d].iter().chain(&o).any(|x| !x.is_finite()) {
            return Err(h.error(
                256,
                "finite quatern and qoffset values",
                format!("{:?}", [b, c, d]),
            ));
        }
        // a from the unit quaternion (clamped: f32 rounding can make the
        // sum of squares pass 1 by an ulp).
        let a = (1.0 - (b * b + c * c + d * d)).max(0.0).sqrt();
        let r = [
            [
                a * a + b * b - c * c - d * d,
                2.0 * (b * c - a * d),
                2.0 * (b * d + a * c),
            ],
            [
                2.0 * (b * c + a * d),
                a * a + c * c - b * b - d * d,
                2.0 * (c * d - a * b),
            ],
            [
                2.0 * (b * d - a * c),
                2.0 * (c * d + a * b),
                a * a + d * d - c * c - b * b,
            ],
        ];
        let qfac = if h.f32(76) < 0.0 { -1.0 } else { 1.0 };
        let axes = std::array::from_fn(|k| {
            let sign = if k == 2 { qfac } else { 1.0 };
            std::array::from_fn(|row| r[row][k] * sign)
        });
        return Ok(Some(Placement {
            origin: o,
            axes,
            spacing,
        }));
    }
    Ok(None)
}

/// The unit quaternion (b, c, d; a ≥ 0) of rotation `r` (rows), as
/// NIfTI's `mat44_to_quatern` derives it.
fn quaternion(r: [[f64; 3]; 3]) -> [f64; 3] {
    let trace = r[0][0] + r[1][1] + r[2][2] + 1.0;
    let (a, b, c, d) = if trace > 0.5 {
        let a = 0.5 * trace.sqrt();
        (
            a,
            0.25 * (r[2][1] - r[1][2]) / a,
            0.25 * (r[0][2] - r[2][0]) / a,
            0.25 * (r[1][0] - r[0][1]) / a,
        )
    } else {
        let xd = 1.0 + r[0][0] - (r[1][1] + r[2][2]);
        let yd = 1.0 + r[1][1] - (r[0][0] + r[2][2]);
        let zd = 1.0 + r[2][2] - (r[0][0] + r[1][1]);
        if xd > 1.0 {
            let b = 0.5 * xd.sqrt();
            (
                0.25 * (r[2][1] - r[1][2]) / b,
                b,
                0.25 * (r[0][1] + r[1][0]) / b,
                0.25 * (r[0][2] + r[2][0]) / b,
            )
        } else if yd > 1.0 {
            let c = 0.5 * yd.sqrt();
            (
                0.25 * (r[0][2] - r[2][0]) / c,
                0.25 * (r[0][1] + r[1][0]) / c,
                c,
                0.25 * (r[1][2] + r[2][1]) / c,
            )
        } else {
            let d = 0.5 * zd.sqrt();
            (
                0.25 * (r[1][0] - r[0][1]) / d,
                0.25 * (r[0][2] + r[2][0]) / d,
                0.25 * (r[1][2] + r[2][1]) / d,
                d,
            )
        }
    };
    if a < 0.0 { [-b, -c, -d] } else { [b, c, d] }
}

fn read_up_to(r: &mut dyn io::Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(k) => got += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// The 352-byte little-endian header (348 + empty extension flag) for `v`.
fn header(v: &Volume) -> Result<Vec<u8>> {
    let mut b = vec![0u8; 352];
    let put =
        |b: &mut Vec<u8>, at: usize, bytes: &[u8]| b[at..at + bytes.len()].copy_from_slice(bytes);
    put(&mut b, 0, &348i32.to_le_bytes());
    let ty = v.data.scalar_type();
    let dims = v.dims.map(i16::try_from);
    let [Ok(nx), Ok(ny), Ok(nz)] = dims else {
        return Err(Error::limit(
            format!("NIfTI-1 samples per axis (dims {:?})", v.dims),
            v.dims.into_iter().max().unwrap_or(0),
            i16::MAX,
        ));
    };
    for (i, d) in [3, nx, ny, nz, 1, 1, 1, 1].iter().enumerate() {
        put(&mut b, 40 + 2 * i, &d.to_le_bytes());
    }
    let code: i16 = match ty {
        ScalarType::U8 => 2,
        ScalarType::I16 => 4,
        ScalarType::I32 => 8,
        ScalarType::F32 => 16,
        ScalarType::F64 => 64,
        ScalarType::I8 => 256,
        ScalarType::U16 => 512,
        ScalarType::U32 => 768,
    };
    put(&mut b, 70, &code.to_le_bytes());
    put(&mut b, 72, &(8 * ty.size() as i16).to_le_bytes());
    // The frame in RAS, as qform (rotation, qfac for a reflection) and as
    // sform (the same affine, both with code 1).
    let (origin, axes) = v.frame_in(Space::Ras);
    let qfac = if v.reflects() { -1.0 } else { 1.0 };
    let rotation: [[f64; 3]; 3] = std::array::from_fn(|row| {
        std::array::from_fn(|k| axes[k][row] * if k == 2 { qfac } else { 1.0 })
    });
    let pixdim = [qfac, v.spacing[0], v.spacing[1], v.spacing[2]];
    for (i, p) in pixdim.iter().enumerate() {
        put(&mut b, 76 + 4 * i, &(*p as f32).to_le_bytes());
    }
    put(&mut b, 108, &352f32.to_le_bytes());
    put(&mut b, 112, &1f32.to_le_bytes());
    b[123] = 2; // xyzt_units: millimetres
    put(&mut b, 252, &1i16.to_le_bytes());
    put(&mut b, 254, &1i16.to_le_bytes());
    for (i, q) in quaternion(rotation).iter().enumerate() {
        put(&mut b, 256 + 4 * i, &(*q as f32).to_le_bytes());
    }
    for (i, o) in origin.iter().enumerate() {
        put(&mut b, 268 + 4 * i, &(*o as f32).to_le_bytes());
    }
    for row in 0..3 {
        for (k, (axis, spacing)) in axes.iter().zip(v.spacing).enumerate() {
            let x = axis[row] * spacing;
            put(&mut b, 280 + 16 * row + 4 * k, &(x as f32).to_le_bytes());
        }
        put(
            &mut b,
            280 + 16 * row + 12,
            &(origin[row] as f32).to_le_bytes(),
        );
    }
    put(&mut b, 344, b"n+1\0");
    Ok(b)
}

/// Writes `v` as little-endian NIfTI-1, gzip-compressed when `gz`.
pub(crate) fn write(path: &Path, v: &Volume, gz: bool) -> Result<()> {
    let head = header(v)?;
    write_atomic_with(path, |w| {
        if gz {
            let mut enc = GzEncoder::new(w, Compression::default());
            enc.write_all(&head)?;
            write_le(&mut enc, &v.data)?;
            enc.finish()?;
            Ok(())
        } else {
            w.write_all(&head)?;
            write_le(w, &v.data)
        }
    })
}
