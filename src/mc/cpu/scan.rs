//! The *scan* pass: the volume's inside flags as bit rows ([`Bits`], 64
//! points per `u64`), and per z layer its vertices' interpolation
//! parameters and the number of triangles it will emit ([`scan`]).

use rayon::prelude::*;

use super::super::field::{Field, NativeSamples, SampleVisitor, Scalar};
use super::super::tables;
use super::T_MIN;
use crate::Result;
use crate::foundation::alloc::zeroed;

/// The bit-row geometry: row length and the mask of the points that own a
/// +x edge (`x < nx − 1`), per word.
pub(super) struct Rows {
    pub(super) nx: usize,
    pub(super) ny: usize,
    pub(super) words: usize,
    pub(super) has_x: Vec<u64>,
}

impl Rows {
    fn new(field: &Field<'_>) -> Self {
        let [nx, ny, _] = field.dims;
        let words = field.row_words();
        let has_x = (0..words)
            .map(|w| {
                let n = (nx - 1).saturating_sub(64 * w).min(64);
                if n == 64 { u64::MAX } else { (1u64 << n) - 1 }
            })
            .collect();
        Rows {
            nx,
            ny,
            words,
            has_x,
        }
    }
}

/// Inside flags of the whole (padded) grid: `nz` layers of `ny` rows of
/// `words` words, 1 bit per sample.
pub(super) struct Bits {
    pub(super) rows: Rows,
    nz: usize,
    data: Vec<u64>,
}

impl Bits {
    /// Point layer `z` with the layer above it (none on the top layer).
    #[inline]
    pub(super) fn pair(&self, z: usize) -> LayerPair<'_> {
        let plane = self.rows.ny * self.rows.words;
        LayerPair {
            rows: &self.rows,
            lower: &self.data[z * plane..(z + 1) * plane],
            upper: (z + 1 < self.nz).then(|| &self.data[(z + 1) * plane..(z + 2) * plane]),
        }
    }
}

/// The bits of point layer `z` (`lower`) and `z + 1` (`upper`, `None` on
/// the top layer): all a layer's crossings and its cell layer's cases
/// depend on.
#[derive(Clone, Copy)]
pub(super) struct LayerPair<'a> {
    pub(super) rows: &'a Rows,
    lower: &'a [u64],
    upper: Option<&'a [u64]>,
}

impl<'a> LayerPair<'a> {
    #[inline]
    fn row(&self, layer: &'a [u64], y: usize) -> &'a [u64] {
        let w = self.rows.words;
        &layer[y * w..(y + 1) * w]
    }

    /// Crossing masks `[x, y, z]` of word `w` of row `y`: the points whose
    /// +x, +y, +z edge joins an inside and an outside sample.
    #[inline]
    pub(super) fn crossings(&self, y: usize, w: usize) -> [u64; 3] {
        let m = self.row(self.lower, y);
        let ex = (m[w] ^ next_bits(m, w)) & self.rows.has_x[w];
        let ey = if y + 1 < self.rows.ny {
            m[w] ^ self.row(self.lower, y + 1)[w]
        } else {
            0
        };
        let ez = self.upper.map_or(0, |u| m[w] ^ self.row(u, y)[w]);
        [ex, ey, ez]
    }

    /// The four corner rows of cell row `y` of the cell layer between the
    /// two point layers: (y, z), (y + 1, z), (y, z + 1), (y + 1, z + 1).
    /// `None` on the top layer.
    #[inline]
    pub(super) fn cell_rows(&self, y: usize) -> Option<[&'a [u64]; 4]> {
        let u = self.upper?;
        Some([
            self.row(self.lower, y),
            self.row(self.lower, y + 1),
            self.row(u, y),
            self.row(u, y + 1),
        ])
    }
}

/// What the scan learns of point layer `z`.
pub(super) struct LayerScan {
    /// Interpolation parameter of each vertex of the layer, in numbering
    /// order (see [`super::emit`]): computed while the layer's samples are
    /// in cache, so emission never reads samples.
    pub(super) ts: Vec<f32>,
    /// Triangles of cell layer `z` (none on the top layer).
    pub(super) triangles: u64,
}

/// The *scan* pass: the inside bits of every layer ([`Field::inside_row`],
/// rows checked finite as they are packed) and each layer's
/// [`LayerScan`]. Parallel over slabs of z layers; inside a slab, layer
/// `z + 1` is packed, then layer `z` scanned while both are in cache. A
/// slab packs the first layer of the next one a second time (into scratch)
/// to scan its own last layer.
pub(super) fn scan(field: &Field<'_>) -> Result<(Bits, Vec<LayerScan>)> {
    let rows = Rows::new(field);
    let nz = field.dims[2];
    let plane = rows.ny * rows.words;
    let mut data = zeroed("marching cubes: inside bits", nz * plane)?;
    let per_slab = nz.div_ceil(4 * rayon::current_num_threads().max(1)).max(1);
    let layers = field.visit_samples(ScanSlabs {
        field,
        rows: &rows,
        data: &mut data,
        per_slab,
    })?;
    Ok((Bits { rows, nz, data }, layers))
}

struct ScanSlabs<'f, 'a> {
    field: &'f Field<'a>,
    rows: &'f Rows,
    data: &'f mut [u64],
    per_slab: usize,
}

impl SampleVisitor for ScanSlabs<'_, '_> {
    type Output = Result<Vec<LayerScan>>;

