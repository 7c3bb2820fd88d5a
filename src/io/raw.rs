//! Sample payloads shared by the volume readers and writers: raw, gzip,
//! zlib or ASCII data in one or more files, decoded into a [`VolumeData`]
//! of the header's element type, byte-swapped to host order.
//!
//! Sizes are checked before allocating: the sample count against the memory
//! budget, raw files against their length. Compressed streams are inflated
//! into a buffer that grows only as data actually arrives (a header cannot
//! make us allocate what the stream does not hold) and are read to the end
//! of the stream; then the sample count must equal the product of the dims.

use std::fs::File;
use std::io::{self, BufRead, BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use bytemuck::Pod;

use super::text::{Endian, Scanner, clip};
use super::{check_budget, read_whole};
use crate::volume::{ScalarType, VolumeData};
use crate::{Error, Position, Result, Volume};

/// Layout of a headerless sample file for [`read_raw_volume`].
#[derive(Debug, Clone, PartialEq)]
pub struct RawSpec {
    /// Samples per axis `[nx, ny, nz]`, x fastest in the file.
    pub dims: [usize; 3],
    /// Element type of every sample.
    pub scalar_type: ScalarType,
    /// Whether multi-byte samples are stored most significant byte first.
    pub big_endian: bool,
    /// Voxel spacing (world units, positive).
    pub spacing: [f64; 3],
    /// World position of sample (0,0,0).
    pub origin: [f64; 3],
    /// Bytes to skip at the start of the file.
    pub header_bytes: u64,
}

/// Reads `nx·ny·nz` samples at `spec.header_bytes` of `path`. Without
/// header bytes the file must hold exactly the samples; with them it holds
/// at least that many bytes after the skip (a region of a larger file).
pub fn read_raw_volume(path: &Path, spec: &RawSpec) -> Result<Volume> {
    let data = read_samples(&Payload {
        header: path,
        field: Position::Whole,
        ty: spec.scalar_type,
        dims: spec.dims,
        endian: if spec.big_endian {
            Endian::Big
        } else {
            Endian::Little
        },
        encoding: Encoding::Raw,
        pieces: vec![Piece::new(
            path.into(),
            0,
            0,
            Skip::Bytes(spec.header_bytes),
        )],
    })?;
    Volume::new(spec.dims, spec.spacing, spec.origin, data)
}

/// How the sample bytes are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Encoding {
    Raw,
    Gzip,
    Zlib,
    Ascii,
}

/// Where the samples start inside a data file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Skip {
    /// After this many bytes (of the decoded stream for compressed data).
    Bytes(u64),
    /// At the end of the file: skip whatever precedes the samples (raw only).
    FromEnd,
}

/// One data file holding an equal share of the samples.
#[derive(Debug, Clone)]
pub(crate) struct Piece {
    pub path: PathBuf,
    /// Byte offset where the data part begins (after an attached header).
    pub start: u64,
    /// Text lines to skip before anything else.
    pub line_skip: u64,
    pub skip: Skip,
}

impl Piece {
    pub fn new(path: PathBuf, start: u64, line_skip: u64, skip: Skip) -> Self {
        Piece {
            path,
            start,
            line_skip,
            skip,
        }
    }
}

/// Everything needed to decode a volume's samples.
#[derive(Debug)]
pub(crate) struct Payload<'a> {
    /// The header file, for errors about the header's own claims.
    pub header: &'a Path,
    /// The header field that sets the sizes.
    pub field: Position,
    pub ty: ScalarType,
    pub dims: [usize; 3],
    pub endian: Endian,
    pub encoding: Encoding,
    pub pieces: Vec<Piece>,
}

macro_rules! each {
    ($data:expr, $v:ident => $body:expr) => {
        match $data {
            VolumeData::U8($v) => $body,
            VolumeData::I8($v) => $body,
            VolumeData::U16($v) => $body,
            VolumeData::I16($v) => $body,
            VolumeData::U32($v) => $body,
            VolumeData::I32($v) => $body,
            VolumeData::F32($v) => $body,
            VolumeData::F64($v) => $body,
        }
    };
}

