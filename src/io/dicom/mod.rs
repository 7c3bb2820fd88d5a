//! DICOM (PS3.10 files) through the dicom-rs crates: one file (a single
//! slice or a multi-frame image) or a directory holding one or more series.
//!
//! **Recognised by content**: 128 bytes of preamble then `DICM`, or, for old
//! files without preamble and file-meta group, a data set whose first tag is
//! in group 0008 ([`is_dicom`]). Files with a preamble but no file-meta group,
//! and files with neither, are read as implicit-VR little endian.
//!
//! **Geometry** (PS3.3 C.7.6.2): each frame's Image Position (Patient) is
//! the LPS position of its first pixel; Image Orientation (Patient) gives
//! the row direction (columns increase along it) and the column direction;
//! Pixel Spacing is *row spacing \ column spacing*. Enhanced multi-frame
//! files take these per frame from the Per-frame Functional Groups, else
//! from the Shared ones. Frames are ordered by their position along the
//! slice normal, never by file name or instance number ([`series`]).
//!
//! **Values**: Rescale Slope / Intercept (per frame) turn stored values
//! into modality values (Hounsfield units for CT). Integral results are
//! kept as `i16`, `u16` or `i32` (the smallest that holds them), others as
//! `f32`.
//!
//! **Refused, with the reason**: images with more than one sample per
//! pixel (colour), transfer syntaxes dicom-rs cannot decode (named in the
//! error: JPEG 2000, JPEG-LS, JPEG XL, … need native codecs this build
//! leaves out), frames of different size or orientation in one series, two
//! frames at the same position, gantry tilt and non-uniform slice spacing
//! (the grid would be sheared or uneven, which a [`Volume`] does not
//! represent; resample first).

mod series;

pub use series::SeriesInfo;
pub(crate) use series::{list_series, read_dir};

use std::path::Path;

use dicom_core::Tag;
use dicom_dictionary_std::tags;
use dicom_encoding::TransferSyntaxIndex;
use dicom_encoding::transfer_syntax::TransferSyntax;
use dicom_object::mem::InMemElement;
use dicom_object::{
    DefaultDicomObject, FileMetaTableBuilder, InMemDicomObject, OpenFileOptions, file::ReadPreamble,
};
use dicom_pixeldata::{ConvertOptions, ModalityLutOption, PixelDecoder};
use dicom_transfer_syntax_registry::TransferSyntaxRegistry;

use super::read_whole_with;
use crate::volume::{Space, Volume, VolumeData};
use crate::{Error, Position, Result};

/// Whether `head` (a file's first bytes) begins a DICOM file: `DICM` after
/// the 128-byte preamble, or (no preamble, no file meta) a little-endian
/// data set whose first element is in group 0008.
pub(crate) fn is_dicom(head: &[u8]) -> bool {
    head.get(128..132) == Some(b"DICM") || bare_dataset(head)
}

/// A data set without preamble and meta group: its first tag (group,
/// element; little endian) is in group 0008, as every image's is.
fn bare_dataset(head: &[u8]) -> bool {
    head.len() >= 8 && head[0..2] == [0x08, 0x00] && head[2..4] != [0xff, 0xff]
}

fn not_dicom(path: &Path) -> Error {
    Error::format(
        path,
        Position::Byte(128),
        "a DICOM file (`DICM` after the 128-byte preamble, or a data set starting with group 0008)",
        "other bytes",
    )
}

/// Wraps a dicom-rs error as a format error of `path`.
fn crate_error(path: &Path, what: &str, e: impl std::fmt::Display) -> Error {
    Error::format(path, Position::Whole, what, format!("dicom-rs: {e}"))
}

/// Reads one DICOM file boundedly (the whole file, checked against the
/// memory budget); `header_only` stops before the pixel data.
pub(crate) fn open(path: &Path, header_only: bool) -> Result<DefaultDicomObject> {
    let bytes = read_whole_with(path, |head| {
        if is_dicom(head) {
            Ok(None)
        } else {
            Err(not_dicom(path))
        }
    })?;
    parse(path, &bytes, header_only)
}

