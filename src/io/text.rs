//! A byte scanner shared by every reader: whitespace tokens, lines and raw
//! byte blocks over one file held in memory, with errors that name the file,
//! the position (1-based line while the file is text, 0-based byte offset
//! once a binary block has been read) and what was expected.

use std::cell::Cell;
use std::path::Path;
use std::str::FromStr;

use crate::{Error, Position, Result};

/// Limit kind used in [`Error::Size`] when a count exceeds what is left of the file.
pub(crate) const REST_OF_FILE: &str = "the rest of the file";

/// Cursor over the bytes of one file.
#[derive(Debug)]
pub(crate) struct Scanner<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    pos: usize,
    binary: bool,
    /// A binary payload starts at `pos` (or has started): whitespace bytes
    /// there are data, never skipped.
    payload: bool,
    /// `(offset, line at offset)` of the last position asked for, so that
    /// positions requested in file order cost O(file) in total.
    line_cache: Cell<(usize, usize)>,
}

impl<'a> Scanner<'a> {
    /// A scanner at byte 0 of `bytes`, the contents of `path`.
    pub fn new(path: &'a Path, bytes: &'a [u8]) -> Self {
        Scanner {
            path,
            bytes,
            pos: 0,
            binary: false,
            payload: false,
            line_cache: Cell::new((0, 1)),
        }
    }

    /// Current byte offset.
    pub fn pos(&self) -> usize {
        self.pos
    }

    /// Offset of the next token: skips whitespace first while the file is
    /// text (never inside binary payloads), so errors point at the token.
    pub fn mark(&mut self) -> usize {
        if !self.binary && !self.payload {
            self.skip_ws();
        }
        self.pos
    }

    /// Bytes left after the current offset.
    pub fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    /// From now on report positions as byte offsets (binary payload follows).
    pub fn set_binary(&mut self) {
        self.binary = true;
        self.payload = true;
    }

    /// A binary payload starts here: from now on [`Scanner::mark`] skips
    /// nothing, while positions stay lines until the payload is read (so a
    /// size error still names the header line).
    pub fn payload_follows(&mut self) {
        self.payload = true;
    }

    /// Position of byte offset `at`: a line number for text, a byte offset
    /// once binary data has been read.
    pub fn position(&self, at: usize) -> Position {
        if self.binary {
            Position::Byte(at as u64)
        } else {
            let at = at.min(self.bytes.len());
            let (from, line) = match self.line_cache.get() {
                (off, line) if off <= at => (off, line),
                _ => (0, 1),
            };
            let line = line + self.bytes[from..at].iter().filter(|&&b| b == b'\n').count();
            self.line_cache.set((at, line));
            Position::Line(line)
        }
    }

    /// An [`Error::Format`] at byte offset `at`.
    pub fn error(&self, at: usize, expected: impl Into<String>, found: impl Into<String>) -> Error {
        Error::format(self.path, self.position(at), expected, found)
    }

    /// An [`Error::Size`] at byte offset `at`: `needed` bytes for `what` do
    /// not fit in the rest of the file.
    pub fn size_error(&self, at: usize, what: impl Into<String>, needed: u64) -> Error {
        self.size_error_at(self.position(at), what, needed)
    }

    fn size_error_at(&self, at: Position, what: impl Into<String>, needed: u64) -> Error {
        Error::Size {
            path: self.path.into(),
            at,
            what: what.into(),
            needed,
            limit_kind: REST_OF_FILE,
            limit: self.remaining() as u64,
        }
    }

    /// Checks that `count` items of at least `min_bytes` each can still be in
    /// the file before anything is allocated for them; returns `count` as `usize`.
    pub fn check_count(&self, at: usize, what: &str, count: u64, min_bytes: u64) -> Result<usize> {
        // The position (a newline count) is only computed on the error path.
        let needed = count.saturating_mul(min_bytes);
        match usize::try_from(count) {
            Ok(n) if needed <= self.remaining() as u64 => Ok(n),
            _ => self.check_count_at(self.position(at), what, count, min_bytes),
        }
    }

    /// [`Scanner::check_count`] with an explicit position (e.g. a header line
    /// of a binary file).
    pub fn check_count_at(
        &self,
        at: Position,
        what: &str,
        count: u64,
        min_bytes: u64,
    ) -> Result<usize> {
        let needed = count.saturating_mul(min_bytes);
        if needed > self.remaining() as u64 {
            return Err(self.size_error_at(at, format!("{count} {what}"), needed));
        }
        usize::try_from(count)
            .map_err(|_| self.size_error_at(at, format!("{count} {what}"), needed))
    }

    fn skip_ws(&mut self) {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    /// The bytes after the current offset.
    pub fn rest(&self) -> &'a [u8] {
        &self.bytes[self.pos..]
    }

