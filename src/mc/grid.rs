//! How the GPU kernels read a [`Field`]: the volume's samples in their own
//! type, packed into 32-bit words, and the [`SampleGrid`] that says how to
//! decode them — the padding, the label and the level are applied in the
//! kernels, not by a conversion pass on the host. [`grid_sample`] is the
//! mirror of `kernels/shared/mc_grid.wgsl` (read them side by side); it
//! gives exactly [`Field::sample`] (tested for every scalar type, with and
//! without padding, in level and label mode).
//!
//! 8- and 16-bit integers and `f32` travel as they are (a CT volume of
//! `i16` uploads 2 bytes a sample, not 4). `u32`, `i32` and `f64` samples
//! are converted to `f32` on the host first: WGSL has no `f64`, and its
//! integer-to-float conversion of values beyond 2²⁴ is not specified to
//! round like Rust's `as` (a label volume of those types uploads its 0/1
//! flags as `f32`).
//!
//! The inside flags of the points, one bit each in [`BitRows`] (written by
//! `mc_inside`), are what `mc_classify`, `mc_vertices` and `mc_triangles`
//! read to find cases and crossing edges; [`inside_bit`] and
//! [`inside_run`] are the mirrors of `kernels/shared/mc_bits.wgsl`.

use rayon::prelude::*;

use super::IsoSpec;
use super::field::Field;
use crate::Result;
use crate::foundation::alloc::zeroed;
use crate::volume::Samples;

/// Sample encodings of [`SampleGrid::kind`]; the values of
/// `kernels/shared/mc_grid.wgsl`, whose decoding relies on them: 0 is
/// `f32`, 1–2 are 16-bit and 3–4 8-bit, and the odd kinds are signed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum SampleKind {
    /// One `f32` per word (its bits).
    F32 = 0,
    /// Two `i16` per word, the first in the low half.
    I16 = 1,
    /// Two `u16` per word.
    U16 = 2,
    /// Four `i8` per word, the first in the low byte.
    I8 = 3,
    /// Four `u8` per word.
    U8 = 4,
}

impl SampleKind {
    /// Samples per 32-bit word.
    pub fn per_word(self) -> usize {
        match self {
            SampleKind::F32 => 1,
            SampleKind::I16 | SampleKind::U16 => 2,
            SampleKind::I8 | SampleKind::U8 => 4,
        }
    }
}

/// The `grid` member of `mc_inside`'s and `mc_vertices`' parameters: the padded grid,
/// which inner layers the `samples` words hold, and how to decode them.
/// 48 bytes (two unused words), so that it is laid out alike as the first
/// member of a uniform struct in WGSL and by encase.
#[derive(Debug, Clone, Copy, PartialEq, encase::ShaderType)]
pub struct SampleGrid {
    /// Sample counts per axis of the padded grid.
    pub nx: u32,
    pub ny: u32,
    pub nz: u32,
    /// The first inner (unpadded) layer the words hold.
    pub z_first: u32,
    /// 1 when the border is closed (one padding sample per side), else 0.
    pub pad: u32,
    /// A [`SampleKind`] as `u32`.
    pub kind: u32,
    /// 1: a sample is 1 where it equals `label`, else 0 (label mode).
    pub labels: u32,
    /// The label as `f32`; NaN where no sample of the type can equal it.
    pub label: f32,
    /// The outside value of the padding ([`Field`]'s `outside()`).
    pub outside: f32,
    /// Iso level: inside is `sample >= level`.
    pub level: f32,
    pub unused0: u32,
    pub unused1: u32,
}

/// The kind, label flag and label of `field`'s words (before conversion:
/// `None` where the host converts to `f32`).
fn native(field: &Field<'_>) -> Option<(SampleKind, bool)> {
    let labels = matches!(field.iso(), IsoSpec::Label(_));
    match field.volume().data {
        Samples::F32(_) => Some((SampleKind::F32, labels)),
        Samples::I16(_) => Some((SampleKind::I16, labels)),
        Samples::U16(_) => Some((SampleKind::U16, labels)),
        Samples::I8(_) => Some((SampleKind::I8, labels)),
        Samples::U8(_) => Some((SampleKind::U8, labels)),
        Samples::U32(_) | Samples::I32(_) | Samples::F64(_) => None,
    }
}

