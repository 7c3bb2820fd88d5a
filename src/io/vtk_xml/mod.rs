//! VTK XML files: `.vti` ImageData (a [`Volume`]) and `.vtp` PolyData (a
//! [`TriMesh`]), as written by VTK, ParaView and 3D Slicer.
//!
//! | | read | refused |
//! |---|---|---|
//! | header | `version` 0.1–2.x, `byte_order` `LittleEndian`/`BigEndian`, `header_type` `UInt32` (default)/`UInt64`, `compressor` none or `vtkZLibDataCompressor` | LZ4 and LZMA compressors ([`Error::Unsupported`]) |
//! | `DataArray` | `format` `ascii`, `binary` (inline base64), `appended` (`offset` into `<AppendedData encoding="raw">` or `"base64"`); types `Int8`…`UInt64`, `Float32`, `Float64` | `String` and `Bit` arrays where they are needed |
//! | `.vti` | `WholeExtent`, `Origin`, `Spacing`, `Direction` (orthonormal); the active point `Scalars` (else the first one-component point array) as the volume, element type kept; several `Piece`s when they cover the whole extent | more than one component, 64-bit integer samples, sheared `Direction`, pieces that leave points uncovered |
//! | `.vtp` | `Points` (3 components), `Polys` (fan-triangulated), `Strips` (alternating winding), several `Piece`s concatenated; one-component point arrays as [`ScalarField`](crate::mesh::ScalarField)s | — (`Verts`, `Lines`, multi-component and cell arrays are read, checked and reported in [`PolyNotes`], not kept) |
//!
//! Every array the file holds is decoded (so the whole file is checked)
//! and those not kept are named in the result. Sizes are checked before
//! allocating: each array's value count (from the extent, `NumberOfPoints`,
//! the last offset) times its type size against [`check_budget`](super::check_budget),
//! and every byte count a binary header announces against that size and
//! against the bytes actually present. A zlib block is inflated to at most
//! its announced size plus one byte, so a stream longer or shorter than
//! its header says is an error naming the block. Errors name the file, the
//! byte offset (of the element, attribute value, token or payload byte) and
//! what was expected.
//!
//! **Layouts checked against VTK 9.7.2's writers** (the reference files in
//! `tests/data/vtk`, made by `scripts/make_vtk_references.py`): an
//! uncompressed binary array is one base64 run of `[byte count][data]`; a
//! compressed one is the base64 of the header `[#blocks, block size, last
//! block size, compressed sizes…]` *followed by a separate base64 run* of
//! the compressed blocks (the header run ends in `=` padding). The decoder
//! here reads any sequence of padded base64 runs, so both layouts (and
//! writers that encode the header separately when uncompressed) are read.
//! Appended base64 offsets count base64 characters from the `_` marker.
//! `Direction` is row-major with the index axes as its columns
//! (`world = Origin + Direction · (index ⊙ Spacing)`, as in
//! `vtkImageData::TransformContinuousIndexToPhysicalPoint`), so
//! `axes[k]` is column `k`.
//!
//! **Write**: `version="1.0"`, `header_type="UInt64"`, little-endian, one
//! uncompressed appended raw block. `.vti` stores `Origin`, `Spacing`,
//! `Direction` and the samples in their own type; the anatomical frame
//! (`Volume::space`, LPS/RAS) has no place in a `.vti` and is not written:
//! world coordinates are written as they are. `.vtp` stores `Points`
//! (`Float32`), `Polys` (`Int64` connectivity and offsets) and each scalar
//! field as a `Float32` point array.
//!
//! **Why a hand-written reader on quick-xml rather than the `vtkio`
//! crate.** `vtkio`'s last release is 0.6.3 (March 2021; a 0.7.0-rc1
//! pre-release followed in 2024). Its XML reader (`src/xml.rs` at the
//! repository's 2025 head) slices the decoded bytes with
//! `&bytes[header_bytes..]` and unwraps the appended `offset`
//! conversion, so short or malformed arrays can panic; its
//! `ValidationError` carries no file position; and nothing bounds the
//! allocations against a memory budget. The readers here share the io
//! module's guarantees (no panic, no partial result, positions in every
//! error, budget checked before allocating).

