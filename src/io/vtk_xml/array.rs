//! `DataArray` payloads: ASCII tokens, inline base64, appended raw or
//! base64 data, each optionally zlib-compressed in VTK's block layout.

use std::borrow::Cow;
use std::io::Read;

use super::super::text::{Endian, Num, clip};
use super::super::vtk::{check_samples_budget, empty_samples, push_binary, push_text};
use super::source::{B64, Raw, Source, SrcErr};
use super::{Doc, Elem, xml_type};
use crate::volume::VolumeData;
use crate::{Error, Position, Result};

/// How a `DataArray` stores its values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Ascii,
    Binary,
    Appended(u64),
}

/// One `<DataArray>` element, described.
#[derive(Debug)]
pub(crate) struct Array<'e> {
    pub el: &'e Elem,
    pub name: String,
    /// `None` for types chisel does not decode (`String`, `Bit`).
    pub num: Option<Num>,
    pub comps: u64,
    format: Format,
}

impl Array<'_> {
    /// The numeric type, or an [`Error::Unsupported`] for `String`/`Bit`.
    pub fn numeric(&self, doc: &Doc) -> Result<Num> {
        self.num.ok_or_else(|| Error::Unsupported {
            path: doc.path.into(),
            what: format!(
                "DataArray `{}` at byte {} of type \"{}\" (chisel reads Int8..UInt64, Float32, \
                 Float64)",
                clip(&self.name),
                self.el.at,
                clip(self.el.attr("type").unwrap_or(""))
            ),
        })
    }

    /// `name` as it appears in error messages.
    pub fn label(&self) -> String {
        format!("DataArray `{}`", clip(&self.name))
    }
}

