//! VTK legacy files (`.vtk`): the shared header (`# vtk DataFile Version
//! x.y`, title, `ASCII`/`BINARY`, `DATASET <kind>`), the data type names,
//! and typed sample decoding (also used by the VTK XML reader).
//!
//! | data set | read | write |
//! |---|---|---|
//! | `POLYDATA` ([`polydata`]) | ASCII + BINARY, polygons, strips, 5.1 `OFFSETS`/`CONNECTIVITY` | ASCII, triangles + point scalars |
//! | `STRUCTURED_POINTS` ([`structured_points`]) | ASCII + BINARY, the first point `SCALARS` (one component) as the volume, other arrays skipped and named | BINARY, axis-aligned volumes only |
//!
//! BINARY payloads are big-endian, as the VTK file-format spec says.

mod polydata;
mod structured_points;

pub(crate) use polydata::{read, write};
pub(crate) use structured_points::{
    read_structured_points, structured_points_can_hold, write_structured_points,
};

use std::path::Path;

use super::text::{Endian, Num, Scanner, clip};
use crate::volume::VolumeData;
use crate::{Error, Position, Result};

/// Skips the lines of a `METADATA` block up to and including the first
/// blank one (VTK 9 writes `INFORMATION` entries there).
fn skip_metadata_lines(sc: &mut Scanner) {
    while let Some((_, line)) = sc.line() {
        if line.iter().all(u8::is_ascii_whitespace) {
            break;
        }
    }
}

/// After the values of an ASCII array: the `METADATA` block that may
/// follow it, skipped.
fn skip_array_metadata(sc: &mut Scanner) -> Result<()> {
    if sc
        .peek()
        .is_some_and(|t| t.eq_ignore_ascii_case(b"METADATA"))
    {
        sc.next("METADATA")?;
        skip_metadata_lines(sc);
    }
    Ok(())
}

/// The data type named `name` (VTK legacy spelling, or a `vtktype*` name).
fn vtk_type(sc: &Scanner, at: usize, name: &str) -> Result<Num> {
    Ok(match name.to_ascii_lowercase().as_str() {
        "char" | "signed_char" | "vtktypeint8" => Num::I8,
        "unsigned_char" | "vtktypeuint8" => Num::U8,
        "short" | "vtktypeint16" => Num::I16,
        "unsigned_short" | "vtktypeuint16" => Num::U16,
        "int" | "vtktypeint32" | "vtkidtype" => Num::I32,
        "unsigned_int" | "vtktypeuint32" => Num::U32,
        "long" | "vtktypeint64" => Num::I64,
        "unsigned_long" | "vtktypeuint64" => Num::U64,
        "float" | "vtktypefloat32" => Num::F32,
        "double" | "vtktypefloat64" => Num::F64,
        _ => {
            return Err(sc.error(
                at,
                "a VTK data type (unsigned_char, short, int, float, double, ...)",
                format!("`{}`", clip(name)),
            ));
        }
    })
}

/// The header of a legacy file up to its data set: the magic line, the
/// title, `ASCII` or `BINARY` (big-endian payloads) and `DATASET <kind>`.
/// Returns the scanner after the kind and the payload byte order.
pub(crate) fn header<'a>(
    path: &'a Path,
    bytes: &'a [u8],
    kind: &str,
) -> Result<(Scanner<'a>, Option<Endian>)> {
    let mut sc = magic(path, bytes)?;
    let at = sc.mark();
    sc.line()
        .ok_or_else(|| sc.error(at, "a title line", "end of file"))?;
    let (at, mode) = sc.next("ASCII or BINARY")?;
    let binary = if mode.eq_ignore_ascii_case("ascii") {
        None
    } else if mode.eq_ignore_ascii_case("binary") {
        Some(Endian::Big)
    } else {
        return Err(sc.error(at, "ASCII or BINARY", format!("`{}`", clip(mode))));
    };
    sc.keyword("DATASET")?;
    let (at, found) = sc.next(kind)?;
    if !found.eq_ignore_ascii_case(kind) {
        return Err(sc.error(
            at,
            format!("DATASET {kind}"),
            format!("DATASET {}", clip(found)),
        ));
    }
    Ok((sc, binary))
}