/// Checks, with dicom-rs's lazy tokenizer, that no element of `data`
/// announces more bytes than follow it: dicom-rs allocates (and zeroes) an
/// element's announced length before reading it, so a 1 KB file could ask
/// for 4 GB. With `meta_only`, stops at the first element after group
/// 0002 and returns where it starts.
fn check_lengths(path: &Path, data: &[u8], ts: &TransferSyntax, meta_only: bool) -> Result<usize> {
    use dicom_parser::dataset::LazyDataToken;
    use dicom_parser::dataset::lazy_read::LazyDataSetReader;
    use dicom_parser::stateful::decode::StatefulDecode;
    let what = "a DICOM data set";
    let mut reader = LazyDataSetReader::new_with_ts(std::io::Cursor::new(data), ts)
        .map_err(|e| crate_error(path, what, e))?;
    let total = data.len() as u64;
    let mut start = 0u64;
    while let Some(token) = reader.advance() {
        let token = token.map_err(|e| crate_error(path, what, e))?;
        let (tag, len, at) = match &token {
            LazyDataToken::LazyValue { header, decoder } => {
                (Some(header.tag), header.len.0, decoder.position())
            }
            LazyDataToken::LazyItemValue { len, decoder } => (None, *len, decoder.position()),
            LazyDataToken::SequenceStart { tag, .. } if meta_only && tag.group() != 2 => {
                return Ok(start as usize);
            }
            _ => continue,
        };
        if meta_only && tag.is_some_and(|t| t.group() != 2) {
            return Ok(start as usize);
        }
        if u64::from(len) > total.saturating_sub(at) {
            return Err(Error::format(
                path,
                Position::Byte(at),
                format!(
                    "an element value of at most the {} bytes left",
                    total.saturating_sub(at)
                ),
                format!(
                    "{} announcing {len} bytes",
                    tag.map_or("an item".to_string(), |t| format!("element {t}"))
                ),
            ));
        }
        token.skip().map_err(|e| crate_error(path, what, e))?;
        start = at + u64::from(len);
    }
    Ok(start as usize)
}

fn parse(path: &Path, bytes: &[u8], header_only: bool) -> Result<DefaultDicomObject> {
    let what = "a DICOM data set";
    let with_meta = bytes.get(128..132) == Some(b"DICM") && bytes.get(132..134) == Some(&[2, 0]);
    if with_meta {
        // Element lengths checked first: the meta group (explicit VR
        // little endian), then the data set in the syntax it names.
        let explicit = dicom_transfer_syntax_registry::entries::EXPLICIT_VR_LITTLE_ENDIAN.erased();
        let meta_len = check_lengths(path, &bytes[132..], &explicit, true)?;
        let meta = dicom_object::FileMetaTable::from_reader(&bytes[128..])
            .map_err(|e| crate_error(path, "a DICOM file meta group", e))?;
        let uid = meta.transfer_syntax();
        let ts = TransferSyntaxRegistry
            .get(uid)
            .ok_or_else(|| Error::Unsupported {
                path: path.into(),
                what: format!("DICOM transfer syntax {uid} (dicom-rs does not know it)"),
            })?;
        // A data-set codec (deflate) would hide the elements from the
        // length check; this build leaves it out.
        if !(ts.is_codec_free() || ts.is_encapsulated_pixel_data()) {
            return Err(Error::Unsupported {
                path: path.into(),
                what: format!(
                    "DICOM transfer syntax {} ({uid}): this build reads native and \
                     encapsulated (RLE, JPEG) data sets, not deflated ones",
                    ts.name()
                ),
            });
        }
        check_lengths(path, &bytes[132 + meta_len..], ts, false)?;
        let mut options = OpenFileOptions::new().read_preamble(ReadPreamble::Never);
        if header_only {
            options = options.read_until(tags::PIXEL_DATA);
        }
        return options
            .from_reader(&bytes[128..])
            .map_err(|e| crate_error(path, what, e));
    }
    // No file-meta group: implicit VR little endian, the default
    // transfer syntax (PS3.5 §10.1), after the preamble if there is one.
    let start = if bytes.get(128..132) == Some(b"DICM") {
        132
    } else if bare_dataset(bytes) {
        0
    } else {
        return Err(not_dicom(path));
    };
    let ts = dicom_transfer_syntax_registry::entries::IMPLICIT_VR_LITTLE_ENDIAN.erased();
    check_lengths(path, &bytes[start..], &ts, false)?;
    let data = InMemDicomObject::read_dataset_with_ts(&bytes[start..], &ts)
        .map_err(|e| crate_error(path, what, e))?;
    // A meta group for the decoder; the data set's own UIDs replace these
    // placeholders when present.
    let meta = FileMetaTableBuilder::new()
        .transfer_syntax(ts.uid())
        .media_storage_sop_class_uid("1.2.840.10008.5.1.4.1.1.7")
        .media_storage_sop_instance_uid("2.25.0");
    data.with_meta(meta)
        .map_err(|e| crate_error(path, "a data set with SOP class and instance UIDs", e))
}