    /// The remaining tokens of the current line (the `\n` is not consumed).
    pub fn line_tokens(&mut self) -> Vec<(usize, &'a str)> {
        let mut out = Vec::new();
        loop {
            // Every whitespace byte but the line's end separates tokens (a
            // form feed once stopped both loops: an endless empty token).
            while self.pos < self.bytes.len()
                && self.bytes[self.pos].is_ascii_whitespace()
                && self.bytes[self.pos] != b'\n'
            {
                self.pos += 1;
            }
            if self.pos >= self.bytes.len() || self.bytes[self.pos] == b'\n' {
                return out;
            }
            let start = self.pos;
            while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
                self.pos += 1;
            }
            out.push((
                start,
                std::str::from_utf8(&self.bytes[start..self.pos]).unwrap_or(""),
            ));
        }
    }

    /// Whether only whitespace is left.
    pub fn at_end(&mut self) -> bool {
        self.skip_ws();
        self.pos >= self.bytes.len()
    }

    /// The next whitespace-separated token and its offset, without consuming it.
    pub fn peek(&mut self) -> Option<&'a [u8]> {
        self.skip_ws();
        let start = self.pos;
        let end = self.bytes[start..]
            .iter()
            .position(u8::is_ascii_whitespace)
            .map_or(self.bytes.len(), |n| start + n);
        (end > start).then(|| &self.bytes[start..end])
    }

    /// The next token as text; an error mentioning `expected` at end of file.
    pub fn next(&mut self, expected: &str) -> Result<(usize, &'a str)> {
        let tok = self.peek();
        let start = self.pos;
        let Some(tok) = tok else {
            return Err(self.error(start, expected, "end of file"));
        };
        self.pos += tok.len();
        let text = std::str::from_utf8(tok)
            .map_err(|_| self.error(start, expected, format!("non-text bytes {}", show(tok))))?;
        Ok((start, text))
    }

    /// The next token parsed as `T`.
    pub fn parse<T: FromStr>(&mut self, expected: &str) -> Result<T> {
        let (at, tok) = self.next(expected)?;
        tok.parse()
            .map_err(|_| self.error(at, expected, format!("`{}`", clip(tok))))
    }

    /// The next token parsed as a finite `f32` (a coordinate).
    pub fn finite_f32(&mut self, expected: &str) -> Result<f32> {
        let (at, tok) = self.next(expected)?;
        match tok.parse::<f32>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.error(at, expected, format!("`{}`", clip(tok)))),
        }
    }

    /// The next token parsed as a non-negative count.
    pub fn count(&mut self, expected: &str) -> Result<(usize, u64)> {
        let (at, tok) = self.next(expected)?;
        let n = tok
            .parse::<u64>()
            .map_err(|_| self.error(at, expected, format!("`{}`", clip(tok))))?;
        Ok((at, n))
    }

    /// Consumes the next token, which must equal `keyword` (ASCII case-insensitive).
    pub fn keyword(&mut self, keyword: &str) -> Result<usize> {
        let expected = format!("`{keyword}`");
        let (at, tok) = self.next(&expected)?;
        if tok.eq_ignore_ascii_case(keyword) {
            Ok(at)
        } else {
            Err(self.error(at, expected, format!("`{}`", clip(tok))))
        }
    }

    /// The next line (without its `\n` or `\r\n`) and its starting offset;
    /// `None` at end of file.
    pub fn line(&mut self) -> Option<(usize, &'a [u8])> {
        if self.pos >= self.bytes.len() {
            return None;
        }
        let start = self.pos;
        let end = self.bytes[start..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(self.bytes.len(), |n| start + n);
        self.pos = (end + 1).min(self.bytes.len());
        let mut line = &self.bytes[start..end];
        if let [head @ .., b'\r'] = line {
            line = head;
        }
        Some((start, line))
    }

    /// The next line as text; an error if it is missing or not UTF-8.
    pub fn text_line(&mut self, expected: &str) -> Result<(usize, &'a str)> {
        let at = self.pos;
        let (start, line) = self
            .line()
            .ok_or_else(|| self.error(at, expected, "end of file"))?;
        let text = std::str::from_utf8(line)
            .map_err(|_| self.error(start, expected, format!("non-text bytes {}", show(line))))?;
        Ok((start, text))
    }

    /// Skips the rest of the current line, including its `\n`.
    pub fn skip_line(&mut self) {
        self.line();
    }

    /// The next `n` bytes (binary payload); [`Error::Size`] if the file is shorter.
    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8]> {
        self.binary = true;
        if n > self.remaining() {
            return Err(self.size_error(self.pos, what.to_string(), n as u64));
        }
        let block = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(block)
    }
}

