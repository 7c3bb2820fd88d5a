//! NRRD (`.nrrd` attached, `.nhdr` detached), after the teem NRRD0001–0005
//! format description.
//!
//! Read: `dimension` 1–3 (more only with extra sizes of 1), every scalar
//! `type` up to 32-bit integers plus `float`/`double`, `encoding` `raw`,
//! `gzip`/`gz` or `ascii`/`text`/`txt`, `endian`, `line skip`, `byte skip`
//! (`-1` = data at the end of a raw file). Spacing comes from `space
//! directions` when present, else `spacings`, else 1. Directions must be
//! axis-aligned with a positive component on their own axis: a [`Volume`]
//! has no orientation, so oblique, permuted or flipped axes are an
//! [`Error::Unsupported`] rather than silently dropped. `space origin` gives
//! the origin (0 when absent). `data file:` may name one file, a
//! `LIST [subdim]` of files on the following header lines, or a printf-style
//! pattern `fmt min max step [subdim]` (`%d`, `%i`, `%u` with optional `0`
//! flag and width), with paths relative to the header's folder. Without
//! `subdim`, each file holds one slice of the last axis.
//!
//! Write: attached (`.nrrd`) or detached with `data file: <stem>.raw`
//! (`.nhdr`), raw little-endian, `space directions` diagonal + `space origin`.

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use super::raw::{Encoding, Payload, Piece, Skip, read_samples, sample_count, write_le};
use super::text::{Endian, Scanner, clip, read_prefix};
use crate::foundation::fs::write_atomic_with;
use crate::volume::ScalarType;
use crate::volume::{IDENTITY_AXES, Space};
use crate::{Error, Position, Result, Volume};

/// Most bytes a header may take (a `LIST` of many file names fits easily).
const HEADER_CAP: u64 = 16 << 20;

/// One `key: value` line of the header.
#[derive(Debug)]
struct Field {
    at: Position,
    value: String,
}

#[derive(Debug, Default)]
struct Header {
    fields: Vec<(String, Field)>,
    list: Vec<(Position, String)>,
    data_offset: Option<u64>,
}

impl Header {
    fn get(&self, key: &str) -> Option<&Field> {
        self.fields
            .iter()
            .rev()
            .find(|(k, _)| k == key)
            .map(|(_, f)| f)
    }
}

/// Field names without spaces, lower-case (`data file` = `datafile`).
fn canonical(key: &str) -> String {
    key.chars()
        .filter(|c| !c.is_whitespace())
        .flat_map(char::to_lowercase)
        .collect()
}

fn parse_header(path: &Path, head: &[u8], file_len: u64) -> Result<Header> {
    let mut sc = Scanner::new(path, head);
    let (at, magic) = sc.text_line("`NRRD000x`")?;
    if !magic.starts_with("NRRD") {
        return Err(sc.error(at, "`NRRD000x` magic", format!("`{}`", clip(magic))));
    }
    let mut h = Header::default();
    let mut list_mode = false;
    loop {
        let before = sc.pos();
        let Some((at, line)) = sc.line() else { break };
        if line.iter().all(u8::is_ascii_whitespace) {
            h.data_offset = Some(sc.pos() as u64);
            break;
        }
        if sc.pos() == head.len() && head.len() as u64 == HEADER_CAP && file_len > HEADER_CAP {
            return Err(sc.error(
                before,
                format!("a header shorter than {HEADER_CAP} bytes"),
                "no blank line ending the header",
            ));
        }
        let line = std::str::from_utf8(line)
            .map_err(|_| sc.error(at, "a text header line", "non-text bytes"))?;
        if line.starts_with('#') {
            continue;
        }
        if list_mode {
            h.list.push((sc.position(at), line.trim().to_string()));
            continue;
        }
        if line.contains(":=") {
            continue;
        }
        let Some((key, value)) = line.split_once(": ") else {
            return Err(sc.error(at, "`field: value`", format!("`{}`", clip(line))));
        };
        let key = canonical(key);
        let value = value.trim().to_string();
        if key == "datafile" && value.split_whitespace().next() == Some("LIST") {
            list_mode = true;
        }
        h.fields.push((
            key,
            Field {
                at: sc.position(at),
                value,
            },
        ));
    }
    Ok(h)
}

