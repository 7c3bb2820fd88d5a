//! CPU mirrors of the hull-scan kernels: `hull_scan` (every voxel against
//! every face, `kernels/hull_scan.wgsl`), `hull_rows` (per-row intervals by
//! exact floor/ceil division, `kernels/hull_rows.wgsl`) and
//! `hull_rows_i32x2` (per-row intervals by binary search on emulated 64-bit
//! products, `kernels/hull_rows_i32x2.wgsl`), plus [`i32x2`], the Rust twin
//! of `kernels/shared/i32x2.wgsl`. Arithmetic bounds: see the module docs of
//! [`crate::hull_scan`] (callers run [`super::check_range`] first).

use rayon::prelude::*;

use super::{Classification, EMPTY_SPAN, HalfSpace, RowSpan, RowSpans, Side, VoxelBox};
use crate::Result;

/// The side of the point `p` (Def. VI): outside as soon as one face is
/// visible, on if some face is coplanar, inside otherwise. i64 arithmetic,
/// exact within the checked range.
pub fn point_side(faces: &[HalfSpace], p: [i64; 3]) -> Side {
    let mut on = false;
    for f in faces {
        let s = f.normal[0] * p[0] + f.normal[1] * p[1] + f.normal[2] * p[2] - f.offset;
        if s > 0 {
            return Side::Outside;
        }
        on |= s == 0;
    }
    if on { Side::On } else { Side::Inside }
}

/// Brute-force scan: the side of every voxel centre of `bbox` (mirror of
/// `hull_scan.wgsl`; rayon over z layers).
pub fn hull_scan(faces: &[HalfSpace], bbox: &VoxelBox) -> Result<Classification> {
    let n = bbox.n_voxels()?;
    let [nx, ny, _] = bbox.dims;
    let mut sides = vec![0u8; n];
    if n > 0 {
        sides
            .par_chunks_mut(nx * ny)
            .enumerate()
            .for_each(|(z, layer)| {
                for (i, code) in layer.iter_mut().enumerate() {
                    let p = bbox.centre([i % nx, i / nx, z]);
                    *code = point_side(faces, p) as u8;
                }
            });
    }
    Ok(Classification { bbox: *bbox, sides })
}

/// Per-row intervals of the voxel rows of `bbox` (mirror of `hull_rows.wgsl`).
pub fn hull_rows(faces: &[HalfSpace], bbox: &VoxelBox) -> RowSpans {
    RowSpans {
        bbox: *bbox,
        spans: lattice_rows(faces, None, bbox.origin, bbox.dims, 1),
    }
}

/// [`hull_rows`] of a convex polytope whose face `f` spans the
/// combinatorial z range `z_extents[f]` (inclusive; same length as
/// `faces`): each layer uses only the faces whose range holds it, and
/// layers outside every range are empty. The spans are those of
/// [`hull_rows`]: for z in the polytope's range, P ∩ {z} is the
/// intersection of the half-spaces of the faces meeting the plane — a
/// point q of the plane outside P leaves P, on the segment from a point of
/// P ∩ {z}, at a boundary point b, and q violates a face through b, whose
/// range holds z.
pub fn hull_rows_culled(faces: &[HalfSpace], z_extents: &[[i64; 2]], bbox: &VoxelBox) -> RowSpans {
    RowSpans {
        bbox: *bbox,
        spans: lattice_rows(faces, Some(z_extents), bbox.origin, bbox.dims, 1),
    }
}

/// Per-row intervals on the lattice of points `2·(origin + local) + parity`
/// (parity 1: voxel centres, 0: cell corners), `dims[1]·dims[2]` rows; with
/// `z_extents` (one inclusive combinatorial z range per face of a convex
/// polytope) each layer keeps only the faces meeting it
/// ([`hull_rows_culled`]).
///
/// The faces are split once by the sign of `n_x`, and per z layer reduced
/// to `[a, b, d − c·z]`, so a row costs two products per face. Splitting
/// changes only the order in which faces are met; the spans are exact
/// minima/maxima, the same in any order (and the same as the kernel's).
pub(crate) fn lattice_rows(
    faces: &[HalfSpace],
    z_extents: Option<&[[i64; 2]]>,
    origin: [i64; 3],
    dims: [usize; 3],
    parity: i64,
) -> Vec<RowSpan> {
    let [nx, ny, nz] = dims;
    let mut spans = vec![EMPTY_SPAN; ny * nz];
    if nx == 0 || ny == 0 {
        return spans;
    }
    let extent = |f: usize| z_extents.and_then(|e| e.get(f)).copied();
    let by_sign = |sign: i64| -> Vec<(HalfSpace, Option<[i64; 2]>)> {
        (0..faces.len())
            .filter(|&f| faces[f].normal[0].signum() == sign)
            .map(|f| (faces[f], extent(f)))
            .collect()
    };
    let (pos, neg, zero) = (by_sign(1), by_sign(-1), by_sign(0));
    let range = z_extents.map(|e| {
        e.iter().fold([i64::MAX, i64::MIN], |r, x| {
            [r[0].min(x[0]), r[1].max(x[1])]
        })
    });
    spans.par_chunks_mut(ny).enumerate().for_each(|(k, layer)| {
        let z = 2 * (origin[2] + k as i64) + parity;
        if range.is_some_and(|r| z < r[0] || z > r[1]) {
            return;
        }
        let at_z = |fs: &[(HalfSpace, Option<[i64; 2]>)]| -> Vec<[i64; 3]> {
            fs.iter()
                .filter(|(_, e)| e.is_none_or(|e| e[0] <= z && z <= e[1]))
                .map(|(f, _)| [f.normal[0], f.normal[1], f.offset - f.normal[2] * z])
                .collect()
        };
        let layer_faces = LayerFaces {
            pos: at_z(&pos),
            neg: at_z(&neg),
            zero: at_z(&zero),
        };
        for (j, span) in layer.iter_mut().enumerate() {
            let y = 2 * (origin[1] + j as i64) + parity;
            *span = row_span(&layer_faces, origin[0], nx as i64, y, parity);
        }
    });
    spans
}