/// One element's value as text, trimmed; `None` when absent or empty.
fn text(obj: &InMemDicomObject, tag: Tag) -> Option<String> {
    let s = obj.get(tag)?.to_str().ok()?.trim().to_string();
    (!s.is_empty()).then_some(s)
}

/// The element `tag`: in the per-frame functional group item, else in the
/// shared one, else at the top level (`seq` names the functional group
/// macro's sequence, e.g. Plane Position Sequence).
fn frame_element<'a>(
    obj: &'a InMemDicomObject,
    frame: Option<&'a InMemDicomObject>,
    seq: Tag,
    tag: Tag,
) -> Option<&'a InMemElement> {
    let in_group = |group: &'a InMemDicomObject| -> Option<&'a InMemElement> {
        group.get(seq)?.items()?.first()?.get(tag)
    };
    let shared = obj
        .get(tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE)
        .and_then(|e| e.items())
        .and_then(|items| items.first());
    frame
        .and_then(in_group)
        .or_else(|| shared.and_then(in_group))
        .or_else(|| obj.get(tag))
}

fn floats(path: &Path, e: Option<&InMemElement>, name: &str, n: usize) -> Result<Option<Vec<f64>>> {
    let Some(e) = e else {
        return Ok(None);
    };
    let v = e.to_multi_float64().map_err(|err| {
        Error::format(
            path,
            Position::Field(name.into()),
            format!("{n} decimal numbers"),
            err.to_string(),
        )
    })?;
    if v.len() != n || v.iter().any(|x| !x.is_finite()) {
        return Err(Error::format(
            path,
            Position::Field(name.into()),
            format!("{n} finite numbers"),
            format!("{v:?}"),
        ));
    }
    Ok(Some(v))
}

fn uint(path: &Path, obj: &InMemDicomObject, tag: Tag, name: &str) -> Result<Option<u32>> {
    match obj.get(tag) {
        None => Ok(None),
        Some(e) => e.to_int::<u32>().map(Some).map_err(|err| {
            Error::format(
                path,
                Position::Field(name.into()),
                "a non-negative integer",
                err.to_string(),
            )
        }),
    }
}

/// The geometry and value transform of one frame.
#[derive(Debug, Clone)]
pub(crate) struct Frame {
    /// LPS position of the first pixel (Image Position (Patient)).
    pub position: Option<[f64; 3]>,
    /// Row and column directions (Image Orientation (Patient)).
    pub orientation: Option<[f64; 6]>,
    /// Pixel Spacing: between rows, between columns.
    pub pixel_spacing: Option<[f64; 2]>,
    pub slope: f64,
    pub intercept: f64,
}

/// What a series needs of one file, read from its header.
#[derive(Debug, Clone)]
pub(crate) struct Header {
    pub series_uid: Option<String>,
    pub description: Option<String>,
    pub modality: Option<String>,
    pub transfer_syntax: String,
    pub rows: u32,
    pub columns: u32,
    pub frames: Vec<Frame>,
    /// Spacing Between Slices, else Slice Thickness: the slice spacing of
    /// a single frame.
    pub slice_step: Option<f64>,
}