fn nrrd_type(path: &Path, f: &Field) -> Result<ScalarType> {
    let name = f.value.split_whitespace().collect::<Vec<_>>().join(" ");
    Ok(match name.as_str() {
        "signed char" | "int8" | "int8_t" => ScalarType::I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => ScalarType::U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            ScalarType::I16
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => {
            ScalarType::U16
        }
        "int" | "signed int" | "int32" | "int32_t" => ScalarType::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => ScalarType::U32,
        "float" => ScalarType::F32,
        "double" => ScalarType::F64,
        "longlong"
        | "long long"
        | "long long int"
        | "signed long long"
        | "signed long long int"
        | "int64"
        | "int64_t"
        | "ulonglong"
        | "unsigned long long"
        | "unsigned long long int"
        | "uint64"
        | "uint64_t"
        | "block" => {
            return Err(Error::Unsupported {
                path: path.into(),
                what: format!("{}: NRRD type `{name}`", f.at),
            });
        }
        _ => {
            return Err(Error::format(
                path,
                f.at.clone(),
                "an NRRD type (uchar, short, ushort, int, float, double, ...)",
                format!("`{}`", clip(&name)),
            ));
        }
    })
}

/// Parses `(a,b,c)` vectors and `none` entries of a field value.
fn vectors(path: &Path, f: &Field) -> Result<Vec<Option<Vec<f64>>>> {
    let bad = |found: &str| {
        Error::format(
            path,
            f.at.clone(),
            "vectors like `(1,0,0)` or `none`",
            format!("`{}`", clip(found)),
        )
    };
    let mut out = Vec::new();
    let mut rest = f.value.trim();
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("none") {
            out.push(None);
            rest = r.trim_start();
        } else if let Some(r) = rest.strip_prefix('(') {
            let (inner, r) = r.split_once(')').ok_or_else(|| bad(rest))?;
            let v = inner
                .split(',')
                .map(|c| c.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
                .collect::<Option<Vec<f64>>>()
                .ok_or_else(|| bad(inner))?;
            out.push(Some(v));
            rest = r.trim_start();
        } else {
            return Err(bad(rest));
        }
    }
    Ok(out)
}

fn numbers<T: std::str::FromStr>(path: &Path, f: &Field, expected: &str) -> Result<Vec<T>> {
    f.value
        .split_whitespace()
        .map(|t| {
            t.parse()
                .map_err(|_| Error::format(path, f.at.clone(), expected, format!("`{}`", clip(t))))
        })
        .collect()
}

/// Expands a printf-style pattern (one `%d`/`%i`/`%u` with optional `0`
/// flag and width, `%%` for a literal `%`) for the index `i`.
pub(crate) fn format_index(pattern: &str, i: i64) -> Option<String> {
    let mut out = String::new();
    let mut chars = pattern.chars().peekable();
    let mut used = false;
    while let Some(c) = chars.next() {
        if c != '%' {
            out.push(c);
            continue;
        }
        if chars.peek() == Some(&'%') {
            chars.next();
            out.push('%');
            continue;
        }
        let zero = chars.peek() == Some(&'0');
        let mut width = 0usize;
        while let Some(d) = chars.peek().and_then(|c| c.to_digit(10)) {
            width = width.checked_mul(10)?.checked_add(d as usize)?;
            chars.next();
        }
        if used || width > 64 || !matches!(chars.next(), Some('d' | 'i' | 'u')) {
            return None;
        }
        used = true;
        if zero {
            out.push_str(&format!("{i:0width$}"));
        } else {
            out.push_str(&format!("{i:width$}"));
        }
    }
    used.then_some(out)
}

/// The files of a `fmt min max step` pattern; more than `limit` (the number
/// of blocks the sizes call for) is an error before any name is made.
pub(crate) fn pattern_files(
    path: &Path,
    at: &Position,
    dir: &Path,
    words: &[&str],
    limit: usize,
) -> Result<Vec<PathBuf>> {
    let bad = |what: &str, found: String| Error::format(path, at.clone(), what, found);
    let nums = words[1..4]
        .iter()
        .map(|w| w.parse::<i64>())
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(|_| {
            bad(
                "integers `min max step` after the pattern",
                words[1..4].join(" "),
            )
        })?;
    let (min, max, step) = (nums[0], nums[1], nums[2]);
    if step == 0 || (i128::from(max) - i128::from(min)).signum() * i128::from(step.signum()) < 0 {
        return Err(bad(
            "a non-zero step going from min to max",
            format!("{min} {max} {step}"),
        ));
    }
    let count = (i128::from(max) - i128::from(min)) / i128::from(step) + 1;
    if count > limit as i128 {
        return Err(bad(
            &format!("at most {limit} data files (one per slice)"),
            format!("{count}"),
        ));
    }
    (0..count as i64)
        .map(|k| {
            format_index(words[0], min.saturating_add(k.saturating_mul(step)))
                .map(|name| dir.join(name))
                .ok_or_else(|| {
                    bad(
                        "a pattern with one %d, %i or %u",
                        format!("`{}`", clip(words[0])),
                    )
                })
        })
        .collect()
}