/// The faces of one z layer as `[a, b, t]` with `t = d − c·z`, by the sign
/// of `a`.
struct LayerFaces {
    pos: Vec<[i64; 3]>,
    neg: Vec<[i64; 3]>,
    zero: Vec<[i64; 3]>,
}

/// The span of one row at combinatorial `y` of a layer: points
/// `x = 2i + parity` for global indices `i` in `ox .. ox + nx` (`nx ≥ 1`).
///
/// Per face `a·x ≤ r` with `r = t − b·y = d − b·y − c·z`. For `a > 0` the
/// closed bound is `i ≤ ⌊(r − a·parity) / 2a⌋`, the open one one less when
/// the division is exact; for `a < 0` symmetrically
/// `i ≥ ⌈(−r − m·parity) / 2m⌉`, `m = −a`; for `a = 0` the face keeps all
/// (`r > 0`), only the closed interval (`r = 0`) or nothing (`r < 0`). A
/// face that cannot tighten the current interval (checked with one product
/// at its end) is skipped without dividing.
fn row_span(faces: &LayerFaces, ox: i64, nx: i64, y: i64, parity: i64) -> RowSpan {
    let (mut lo_c, mut hi_c) = (ox, ox + nx - 1);
    let (mut lo_o, mut hi_o) = (lo_c, hi_c);
    let mut open = true;
    for &[_, b, t] in &faces.zero {
        let r = t - b * y;
        if r < 0 {
            return EMPTY_SPAN;
        }
        open &= r > 0;
    }
    for &[a, b, t] in &faces.pos {
        let r = t - b * y;
        let v = a * (2 * hi_c + parity);
        if v < r {
            continue;
        }
        if v == r {
            hi_o = hi_o.min(hi_c - 1);
            continue;
        }
        let (num, den) = (r - a * parity, 2 * a);
        let q = num.div_euclid(den);
        if q < lo_c {
            return EMPTY_SPAN;
        }
        hi_c = q;
        hi_o = hi_o.min(if q * den == num { q - 1 } else { q });
    }
    for &[a, b, t] in &faces.neg {
        let r = t - b * y;
        let v = a * (2 * lo_c + parity);
        if v < r {
            continue;
        }
        if v == r {
            lo_o = lo_o.max(lo_c + 1);
            continue;
        }
        let m = -a;
        let (num, den) = (-r - m * parity, 2 * m);
        let q = -(-num).div_euclid(den);
        if q > hi_c {
            return EMPTY_SPAN;
        }
        lo_c = q;
        lo_o = lo_o.max(if q * den == num { q + 1 } else { q });
    }
    finish_span(ox, lo_c, hi_c, lo_o, hi_o, open)
}

/// Local, canonical span from global bounds (`open` false: no open part).
fn finish_span(ox: i64, lo_c: i64, hi_c: i64, lo_o: i64, hi_o: i64, open: bool) -> RowSpan {
    let closed = [(lo_c - ox) as i32, (hi_c - ox) as i32];
    if open && lo_o <= hi_o {
        [closed[0], closed[1], (lo_o - ox) as i32, (hi_o - ox) as i32]
    } else {
        [closed[0], closed[1], 0, -1]
    }
}

/// Exact signed 64-bit integers as `[low, high]` u32 words (two's
/// complement), built only from 32-bit operations: the Rust twin of
/// `kernels/shared/i32x2.wgsl`, function for function.
pub mod i32x2 {
    /// A 64-bit value as `[low word, high word]`.
    pub type W = [u32; 2];

    /// Sign-extends `a`.
    pub fn from_i32(a: i32) -> W {
        [a as u32, if a < 0 { u32::MAX } else { 0 }]
    }

    /// The words of `a` (host side: uploading offsets).
    pub fn from_i64(a: i64) -> W {
        [a as u32, (a >> 32) as u32]
    }

    /// The value of `w` (tests).
    pub fn to_i64(w: W) -> i64 {
        (i64::from(w[1] as i32) << 32) | i64::from(w[0])
    }

    /// `a + b` mod 2⁶⁴.
    pub fn add(a: W, b: W) -> W {
        let lo = a[0].wrapping_add(b[0]);
        let carry = u32::from(lo < a[0]);
        [lo, a[1].wrapping_add(b[1]).wrapping_add(carry)]
    }