mod array;
mod image;
mod poly;
mod source;
#[cfg(test)]
mod tests;

pub(crate) use image::{read_image, write_image};
pub(crate) use poly::{read_poly, write_poly};

use std::ops::Range;
use std::path::Path;

use quick_xml::events::{BytesStart, Event};

use super::text::{Endian, Num, clip};
use crate::{Error, Position, Result};

#[cfg(doc)]
use crate::{TriMesh, Volume};

/// The data set type of a VTK XML file (`<VTKFile type="...">`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum XmlDataset {
    /// `.vti`: read by [`read_image`].
    ImageData,
    /// `.vtp`: read by [`read_poly`].
    PolyData,
    /// Any other type (`UnstructuredGrid`, `RectilinearGrid`, parallel
    /// `P*` files, ...): not read by chisel.
    Other,
}

/// Which VTK XML data set `head` (the first bytes of a file) holds: `None`
/// when the bytes do not begin an XML document whose root is `VTKFile`
/// with a `type` attribute within `head`.
pub(crate) fn dataset_type(head: &[u8]) -> Option<XmlDataset> {
    let mut reader = quick_xml::Reader::from_reader(head);
    loop {
        match reader.read_event().ok()? {
            Event::Start(e) | Event::Empty(e) => {
                if e.name().as_ref() != "VTKFile" {
                    return None;
                }
                let ty = e.try_get_attribute("type").ok()??;
                return Some(match ty.value.as_ref() {
                    "ImageData" => XmlDataset::ImageData,
                    "PolyData" => XmlDataset::PolyData,
                    _ => XmlDataset::Other,
                });
            }
            Event::Decl(_) | Event::Comment(_) | Event::PI(_) | Event::DocType(_) => {}
            Event::Text(t) if t.trim_ascii().is_empty() => {}
            _ => return None,
        }
    }
}

/// One XML element of the document (up to `<AppendedData>`).
#[derive(Debug)]
pub(super) struct Elem {
    pub name: String,
    /// Byte offset of its `<`.
    pub at: usize,
    pub attrs: Vec<(String, String)>,
    /// Byte ranges of the text directly inside it.
    pub text: Vec<Range<usize>>,
    pub children: Vec<Elem>,
}

impl Elem {
    pub fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    pub fn child(&self, name: &str) -> Option<&Elem> {
        self.children.iter().find(|c| c.name == name)
    }

    pub fn children_named<'e>(&'e self, name: &'e str) -> impl Iterator<Item = &'e Elem> + 'e {
        self.children.iter().filter(move |c| c.name == name)
    }
}

/// How binary arrays are stored (the `VTKFile` attributes).
#[derive(Debug, Clone, Copy)]
pub(super) struct Encoding {
    pub endian: Endian,
    /// `UInt32` or `UInt64`.
    pub header: Num,
    pub zlib: bool,
}

/// The `<AppendedData>` section.
#[derive(Debug, Clone, Copy)]
pub(super) struct Appended {
    /// Byte offset of the element's `<`.
    pub at: usize,
    /// First byte after the `_` marker (offset 0 of the arrays).
    pub start: usize,
    /// Start of the closing `</AppendedData>`.
    pub end: usize,
    pub base64: bool,
}

/// A parsed VTK XML document.
#[derive(Debug)]
pub(super) struct Doc<'a> {
    pub path: &'a Path,
    pub bytes: &'a [u8],
    /// The `VTKFile` element.
    pub root: Elem,
    pub enc: Encoding,
    pub appended: Option<Appended>,
    /// The furthest end of an appended array decoded so far, and whether
    /// every appended array had a measurable length.
    pub appended_end: std::cell::Cell<(usize, bool)>,
}

