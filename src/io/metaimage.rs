//! MetaImage (`.mhd` header + data file, `.mha`), after ITK's MetaIO.
//!
//! Read: `Key = Value` lines in any order (keys case-insensitive) up to
//! `ElementDataFile`, which must come last. `NDims` 1–3 (more only with
//! extra sizes of 1), `DimSize`, `ElementType` (`MET_UCHAR`, `MET_CHAR`,
//! `MET_SHORT`, `MET_USHORT`, `MET_INT`, `MET_UINT`, `MET_FLOAT`,
//! `MET_DOUBLE`), `ElementSpacing` (extra values beyond `NDims` ignored;
//! `ElementSize` used when it is absent), `Offset`/`Origin`/`Position`,
//! `BinaryDataByteOrderMSB` or `ElementByteOrderMSB`, `BinaryData = False`
//! (text samples), `HeaderSize` (`-1` = data at the end), and
//! `CompressedData = True`: the zlib stream is inflated to its end and
//! `CompressedDataSize` is ignored, because it is only a hint and known to be
//! wrong in real files (frogtissue's is 2,067 bytes short: trusting it loses
//! 2,670 voxels); the inflated length must equal the product of the dims.
//! `TransformMatrix`/`Rotation`/`Orientation` gives the axes (row k the
//! world direction of index axis k, as ITK reads it; it must be
//! orthonormal); with `AnatomicalOrientation` (as ITK writes it) the world
//! is LPS, ITK's convention, else no anatomical frame is named. `ElementDataFile` may be `LOCAL` (data after the
//! header, in `.mhd` too), a file name (also for `.mha`), `LIST [subdim]`
//! with names on the following lines, or a pattern `fmt min max step [subdim]`.
//!
//! Write: `.mha` with `ElementDataFile = LOCAL`, or `.mhd` with
//! `<stem>.raw`; little-endian, uncompressed; `TransformMatrix` and
//! `Offset` in LPS (a RAS volume's x and y negated) with ITK's
//! `AnatomicalOrientation` code when the volume names a frame.

use std::io::{self, Write};
use std::path::Path;

use super::nrrd::pattern_files;
use super::raw::{Encoding, Payload, Piece, Skip, read_samples, sample_count, write_le};
use super::text::{Endian, Scanner, clip, read_prefix};
use crate::foundation::fs::write_atomic_with;
use crate::volume::ScalarType;
use crate::volume::{IDENTITY_AXES, Space};
use crate::{Error, Position, Result, Volume};

const HEADER_CAP: u64 = 16 << 20;

#[derive(Debug)]
struct Field {
    at: Position,
    value: String,
}

struct Header {
    fields: Vec<(String, Field)>,
    list: Vec<String>,
    data_offset: u64,
}

impl Header {
    fn get(&self, keys: &[&str]) -> Option<&Field> {
        self.fields
            .iter()
            .rev()
            .find(|(k, _)| keys.iter().any(|key| k.eq_ignore_ascii_case(key)))
            .map(|(_, f)| f)
    }
}

fn parse_header(path: &Path, head: &[u8]) -> Result<Header> {
    let mut sc = Scanner::new(path, head);
    let mut fields = Vec::new();
    let mut list = Vec::new();
    loop {
        let Some((at, line)) = sc.line() else {
            return Err(sc.error(sc.pos(), "an `ElementDataFile = ...` line", "end of header"));
        };
        let line = std::str::from_utf8(line)
            .map_err(|_| sc.error(at, "a `Key = Value` header line", "non-text bytes"))?;
        if line.trim().is_empty() || line.trim_start().starts_with('#') {
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            return Err(sc.error(at, "`Key = Value`", format!("`{}`", clip(line))));
        };
        let key = key.trim().to_string();
        let value = value.trim().to_string();
        let last = key.eq_ignore_ascii_case("ElementDataFile");
        if last && value.split_whitespace().next() == Some("LIST") {
            while let Some((_, name)) = sc.line() {
                let name = String::from_utf8_lossy(name).trim().to_string();
                if !name.is_empty() {
                    list.push(name);
                }
            }
        }
        fields.push((
            key,
            Field {
                at: sc.position(at),
                value,
            },
        ));
        if last {
            return Ok(Header {
                fields,
                list,
                data_offset: sc.pos() as u64,
            });
        }
    }
}