/// The header of an image file; `None` for a DICOM file without an
/// image (no Rows/Columns, e.g. a DICOMDIR or a structured report).
pub(crate) fn header(path: &Path, obj: &DefaultDicomObject) -> Result<Option<Header>> {
    let (Some(rows), Some(columns)) = (
        uint(path, obj, tags::ROWS, "Rows")?,
        uint(path, obj, tags::COLUMNS, "Columns")?,
    ) else {
        return Ok(None);
    };
    if let Some(samples) = uint(path, obj, tags::SAMPLES_PER_PIXEL, "SamplesPerPixel")?
        && samples != 1
    {
        return Err(Error::Unsupported {
            path: path.into(),
            what: format!(
                "DICOM images with {samples} samples per pixel (colour); a volume holds one"
            ),
        });
    }
    let n_frames = uint(path, obj, tags::NUMBER_OF_FRAMES, "NumberOfFrames")?.unwrap_or(1);
    if n_frames == 0 {
        return Err(Error::format(
            path,
            Position::Field("NumberOfFrames".into()),
            "at least 1",
            "0",
        ));
    }
    let per_frame = obj
        .get(tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE)
        .and_then(|e| e.items());
    if let Some(items) = per_frame
        && items.len() != n_frames as usize
    {
        return Err(Error::format(
            path,
            Position::Field("PerFrameFunctionalGroupsSequence".into()),
            format!("{n_frames} items (NumberOfFrames)"),
            items.len().to_string(),
        ));
    }
    let mut frames = Vec::new();
    for f in 0..n_frames as usize {
        let item = per_frame.map(|items| &items[f]);
        let el = |seq, tag| frame_element(obj, item, seq, tag);
        let position = floats(
            path,
            el(tags::PLANE_POSITION_SEQUENCE, tags::IMAGE_POSITION_PATIENT),
            "ImagePositionPatient",
            3,
        )?;
        let orientation = floats(
            path,
            el(
                tags::PLANE_ORIENTATION_SEQUENCE,
                tags::IMAGE_ORIENTATION_PATIENT,
            ),
            "ImageOrientationPatient",
            6,
        )?;
        let spacing = floats(
            path,
            el(tags::PIXEL_MEASURES_SEQUENCE, tags::PIXEL_SPACING),
            "PixelSpacing",
            2,
        )?;
        if let Some(s) = &spacing
            && s.iter().any(|&x| x <= 0.0)
        {
            return Err(Error::format(
                path,
                Position::Field("PixelSpacing".into()),
                "positive spacings",
                format!("{s:?}"),
            ));
        }
        let rescale = |tag, name| {
            floats(
                path,
                el(tags::PIXEL_VALUE_TRANSFORMATION_SEQUENCE, tag),
                name,
                1,
            )
        };
        let slope = rescale(tags::RESCALE_SLOPE, "RescaleSlope")?.map_or(1.0, |v| v[0]);
        let intercept = rescale(tags::RESCALE_INTERCEPT, "RescaleIntercept")?.map_or(0.0, |v| v[0]);
        frames.push(Frame {
            position: position.map(|v| [v[0], v[1], v[2]]),
            orientation: orientation.map(|v| std::array::from_fn(|i| v[i])),
            pixel_spacing: spacing.map(|v| [v[0], v[1]]),
            slope,
            intercept,
        });
    }
    let step = |tag, name| -> Result<Option<f64>> {
        Ok(floats(path, obj.get(tag), name, 1)?
            .map(|v| v[0].abs())
            .filter(|&s| s > 0.0))
    };
    let slice_step = match step(tags::SPACING_BETWEEN_SLICES, "SpacingBetweenSlices")? {
        Some(s) => Some(s),
        None => step(tags::SLICE_THICKNESS, "SliceThickness")?,
    };
    Ok(Some(Header {
        series_uid: text(obj, tags::SERIES_INSTANCE_UID),
        description: text(obj, tags::SERIES_DESCRIPTION),
        modality: text(obj, tags::MODALITY),
        transfer_syntax: obj
            .meta()
            .transfer_syntax()
            .trim_end_matches('\0')
            .to_string(),
        rows,
        columns,
        frames,
        slice_step,
    }))
}