/// The first `cap` bytes of `path` (all of it when shorter): header text
/// of a reader that opens the file again for its data. A pipe or FIFO
/// cannot be read twice (the second open would wait for a writer without
/// end), so it is refused before it is opened.
pub(crate) fn read_prefix(path: &Path, cap: u64) -> Result<Vec<u8>> {
    use std::io::Read;
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let kind = std::fs::metadata(path)
            .map_err(|e| Error::io(path, e))?
            .file_type();
        if kind.is_fifo() || kind.is_socket() {
            return Err(Error::format(
                path,
                Position::Whole,
                "a regular file (this format's reader opens the file twice: header, then data)",
                "a pipe or FIFO",
            ));
        }
    }
    let (file, _) = crate::foundation::fs::open_input(path)?;
    let mut head = Vec::new();
    file.take(cap)
        .read_to_end(&mut head)
        .map_err(|e| Error::io(path, e))?;
    Ok(head)
}

/// At most 40 characters of `s`, for error messages.
pub(crate) fn clip(s: &str) -> String {
    match s.char_indices().nth(40) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s.to_string(),
    }
}

/// Up to 16 bytes as escaped text, for error messages.
pub(crate) fn show(bytes: &[u8]) -> String {
    let head = &bytes[..bytes.len().min(16)];
    format!("`{}`", head.escape_ascii())
}

/// Byte order of binary payloads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Endian {
    Little,
    Big,
}

/// A numeric element type as named by a file header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Num {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Num {
    /// Bytes per value.
    pub fn size(self) -> usize {
        match self {
            Num::I8 | Num::U8 => 1,
            Num::I16 | Num::U16 => 2,
            Num::I32 | Num::U32 | Num::F32 => 4,
            Num::I64 | Num::U64 | Num::F64 => 8,
        }
    }

    /// Whether the type holds integers.
    pub fn is_integer(self) -> bool {
        !matches!(self, Num::F32 | Num::F64)
    }

    /// Decodes one binary value (`bytes.len() == self.size()`) as `f64`
    /// (exact except for 64-bit integers beyond 2⁵³).
    pub fn decode(self, bytes: &[u8], endian: Endian) -> f64 {
        macro_rules! get {
            ($t:ty) => {{
                let mut a = [0u8; std::mem::size_of::<$t>()];
                a.copy_from_slice(bytes);
                match endian {
                    Endian::Little => <$t>::from_le_bytes(a),
                    Endian::Big => <$t>::from_be_bytes(a),
                }
            }};
        }
        match self {
            Num::I8 => f64::from(get!(i8)),
            Num::U8 => f64::from(get!(u8)),
            Num::I16 => f64::from(get!(i16)),
            Num::U16 => f64::from(get!(u16)),
            Num::I32 => f64::from(get!(i32)),
            Num::U32 => f64::from(get!(u32)),
            Num::I64 => get!(i64) as f64,
            Num::U64 => get!(u64) as f64,
            Num::F32 => f64::from(get!(f32)),
            Num::F64 => get!(f64),
        }
    }

    /// Parses one text value: floats of an `F32` type are parsed as `f32`
    /// (so the value is exactly the one a writer of `f32` meant).
    pub fn parse_text(self, tok: &str) -> Option<f64> {
        match self {
            Num::F32 => tok.parse::<f32>().ok().map(f64::from),
            Num::F64 => tok.parse::<f64>().ok(),
            _ => tok.parse::<i64>().ok().map(|v| v as f64),
        }
    }
}

impl Scanner<'_> {
    /// One value of type `num`, as text or binary.
    pub fn value(&mut self, num: Num, binary: Option<Endian>, expected: &str) -> Result<f64> {
        match binary {
            Some(endian) => {
                let bytes = self.take(num.size(), expected)?;
                Ok(num.decode(bytes, endian))
            }
            None => {
                let (at, tok) = self.next(expected)?;
                num.parse_text(tok)
                    .ok_or_else(|| self.error(at, expected, format!("`{}`", clip(tok))))
            }
        }
    }

    /// One vertex index of type `num` (an integer that fits `i64`).
    pub fn index(&mut self, num: Num, binary: Option<Endian>, expected: &str) -> Result<i64> {
        let at = self.mark();
        let v = self.value(num, binary, expected)?;
        if v.fract() != 0.0 || !v.is_finite() || v.abs() > 9.0e15 {
            return Err(self.error(at, expected, format!("{v}")));
        }
        Ok(v as i64)
    }
}

/// Appends the fan triangulation `(p0, pi, pi+1)` of polygon `poly` (≥ 3 corners).
pub(crate) fn fan(poly: &[u32], out: &mut Vec<[u32; 3]>) {
    for w in 1..poly.len().saturating_sub(1) {
        out.push([poly[0], poly[w], poly[w + 1]]);
    }
}