/// The [`SampleGrid`] of `field` for words holding inner layers from
/// `z_first`.
pub fn sample_grid(field: &Field<'_>, z_first: usize) -> SampleGrid {
    let (kind, labels) = native(field).unwrap_or((SampleKind::F32, false));
    let label = match field.iso() {
        IsoSpec::Label(l) if labels && f64::from(l as f32) == l => l as f32,
        _ => f32::NAN,
    };
    SampleGrid {
        nx: field.dims[0] as u32,
        ny: field.dims[1] as u32,
        nz: field.dims[2] as u32,
        z_first: z_first as u32,
        pad: field.pad as u32,
        kind: kind as u32,
        labels: u32::from(labels),
        label,
        outside: field.outside(),
        level: field.level,
        unused0: 0,
        unused1: 0,
    }
}

/// The `rows` member of `mc_classify`'s, `mc_vertices`' and
/// `mc_triangles`' parameters: the padded grid and the layers of the inside
/// flags `mc_inside` wrote — bit `x & 31` of word `x >> 5` of row
/// `y + ny·(z − z_first)`, [`BitRows::row_words`] words a row, bits past
/// `nx` zero. 32 bytes (three unused words), laid out alike in WGSL and by
/// encase.
#[derive(Debug, Clone, Copy, PartialEq, encase::ShaderType)]
pub struct BitRows {
    /// Sample counts per axis of the padded grid.
    pub nx: u32,
    pub ny: u32,
    pub nz: u32,
    /// The first (padded) layer the words hold.
    pub z_first: u32,
    /// Words per row: `⌈nx / 32⌉`.
    pub row_words: u32,
    pub unused0: u32,
    pub unused1: u32,
    pub unused2: u32,
}

impl BitRows {
    /// The rows of `field`'s padded grid for words holding layers from
    /// `z_first`.
    pub fn new(field: &Field<'_>, z_first: usize) -> Self {
        BitRows {
            nx: field.dims[0] as u32,
            ny: field.dims[1] as u32,
            nz: field.dims[2] as u32,
            z_first: z_first as u32,
            row_words: field.dims[0].div_ceil(32) as u32,
            unused0: 0,
            unused1: 0,
            unused2: 0,
        }
    }

    /// Words of `n_layers` layers.
    pub fn words(&self, n_layers: usize) -> usize {
        n_layers * self.ny as usize * self.row_words as usize
    }
}

/// `inside` of `kernels/shared/mc_bits.wgsl`: the inside flag (0 or 1) of
/// point `(x, y, z)` of the padded grid from the bit rows `bits`.
pub fn inside_bit(r: &BitRows, bits: &[u32], x: u32, y: u32, z: u32) -> u32 {
    let word = bits[((y + r.ny * (z - r.z_first)) * r.row_words + (x >> 5)) as usize];
    (word >> (x & 31)) & 1
}

/// `inside_run` of `kernels/shared/mc_bits.wgsl`: the inside flags of
/// points `x`, `x + 1`, `x + 2` of row `(y, z)` as bits 0–2 (one or two word
/// reads); 0 past the row's end and for a row past the grid.
pub fn inside_run(r: &BitRows, bits: &[u32], x: u32, y: u32, z: u32) -> u32 {
    if y >= r.ny || z >= r.nz {
        return 0;
    }
    let at = ((y + r.ny * (z - r.z_first)) * r.row_words + (x >> 5)) as usize;
    let s = x & 31;
    let mut run = bits[at] >> s;
    if s > 29 && (x >> 5) + 1 < r.row_words {
        run |= bits[at + 1] << (32 - s);
    }
    run & 7
}

/// Bytes one sample takes in the words (for binding-size limits).
pub fn sample_bytes(field: &Field<'_>) -> usize {
    native(field).map_or(4, |(k, _)| 4 / k.per_word())
}

/// The inner layers `k0..k1` the kernels read for padded point layers
/// `z0..z1` (a padding layer mirrors the inner layer next to it).
pub fn inner_layers(field: &Field<'_>, z0: usize, z1: usize) -> (usize, usize) {
    let (p, vz) = (field.pad, field.volume().dims[2]);
    let inner = |z: usize| z.saturating_sub(p).min(vz - 1);
    (inner(z0), inner(z1.max(z0 + 1) - 1) + 1)
}