/// No samples yet, room for `capacity` reserved exactly and fallibly (so
/// filling it never grows the buffer past the samples the header
/// announced, and a machine without that memory gives an error, not an
/// abort).
fn empty(path: &Path, ty: ScalarType, capacity: usize) -> Result<VolumeData> {
    let mut data = match ty {
        ScalarType::U8 => VolumeData::U8(Vec::new()),
        ScalarType::I8 => VolumeData::I8(Vec::new()),
        ScalarType::U16 => VolumeData::U16(Vec::new()),
        ScalarType::I16 => VolumeData::I16(Vec::new()),
        ScalarType::U32 => VolumeData::U32(Vec::new()),
        ScalarType::I32 => VolumeData::I32(Vec::new()),
        ScalarType::F32 => VolumeData::F32(Vec::new()),
        ScalarType::F64 => VolumeData::F64(Vec::new()),
    };
    each!(&mut data, v => v.try_reserve_exact(capacity)).map_err(|_| Error::HostMemory {
        what: format!("{}: {capacity} samples of {}", path.display(), ty.name()),
        bytes: capacity as u64 * ty.size() as u64,
    })?;
    Ok(data)
}

/// Reads until `buf` is full or the stream ends; returns the bytes read.
fn read_full(r: &mut dyn Read, buf: &mut [u8]) -> io::Result<usize> {
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

/// Appends up to `count` samples from `r`, growing `buf` in 16 MiB steps as
/// data arrives; returns how many whole samples were appended.
fn append<T: Pod>(buf: &mut Vec<T>, count: usize, r: &mut dyn Read) -> io::Result<usize> {
    const STEP_BYTES: usize = 16 << 20;
    let size = std::mem::size_of::<T>();
    let start = buf.len();
    let target = start + count;
    while buf.len() < target {
        let old = buf.len();
        let chunk = (STEP_BYTES / size).min(target - old);
        buf.resize(old + chunk, T::zeroed());
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut buf[old..]);
        let got = read_full(r, bytes)?;
        if got < bytes.len() {
            buf.truncate(old + got / size);
            break;
        }
    }
    Ok(buf.len() - start)
}

fn swap_bytes(data: &mut VolumeData) {
    match data {
        VolumeData::U8(_) | VolumeData::I8(_) => {}
        VolumeData::U16(v) => v.iter_mut().for_each(|x| *x = x.swap_bytes()),
        VolumeData::I16(v) => v.iter_mut().for_each(|x| *x = x.swap_bytes()),
        VolumeData::U32(v) => v.iter_mut().for_each(|x| *x = x.swap_bytes()),
        VolumeData::I32(v) => v.iter_mut().for_each(|x| *x = x.swap_bytes()),
        VolumeData::F32(v) => v
            .iter_mut()
            .for_each(|x| *x = f32::from_bits(x.to_bits().swap_bytes())),
        VolumeData::F64(v) => v
            .iter_mut()
            .for_each(|x| *x = f64::from_bits(x.to_bits().swap_bytes())),
    }
}

/// Pushes a text sample if it is representable in the element type.
fn push_text(data: &mut VolumeData, x: f64) -> bool {
    macro_rules! int {
        ($v:expr, $t:ty) => {{
            let ok = x.fract() == 0.0 && x >= <$t>::MIN as f64 && x <= <$t>::MAX as f64;
            if ok {
                $v.push(x as $t);
            }
            ok
        }};
    }
    match data {
        VolumeData::U8(v) => int!(v, u8),
        VolumeData::I8(v) => int!(v, i8),
        VolumeData::U16(v) => int!(v, u16),
        VolumeData::I16(v) => int!(v, i16),
        VolumeData::U32(v) => int!(v, u32),
        VolumeData::I32(v) => int!(v, i32),
        VolumeData::F32(v) => {
            v.push(x as f32);
            true
        }
        VolumeData::F64(v) => {
            v.push(x);
            true
        }
    }
}

/// Opens a data file at `piece.start`, skips `line_skip` lines; returns the
/// reader and the byte offset reached.
fn open_after_lines(piece: &Piece) -> Result<(BufReader<File>, u64)> {
    let (mut file, _) = crate::foundation::fs::open_input(&piece.path)?;
    file.seek(SeekFrom::Start(piece.start))
        .map_err(|e| Error::io(&piece.path, e))?;
    let mut r = BufReader::new(file);
    let mut offset = piece.start;
    let mut sink = Vec::new();
    for line in 0..piece.line_skip {
        sink.clear();
        let k = r
            .read_until(b'\n', &mut sink)
            .map_err(|e| Error::io(&piece.path, e))?;
        if k == 0 {
            return Err(Error::format(
                &piece.path,
                Position::Line(line as usize + 1),
                format!("{} lines to skip", piece.line_skip),
                "end of file",
            ));
        }
        offset += k as u64;
    }
    Ok((r, offset))
}