impl<'a> Doc<'a> {
    /// Parses the XML of `bytes` up to (and including the start tag of)
    /// `<AppendedData>` and checks the `VTKFile` attributes; `kind` is the
    /// expected `type`.
    pub fn parse(path: &'a Path, bytes: &'a [u8], kind: &str) -> Result<Doc<'a>> {
        let mut reader = quick_xml::Reader::from_reader(bytes);
        let mut stack: Vec<Elem> = Vec::new();
        let mut root: Option<Elem> = None;
        let mut appended = None;
        let xml_error = |at: u64, e: &dyn std::fmt::Display| {
            Error::format(path, Position::Byte(at), "well-formed XML", e.to_string())
        };
        loop {
            let before = reader.buffer_position() as usize;
            let event = reader
                .read_event()
                .map_err(|e| xml_error(reader.error_position(), &e))?;
            let after = reader.buffer_position() as usize;
            match event {
                Event::Start(e) | Event::Empty(e) if root.is_some() => {
                    let _ = e;
                    return Err(Error::format(
                        path,
                        Position::Byte(before as u64),
                        "the end of the file after </VTKFile>",
                        "another element",
                    ));
                }
                Event::Start(e) if e.name().as_ref() == "AppendedData" => {
                    if stack.len() != 1 {
                        return Err(Error::format(
                            path,
                            Position::Byte(before as u64),
                            "<AppendedData> directly inside <VTKFile>",
                            "it deeper in the document",
                        ));
                    }
                    let el = element(path, &e, before)?;
                    appended = Some(appended_section(path, bytes, &el, after)?);
                    root = stack.pop();
                    break;
                }
                Event::Start(e) => stack.push(element(path, &e, before)?),
                Event::Empty(e) => {
                    let el = element(path, &e, before)?;
                    match stack.last_mut() {
                        Some(parent) => parent.children.push(el),
                        None => root = Some(el),
                    }
                }
                Event::End(_) => {
                    let el = stack.pop().ok_or_else(|| {
                        xml_error(before as u64, &"a closing tag without an opening tag")
                    })?;
                    match stack.last_mut() {
                        Some(parent) => parent.children.push(el),
                        None => root = Some(el),
                    }
                }
                Event::Text(t) => {
                    if let Some(top) = stack.last_mut() {
                        top.text.push(before..after);
                    } else if !t.trim_ascii().is_empty() {
                        return Err(Error::format(
                            path,
                            Position::Byte(before as u64),
                            if root.is_some() {
                                "the end of the file after </VTKFile>"
                            } else {
                                "`<VTKFile`"
                            },
                            format!("text {}", super::text::show(&bytes[before..after])),
                        ));
                    }
                }
                Event::GeneralRef(_) => match stack.last_mut() {
                    Some(top) => top.text.push(before..after),
                    None => return Err(xml_error(before as u64, &"an entity outside elements")),
                },
                Event::CData(_) => {
                    return Err(Error::Unsupported {
                        path: path.into(),
                        what: format!("a CDATA section at byte {before} (VTK writes none)"),
                    });
                }
                Event::Eof => {
                    if !stack.is_empty() {
                        return Err(Error::format(
                            path,
                            Position::Byte(bytes.len() as u64),
                            format!("`</{}>`", stack.last().map_or("", |e| e.name.as_str())),
                            "end of file",
                        ));
                    }
                    break;
                }
                Event::Decl(_) | Event::Comment(_) | Event::PI(_) | Event::DocType(_) => {}
            }
        }
        let root = root.ok_or_else(|| {
            Error::format(path, Position::Byte(0), "a <VTKFile> element", "no element")
        })?;
        let at = Position::Byte(root.at as u64);
        if root.name != "VTKFile" {
            return Err(Error::format(
                path,
                at,
                "a <VTKFile> root element",
                format!("<{}>", clip(&root.name)),
            ));
        }
        let ty = root.attr("type").unwrap_or("");
        if ty != kind {
            return Err(Error::format(
                path,
                at,
                format!("<VTKFile type=\"{kind}\">"),
                format!("type=\"{}\"", clip(ty)),
            ));
        }
        if let Some(v) = root.attr("version") {
            let major = v.split('.').next().and_then(|m| m.parse::<u32>().ok());
            if !matches!(major, Some(0..=2)) {
                return Err(Error::Unsupported {
                    path: path.into(),
                    what: format!("VTK XML version \"{}\" (chisel reads 0.1 to 2.x)", clip(v)),
                });
            }
        }
        let endian = match root.attr("byte_order") {
            None | Some("LittleEndian") => Endian::Little,
            Some("BigEndian") => Endian::Big,
            Some(o) => {
                return Err(Error::format(
                    path,
                    at,
                    "byte_order=\"LittleEndian\" or \"BigEndian\"",
                    format!("\"{}\"", clip(o)),
                ));
            }
        };
        let header = match root.attr("header_type") {
            None | Some("UInt32") => Num::U32,
            Some("UInt64") => Num::U64,
            Some(h) => {
                return Err(Error::format(
                    path,
                    at,
                    "header_type=\"UInt32\" or \"UInt64\"",
                    format!("\"{}\"", clip(h)),
                ));
            }
        };
        let zlib = match root.attr("compressor") {
            None | Some("") => false,
            Some("vtkZLibDataCompressor") => true,
            Some(c) => {
                return Err(Error::Unsupported {
                    path: path.into(),
                    what: format!(
                        "VTK XML compressor \"{}\" (chisel reads uncompressed and \
                         vtkZLibDataCompressor data; re-save with zlib or no compression)",
                        clip(c)
                    ),
                });
            }
        };
        Ok(Doc {
            path,
            bytes,
            root,
            enc: Encoding {
                endian,
                header,
                zlib,
            },
            appended,
            appended_end: std::cell::Cell::new((0, true)),
        })
    }

    /// An [`Error::Format`] at byte `at`.
    pub fn error(&self, at: usize, expected: impl Into<String>, found: impl Into<String>) -> Error {
        Error::format(self.path, Position::Byte(at as u64), expected, found)
    }

    /// The one child `name` of `parent` (an error naming `parent` if missing).
    pub fn one<'e>(&self, parent: &'e Elem, name: &str) -> Result<&'e Elem> {
        parent.child(name).ok_or_else(|| {
            self.error(
                parent.at,
                format!("a <{name}> element inside <{}>", parent.name),
                "none",
            )
        })
    }

    /// `n` numbers of attribute `key` of `el`; `default` when it is absent.
    pub fn numbers<T: std::str::FromStr + Copy, const N: usize>(
        &self,
        el: &Elem,
        key: &str,
        default: Option<[T; N]>,
    ) -> Result<[T; N]> {
        let Some(text) = el.attr(key) else {
            return default.ok_or_else(|| {
                self.error(
                    el.at,
                    format!("attribute {key}=\"{N} numbers\" on <{}>", el.name),
                    "none",
                )
            });
        };
        let bad = || {
            self.error(
                el.at,
                format!("{key}=\"{N} numbers\" on <{}>", el.name),
                format!("\"{}\"", clip(text)),
            )
        };
        let mut out = Vec::with_capacity(N);
        for tok in text.split_ascii_whitespace() {
            if out.len() == N {
                return Err(bad());
            }
            out.push(tok.parse::<T>().map_err(|_| bad())?);
        }
        out.try_into().map_err(|_| bad())
    }

    /// A non-negative count attribute (`NumberOfPoints`, ...); 0 when absent.
    pub fn count(&self, el: &Elem, key: &str) -> Result<u64> {
        Ok(self.numbers::<u64, 1>(el, key, Some([0]))?[0])
    }

    /// Checks the end of the file after the appended data: whitespace,
    /// `</VTKFile>`, whitespace; and, when every appended array was
    /// measured, no bytes but whitespace after the last one.
    pub fn check_appended_tail(&self) -> Result<()> {
        let Some(app) = self.appended else {
            return Ok(());
        };
        let (end, all) = self.appended_end.get();
        if all {
            let from = end.max(app.start);
            if let Some(k) = self.bytes[from..app.end]
                .iter()
                .position(|b| !b.is_ascii_whitespace())
            {
                return Err(self.error(
                    from + k,
                    "`</AppendedData>` after the last appended array",
                    format!(
                        "{} more bytes (data no array refers to)",
                        app.end - from - k
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// An element's name, position and attributes (values unescaped).
fn element(path: &Path, e: &BytesStart, at: usize) -> Result<Elem> {
    let name = e.name().as_ref().to_string();
    let mut attrs = Vec::new();
    for a in e.attributes() {
        let a = a.map_err(|err| {
            Error::format(
                path,
                Position::Byte(at as u64),
                "well-formed attributes",
                err.to_string(),
            )
        })?;
        let value = a
            .normalized_value(quick_xml::XmlVersion::Implicit1_0)
            .map_err(|err| {
                Error::format(
                    path,
                    Position::Byte(at as u64),
                    "an attribute value",
                    err.to_string(),
                )
            })?;
        attrs.push((a.key.as_ref().to_string(), value.into_owned()));
    }
    Ok(Elem {
        name,
        at,
        attrs,
        text: Vec::new(),
        children: Vec::new(),
    })
}

/// Locates the appended data after its start tag (ending at `after`): the
/// `_` marker, and the closing `</AppendedData>` `</VTKFile>` at the end of
/// the file (only whitespace may follow). Raw data may hold any bytes, so
/// nothing between is parsed as XML.
fn appended_section(path: &Path, bytes: &[u8], el: &Elem, after: usize) -> Result<Appended> {
    let base64 = match el.attr("encoding") {
        Some("raw") => false,
        Some("base64") => true,
        other => {
            return Err(Error::format(
                path,
                Position::Byte(el.at as u64),
                "<AppendedData encoding=\"raw\"> or \"base64\"",
                format!("{:?}", other.map(clip)),
            ));
        }
    };
    let ws = bytes[after..]
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .map_or(bytes.len(), |k| after + k);
    if bytes.get(ws) != Some(&b'_') {
        return Err(Error::format(
            path,
            Position::Byte(ws as u64),
            "the `_` that starts the appended data",
            match bytes.get(ws) {
                Some(_) => super::text::show(&bytes[ws..]),
                None => "end of file".into(),
            },
        ));
    }
    let start = ws + 1;
    // The file ends with `</AppendedData>`, whitespace, `</VTKFile>`, whitespace.
    let mut tail = bytes.len();
    let strip = |tail: &mut usize| {
        while *tail > start && bytes[*tail - 1].is_ascii_whitespace() {
            *tail -= 1;
        }
    };
    strip(&mut tail);
    let bad_end = |at: usize| {
        Error::format(
            path,
            Position::Byte(at as u64),
            "the file to end with `</AppendedData>` and `</VTKFile>`",
            super::text::show(&bytes[at..]),
        )
    };
    const VTK_END: &[u8] = b"</VTKFile>";
    const APP_END: &[u8] = b"</AppendedData>";
    if !bytes[start..tail].ends_with(VTK_END) {
        return Err(bad_end(tail.saturating_sub(VTK_END.len()).max(start)));
    }
    tail -= VTK_END.len();
    strip(&mut tail);
    if !bytes[start..tail].ends_with(APP_END) {
        return Err(bad_end(tail.saturating_sub(APP_END.len()).max(start)));
    }
    Ok(Appended {
        at: el.at,
        start,
        end: tail - APP_END.len(),
        base64,
    })
}

/// The numeric type of a `DataArray type="..."` name.
pub(super) fn xml_type(name: &str) -> Option<Num> {
    Some(match name {
        "Int8" | "Char" => Num::I8,
        "UInt8" | "UnsignedChar" => Num::U8,
        "Int16" => Num::I16,
        "UInt16" => Num::U16,
        "Int32" => Num::I32,
        "UInt32" => Num::U32,
        "Int64" => Num::I64,
        "UInt64" => Num::U64,
        "Float32" => Num::F32,
        "Float64" => Num::F64,
        _ => return None,
    })
}

/// The `DataArray type` name of `num`.
pub(super) fn xml_type_name(num: Num) -> &'static str {
    match num {
        Num::I8 => "Int8",
        Num::U8 => "UInt8",
        Num::I16 => "Int16",
        Num::U16 => "UInt16",
        Num::I32 => "Int32",
        Num::U32 => "UInt32",
        Num::I64 => "Int64",
        Num::U64 => "UInt64",
        Num::F32 => "Float32",
        Num::F64 => "Float64",
    }
}

/// Escapes `s` for an XML attribute value.
pub(super) fn escape(s: &str) -> String {
    quick_xml::escape::escape(s).into_owned()
}