/// Reads an NRRD volume (attached or detached header).
pub(crate) fn read(path: &Path) -> Result<Volume> {
    let file_len = std::fs::metadata(path)
        .map_err(|e| Error::io(path, e))?
        .len();
    let head = read_prefix(path, HEADER_CAP)?;
    let h = parse_header(path, &head, file_len)?;
    let need = |key: &str| {
        h.get(key).ok_or_else(|| {
            Error::format(
                path,
                Position::Field(key.into()),
                format!("a `{key}:` field"),
                "none",
            )
        })
    };
    let dim_field = need("dimension")?;
    let dimension: usize = dim_field
        .value
        .parse()
        .ok()
        .filter(|d| (1..=16).contains(d))
        .ok_or_else(|| {
            Error::format(
                path,
                dim_field.at.clone(),
                "a dimension 1..16",
                dim_field.value.clone(),
            )
        })?;
    let ty = nrrd_type(path, need("type")?)?;
    let sizes_field = need("sizes")?;
    let sizes: Vec<usize> = numbers(path, sizes_field, "positive sizes")?;
    if sizes.len() != dimension || sizes.contains(&0) {
        return Err(Error::format(
            path,
            sizes_field.at.clone(),
            format!("{dimension} positive sizes"),
            sizes_field.value.clone(),
        ));
    }
    if sizes.iter().skip(3).any(|&s| s != 1) {
        return Err(Error::Unsupported {
            path: path.into(),
            what: format!(
                "{}: more than 3 axes with samples: sizes {sizes:?}",
                sizes_field.at
            ),
        });
    }
    if let Some(kinds) = h.get("kinds") {
        let spatial = ["domain", "space", "time", "???", "none"];
        for (kind, &size) in kinds.value.split_whitespace().zip(&sizes) {
            if size > 1 && !spatial.contains(&kind.to_ascii_lowercase().as_str()) {
                return Err(Error::Unsupported {
                    path: path.into(),
                    what: format!("{}: multi-component axis of kind `{kind}`", kinds.at),
                });
            }
        }
    }
    let mut dims = [1usize; 3];
    for (d, s) in dims.iter_mut().zip(&sizes) {
        *d = *s;
    }
    sample_count(path, &sizes_field.at, dims, ty)?;

    let mut spacing = [1.0f64; 3];
    if let Some(f) = h.get("spacings") {
        let values: Vec<f64> = numbers(path, f, "spacings (numbers or nan)")?;
        if values.len() != dimension {
            return Err(Error::format(
                path,
                f.at.clone(),
                format!("{dimension} spacings"),
                f.value.clone(),
            ));
        }
        for (s, &v) in spacing.iter_mut().zip(&values) {
            if v.is_nan() {
                continue;
            }
            if !v.is_finite() || v <= 0.0 {
                return Err(Error::format(
                    path,
                    f.at.clone(),
                    "positive finite spacings",
                    f.value.clone(),
                ));
            }
            *s = v;
        }
    }
    let mut axes = IDENTITY_AXES;
    if let Some(f) = h.get("spacedirections") {
        let dirs = vectors(path, f)?;
        if dirs.len() != dimension {
            return Err(Error::format(
                path,
                f.at.clone(),
                format!("{dimension} directions"),
                f.value.clone(),
            ));
        }
        let mut given = 0;
        for (axis, dir) in dirs.iter().enumerate().take(3) {
            let Some(v) = dir else { continue };
            let len = v.iter().map(|c| c * c).sum::<f64>().sqrt();
            if v.len() > 3 {
                return Err(Error::Unsupported {
                    path: path.into(),
                    what: format!("{}: a {}-D space direction", f.at, v.len()),
                });
            }
            if !(len.is_finite() && len > 0.0) {
                return Err(Error::format(
                    path,
                    f.at.clone(),
                    "non-zero finite `space directions`",
                    f.value.clone(),
                ));
            }
            spacing[axis] = len;
            axes[axis] = std::array::from_fn(|c| v.get(c).copied().unwrap_or(0.0) / len);
            given += 1;
        }
        crate::volume::complete_axes(&mut axes, given);
    }
    // The space's dimension: `space dimension`, else the length of the
    // direction vectors; the origin must have exactly that many components.
    let space_dimension = match h.get("spacedimension") {
        Some(f) => Some(f.value.trim().parse::<usize>().map_err(|_| {
            Error::format(
                path,
                f.at.clone(),
                "a space dimension (an integer)",
                f.value.clone(),
            )
        })?),
        None => match (h.get("spacedirections"), h.get("space")) {
            (Some(f), _) => vectors(path, f)?
                .into_iter()
                .flatten()
                .map(|v| v.len())
                .next(),
            // A named space: 3-D, or 4-D with time.
            (None, Some(f)) => Some(3 + usize::from(f.value.to_ascii_lowercase().contains("time"))),
            (None, None) => None,
        },
    };
    let mut origin = [0.0f64; 3];
    if let Some(f) = h.get("spaceorigin") {
        let v = vectors(path, f)?;
        let Some(Some(v)) = v.first().filter(|_| v.len() == 1) else {
            return Err(Error::format(
                path,
                f.at.clone(),
                "one origin vector",
                f.value.clone(),
            ));
        };
        if let Some(d) = space_dimension.filter(|&d| d != v.len()) {
            return Err(Error::format(
                path,
                f.at.clone(),
                format!("a `space origin` of {d} components (the space's dimension)"),
                f.value.clone(),
            ));
        }
        if v.len() > 3 {
            return Err(Error::Unsupported {
                path: path.into(),
                what: format!("{}: a {}-D space origin", f.at, v.len()),
            });
        }
        origin[..v.len()].copy_from_slice(v);
    }

    let enc_field = need("encoding")?;
    let encoding = match enc_field.value.to_ascii_lowercase().as_str() {
        "raw" => Encoding::Raw,
        "gzip" | "gz" => Encoding::Gzip,
        "ascii" | "text" | "txt" => Encoding::Ascii,
        other => {
            return Err(Error::Unsupported {
                path: path.into(),
                what: format!("{}: NRRD encoding `{}`", enc_field.at, clip(other)),
            });
        }
    };
    let endian = match h.get("endian") {
        Some(f) if f.value.eq_ignore_ascii_case("little") => Endian::Little,
        Some(f) if f.value.eq_ignore_ascii_case("big") => Endian::Big,
        Some(f) => {
            return Err(Error::format(
                path,
                f.at.clone(),
                "`little` or `big`",
                f.value.clone(),
            ));
        }
        None if ty.size() == 1 || encoding == Encoding::Ascii => Endian::Little,
        None => {
            return Err(Error::format(
                path,
                Position::Field("endian".into()),
                format!("an `endian:` field for {}-byte samples", ty.size()),
                "none",
            ));
        }
    };
    let skip_field = |key: &str| -> Result<i64> {
        h.get(key).map_or(Ok(0), |f| {
            f.value
                .parse::<i64>()
                .ok()
                .filter(|&v| v >= -1)
                .ok_or_else(|| {
                    Error::format(path, f.at.clone(), "an integer ≥ -1", f.value.clone())
                })
        })
    };
    let line_skip = skip_field("lineskip")?.max(0) as u64;
    let byte_skip = skip_field("byteskip")?;
    let skip = if byte_skip == -1 {
        if encoding != Encoding::Raw {
            return Err(Error::format(
                path,
                Position::Field("byte skip".into()),
                "`byte skip: -1` only with raw encoding",
                "-1",
            ));
        }
        Skip::FromEnd
    } else {
        Skip::Bytes(byte_skip as u64)
    };

    let dir = path.parent().unwrap_or(Path::new(""));
    let (files, subdim, field_at) = match h.get("datafile") {
        None => {
            let offset = h.data_offset.ok_or_else(|| {
                Error::format(
                    path,
                    Position::Whole,
                    "a blank line followed by data, or a `data file:` field",
                    "end of header",
                )
            })?;
            let piece = Piece::new(path.into(), offset, line_skip, skip);
            (vec![piece], None, Position::Field("sizes".into()))
        }
        Some(f) => {
            let words: Vec<&str> = f.value.split_whitespace().collect();
            let subdim_at = |i: usize| -> Result<Option<usize>> {
                words
                    .get(i)
                    .map(|w| {
                        w.parse::<usize>()
                            .ok()
                            .filter(|s| (1..=dimension).contains(s))
                            .ok_or_else(|| {
                                Error::format(
                                    path,
                                    f.at.clone(),
                                    format!("a subdim 1..={dimension}"),
                                    *w,
                                )
                            })
                    })
                    .transpose()
            };
            let (names, subdim) = if words.first() == Some(&"LIST") {
                let names = h.list.iter().map(|(_, name)| dir.join(name)).collect();
                (names, subdim_at(1)?)
            } else if words.len() >= 4 && words[0].contains('%') {
                let sub = subdim_at(4)?;
                let blocks = sizes[sub.unwrap_or(dimension - 1)..].iter().product();
                (pattern_files(path, &f.at, dir, &words, blocks)?, sub)
            } else {
                (vec![dir.join(&f.value)], None)
            };
            let pieces = names
                .into_iter()
                .map(|p| Piece::new(p, 0, line_skip, skip))
                .collect();
            (pieces, subdim, f.at.clone())
        }
    };
    if files.len() > 1 || subdim.is_some() {
        let sub = subdim.unwrap_or(dimension - 1);
        let expected: usize = sizes[sub..].iter().product();
        if files.len() != expected {
            return Err(Error::format(
                path,
                field_at,
                format!("{expected} data files (one per {sub}-D block of sizes {sizes:?})"),
                format!("{} files", files.len()),
            ));
        }
    }
    let data = read_samples(&Payload {
        header: path,
        field: sizes_field.at.clone(),
        ty,
        dims,
        endian,
        encoding,
        pieces: files,
    })?;
    // The anatomical frame: LPS and RAS as named; LAS turned into RAS (x
    // negated); other spaces (scanner-xyz, 3D-right-handed) name none.
    let mut space = None;
    if let Some(f) = h.get("space") {
        let name = f.value.trim().to_ascii_lowercase();
        let name = name.trim_end_matches("-time");
        space = match name {
            "left-posterior-superior" | "lps" => Some(Space::Lps),
            "right-anterior-superior" | "ras" => Some(Space::Ras),
            "left-anterior-superior" | "las" => {
                origin[0] = -origin[0];
                axes.iter_mut().for_each(|a| a[0] = -a[0]);
                Some(Space::Ras)
            }
            _ => None,
        };
    }
    let at = h
        .get("spacedirections")
        .map_or(Position::Whole, |f| f.at.clone());
    Volume::new(dims, spacing, origin, data)?
        .with_frame(axes, space)
        .map_err(|_| Error::Unsupported {
            path: path.into(),
            what: format!(
                "{at}: `space directions` {axes:?} are not at right angles (a sheared grid is not \
                 represented)"
            ),
        })
}