/// The rest of a `SCALARS name type [components]` header after the
/// keyword, and the optional `LOOKUP_TABLE name` line that follows it; in
/// binary mode the scanner is left at the payload. Returns the name, the
/// type as written and as a [`Num`], and the component count (1 to 4).
pub(crate) fn scalars_header<'a>(
    sc: &mut Scanner<'a>,
    binary: bool,
) -> Result<(&'a str, &'a str, Num, u64)> {
    let (_, name) = sc.next("a scalar name")?;
    let (tat, ty) = sc.next("a data type")?;
    let num = vtk_type(sc, tat, ty)?;
    let mut comps = 1u64;
    if let Some((cat, tok)) = sc.line_tokens().first() {
        comps = tok
            .parse()
            .ok()
            .filter(|c| (1..=4).contains(c))
            .ok_or_else(|| sc.error(*cat, "1..4 components", format!("`{}`", clip(tok))))?;
    }
    if binary {
        sc.skip_line();
        sc.payload_follows();
        if sc.rest().starts_with(b"LOOKUP_TABLE") {
            sc.skip_line();
        }
    } else if sc
        .peek()
        .is_some_and(|t| t.eq_ignore_ascii_case(b"LOOKUP_TABLE"))
    {
        sc.next("LOOKUP_TABLE")?;
        sc.next("a lookup table name")?;
    }
    Ok((name, ty, num, comps))
}

/// Checks the first line, `# vtk DataFile Version x.y`, of `bytes` (the
/// file, or its first bytes before the rest is read); returns the scanner
/// after it.
pub(crate) fn magic<'a>(path: &'a Path, bytes: &'a [u8]) -> Result<Scanner<'a>> {
    let mut sc = Scanner::new(path, bytes);
    let magic = "`# vtk DataFile Version x.y`";
    let (at, first) = sc.text_line(magic)?;
    if !first
        .trim()
        .to_ascii_lowercase()
        .starts_with("# vtk datafile")
    {
        return Err(sc.error(at, magic, format!("`{}`", clip(first.trim()))));
    }
    Ok(sc)
}

/// The data set kind of a legacy VTK file, from its `DATASET` line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LegacyDataset {
    /// `DATASET POLYDATA`: a mesh ([`read`]).
    PolyData,
    /// `DATASET STRUCTURED_POINTS`: a volume ([`read_structured_points`]).
    StructuredPoints,
    /// Any other data set (`STRUCTURED_GRID`, `UNSTRUCTURED_GRID`,
    /// `RECTILINEAR_GRID`, `FIELD`): not read by chisel.
    Other,
}

/// What kind of legacy VTK file `head` (the first bytes of a file, e.g.
/// [`SNIFF_BYTES`](super::SNIFF_BYTES)) begins: `None` when it is not a
/// legacy VTK file or the `DATASET` line is not within `head`.
pub(crate) fn dataset_kind(head: &[u8]) -> Option<LegacyDataset> {
    let path = Path::new("");
    let mut sc = magic(path, head).ok()?;
    sc.line()?; // title
    sc.next("ASCII or BINARY").ok()?;
    if !sc.next("DATASET").ok()?.1.eq_ignore_ascii_case("dataset") {
        return None;
    }
    let (_, kind) = sc.next("a data set kind").ok()?;
    // The token must be complete (followed by whitespace within `head`).
    sc.rest().first().filter(|b| b.is_ascii_whitespace())?;
    Some(match kind.to_ascii_uppercase().as_str() {
        "POLYDATA" => LegacyDataset::PolyData,
        "STRUCTURED_POINTS" => LegacyDataset::StructuredPoints,
        _ => LegacyDataset::Other,
    })
}

/// A scalar name as one whitespace-free token that cannot be taken for a
/// coordinate: whitespace becomes `_`, an empty name `scalar`, and `x`, `y`,
/// `z` get a `scalar_` prefix.
pub(crate) fn field_name(name: &str) -> String {
    let n: String = name
        .chars()
        .map(|c| if c.is_whitespace() { '_' } else { c })
        .collect();
    match n.as_str() {
        "" => "scalar".into(),
        "x" | "y" | "z" => format!("scalar_{n}"),
        _ => n,
    }
}