    fn visit<T: Scalar>(self, samples: NativeSamples<'_, '_, T>) -> Result<Vec<LayerScan>> {
        let ScanSlabs {
            field,
            rows,
            data,
            per_slab,
        } = self;
        let plane = rows.ny * rows.words;
        let nz = field.dims[2];
        let table = tables::table();
        let slabs: Vec<Vec<LayerScan>> = data
            .par_chunks_mut(plane * per_slab)
            .enumerate()
            .map(|(c, slab)| {
                let z0 = c * per_slab;
                let n = slab.len() / plane;
                let mut next = Vec::new();
                let mut out = Vec::with_capacity(n);
                for i in 0..=n {
                    let z = z0 + i;
                    if i < n {
                        pack_layer(field, rows, z, &mut slab[i * plane..(i + 1) * plane], true)?;
                    } else if z < nz {
                        next = vec![0u64; plane];
                        pack_layer(field, rows, z, &mut next, false)?;
                    }
                    if i > 0 {
                        let upper = if i < n {
                            Some(&slab[i * plane..(i + 1) * plane])
                        } else {
                            (z < nz).then_some(next.as_slice())
                        };
                        let pair = LayerPair {
                            rows,
                            lower: &slab[(i - 1) * plane..i * plane],
                            upper,
                        };
                        out.push(scan_layer(&samples, pair, z - 1, table));
                    }
                }
                Ok(out)
            })
            .collect::<Result<_>>()?;
        Ok(slabs.into_iter().flatten().collect())
    }
}

/// Packs layer `z`'s rows, checking them finite when `check`.
fn pack_layer(
    field: &Field<'_>,
    rows: &Rows,
    z: usize,
    out: &mut [u64],
    check: bool,
) -> Result<()> {
    for (y, row) in out.chunks_exact_mut(rows.words).enumerate() {
        field.inside_row(y, z, row);
        if check {
            field.check_finite_row(y, z)?;
        }
    }
    Ok(())
}

/// The interpolation parameter of an edge from sample `a` (at its lower
/// end) to `b`: `clamp((level − a) / (b − a), T_MIN, 1 − T_MIN)`.
#[inline]
fn edge_t(level: f32, a: f32, b: f32) -> f32 {
    ((level - a) / (b - a)).clamp(T_MIN, 1.0 - T_MIN)
}

/// Point layer `z`'s vertex parameters (points in order, x fastest, then
/// y; axes x < y < z within a point) and its cell layer's triangle count.
fn scan_layer<T: Scalar>(
    samples: &NativeSamples<'_, '_, T>,
    pair: LayerPair<'_>,
    z: usize,
    table: &tables::CaseTable,
) -> LayerScan {
    let Rows { ny, words, .. } = *pair.rows;
    let level = samples.level();
    let mut ts = Vec::new();
    for y in 0..ny {
        for w in 0..words {
            let [ex, ey, ez] = pair.crossings(y, w);
            let mut any = ex | ey | ez;
            while any != 0 {
                let s = any.trailing_zeros();
                any &= any - 1;
                let x = 64 * w + s as usize;
                let a = samples.sample(x, y, z);
                if ex >> s & 1 == 1 {
                    ts.push(edge_t(level, a, samples.sample(x + 1, y, z)));
                }
                if ey >> s & 1 == 1 {
                    ts.push(edge_t(level, a, samples.sample(x, y + 1, z)));
                }
                if ez >> s & 1 == 1 {
                    ts.push(edge_t(level, a, samples.sample(x, y, z + 1)));
                }
            }
        }
    }
    let mut triangles = 0u64;
    for y in 0..ny - 1 {
        let Some(r) = pair.cell_rows(y) else { break };
        for w in 0..words {
            let (lo, hi, mut crossed) = cell_word(&r, w, pair.rows.has_x[w]);
            while crossed != 0 {
                let s = crossed.trailing_zeros();
                crossed &= crossed - 1;
                triangles += table.case(case_at(&lo, &hi, s)).len() as u64;
            }
        }
    }
    LayerScan { ts, triangles }
}

/// Word `w` of `row` shifted down by one bit: bit `x` holds point `x + 1`.
#[inline]
fn next_bits(row: &[u64], w: usize) -> u64 {
    row[w] >> 1 | row.get(w + 1).map_or(0, |n| n << 63)
}

/// Word `w` of 64 cells of a cell row: corner bits at `x` (`lo`) and at
/// `x + 1` (`hi`) of the four corner rows, and the mask of crossed cells
/// (corners neither all inside nor all outside).
#[inline]
pub(super) fn cell_word(r: &[&[u64]; 4], w: usize, has_x: u64) -> ([u64; 4], [u64; 4], u64) {
    let lo = r.map(|row| row[w]);
    let hi = r.map(|row| next_bits(row, w));
    let any = lo[0] | lo[1] | lo[2] | lo[3] | hi[0] | hi[1] | hi[2] | hi[3];
    let all = lo[0] & lo[1] & lo[2] & lo[3] & hi[0] & hi[1] & hi[2] & hi[3];
    (lo, hi, any & !all & has_x)
}

/// Case index of the cell at bit `s` (corner `c = x + 2y + 4z` is bit `c`).
#[inline]
pub(super) fn case_at(lo: &[u64; 4], hi: &[u64; 4], s: u32) -> usize {
    let mut case = 0usize;
    for k in 0..4 {
        case |= ((lo[k] >> s & 1) as usize) << (2 * k);
        case |= ((hi[k] >> s & 1) as usize) << (2 * k + 1);
    }
    case
}