/// Inner layers `k0..k1` of `field` as the kernels' `samples` words.
/// Errors when the words exceed the memory budget.
pub fn sample_words(field: &Field<'_>, k0: usize, k1: usize) -> Result<Vec<u32>> {
    let v = field.volume();
    let layer = v.dims[0] * v.dims[1];
    let range = k0 * layer..k1 * layer;
    let what = "marching cubes: GPU sample words";
    match v.data {
        Samples::F32(s) => pack(what, &s[range], 1, f32::to_bits),
        Samples::I16(s) => pack(what, &s[range], 2, |x| u32::from(x as u16)),
        Samples::U16(s) => pack(what, &s[range], 2, u32::from),
        Samples::I8(s) => pack(what, &s[range], 4, |x| u32::from(x as u8)),
        Samples::U8(s) => pack(what, &s[range], 4, u32::from),
        Samples::U32(_) | Samples::I32(_) | Samples::F64(_) => {
            // Converted on the host exactly as the CPU path converts them
            // (`Field::inner_row`: f32 values, 0/1 flags in label mode).
            let mut words: Vec<u32> = zeroed(what, range.len())?;
            let (vx, vy) = (v.dims[0], v.dims[1]);
            words.par_chunks_mut(vx).enumerate().for_each(|(r, row)| {
                field.inner_row(r % vy, k0 + r / vy, bytemuck::cast_slice_mut(row));
            });
            Ok(words)
        }
    }
}

/// `src` packed `per` samples a word, the first in the low bits, each
/// sample's bits given by `bits` (in parallel over blocks of words).
fn pack<T: Copy + Sync>(
    what: &str,
    src: &[T],
    per: usize,
    bits: impl Fn(T) -> u32 + Sync,
) -> Result<Vec<u32>> {
    const BLOCK: usize = 1 << 14;
    let mut words: Vec<u32> = zeroed(what, src.len().div_ceil(per))?;
    let width = 32 / per;
    words
        .par_chunks_mut(BLOCK)
        .zip(src.par_chunks(BLOCK * per))
        .for_each(|(out, src)| {
            for (w, s) in out.iter_mut().zip(src.chunks(per)) {
                *w = (s.iter().enumerate()).fold(0, |a, (k, &x)| a | bits(x) << (width * k));
            }
        });
    Ok(words)
}

/// `grid_sample` of `kernels/shared/mc_grid.wgsl`: sample `(x, y, z)` of
/// the padded grid from the `samples` words.
pub fn grid_sample(g: &SampleGrid, words: &[u32], x: u32, y: u32, z: u32) -> f32 {
    let p = g.pad;
    let v = [g.nx - 2 * p, g.ny - 2 * p, g.nz - 2 * p];
    let c = [x, y, z];
    // Below the padding the subtraction wraps past every inner index.
    let i = c.map(|c| c.wrapping_sub(p));
    if (0..3).all(|a| i[a] < v[a]) {
        return inner_sample(g, words, i[0] + v[0] * (i[1] + v[1] * (i[2] - g.z_first)));
    }
    padding_sample(g, words, c, v)
}

/// `padding_sample` of `kernels/shared/mc_grid.wgsl`: a padding sample
/// next to one inner sample `s` (one coordinate outside) is `2·level − s`
/// capped at `outside` where `s > level`, else `outside`; padding edges and
/// corners are `outside`.
fn padding_sample(g: &SampleGrid, words: &[u32], c: [u32; 3], v: [u32; 3]) -> f32 {
    let p = g.pad;
    let mut i = [0u32; 3];
    let mut n_pad = 0u32;
    for a in 0..3 {
        let below = c[a] < p;
        i[a] = (if below { 0 } else { c[a] - p }).min(v[a] - 1);
        n_pad += u32::from(below || c[a] >= v[a] + p);
    }
    let s = inner_sample(g, words, i[0] + v[0] * (i[1] + v[1] * (i[2] - g.z_first)));
    if n_pad == 1 && s > g.level {
        (2.0 * g.level - s).min(g.outside)
    } else {
        g.outside
    }
}

/// `inner_sample` of `kernels/shared/mc_grid.wgsl`: inner sample `i`
/// (relative to layer `z_first`) decoded from its word, with the kernel's
/// branch-free shifts (kind 0 is `f32`, kinds 1–2 16-bit, 3–4 8-bit; odd
/// kinds are signed).
fn inner_sample(g: &SampleGrid, words: &[u32], i: u32) -> f32 {
    let lg = if g.kind == 0 {
        0
    } else if g.kind <= 2 {
        1
    } else {
        2
    };
    let w = words[(i >> lg) as usize];
    let width = 32 >> lg;
    let top = (w >> ((i & ((1 << lg) - 1)) * width)) << (32 - width);
    let n = if g.kind & 1 == 1 {
        ((top as i32) >> (32 - width)) as f32
    } else {
        (top >> (32 - width)) as f32
    };
    let s = if g.kind == 0 { f32::from_bits(w) } else { n };
    if g.labels == 1 {
        if s == g.label { 1.0 } else { 0.0 }
    } else {
        s
    }
}
