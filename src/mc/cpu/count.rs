//! The *count* pass: the volume's inside flags as bit rows ([`Bits`], 64
//! points per `u64`), and per z layer the number of vertices
//! ([`count_vertices`]) and triangles ([`count_triangles`]) it will emit.

use rayon::prelude::*;

use super::super::field::Field;
use super::super::tables;
use crate::Result;
use crate::foundation::alloc::filled;

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
    /// Reads every layer (in parallel) through [`Field::inside_row`].
    pub(super) fn load(field: &Field<'_>) -> Result<Self> {
        let rows = Rows::new(field);
        let nz = field.dims[2];
        let plane = rows.ny * rows.words;
        let mut data = filled("marching cubes: inside bits", nz * plane, 0u64)?;
        data.par_chunks_mut(plane)
            .enumerate()
            .for_each(|(z, layer)| {
                for (y, row) in layer.chunks_exact_mut(rows.words).enumerate() {
                    field.inside_row(y, z, row);
                }
            });
        Ok(Bits { rows, nz, data })
    }

    /// Row `y` of layer `z`.
    #[inline]
    fn row(&self, y: usize, z: usize) -> &[u64] {
        let w = self.rows.words;
        let start = (z * self.rows.ny + y) * w;
        &self.data[start..start + w]
    }

    /// Crossing masks `[x, y, z]` of word `w` of row `y` of layer `z`: the
    /// points whose +x, +y, +z edge joins an inside and an outside sample.
    #[inline]
    pub(super) fn crossings(&self, y: usize, z: usize, w: usize) -> [u64; 3] {
        let m = self.row(y, z);
        let ex = (m[w] ^ next_bits(m, w)) & self.rows.has_x[w];
        let ey = if y + 1 < self.rows.ny {
            m[w] ^ self.row(y + 1, z)[w]
        } else {
            0
        };
        let ez = if z + 1 < self.nz {
            m[w] ^ self.row(y, z + 1)[w]
        } else {
            0
        };
        [ex, ey, ez]
    }

    /// The four corner rows of cell row `y` of cell layer `z`:
    /// (y, z), (y + 1, z), (y, z + 1), (y + 1, z + 1).
    #[inline]
    pub(super) fn cell_rows(&self, y: usize, z: usize) -> [&[u64]; 4] {
        [
            self.row(y, z),
            self.row(y + 1, z),
            self.row(y, z + 1),
            self.row(y + 1, z + 1),
        ]
    }
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

/// Vertices numbered on point layer `z`.
pub(super) fn count_vertices(bits: &Bits, z: usize) -> u64 {
    let mut n = 0u64;
    for y in 0..bits.rows.ny {
        for w in 0..bits.rows.words {
            let [ex, ey, ez] = bits.crossings(y, z, w);
            n += u64::from(ex.count_ones() + ey.count_ones() + ez.count_ones());
        }
    }
    n
}

/// Triangles emitted on cell layer `z`.
pub(super) fn count_triangles(bits: &Bits, z: usize, table: &tables::CaseTable) -> u64 {
    let mut n = 0u64;
    for y in 0..bits.rows.ny - 1 {
        let r = bits.cell_rows(y, z);
        for w in 0..bits.rows.words {
            let (lo, hi, mut crossed) = cell_word(&r, w, bits.rows.has_x[w]);
            while crossed != 0 {
                let s = crossed.trailing_zeros();
                crossed &= crossed - 1;
                n += table.case(case_at(&lo, &hi, s)).len() as u64;
            }
        }
    }
    n
}