    /// `−a` mod 2⁶⁴.
    pub fn neg(a: W) -> W {
        add([!a[0], !a[1]], [1, 0])
    }

    /// `a − b` mod 2⁶⁴.
    pub fn sub(a: W, b: W) -> W {
        add(a, neg(b))
    }

    /// `a · b` for unsigned words, exact in 64 bits (16-bit limbs).
    pub fn mul_u32(a: u32, b: u32) -> W {
        let (a0, a1) = (a & 0xffff, a >> 16);
        let (b0, b1) = (b & 0xffff, b >> 16);
        let p00 = a0 * b0;
        let p01 = a0 * b1;
        let p10 = a1 * b0;
        let p11 = a1 * b1;
        let mid = p01.wrapping_add(p10);
        let mid_carry = if mid < p01 { 0x1_0000 } else { 0 };
        let lo = p00.wrapping_add(mid << 16);
        let lo_carry = u32::from(lo < p00);
        [lo, p11 + (mid >> 16) + mid_carry + lo_carry]
    }

    /// `a · b`, exact (`|a·b| ≤ 2⁶²`).
    pub fn mul(a: i32, b: i32) -> W {
        let p = mul_u32(a.unsigned_abs(), b.unsigned_abs());
        if (a < 0) != (b < 0) { neg(p) } else { p }
    }

    /// `a < b`, signed.
    pub fn lt(a: W, b: W) -> bool {
        let (ah, bh) = (a[1] as i32, b[1] as i32);
        ah < bh || (ah == bh && a[0] < b[0])
    }

    /// `a = b`.
    pub fn eq_w(a: W, b: W) -> bool {
        a == b
    }

    /// `a ≤ b`, signed.
    pub fn le(a: W, b: W) -> bool {
        !lt(b, a)
    }
}

/// Per-row intervals by binary search on exact emulated products (mirror
/// of `hull_rows_i32x2.wgsl`, the GPU path without `SHADER_INT64`): the
/// same intervals as [`hull_rows`], found without 64-bit division.
pub fn hull_rows_i32x2(faces: &[HalfSpace], bbox: &VoxelBox) -> RowSpans {
    let [nx, ny, nz] = bbox.dims;
    let spans = (0..ny * nz)
        .into_par_iter()
        .map(|row| {
            let y = 2 * (bbox.origin[1] + (row % ny) as i64) + 1;
            let z = 2 * (bbox.origin[2] + (row / ny) as i64) + 1;
            row_span_i32x2(faces, bbox.origin[0] as i32, nx as i32, y as i32, z as i32)
        })
        .collect();
    RowSpans { bbox: *bbox, spans }
}

/// One row of [`hull_rows_i32x2`]; operands are `i32` after
/// [`super::check_range`] (normals, combinatorial coordinates).
fn row_span_i32x2(faces: &[HalfSpace], ox: i32, nx: i32, y: i32, z: i32) -> RowSpan {
    use i32x2::{W, eq_w, le, lt, mul, sub};
    if nx == 0 {
        return EMPTY_SPAN;
    }
    let (mut lo_c, mut hi_c) = (ox, ox + nx - 1);
    let (mut lo_o, mut hi_o) = (lo_c, hi_c);
    let mut open = true;
    for f in faces {
        let [a, b, c] = f.normal.map(|v| v as i32);
        let r: W = sub(sub(i32x2::from_i64(f.offset), mul(b, y)), mul(c, z));
        let p = |i: i32| mul(a, 2 * i + 1);
        if a == 0 {
            if lt(r, [0, 0]) {
                return EMPTY_SPAN;
            }
            open &= r != [0, 0];
        } else if a > 0 {
            let v = p(hi_c);
            if lt(v, r) {
                continue;
            }
            if eq_w(v, r) {
                hi_o = hi_o.min(hi_c - 1);
                continue;
            }
            if !le(p(lo_c), r) {
                return EMPTY_SPAN;
            }
            let (mut lo, mut hi) = (lo_c, hi_c - 1);
            while lo < hi {
                let mid = lo + (hi - lo + 1) / 2;
                if le(p(mid), r) {
                    lo = mid;
                } else {
                    hi = mid - 1;
                }
            }
            hi_c = lo;
            hi_o = hi_o.min(if eq_w(p(lo), r) { lo - 1 } else { lo });
        } else {
            let v = p(lo_c);
            if lt(v, r) {
                continue;
            }
            if eq_w(v, r) {
                lo_o = lo_o.max(lo_c + 1);
                continue;
            }
            if !le(p(hi_c), r) {
                return EMPTY_SPAN;
            }
            let (mut lo, mut hi) = (lo_c + 1, hi_c);
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if le(p(mid), r) {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            lo_c = lo;
            lo_o = lo_o.max(if eq_w(p(lo), r) { lo + 1 } else { lo });
        }
    }
    finish_span(
        i64::from(ox),
        i64::from(lo_c),
        i64::from(hi_c),
        i64::from(lo_o),
        i64::from(hi_o),
        open,
    )
}