fn floats(path: &Path, f: &Field, at_least: usize, what: &str) -> Result<Vec<f64>> {
    let v: Option<Vec<f64>> = f
        .value
        .split_whitespace()
        .map(|t| t.parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect();
    match v {
        Some(v) if v.len() >= at_least => Ok(v),
        _ => Err(Error::format(
            path,
            f.at.clone(),
            format!("{at_least} finite {what}"),
            format!("`{}`", clip(&f.value)),
        )),
    }
}

fn boolean(path: &Path, f: Option<&Field>, default: bool) -> Result<bool> {
    match f {
        None => Ok(default),
        Some(f) if f.value.eq_ignore_ascii_case("true") => Ok(true),
        Some(f) if f.value.eq_ignore_ascii_case("false") => Ok(false),
        Some(f) => Err(Error::format(
            path,
            f.at.clone(),
            "True or False",
            f.value.clone(),
        )),
    }
}

fn met_type(path: &Path, f: &Field) -> Result<ScalarType> {
    Ok(match f.value.as_str() {
        "MET_UCHAR" => ScalarType::U8,
        "MET_CHAR" => ScalarType::I8,
        "MET_USHORT" => ScalarType::U16,
        "MET_SHORT" => ScalarType::I16,
        "MET_UINT" => ScalarType::U32,
        "MET_INT" => ScalarType::I32,
        "MET_FLOAT" => ScalarType::F32,
        "MET_DOUBLE" => ScalarType::F64,
        "MET_LONG" | "MET_ULONG" | "MET_LONG_LONG" | "MET_ULONG_LONG" => {
            return Err(Error::Unsupported {
                path: path.into(),
                what: format!("{}: element type {}", f.at, f.value),
            });
        }
        other => {
            return Err(Error::format(
                path,
                f.at.clone(),
                "MET_UCHAR, MET_CHAR, MET_USHORT, MET_SHORT, MET_UINT, MET_INT, MET_FLOAT or MET_DOUBLE",
                format!("`{}`", clip(other)),
            ));
        }
    })
}

/// Reads a MetaImage volume.
pub(crate) fn read(path: &Path) -> Result<Volume> {
    let head = read_prefix(path, HEADER_CAP)?;
    let h = parse_header(path, &head)?;
    let need = |key: &str| {
        h.get(&[key]).ok_or_else(|| {
            Error::format(
                path,
                Position::Field(key.into()),
                format!("a `{key} = ...` line"),
                "none",
            )
        })
    };
    if let Some(f) = h.get(&["ObjectType"])
        && !f.value.eq_ignore_ascii_case("image")
    {
        return Err(Error::Unsupported {
            path: path.into(),
            what: format!("{}: ObjectType {}", f.at, clip(&f.value)),
        });
    }
    let nd_field = need("NDims")?;
    let ndims: usize = nd_field
        .value
        .parse()
        .ok()
        .filter(|d| (1..=16).contains(d))
        .ok_or_else(|| {
            Error::format(
                path,
                nd_field.at.clone(),
                "NDims 1..16",
                nd_field.value.clone(),
            )
        })?;
    let size_field = need("DimSize")?;
    let sizes: Vec<usize> = size_field
        .value
        .split_whitespace()
        .map(|t| t.parse::<usize>().ok().filter(|&s| s > 0))
        .collect::<Option<_>>()
        .filter(|v: &Vec<usize>| v.len() == ndims)
        .ok_or_else(|| {
            Error::format(
                path,
                size_field.at.clone(),
                format!("{ndims} positive sizes"),
                format!("`{}`", clip(&size_field.value)),
            )
        })?;
    if sizes.iter().skip(3).any(|&s| s != 1) {
        return Err(Error::Unsupported {
            path: path.into(),
            what: format!(
                "{}: more than 3 axes with samples: {sizes:?}",
                size_field.at
            ),
        });
    }
    let mut dims = [1usize; 3];
    for (d, s) in dims.iter_mut().zip(&sizes) {
        *d = *s;
    }
    if let Some(f) = h.get(&["ElementNumberOfChannels"])
        && f.value.trim() != "1"
    {
        return Err(Error::Unsupported {
            path: path.into(),
            what: format!("{}: {} channels per element", f.at, clip(&f.value)),
        });
    }
    let ty = met_type(path, need("ElementType")?)?;
    sample_count(path, &size_field.at, dims, ty)?;
    let mut spacing = [1.0f64; 3];
    if let Some(f) = h
        .get(&["ElementSpacing"])
        .or_else(|| h.get(&["ElementSize"]))
    {
        let v = floats(path, f, ndims, "spacings")?;
        if v.iter().take(ndims).any(|&s| s <= 0.0) {
            return Err(Error::format(
                path,
                f.at.clone(),
                "positive spacings",
                f.value.clone(),
            ));
        }
        for (s, x) in spacing.iter_mut().zip(v.iter().take(ndims)) {
            *s = *x;
        }
    }
    let mut origin = [0.0f64; 3];
    if let Some(f) = h.get(&["Offset", "Origin", "Position"]) {
        let v = floats(path, f, ndims, "origin coordinates")?;
        for (o, x) in origin.iter_mut().zip(v.iter().take(ndims)) {
            *o = *x;
        }
    }
    // Row k of the matrix is the world direction of index axis k (as ITK's
    // MetaImageIO reads it); the world is LPS (ITK's convention).
    let mut axes = IDENTITY_AXES;
    let matrix = h.get(&["TransformMatrix", "Rotation", "Orientation"]);
    if let Some(f) = matrix {
        let v = floats(path, f, ndims * ndims, "matrix entries")?;
        if v.len() != ndims * ndims {
            return Err(Error::format(
                path,
                f.at.clone(),
                format!("{} matrix entries", ndims * ndims),
                f.value.clone(),
            ));
        }
        for k in 0..ndims.min(3) {
            for c in 0..ndims.min(3) {
                axes[k][c] = v[k * ndims + c];
            }
        }
    }
    let msb = boolean(
        path,
        h.get(&["BinaryDataByteOrderMSB", "ElementByteOrderMSB"]),
        false,
    )?;
    let binary = boolean(path, h.get(&["BinaryData"]), true)?;
    let compressed = boolean(path, h.get(&["CompressedData"]), false)?;
    let encoding = match (binary, compressed) {
        (false, _) => Encoding::Ascii,
        (true, true) => Encoding::Zlib,
        (true, false) => Encoding::Raw,
    };
    let skip = match h.get(&["HeaderSize"]) {
        None => Skip::Bytes(0),
        Some(f) => match f.value.parse::<i64>() {
            Ok(-1) if encoding == Encoding::Raw => Skip::FromEnd,
            Ok(b) if b >= 0 => Skip::Bytes(b as u64),
            _ => {
                return Err(Error::format(
                    path,
                    f.at.clone(),
                    "HeaderSize ≥ 0 (or -1 for raw data)",
                    f.value.clone(),
                ));
            }
        },
    };
    let df = need("ElementDataFile")?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let words: Vec<&str> = df.value.split_whitespace().collect();
    let subdim = |i: usize| -> Result<usize> {
        words.get(i).map_or(Ok(ndims - 1), |w| {
            w.parse::<usize>()
                .ok()
                .filter(|s| (1..=ndims).contains(s))
                .ok_or_else(|| {
                    Error::format(path, df.at.clone(), format!("a dimension 1..={ndims}"), *w)
                })
        })
    };
    let (pieces, sub) = if df.value.eq_ignore_ascii_case("LOCAL") {
        (vec![Piece::new(path.into(), h.data_offset, 0, skip)], None)
    } else if words.first() == Some(&"LIST") {
        let pieces = h
            .list
            .iter()
            .map(|name| Piece::new(dir.join(name), 0, 0, skip))
            .collect();
        (pieces, Some(subdim(1)?))
    } else if words.len() >= 4 && words[0].contains('%') {
        let sub = subdim(4)?;
        let blocks = sizes[sub..].iter().product();
        let files = pattern_files(path, &df.at, dir, &words, blocks)?;
        let pieces = files
            .into_iter()
            .map(|p| Piece::new(p, 0, 0, skip))
            .collect();
        (pieces, Some(sub))
    } else {
        (vec![Piece::new(dir.join(&df.value), 0, 0, skip)], None)
    };
    if let Some(sub) = sub {
        let expected: usize = sizes[sub..].iter().product();
        if pieces.len() != expected {
            return Err(Error::format(
                path,
                df.at.clone(),
                format!("{expected} data files of {sub}-D blocks"),
                format!("{} files", pieces.len()),
            ));
        }
    }
    let data = read_samples(&Payload {
        header: path,
        field: size_field.at.clone(),
        ty,
        dims,
        endian: if msb { Endian::Big } else { Endian::Little },
        encoding,
        pieces,
    })?;
    let at = matrix.map_or(Position::Whole, |f| f.at.clone());
    // ITK's world is LPS; a file that names an anatomical orientation (as
    // ITK writes one) is in it.
    let space = h.get(&["AnatomicalOrientation"]).map(|_| Space::Lps);
    Volume::new(dims, spacing, origin, data)?
        .with_frame(axes, space)
        .map_err(|_| Error::Unsupported {
            path: path.into(),
            what: format!(
                "{at}: `TransformMatrix` {axes:?} is not orthonormal (a sheared or scaled grid \
                 is not represented)"
            ),
        })
}

fn met_type_name(ty: ScalarType) -> &'static str {
    match ty {
        ScalarType::U8 => "MET_UCHAR",
        ScalarType::I8 => "MET_CHAR",
        ScalarType::U16 => "MET_USHORT",
        ScalarType::I16 => "MET_SHORT",
        ScalarType::U32 => "MET_UINT",
        ScalarType::I32 => "MET_INT",
        ScalarType::F32 => "MET_FLOAT",
        ScalarType::F64 => "MET_DOUBLE",
    }
}