/// `nx·ny·nz`, checked for overflow and (times the sample size) against the
/// memory budget.
pub(crate) fn sample_count(
    header: &Path,
    at: &Position,
    dims: [usize; 3],
    ty: ScalarType,
) -> Result<usize> {
    let bytes = dims
        .iter()
        .try_fold(ty.size() as u64, |a, &d| a.checked_mul(d as u64))
        .unwrap_or(u64::MAX);
    check_budget(
        header,
        at.clone(),
        &format!("{dims:?} samples of {}", ty.name()),
        bytes,
    )?;
    usize::try_from(bytes / ty.size() as u64).map_err(|_| Error::Size {
        path: header.into(),
        at: at.clone(),
        what: format!("{dims:?} samples"),
        needed: bytes,
        limit_kind: super::ADDRESS_SPACE_KIND,
        limit: usize::MAX as u64,
    })
}

/// Decodes all samples described by `p`. An error in a data file the
/// header names also names the header (the file the user gave).
pub(crate) fn read_samples(p: &Payload) -> Result<VolumeData> {
    samples(p).map_err(|e| {
        let in_data_file = match &e {
            Error::Io { path, .. }
            | Error::Format { path, .. }
            | Error::Size { path, .. }
            | Error::Unsupported { path, .. } => path != p.header,
            _ => false,
        };
        if in_data_file {
            Error::In {
                context: format!("{}: the data file it names", p.header.display()),
                inner: Box::new(e),
            }
        } else {
            e
        }
    })
}