impl<'a> Doc<'a> {
    /// Describes the `<DataArray>` element `el`.
    pub fn array<'e>(&self, el: &'e Elem) -> Result<Array<'e>> {
        if el.name != "DataArray" {
            return Err(self.error(
                el.at,
                "a <DataArray> element",
                format!("<{}>", clip(&el.name)),
            ));
        }
        let name = el.attr("Name").unwrap_or("").to_string();
        let ty = el
            .attr("type")
            .ok_or_else(|| self.error(el.at, "a `type` attribute on <DataArray>", "none"))?;
        let comps = self.count(el, "NumberOfComponents")?.max(1);
        let format = match el.attr("format") {
            Some("ascii") => Format::Ascii,
            Some("binary") => Format::Binary,
            Some("appended") => Format::Appended(self.numbers::<u64, 1>(el, "offset", None)?[0]),
            other => {
                return Err(self.error(
                    el.at,
                    "format=\"ascii\", \"binary\" or \"appended\" on <DataArray>",
                    format!("{:?}", other.map(clip)),
                ));
            }
        };
        Ok(Array {
            el,
            name,
            num: xml_type(ty),
            comps,
            format,
        })
    }

    /// The `count` values of `a` (all components) as a [`VolumeData`] of
    /// the array's own type; the budget is checked before allocating.
    pub fn volume_data(&self, a: &Array, count: u64) -> Result<VolumeData> {
        let num = a.numeric(self)?;
        let what = a.label();
        check_samples_budget(
            self.path,
            Position::Byte(a.el.at as u64),
            &what,
            count,
            num.size(),
        )?;
        let n = usize::try_from(count).map_err(|_| self.too_many(a, count))?;
        if a.format == Format::Ascii {
            self.check_text_room(a, count)?;
            let mut data = empty_samples(self.path, num, n, &what)?;
            let expected = format!("a {} value of {what}", super::xml_type_name(num));
            self.tokens(a, count, |at, tok| {
                if push_text(&mut data, tok) {
                    Ok(())
                } else {
                    Err(self.error(at, &expected, format!("`{}`", clip(tok))))
                }
            })?;
            return Ok(data);
        }
        // Room for the samples before the payload is decoded.
        let mut data = empty_samples(self.path, num, n, &what)?;
        let bytes = self.binary(a, Some(count.saturating_mul(num.size() as u64)))?;
        push_binary(&mut data, &bytes, self.enc.endian);
        Ok(data)
    }

    /// The `count` values of `a` as `f64` (exact for all but 64-bit
    /// integers past 2⁵³, which no index or coordinate check accepts).
    pub fn f64s(&self, a: &Array, count: u64) -> Result<Vec<f64>> {
        let num = a.numeric(self)?;
        let what = a.label();
        check_samples_budget(self.path, Position::Byte(a.el.at as u64), &what, count, 8)?;
        let n = usize::try_from(count).map_err(|_| self.too_many(a, count))?;
        let mut out = Vec::new();
        let reserve = |out: &mut Vec<f64>| {
            out.try_reserve_exact(n).map_err(|_| Error::HostMemory {
                what: format!("{}: {what}", self.path.display()),
                bytes: count.saturating_mul(8),
            })
        };
        if a.format == Format::Ascii {
            self.check_text_room(a, count)?;
            reserve(&mut out)?;
            let expected = format!("a {} value of {what}", super::xml_type_name(num));
            self.tokens(a, count, |at, tok| match num.parse_text(tok) {
                Some(v) => {
                    out.push(v);
                    Ok(())
                }
                None => Err(self.error(at, &expected, format!("`{}`", clip(tok)))),
            })?;
            return Ok(out);
        }
        reserve(&mut out)?;
        let bytes = self.binary(a, Some(count.saturating_mul(num.size() as u64)))?;
        out.extend(
            bytes
                .chunks_exact(num.size())
                .map(|c| num.decode(c, self.enc.endian)),
        );
        Ok(out)
    }

    /// Reads and checks every `FieldData` array of `el` (none is kept),
    /// handing `field NAME` of each to `note`.
    pub fn skip_field_data(&self, el: &Elem, mut note: impl FnMut(String)) -> Result<()> {
        for fd in el.children_named("FieldData") {
            for arr in fd.children_named("DataArray") {
                let a = self.array(arr)?;
                let tuples = arr
                    .attr("NumberOfTuples")
                    .and_then(|t| t.parse::<u64>().ok());
                self.skip(&a, tuples.map(|t| t.saturating_mul(a.comps)))?;
                note(format!("field {}", a.name));
            }
        }
        Ok(())
    }

    /// Reads and checks an array that is not kept: `count` values when
    /// known, else as many as its header says. `String`/`Bit` arrays are
    /// passed over (an appended one then leaves the end of the appended
    /// data unchecked).
    pub fn skip(&self, a: &Array, count: Option<u64>) -> Result<()> {
        let Some(num) = a.num else {
            if matches!(a.format, Format::Appended(_)) {
                let (end, _) = self.appended_end.get();
                self.appended_end.set((end, false));
            }
            return Ok(());
        };
        if a.format == Format::Ascii {
            let mut expected_count = count;
            if expected_count.is_none() {
                let mut k = 0u64;
                self.tokens(a, u64::MAX, |_, _| {
                    k += 1;
                    Ok(())
                })?;
                expected_count = Some(k);
            }
            let expected = format!("a {} value of {}", super::xml_type_name(num), a.label());
            return self.tokens(a, expected_count.unwrap_or(0), |at, tok| {
                num.parse_text(tok)
                    .map(|_| ())
                    .ok_or_else(|| self.error(at, &expected, format!("`{}`", clip(tok))))
            });
        }
        let bytes = self.binary(a, count.map(|c| c.saturating_mul(num.size() as u64)))?;
        if bytes.len() % num.size() != 0 {
            return Err(self.error(
                a.el.at,
                format!(
                    "whole {} values in {}",
                    super::xml_type_name(num),
                    a.label()
                ),
                format!("{} bytes", bytes.len()),
            ));
        }
        Ok(())
    }

    fn too_many(&self, a: &Array, count: u64) -> Error {
        Error::Size {
            path: self.path.into(),
            at: Position::Byte(a.el.at as u64),
            what: format!("{count} values of {}", a.label()),
            needed: count,
            limit_kind: super::super::BUDGET_KIND,
            limit: crate::foundation::alloc::memory_budget(),
        }
    }

    /// Each value of an ASCII array needs at least one byte of its text.
    fn check_text_room(&self, a: &Array, count: u64) -> Result<()> {
        let room: usize = a.el.text.iter().map(|r| r.len()).sum();
        if count > room as u64 {
            return Err(Error::Size {
                path: self.path.into(),
                at: Position::Byte(a.el.at as u64),
                what: format!("{count} ASCII values of {}", a.label()),
                needed: count,
                limit_kind: "the array's text",
                limit: room as u64,
            });
        }
        Ok(())
    }

    /// Hands the whitespace-separated tokens of `a`'s text to `f`; there
    /// must be exactly `count` of them (`u64::MAX`: any number).
    fn tokens(
        &self,
        a: &Array,
        count: u64,
        mut f: impl FnMut(usize, &str) -> Result<()>,
    ) -> Result<()> {
        let mut k = 0u64;
        for r in &a.el.text {
            let text = &self.bytes[r.clone()];
            let mut i = 0;
            while i < text.len() {
                if text[i].is_ascii_whitespace() {
                    i += 1;
                    continue;
                }
                let start = i;
                while i < text.len() && !text[i].is_ascii_whitespace() {
                    i += 1;
                }
                let at = r.start + start;
                if k == count {
                    return Err(self.error(
                        at,
                        format!("{count} values in {} (then `</DataArray>`)", a.label()),
                        "more values",
                    ));
                }
                let tok = std::str::from_utf8(&text[start..i]).unwrap_or("\u{fffd}");
                f(at, tok)?;
                k += 1;
            }
        }
        if count != u64::MAX && k != count {
            let end = a.el.text.last().map_or(a.el.at, |r| r.end);
            return Err(self.error(
                end,
                format!("{count} values in {}", a.label()),
                format!("{k} values"),
            ));
        }
        Ok(())
    }

    /// The binary payload of `a` (inline base64 or appended), decompressed,
    /// in file byte order: `nbytes` bytes when known.
    fn binary(&self, a: &Array, nbytes: Option<u64>) -> Result<Cow<'a, [u8]>> {
        match a.format {
            Format::Ascii => Err(Error::Internal("binary() on an ASCII array".into())),
            Format::Binary => {
                let mut src = B64::new(self.bytes, a.el.text.clone());
                let out = self.payload(&mut src, a, nbytes)?;
                let (carry, text) = src.leftover();
                if carry > 0 || text.is_some() {
                    return Err(self.error(
                        text.unwrap_or(src.pos),
                        format!("`</DataArray>` after the data of {}", a.label()),
                        "more base64 data",
                    ));
                }
                Ok(out)
            }
            Format::Appended(offset) => {
                let app = self.appended.ok_or_else(|| {
                    self.error(
                        a.el.at,
                        "an <AppendedData> section for format=\"appended\"",
                        "none",
                    )
                })?;
                let size = app.end - app.start;
                let start = usize::try_from(offset)
                    .ok()
                    .filter(|&o| o < size || (o == size && nbytes == Some(0)))
                    .ok_or_else(|| {
                        self.error(
                            a.el.at,
                            format!(
                                "an offset within the {size} bytes of appended data (<AppendedData> \
                                 at byte {})",
                                app.at
                            ),
                            format!("offset=\"{offset}\" in {}", a.label()),
                        )
                    })?
                    + app.start;
                let (out, end) = if app.base64 {
                    #[allow(clippy::single_range_in_vec_init)] // one text range
                    let mut src = B64::new(self.bytes, vec![start..app.end]);
                    let out = self.payload(&mut src, a, nbytes)?;
                    if src.carry.len() > src.coff {
                        return Err(self.error(
                            src.pos,
                            format!("base64 of {} ending with the data", a.label()),
                            "more decoded bytes than the header announces",
                        ));
                    }
                    (out, src.pos)
                } else {
                    let mut src = Raw {
                        bytes: self.bytes,
                        pos: start,
                        end: app.end,
                    };
                    let out = self.payload(&mut src, a, nbytes)?;
                    (out, src.pos)
                };
                let (far, all) = self.appended_end.get();
                self.appended_end.set((far.max(end), all));
                Ok(out)
            }
        }
    }

    /// Reads one array's header and data from `src`.
    fn payload<'b>(
        &self,
        src: &mut dyn Source<'b>,
        a: &Array,
        nbytes: Option<u64>,
    ) -> Result<Cow<'b, [u8]>> {
        let hw = self.enc.header.size();
        let label = a.label();
        let words = |src: &mut dyn Source<'b>, k: usize, what: &str| -> Result<Vec<u64>> {
            let at = src.pos();
            let bytes = src
                .read(k * hw)
                .map_err(|e| self.src_error(e, at, format!("{what} of {label}"), k * hw))?;
            Ok(bytes
                .chunks_exact(hw)
                .map(|c| word(c, self.enc.endian))
                .collect())
        };
        let at = src.pos();
        if !self.enc.zlib {
            let n = words(src, 1, "the byte count header")?[0];
            if let Some(want) = nbytes
                && n != want
            {
                return Err(self.error(
                    at,
                    format!("a byte count of {want} in the header of {label}"),
                    format!("{n}"),
                ));
            }
            let n = self.checked(at, &label, n)?;
            let dat = src.pos();
            return src
                .read(n)
                .map_err(|e| self.src_error(e, dat, format!("the data of {label}"), n));
        }
        let [nb, bs, last] = <[u64; 3]>::try_from(words(src, 3, "the compression header")?)
            .map_err(|_| Error::Internal("three header words".into()))?;
        let total = match nb {
            0 => 0,
            _ if bs == 0 || last > bs => {
                return Err(self.error(
                    at,
                    format!(
                        "a compression header of {label} with block size > 0 ≥ the last block's"
                    ),
                    format!("block size {bs}, last block {last}"),
                ));
            }
            _ => (nb - 1)
                .checked_mul(bs)
                .and_then(|t| t.checked_add(if last == 0 { bs } else { last }))
                .unwrap_or(u64::MAX),
        };
        if let Some(want) = nbytes
            && total != want
        {
            return Err(self.error(
                at,
                format!("a compression header of {label} announcing {want} bytes"),
                format!("{nb} blocks of {bs} bytes (the last {last}): {total} bytes"),
            ));
        }
        let total = self.checked(at, &label, total)?;
        let sizes_bytes = nb.saturating_mul(hw as u64);
        if sizes_bytes > src.left() as u64 {
            return Err(Error::Size {
                path: self.path.into(),
                at: Position::Byte(at as u64),
                what: format!("{nb} compressed block sizes of {label}"),
                needed: sizes_bytes,
                limit_kind: "the data left in the file",
                limit: src.left() as u64,
            });
        }
        let sizes = words(src, nb as usize, "the compressed block sizes")?;
        let mut out = Vec::new();
        out.try_reserve_exact(total + 1)
            .map_err(|_| Error::HostMemory {
                what: format!("{}: {label}", self.path.display()),
                bytes: total as u64,
            })?;
        for (k, &cs) in sizes.iter().enumerate() {
            let want = if k + 1 == sizes.len() && last != 0 {
                last
            } else {
                bs
            } as usize;
            let cat = src.pos();
            let cs = usize::try_from(cs).unwrap_or(usize::MAX);
            let block_what = format!("compressed block {k} of {label}");
            let comp = src
                .read(cs)
                .map_err(|e| self.src_error(e, cat, block_what.clone(), cs))?;
            let mut z = flate2::read::ZlibDecoder::new(&comp[..]);
            let before = out.len();
            (&mut z)
                .take(want as u64 + 1)
                .read_to_end(&mut out)
                .map_err(|e| {
                    self.error(cat, format!("a zlib stream in {block_what}"), e.to_string())
                })?;
            let got = out.len() - before;
            if got != want {
                return Err(self.error(
                    cat,
                    format!("{block_what} inflating to {want} bytes (its header's size)"),
                    if got > want {
                        "a longer stream".to_string()
                    } else {
                        format!("a stream that ends at byte {got} of {want}")
                    },
                ));
            }
            if z.total_in() != cs as u64 {
                return Err(self.error(
                    cat,
                    format!("{block_what} to be one zlib stream of {cs} bytes"),
                    format!("{} bytes after the stream's end", cs as u64 - z.total_in()),
                ));
            }
        }
        Ok(Cow::Owned(out))
    }

    /// `n` bytes as `usize`, within the memory budget.
    fn checked(&self, at: usize, label: &str, n: u64) -> Result<usize> {
        super::super::check_budget(self.path, Position::Byte(at as u64), label, n)?;
        usize::try_from(n).map_err(|_| Error::HostMemory {
            what: format!("{}: {label}", self.path.display()),
            bytes: n,
        })
    }

    fn src_error(&self, e: SrcErr, at: usize, what: String, n: usize) -> Error {
        match e {
            SrcErr::End { got } => self.error(
                at,
                format!("{n} bytes of {what}"),
                format!("the data ends after {got} bytes"),
            ),
            SrcErr::Char(p, c) => self.error(
                p,
                format!("base64 data of {what}"),
                format!("the byte {}", super::super::text::show(&[c])),
            ),
            SrcErr::Base64(p, m) => self.error(p, format!("base64 data of {what}"), m),
            SrcErr::Memory(n) => Error::HostMemory {
                what: format!("{}: {what}", self.path.display()),
                bytes: n as u64,
            },
        }
    }
}

/// One header word (`UInt32` or `UInt64`, by its length) in `endian` order.
fn word(c: &[u8], endian: Endian) -> u64 {
    let mut a = [0u8; 8];
    match (c.len(), endian) {
        (4, Endian::Little) => a[..4].copy_from_slice(c),
        (4, Endian::Big) => {
            a[..4].copy_from_slice(c);
            a[..4].reverse();
        }
        (_, Endian::Little) => a.copy_from_slice(c),
        (_, Endian::Big) => {
            a.copy_from_slice(c);
            a.reverse();
        }
    }
    u64::from_le_bytes(a)
}