/// An empty [`VolumeData`] of element type `num` with room for `n`
/// samples, allocated fallibly; 64-bit integers (which a [`VolumeData`]
/// cannot hold) are an [`Error::Unsupported`] naming `what`.
pub(crate) fn empty_samples(path: &Path, num: Num, n: usize, what: &str) -> Result<VolumeData> {
    fn vec<T>(path: &Path, n: usize) -> Result<Vec<T>> {
        let mut v = Vec::new();
        v.try_reserve_exact(n).map_err(|_| Error::HostMemory {
            what: format!("{}: volume samples", path.display()),
            bytes: (n as u64).saturating_mul(std::mem::size_of::<T>() as u64),
        })?;
        Ok(v)
    }
    Ok(match num {
        Num::U8 => VolumeData::U8(vec(path, n)?),
        Num::I8 => VolumeData::I8(vec(path, n)?),
        Num::U16 => VolumeData::U16(vec(path, n)?),
        Num::I16 => VolumeData::I16(vec(path, n)?),
        Num::U32 => VolumeData::U32(vec(path, n)?),
        Num::I32 => VolumeData::I32(vec(path, n)?),
        Num::F32 => VolumeData::F32(vec(path, n)?),
        Num::F64 => VolumeData::F64(vec(path, n)?),
        Num::I64 | Num::U64 => {
            return Err(Error::Unsupported {
                path: path.into(),
                what: format!(
                    "{what} of 64-bit integers (chisel volumes hold 8-, 16- and 32-bit \
                     integers, float and double; convert the image to int or double first)"
                ),
            });
        }
    })
}

/// Appends the samples of `bytes` (whole values of `data`'s type, in
/// `endian` order) to `data`, which has room for them.
pub(crate) fn push_binary(data: &mut VolumeData, bytes: &[u8], endian: Endian) {
    macro_rules! push {
        ($v:expr, $t:ty) => {{
            const S: usize = std::mem::size_of::<$t>();
            $v.extend(bytes.chunks_exact(S).map(|c| {
                let mut a = [0u8; S];
                a.copy_from_slice(c);
                match endian {
                    Endian::Little => <$t>::from_le_bytes(a),
                    Endian::Big => <$t>::from_be_bytes(a),
                }
            }))
        }};
    }
    match data {
        VolumeData::U8(v) => v.extend_from_slice(bytes),
        VolumeData::I8(v) => v.extend(bytes.iter().map(|&b| b as i8)),
        VolumeData::U16(v) => push!(v, u16),
        VolumeData::I16(v) => push!(v, i16),
        VolumeData::U32(v) => push!(v, u32),
        VolumeData::I32(v) => push!(v, i32),
        VolumeData::F32(v) => push!(v, f32),
        VolumeData::F64(v) => push!(v, f64),
    }
}

/// Appends the sample written as `tok` to `data`; `false` when `tok` is
/// not a number of `data`'s type (or out of its range).
pub(crate) fn push_text(data: &mut VolumeData, tok: &str) -> bool {
    fn int<T: TryFrom<i64>>(v: &mut Vec<T>, tok: &str) -> bool {
        match tok.parse::<i64>().ok().and_then(|x| T::try_from(x).ok()) {
            Some(x) => {
                v.push(x);
                true
            }
            None => false,
        }
    }
    match data {
        VolumeData::U8(v) => int(v, tok),
        VolumeData::I8(v) => int(v, tok),
        VolumeData::U16(v) => int(v, tok),
        VolumeData::I16(v) => int(v, tok),
        VolumeData::U32(v) => int(v, tok),
        VolumeData::I32(v) => int(v, tok),
        VolumeData::F32(v) => tok.parse().map(|x| v.push(x)).is_ok(),
        VolumeData::F64(v) => tok.parse().map(|x| v.push(x)).is_ok(),
    }
}

/// The data type name of `data` in VTK legacy spelling.
pub(crate) fn legacy_type_name(data: &VolumeData) -> &'static str {
    match data {
        VolumeData::U8(_) => "unsigned_char",
        VolumeData::I8(_) => "signed_char",
        VolumeData::U16(_) => "unsigned_short",
        VolumeData::I16(_) => "short",
        VolumeData::U32(_) => "unsigned_int",
        VolumeData::I32(_) => "int",
        VolumeData::F32(_) => "float",
        VolumeData::F64(_) => "double",
    }
}

/// Checks `count` values of `size` bytes against the memory budget.
pub(crate) fn check_samples_budget(
    path: &Path,
    at: Position,
    what: &str,
    count: u64,
    size: usize,
) -> Result<()> {
    super::check_budget(path, at, what, count.saturating_mul(size as u64))
}
