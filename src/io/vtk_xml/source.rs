//! The bytes of one `DataArray` payload, read in order: raw appended
//! bytes, or base64 text over one or more ranges (VTK writes a compression
//! header and its blocks as separate padded runs).

use std::borrow::Cow;

use base64::prelude::{BASE64_STANDARD, Engine as _};

/// Why a byte source stopped.
pub(super) enum SrcErr {
    /// The data ends after `got` of the requested bytes.
    End {
        got: usize,
    },
    /// A character that is not base64 at this byte offset.
    Char(usize, u8),
    /// Malformed base64 (padding) in the run starting at this byte offset.
    Base64(usize, String),
    Memory(usize),
}

/// Bytes of one array's payload, read in order.
pub(super) trait Source<'b> {
    fn read(&mut self, n: usize) -> std::result::Result<Cow<'b, [u8]>, SrcErr>;
    /// File offset of the next unread byte (or base64 character).
    fn pos(&self) -> usize;
    /// At most this many bytes can still be read.
    fn left(&self) -> usize;
}

/// Raw appended bytes.
pub(super) struct Raw<'b> {
    pub(super) bytes: &'b [u8],
    pub(super) pos: usize,
    pub(super) end: usize,
}

impl<'b> Source<'b> for Raw<'b> {
    fn read(&mut self, n: usize) -> std::result::Result<Cow<'b, [u8]>, SrcErr> {
        if n > self.end - self.pos {
            return Err(SrcErr::End {
                got: self.end - self.pos,
            });
        }
        let out = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(Cow::Borrowed(out))
    }
    fn pos(&self) -> usize {
        self.pos
    }
    fn left(&self) -> usize {
        self.end - self.pos
    }
}

/// Base64 text over one or more byte ranges, possibly several padded runs
/// (VTK encodes a compression header and the blocks as separate runs);
/// ASCII whitespace is skipped.
pub(super) struct B64<'b> {
    bytes: &'b [u8],
    ranges: Vec<std::ops::Range<usize>>,
    ri: usize,
    pub(super) pos: usize,
    chunk: Vec<u8>,
    pub(super) carry: Vec<u8>,
    pub(super) coff: usize,
}

impl<'b> B64<'b> {
    pub(super) fn new(bytes: &'b [u8], ranges: Vec<std::ops::Range<usize>>) -> Self {
        let pos = ranges.first().map_or(0, |r| r.start);
        B64 {
            bytes,
            ranges,
            ri: 0,
            pos,
            chunk: Vec::new(),
            carry: Vec::new(),
            coff: 0,
        }
    }

    /// The next non-whitespace character and its offset.
    fn next_char(&mut self) -> Option<(usize, u8)> {
        while self.ri < self.ranges.len() {
            let r = &self.ranges[self.ri];
            self.pos = self.pos.max(r.start);
            while self.pos < r.end {
                let (at, c) = (self.pos, self.bytes[self.pos]);
                self.pos += 1;
                if !c.is_ascii_whitespace() {
                    return Some((at, c));
                }
            }
            self.ri += 1;
        }
        None
    }

    /// Decodes up to `want` more bytes (whole quanta, at least one, never
    /// past the end of a padded run) into `carry`.
    fn fill(&mut self, want: usize) -> std::result::Result<(), SrcErr> {
        let quanta = want.div_ceil(3).clamp(1, 1 << 18);
        self.chunk.clear();
        let mut first = None;
        'quanta: for _ in 0..quanta {
            let mut padded = false;
            for i in 0..4 {
                match self.next_char() {
                    Some((at, c)) if c.is_ascii_alphanumeric() || c == b'+' || c == b'/' => {
                        if padded {
                            return Err(SrcErr::Base64(at, "data after `=` padding".into()));
                        }
                        first.get_or_insert(at);
                        self.chunk.push(c);
                    }
                    Some((at, b'=')) if i >= 2 => {
                        first.get_or_insert(at);
                        padded = true;
                        self.chunk.push(b'=');
                    }
                    Some((at, c)) => return Err(SrcErr::Char(at, c)),
                    None if i == 0 && self.chunk.is_empty() => {
                        return Err(SrcErr::End { got: 0 });
                    }
                    None if i == 0 => break 'quanta,
                    None => {
                        return Err(SrcErr::Base64(
                            self.pos,
                            "a base64 run whose length is not a multiple of 4".into(),
                        ));
                    }
                }
            }
            if padded {
                break;
            }
        }
        self.carry.clear();
        self.coff = 0;
        BASE64_STANDARD
            .decode_vec(&self.chunk, &mut self.carry)
            .map_err(|e| SrcErr::Base64(first.unwrap_or(self.pos), e.to_string()))
    }

    /// Decoded bytes not yet read, plus whether non-whitespace text is left.
    pub(super) fn leftover(&mut self) -> (usize, Option<usize>) {
        let carry = self.carry.len() - self.coff;
        (carry, self.next_char().map(|(at, _)| at))
    }
}

impl<'b> Source<'b> for B64<'b> {
    fn read(&mut self, n: usize) -> std::result::Result<Cow<'b, [u8]>, SrcErr> {
        let mut out = Vec::new();
        out.try_reserve_exact(n).map_err(|_| SrcErr::Memory(n))?;
        while out.len() < n {
            if self.coff == self.carry.len() {
                match self.fill(n - out.len()) {
                    Err(SrcErr::End { .. }) => return Err(SrcErr::End { got: out.len() }),
                    r => r?,
                }
            }
            let take = (n - out.len()).min(self.carry.len() - self.coff);
            out.extend_from_slice(&self.carry[self.coff..self.coff + take]);
            self.coff += take;
        }
        Ok(Cow::Owned(out))
    }
    fn pos(&self) -> usize {
        self.pos
    }
    fn left(&self) -> usize {
        let chars: usize = self.ranges[self.ri.min(self.ranges.len())..]
            .iter()
            .map(|r| r.end - r.start.max(self.pos.min(r.end)))
            .sum();
        chars / 4 * 3 + 3 + (self.carry.len() - self.coff)
    }
}