/// The stored values of every frame of `obj`, frame after frame (rows ×
/// columns each), decoded by dicom-pixeldata without rescaling.
pub(crate) fn stored_values(path: &Path, obj: &DefaultDicomObject) -> Result<Vec<Vec<f64>>> {
    let ts = obj
        .meta()
        .transfer_syntax()
        .trim_end_matches('\0')
        .to_string();
    if ts == RLE_LOSSLESS {
        check_rle(path, obj)?;
    }
    let decoded = obj.decode_pixel_data().map_err(|e| Error::Unsupported {
        path: path.into(),
        what: format!(
            "DICOM pixel data in transfer syntax {} ({ts}): this build decodes native, RLE and \
             JPEG (baseline, extended, lossless) pixel data; JPEG 2000, JPEG-LS and JPEG XL need \
             native codec libraries it leaves out (dicom-rs: {e})",
            TransferSyntaxRegistry
                .get(&ts)
                .map_or("unknown", |t| t.name())
        ),
    })?;
    let options = ConvertOptions::new().with_modality_lut(ModalityLutOption::None);
    (0..decoded.number_of_frames())
        .map(|f| {
            decoded
                .to_vec_frame_with_options::<f64>(f, &options)
                .map_err(|e| crate_error(path, &format!("decodable pixel data (frame {f})"), e))
        })
        .collect()
}

/// RLE Lossless (PS3.5 Annex G).
const RLE_LOSSLESS: &str = "1.2.840.10008.1.2.5";

/// Checks every RLE fragment before dicom-rs decodes it: a 64-byte header
/// with at most 15 segment offsets, increasing and inside the fragment,
/// and every segment a complete PackBits stream of at least rows × columns
/// bytes. (dicom-rs 0.10 indexes past a short segment and panics.)
fn check_rle(path: &Path, obj: &DefaultDicomObject) -> Result<()> {
    let err = |at: u64, expected: String, found: String| {
        Error::format(
            path,
            Position::Field(format!("PixelData, RLE {at}")),
            expected,
            found,
        )
    };
    let rows = uint(path, obj, tags::ROWS, "Rows")?.unwrap_or(0) as u64;
    let cols = uint(path, obj, tags::COLUMNS, "Columns")?.unwrap_or(0) as u64;
    let bits = uint(path, obj, tags::BITS_ALLOCATED, "BitsAllocated")?.unwrap_or(0);
    let frames = uint(path, obj, tags::NUMBER_OF_FRAMES, "NumberOfFrames")?.unwrap_or(1) as usize;
    let need = rows * cols;
    let segments = (bits as usize).div_ceil(8);
    let fragments = obj
        .get(tags::PIXEL_DATA)
        .and_then(|e| e.fragments())
        .ok_or_else(|| err(0, "encapsulated pixel data".into(), "none".into()))?;
    if fragments.len() < frames {
        return Err(err(
            0,
            format!("{frames} fragments (one per frame)"),
            fragments.len().to_string(),
        ));
    }
    for (f, fragment) in fragments.iter().take(frames).enumerate() {
        let at = f as u64;
        let word = |i: usize| -> Option<u32> {
            let b = fragment.get(4 * i..4 * i + 4)?;
            Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        };
        let count = word(0).ok_or_else(|| {
            err(
                at,
                "a 64-byte RLE header".into(),
                format!("{} bytes", fragment.len()),
            )
        })? as usize;
        if count < segments || count > 15 || fragment.len() < 64 {
            return Err(err(
                at,
                format!("{segments} to 15 segments and a 64-byte header"),
                format!("{count} segments in {} bytes", fragment.len()),
            ));
        }
        for k in 0..segments {
            let start = word(1 + k).unwrap_or(0) as usize;
            let end = match k + 1 < count {
                true => word(2 + k).unwrap_or(0) as usize,
                false => fragment.len(),
            };
            if start < 64 || start > end || end > fragment.len() {
                return Err(err(
                    at,
                    format!("segment {k} inside the fragment after its header"),
                    format!("bytes {start}..{end} of {}", fragment.len()),
                ));
            }
            let seg = &fragment[start..end];
            let (mut i, mut out) = (0usize, 0u64);
            while out < need {
                let Some(&h) = seg.get(i) else {
                    return Err(err(
                        at,
                        format!("segment {k} decoding to {need} bytes"),
                        format!("{out} bytes"),
                    ));
                };
                let h = h as i8;
                let (used, made) = match h {
                    0..=127 => (1 + h as usize + 1, h as u64 + 1),
                    -127..=-1 => (2, 1 + u64::from(h.unsigned_abs())),
                    _ => (1, 0),
                };
                if i + used > seg.len() {
                    return Err(err(
                        at,
                        format!("a complete PackBits run in segment {k}"),
                        format!("a run cut at byte {}", start + seg.len()),
                    ));
                }
                i += used;
                out += made;
            }
        }
    }
    Ok(())
}