fn nrrd_type_name(ty: ScalarType) -> &'static str {
    match ty {
        ScalarType::U8 => "uint8",
        ScalarType::I8 => "int8",
        ScalarType::U16 => "uint16",
        ScalarType::I16 => "int16",
        ScalarType::U32 => "uint32",
        ScalarType::I32 => "int32",
        ScalarType::F32 => "float",
        ScalarType::F64 => "double",
    }
}

fn header(v: &Volume, data_file: Option<&str>) -> String {
    let [ox, oy, oz] = v.origin;
    let [nx, ny, nz] = v.dims;
    let space = match v.space {
        Some(Space::Lps) => "space: left-posterior-superior",
        Some(Space::Ras) => "space: right-anterior-superior",
        None => "space dimension: 3",
    };
    let dirs: Vec<String> = (0..3)
        .map(|k| {
            let d = v.axes[k].map(|c| c * v.spacing[k]);
            format!("({},{},{})", d[0], d[1], d[2])
        })
        .collect();
    let mut h = format!(
        "NRRD0004\n# written by chisel\ntype: {}\ndimension: 3\n{space}\n\
         sizes: {nx} {ny} {nz}\nspace directions: {}\n\
         space origin: ({ox},{oy},{oz})\nendian: little\nencoding: raw\n",
        nrrd_type_name(v.data.scalar_type()),
        dirs.join(" ")
    );
    if let Some(name) = data_file {
        h.push_str(&format!("data file: {name}\n"));
    }
    h
}

/// Writes `v` as an attached raw little-endian NRRD.
pub(crate) fn write_attached(path: &Path, v: &Volume) -> Result<()> {
    let head = header(v, None);
    write_atomic_with(path, |w| {
        w.write_all(head.as_bytes())?;
        w.write_all(b"\n")?;
        write_le(w, &v.data)
    })
}

/// Writes `v` as a detached header `path` plus `<stem>.raw` beside it.
pub(crate) fn write_detached(path: &Path, v: &Volume) -> Result<()> {
    let data_path = path.with_extension("raw");
    let name = data_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    write_atomic_with(&data_path, |w: &mut dyn Write| write_le(w, &v.data))?;
    let head = header(v, Some(&name));
    write_atomic_with(path, |w| -> io::Result<()> { w.write_all(head.as_bytes()) })
}