fn header(v: &Volume, data_file: &str) -> String {
    let [nx, ny, nz] = v.dims;
    let [sx, sy, sz] = v.spacing;
    // The world of MetaImage is LPS: a RAS volume is turned into it.
    let ([ox, oy, oz], axes) = v.frame_in(Space::Lps);
    let matrix: Vec<String> = axes.iter().flatten().map(|c| c.to_string()).collect();
    // ITK's orientation code: per axis the side it starts from (R, A, I
    // for the LPS axes), of its largest component.
    let orientation = match v.space {
        None => String::new(),
        Some(_) => {
            let code: String = axes
                .iter()
                .map(|a| {
                    let c = (0..3)
                        .max_by(|&i, &j| a[i].abs().total_cmp(&a[j].abs()))
                        .unwrap_or(0);
                    let from = if a[c] >= 0.0 {
                        ["R", "A", "I"]
                    } else {
                        ["L", "P", "S"]
                    };
                    from[c]
                })
                .collect();
            format!("AnatomicalOrientation = {code}\n")
        }
    };
    format!(
        "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n\
         CompressedData = False\nTransformMatrix = {}\nOffset = {ox} {oy} {oz}\n\
         {orientation}ElementSpacing = {sx} {sy} {sz}\nDimSize = {nx} {ny} {nz}\n\
         ElementType = {}\nElementDataFile = {data_file}\n",
        matrix.join(" "),
        met_type_name(v.data.scalar_type())
    )
}

/// Writes `v` as `.mha` with the samples after the header.
pub(crate) fn write_local(path: &Path, v: &Volume) -> Result<()> {
    let head = header(v, "LOCAL");
    write_atomic_with(path, |w| {
        w.write_all(head.as_bytes())?;
        write_le(w, &v.data)
    })
}

/// Writes `v` as header `path` plus `<stem>.raw` beside it.
pub(crate) fn write_detached(path: &Path, v: &Volume) -> Result<()> {
    let data_path = path.with_extension("raw");
    let name = data_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    write_atomic_with(&data_path, |w: &mut dyn Write| write_le(w, &v.data))?;
    let head = header(v, &name);
    write_atomic_with(path, |w| -> io::Result<()> { w.write_all(head.as_bytes()) })
}