/// Reads a DICOM file or a directory of DICOM files as one volume; in a
/// directory with several series, `series` names the SeriesInstanceUID.
pub(crate) fn read(path: &Path, series: Option<&str>) -> Result<Volume> {
    if path.is_dir() {
        return read_dir(path, series);
    }
    let obj = open(path, false)?;
    let header = header(path, &obj)?.ok_or_else(|| {
        Error::format(
            path,
            Position::Field("Rows".into()),
            "an image (Rows, Columns, Pixel Data)",
            "a DICOM file without an image",
        )
    })?;
    let values = stored_values(path, &obj)?;
    series::assemble(vec![series::File {
        path: path.into(),
        header,
        values: Some(values),
    }])
}

/// Rescaled samples, gathered frame by frame: integers while every
/// frame's rescale is integral (narrowed at the end to the smallest of
/// `i16`, `u16`, `i32` that holds them), else `f32`.
pub(crate) enum Samples {
    Int(Vec<i32>),
    Float(Vec<f32>),
}

impl Samples {
    /// Room for `n` samples, allocated fallibly.
    pub(crate) fn with_capacity(path: &Path, n: usize, integral: bool) -> Result<Samples> {
        let bytes = (n as u64).saturating_mul(4);
        super::check_budget(path, Position::Whole, "the volume's samples", bytes)?;
        let oom = || Error::HostMemory {
            what: format!("{}: the volume's samples", path.display()),
            bytes,
        };
        Ok(if integral {
            let mut v = Vec::new();
            v.try_reserve_exact(n).map_err(|_| oom())?;
            Samples::Int(v)
        } else {
            let mut v = Vec::new();
            v.try_reserve_exact(n).map_err(|_| oom())?;
            Samples::Float(v)
        })
    }

    /// Appends one frame's stored values, rescaled.
    pub(crate) fn push(&mut self, path: &Path, stored: &[f64], frame: &Frame) -> Result<()> {
        match self {
            Samples::Int(out) => {
                for &s in stored {
                    let v = s * frame.slope + frame.intercept;
                    if v.fract() != 0.0 || v < f64::from(i32::MIN) || v > f64::from(i32::MAX) {
                        return Err(Error::format(
                            path,
                            Position::Field("RescaleSlope".into()),
                            "integral modality values within the 32-bit range",
                            format!("{v} (stored {s})"),
                        ));
                    }
                    out.push(v as i32);
                }
            }
            Samples::Float(out) => {
                out.extend(
                    stored
                        .iter()
                        .map(|&s| (s * frame.slope + frame.intercept) as f32),
                );
            }
        }
        Ok(())
    }

    /// The samples as volume data (the narrowed copy allocated fallibly).
    pub(crate) fn finish(self, path: &Path) -> Result<VolumeData> {
        fn narrow<T>(path: &Path, v: &[i32], f: impl Fn(i32) -> T) -> Result<Vec<T>> {
            let mut out = Vec::new();
            out.try_reserve_exact(v.len())
                .map_err(|_| Error::HostMemory {
                    what: format!("{}: the volume's samples", path.display()),
                    bytes: (v.len() * std::mem::size_of::<T>()) as u64,
                })?;
            out.extend(v.iter().map(|&x| f(x)));
            Ok(out)
        }
        Ok(match self {
            Samples::Float(v) => VolumeData::F32(v),
            Samples::Int(v) => {
                let lo = v.iter().copied().min().unwrap_or(0);
                let hi = v.iter().copied().max().unwrap_or(0);
                if lo >= i32::from(i16::MIN) && hi <= i32::from(i16::MAX) {
                    VolumeData::I16(narrow(path, &v, |x| x as i16)?)
                } else if lo >= 0 && hi <= i32::from(u16::MAX) {
                    VolumeData::U16(narrow(path, &v, |x| x as u16)?)
                } else {
                    VolumeData::I32(v)
                }
            }
        })
    }
}

/// LPS, the patient frame of every DICOM position.
pub(crate) const SPACE: Space = Space::Lps;