fn samples(p: &Payload) -> Result<VolumeData> {
    let n = sample_count(p.header, &p.field, p.dims, p.ty)?;
    let elem = p.ty.size() as u64;
    let pieces = p.pieces.len();
    if pieces == 0 || n % pieces != 0 {
        return Err(Error::format(
            p.header,
            p.field.clone(),
            format!("a number of data files dividing the {n} samples"),
            format!("{pieces} files"),
        ));
    }
    let per = n / pieces;
    let per_bytes = per as u64 * elem;
    let mut data = empty(p.header, p.ty, n)?;
    if p.encoding == Encoding::Raw {
        // Check every file's length before allocating or reading anything.
        let mut starts = Vec::with_capacity(pieces);
        for piece in &p.pieces {
            let (_, lines) = open_after_lines(piece)?;
            let len = std::fs::metadata(&piece.path)
                .map_err(|e| Error::io(&piece.path, e))?
                .len();
            let start = match piece.skip {
                Skip::Bytes(b) => lines.saturating_add(b),
                Skip::FromEnd => len.saturating_sub(per_bytes),
            };
            if len < start.saturating_add(per_bytes) {
                return Err(Error::Size {
                    path: piece.path.clone(),
                    at: Position::Byte(start),
                    what: format!("{per} samples of {}", p.ty.name()),
                    needed: per_bytes,
                    limit_kind: "the bytes after the header",
                    limit: len.saturating_sub(start),
                });
            }
            // More bytes than the header accounts for, where no skip picks a
            // region of a larger file: its sizes or type do not describe
            // this file (compressed streams are checked alike).
            let end = start + per_bytes;
            let region = piece.line_skip > 0 || matches!(piece.skip, Skip::Bytes(b) if b > 0);
            if len > end && !region {
                return Err(Error::format(
                    &piece.path,
                    Position::Byte(end),
                    format!(
                        "the end of the file after {per} samples of {} ({per_bytes} bytes \
                         from byte {start})",
                        p.ty.name()
                    ),
                    format!(
                        "{} more bytes (do the header's sizes, type and byte skip match the data?)",
                        len - end
                    ),
                ));
            }
            starts.push(start);
        }
        for (piece, start) in p.pieces.iter().zip(starts) {
            let (mut f, _) = crate::foundation::fs::open_input(&piece.path)?;
            f.seek(SeekFrom::Start(start))
                .map_err(|e| Error::io(&piece.path, e))?;
            let got = each!(&mut data, buf => append(buf, per, &mut f))
                .map_err(|e| Error::io(&piece.path, e))?;
            if got != per {
                return Err(Error::format(
                    &piece.path,
                    Position::Byte(start + got as u64 * elem),
                    format!("{per} samples"),
                    format!("the file ended after {got} (changed while reading?)"),
                ));
            }
        }
    } else if p.encoding == Encoding::Ascii {
        for piece in &p.pieces {
            let bytes = read_whole(&piece.path)?;
            let start = usize::try_from(piece.start)
                .unwrap_or(usize::MAX)
                .min(bytes.len());
            let mut sc = Scanner::new(&piece.path, &bytes[start..]);
            for _ in 0..piece.line_skip {
                sc.skip_line();
            }
            sc.check_count(sc.pos(), "text samples", per as u64, 2)?;
            for _ in 0..per {
                let (at, tok) = sc.next(&format!("a {} sample", p.ty.name()))?;
                let ok = tok.parse::<f64>().is_ok_and(|x| push_text(&mut data, x));
                if !ok {
                    return Err(sc.error(
                        at,
                        format!("a {} sample", p.ty.name()),
                        format!("`{}`", clip(tok)),
                    ));
                }
            }
        }
    } else {
        for piece in &p.pieces {
            let (mut r, offset) = open_after_lines(piece)?;
            let mut stream: Box<dyn Read + '_> = match p.encoding {
                Encoding::Gzip => Box::new(flate2::bufread::MultiGzDecoder::new(&mut r)),
                _ => Box::new(flate2::bufread::ZlibDecoder::new(&mut r)),
            };
            let kind = if p.encoding == Encoding::Gzip {
                "gzip"
            } else {
                "zlib"
            };
            let bad_stream = |e: io::Error| {
                Error::format(
                    &piece.path,
                    Position::Byte(offset),
                    format!("a valid {kind} stream"),
                    e.to_string(),
                )
            };
            if let Skip::Bytes(b) = piece.skip {
                let skipped =
                    io::copy(&mut (&mut stream).take(b), &mut io::sink()).map_err(bad_stream)?;
                if skipped < b {
                    return Err(Error::format(
                        &piece.path,
                        Position::Byte(offset),
                        format!("{b} bytes to skip in the decompressed data"),
                        format!("{skipped}"),
                    ));
                }
            }
            let got = each!(&mut data, buf => append(buf, per, &mut stream)).map_err(bad_stream)?;
            if got != per {
                return Err(Error::Size {
                    path: piece.path.clone(),
                    at: Position::Byte(offset),
                    what: format!("{per} samples of {} (after decompression)", p.ty.name()),
                    needed: per_bytes,
                    limit_kind: "the decompressed stream",
                    limit: got as u64 * elem,
                });
            }
            let mut extra = [0u8; 1];
            if read_full(&mut stream, &mut extra).map_err(bad_stream)? != 0 {
                return Err(Error::format(
                    &piece.path,
                    Position::Byte(offset),
                    format!("a {kind} stream of exactly {per_bytes} bytes"),
                    "more data",
                ));
            }
            // A zlib stream ends by itself: bytes after it in the file are
            // not data (gzip members after the first are read as one stream,
            // and anything else there is an invalid member).
            drop(stream);
            if read_full(&mut r, &mut extra).map_err(|e| Error::io(&piece.path, e))? != 0 {
                return Err(Error::format(
                    &piece.path,
                    Position::Byte(offset),
                    format!("the end of the file after the {kind} stream"),
                    "more bytes",
                ));
            }
        }
    }
    if p.encoding != Encoding::Ascii && (p.endian == Endian::Big) != cfg!(target_endian = "big") {
        swap_bytes(&mut data);
    }
    Ok(data)
}

/// Writes the samples of `data` little-endian.
pub(crate) fn write_le(w: &mut dyn io::Write, data: &VolumeData) -> io::Result<()> {
    if cfg!(target_endian = "little") {
        each!(data, v => w.write_all(bytemuck::cast_slice(v)))
    } else {
        let mut swapped = data.clone();
        swap_bytes(&mut swapped);
        each!(&swapped, v => w.write_all(bytemuck::cast_slice(v)))
    }
}
