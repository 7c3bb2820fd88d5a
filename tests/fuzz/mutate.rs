//! Mutators: truncations, byte flips, inserted and deleted bytes, repeated
//! runs, interesting numbers in header fields (text or binary), appended
//! bytes, and devices in place of the file.

/// What was done to a seed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mutation {
    /// Cut at a random length (always shorter).
    Truncate,
    /// One to four bits flipped.
    Flip,
    /// Random bytes inserted.
    Insert,
    /// A run of bytes deleted.
    Delete,
    /// A run of bytes repeated.
    Repeat,
    /// A number in the header replaced by an interesting one (a digit run
    /// in a text header; a 1-, 2-, 4- or 8-byte field in a binary one).
    Number,
    /// Bytes appended (at least one).
    Append,
    /// The case is a link to `/dev/zero` or `/dev/urandom`.
    Device,
}

impl Mutation {
    /// The mutators of a file's bytes, taken in turn.
    pub const BYTES: [Mutation; 7] = [
        Mutation::Truncate,
        Mutation::Flip,
        Mutation::Insert,
        Mutation::Delete,
        Mutation::Repeat,
        Mutation::Number,
        Mutation::Append,
    ];
}

/// Numbers that break parsers: zero, signs, the edges of every integer
/// width, overflowing and non-finite floats.
const TEXT_NUMBERS: &[&str] = &[
    "0",
    "-1",
    "1",
    "-0",
    "255",
    "256",
    "65535",
    "65536",
    "2147483647",
    "2147483648",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "18446744073709551616",
    "99999999999999999999999",
    "1e308",
    "1e309",
    "-1e309",
    "nan",
    "inf",
    "-inf",
    "0.5",
    "1e-320",
];

const BINARY_NUMBERS: &[u64] = &[
    0,
    1,
    0xff,
    0x7f,
    0x80,
    0xffff,
    0x7fff,
    0x8000,
    0xffff_ffff,
    0x7fff_ffff,
    0x8000_0000,
    0x7f80_0000, // f32 inf
    0x7fc0_0000, // f32 NaN
    0x7f7f_ffff, // f32 max
    u64::MAX,
    0x7ff0_0000_0000_0000, // f64 inf
    0x8000_0000_0000_0000,
];

/// A small random-number source (xorshift) with helpers.
pub struct Rng(Box<dyn FnMut() -> u64>);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(Box::new(crate::common::xorshift(seed)))
    }

    /// Uniform in `0..n` (0 when n is 0).
    pub fn below(&mut self, n: usize) -> usize {
        ((self.0)() % n.max(1) as u64) as usize
    }

    pub fn byte(&mut self) -> u8 {
        (self.0)() as u8
    }
}

/// Applies `m` to `b` (not [`Mutation::Device`], which the caller makes).
pub fn mutate(rng: &mut Rng, b: &mut Vec<u8>, m: Mutation) {
    let len = b.len();
    match m {
        Mutation::Truncate => b.truncate(rng.below(len)),
        Mutation::Flip => {
            for _ in 0..1 + rng.below(4) {
                if len > 0 {
                    let i = rng.below(len);
                    b[i] ^= 1 << rng.below(8);
                }
            }
        }
        Mutation::Insert => {
            let i = rng.below(len + 1);
            let n = 1 + rng.below(16);
            let bytes: Vec<u8> = (0..n).map(|_| rng.byte()).collect();
            b.splice(i..i, bytes);
        }
        Mutation::Delete => {
            let i = rng.below(len);
            let j = (i + 1 + rng.below(32)).min(len);
            b.drain(i..j);
        }
        Mutation::Repeat => {
            let i = rng.below(len);
            let j = (i + 1 + rng.below(64)).min(len);
            let run = b[i..j].to_vec();
            b.splice(j..j, run);
        }
        Mutation::Number => number(rng, b),
        Mutation::Append => {
            let n = 1 + rng.below(8);
            for _ in 0..n {
                let byte = rng.byte();
                b.push(byte);
            }
        }
        Mutation::Device => {}
    }
}

/// Replaces a digit run of the first 4 KiB with an interesting number, or,
/// in a header without one, writes an interesting value over a field.
fn number(rng: &mut Rng, b: &mut Vec<u8>) {
    let head = &b[..b.len().min(4096)];
    let mut runs = Vec::new();
    let mut i = 0;
    while i < head.len() {
        if head[i].is_ascii_digit() {
            let s = i;
            while i < head.len() && (head[i].is_ascii_digit() || head[i] == b'.') {
                i += 1;
            }
            runs.push(s..i);
        } else {
            i += 1;
        }
    }
    if !runs.is_empty() && b.iter().take(64).all(|c| c.is_ascii()) {
        let r = runs[rng.below(runs.len())].clone();
        let n = TEXT_NUMBERS[rng.below(TEXT_NUMBERS.len())];
        b.splice(r, n.bytes());
        return;
    }
    if b.is_empty() {
        return;
    }
    let width = [1usize, 2, 4, 8][rng.below(4)];
    let at = rng.below(b.len().min(512));
    let value = BINARY_NUMBERS[rng.below(BINARY_NUMBERS.len())].to_le_bytes();
    let n = width.min(b.len() - at);
    b[at..at + n].copy_from_slice(&value[..n]);
}
