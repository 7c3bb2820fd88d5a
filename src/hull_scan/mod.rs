//! Scans inside a convex hull (SPEC §4.3, seed 003 §4.2): classify every
//! voxel of a bounding box as inside / on / outside a convex polyhedron,
//! exactly, then split the background voxels inside into 6-connected
//! components (ZKH) and classify them (Def. CO/CA/TU) in [`zkh`].
//!
//! **Input.** The polyhedron is a list of [`HalfSpace`]s `n·p ≤ d` in
//! combinatorial coordinates (Kovalevsky: voxel `(i, j, k)` has its centre at
//! `(2i+1, 2j+1, 2k+1)`, cell corners have even coordinates). The voxels
//! scanned are those of a [`VoxelBox`]. Nothing requires the half-spaces to
//! be irredundant or the polyhedron to be bounded or non-empty.
//!
//! **Visibility (Def. VI).** For a face `n·p ≤ d` and a point `p`,
//! `s = n·p − d`: `s > 0` the face is visible (p outside), `s = 0` coplanar,
//! `s < 0` invisible. A voxel is [`Side::Outside`] if some face is visible
//! from its centre, [`Side::Inside`] if every face is invisible, and
//! [`Side::On`] otherwise (no face visible, at least one coplanar).
//!
//! **Two methods, one answer.** The brute-force scan tests every voxel
//! against every face ([`classify_voxels`]; independent i128 oracle in
//! [`brute`]). The per-row method ([`classify`], [`row_spans`]) intersects
//! each voxel row (fixed y, z) with each half-space once: the closed
//! polyhedron meets the row in one interval of voxels (inside or on), the
//! open one in a sub-interval (inside), so a row is two integer intervals
//! found by exact floor/ceil division (or, on GPUs without `SHADER_INT64`,
//! by binary search on exact emulated 64-bit products). Both methods agree
//! bit for bit; `tests/hull_scan.rs` and `tests/parity/hull_scan.rs` prove it.
//!
//! **Exactness and range.** All arithmetic is integer; no floats, no
//! epsilons. [`check_range`] refuses inputs outside
//! * `|n_c| ≤ 2³¹ − 1` (normal components fit `i32`),
//! * `|d| ≤ 2⁶⁰`,
//! * every cell of the box within `[−2¹⁶, 2¹⁶]` in combinatorial coordinates
//!   (voxel indices `−32768 ≤ i < 32768`),
//!
//! for which no intermediate overflows 64 bits: `|n_c · x_c| < 2³¹·2¹⁶ = 2⁴⁷`,
//! `|n·p| < 3·2⁴⁷ < 2⁴⁹`, the row remainder `r = d − n_y·y − n_z·z` has
//! `|r| < 2⁶⁰ + 2⁴⁹ < 2⁶¹`, and the division operands `r − n_x` and `2·n_x`
//! stay below `2⁶²` and `2³²`. Normals of hull faces built as cross
//! products of edge vectors between points with coordinates in `[0, 2¹⁵)`
//! satisfy the bound (each product below `2³⁰`, the difference below
//! `2³¹`): every hull of cells of a box of at most 16383 voxels per axis.
//! The GPU fallback multiplies `i32 × i32` into exact 64-bit pairs, which is
//! why normals must fit `i32` on every backend.

pub mod brute;
pub mod cpu;
pub mod gpu;
pub mod zkh;

use rayon::prelude::*;

use crate::gpu::Backend;
use crate::{Error, Result};

/// Largest allowed `|n_c|` of a normal component (fits `i32`).
pub const MAX_NORMAL: i64 = i32::MAX as i64;
/// Largest allowed `|d|` of an offset.
pub const MAX_OFFSET: i64 = 1 << 60;
/// Largest allowed `|c|` of a combinatorial coordinate of any cell of the box.
pub const MAX_COORD: i64 = 1 << 16;

/// The half-space `normal · p ≤ offset` (inside), `= offset` on the face
/// plane; `p` in combinatorial coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct HalfSpace {
    /// Outward normal (not necessarily primitive or unit).
    pub normal: [i64; 3],
    /// Right-hand side `d`.
    pub offset: i64,
}

impl HalfSpace {
    /// `s = n·p − d` (Def. VI) for a point `p` in combinatorial coordinates,
    /// in i128 so it never overflows.
    pub fn side(&self, p: [i64; 3]) -> i128 {
        (0..3)
            .map(|c| i128::from(self.normal[c]) * i128::from(p[c]))
            .sum::<i128>()
            - i128::from(self.offset)
    }
}

/// A box of voxels: indices `origin[a] .. origin[a] + dims[a]` per axis.
/// Voxel `(i, j, k)` has combinatorial centre `(2i+1, 2j+1, 2k+1)`; per-voxel
/// arrays over the box are in order x fastest, then y, then z (local index
/// `x + nx·(y + ny·z)`, as [`crate::volume::analysis::label_6_connected`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct VoxelBox {
    /// Voxel index of the first voxel per axis.
    pub origin: [i64; 3],
    /// Voxels per axis.
    pub dims: [usize; 3],
}

impl VoxelBox {
    /// Number of voxels (errors when it overflows `usize`).
    pub fn n_voxels(&self) -> Result<usize> {
        self.dims
            .iter()
            .try_fold(1usize, |acc, &d| acc.checked_mul(d))
            .ok_or_else(|| {
                Error::param(
                    "voxel box dims",
                    format!("{:?}", self.dims),
                    "the voxel count overflows usize",
                )
            })
    }

    /// Number of rows (fixed y, z): `ny·nz`.
    pub fn n_rows(&self) -> usize {
        self.dims[1].saturating_mul(self.dims[2])
    }

    /// Combinatorial centre of the voxel with local index `(x, y, z)`.
    pub fn centre(&self, local: [usize; 3]) -> [i64; 3] {
        std::array::from_fn(|a| 2 * (self.origin[a] + local[a] as i64) + 1)
    }
}

/// Where a voxel centre lies relative to the polyhedron (Def. VI).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum Side {
    /// Some face is visible (`s > 0`).
    Outside = 0,
    /// No face visible, at least one coplanar (`max s = 0`).
    On = 1,
    /// Every face invisible (`s < 0` for all).
    Inside = 2,
}

impl Side {
    /// The side of a stored code (0, 1, 2); `None` for anything else.
    pub fn from_code(code: u8) -> Option<Side> {
        match code {
            0 => Some(Side::Outside),
            1 => Some(Side::On),
            2 => Some(Side::Inside),
            _ => None,
        }
    }
}

/// One code per voxel of `bbox`: the [`Side`] as `u8` (0 outside, 1 on,
/// 2 inside), in the box's order (x fastest).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Classification {
    /// The box scanned.
    pub bbox: VoxelBox,
    /// `bbox.n_voxels()` side codes.
    pub sides: Vec<u8>,
}

impl Classification {
    /// Voxels per side: `[outside, on, inside]`.
    pub fn counts(&self) -> [u64; 3] {
        let mut c = [0u64; 3];
        for &s in &self.sides {
            if let Some(slot) = c.get_mut(usize::from(s)) {
                *slot += 1;
            }
        }
        c
    }

    /// Whether voxel `i` (local linear index) is inside or on.
    pub fn in_closed_hull(&self, i: usize) -> bool {
        self.sides.get(i).is_some_and(|&s| s != Side::Outside as u8)
    }
}

/// The intersection of one voxel row with the polyhedron, as local x
/// indices (inclusive): `[closed_lo, closed_hi]` inside or on,
/// `[open_lo, open_hi]` inside. An empty interval is `(0, −1)`; the open one
/// lies within the closed one. Stored as `[closed_lo, closed_hi, open_lo,
/// open_hi]` (the GPU's `vec4<i32>`).
pub type RowSpan = [i32; 4];

/// The empty [`RowSpan`].
pub const EMPTY_SPAN: RowSpan = [0, -1, 0, -1];

/// The per-row intervals of a box: `bbox.n_rows()` spans, row `y + ny·z`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RowSpans {
    /// The box scanned.
    pub bbox: VoxelBox,
    /// One span per row.
    pub spans: Vec<RowSpan>,
}

impl RowSpans {
    /// Expands the spans into one side code per voxel (rayon over z layers).
    pub fn to_classification(&self) -> Result<Classification> {
        let n = self.bbox.n_voxels()?;
        let [nx, ny, _] = self.bbox.dims;
        let mut sides = vec![Side::Outside as u8; n];
        if n > 0 {
            sides
                .par_chunks_mut(nx * ny)
                .zip(self.spans.par_chunks(ny))
                .for_each(|(layer, spans)| {
                    for (row, s) in layer.chunks_mut(nx).zip(spans) {
                        fill(row, s[0], s[1], Side::On);
                        fill(row, s[2], s[3], Side::Inside);
                    }
                });
        }
        Ok(Classification {
            bbox: self.bbox,
            sides,
        })
    }
}

/// Sets `row[lo..=hi]` to `side` (nothing when the interval is empty).
fn fill(row: &mut [u8], lo: i32, hi: i32, side: Side) {
    if lo <= hi
        && let (Ok(lo), Ok(hi)) = (usize::try_from(lo), usize::try_from(hi))
        && let Some(part) = row.get_mut(lo..=hi)
    {
        part.fill(side as u8);
    }
}

/// Refuses inputs for which the exact 64-bit arithmetic could overflow
/// (bounds in the module docs) with [`Error::Limit`] naming the offending
/// face or axis.
pub fn check_range(half_spaces: &[HalfSpace], bbox: &VoxelBox) -> Result<()> {
    bbox.n_voxels()?;
    for (f, h) in half_spaces.iter().enumerate() {
        if let Some(c) = h.normal.iter().find(|c| c.abs() > MAX_NORMAL) {
            return Err(Error::limit(
                format!("hull scan: |normal component| of face {f}"),
                c.unsigned_abs(),
                MAX_NORMAL as u64,
            ));
        }
        if h.offset.abs() > MAX_OFFSET {
            return Err(Error::limit(
                format!("hull scan: |offset| of face {f}"),
                h.offset.unsigned_abs(),
                MAX_OFFSET as u64,
            ));
        }
    }
    for a in 0..3 {
        let lo = bbox.origin[a].checked_mul(2);
        let hi = i64::try_from(bbox.dims[a])
            .ok()
            .and_then(|d| bbox.origin[a].checked_add(d))
            .and_then(|e| e.checked_mul(2));
        let ok = matches!((lo, hi), (Some(lo), Some(hi)) if lo >= -MAX_COORD && hi <= MAX_COORD);
        if !ok {
            return Err(Error::param(
                format!("hull scan: box axis {a}"),
                format!("origin {}, {} voxels", bbox.origin[a], bbox.dims[a]),
                "leaves the combinatorial range ±2^16 (voxel indices −32768..32768)",
            ));
        }
    }
    Ok(())
}

/// Per-row intervals of the polyhedron in `bbox` (the fast path). CPU:
/// [`cpu::hull_rows`]; GPU: `hull_rows` with `SHADER_INT64`, else
/// `hull_rows_i32x2`, in z slabs.
pub fn row_spans(
    half_spaces: &[HalfSpace],
    bbox: &VoxelBox,
    backend: Backend<'_>,
) -> Result<RowSpans> {
    check_range(half_spaces, bbox)?;
    match backend {
        Backend::Cpu => Ok(cpu::hull_rows(half_spaces, bbox)),
        Backend::Gpu(g) => gpu::hull_rows(g, half_spaces, bbox),
    }
}

/// [`row_spans`] of a convex polytope whose face `f` (half-space `f`)
/// spans the combinatorial z range `z_extents[f]` (inclusive; e.g.
/// [`crate::hull::ConvexHull::face_z_extents`]): each layer tests only the
/// faces meeting it, the same spans. CPU: [`cpu::hull_rows_culled`]; GPU:
/// [`gpu::hull_rows_culled`], per layer a list of those faces.
///
/// Errors: as [`row_spans`]; `z_extents` not one range per half-space.
pub fn row_spans_culled(
    half_spaces: &[HalfSpace],
    z_extents: &[[i64; 2]],
    bbox: &VoxelBox,
    backend: Backend<'_>,
) -> Result<RowSpans> {
    if z_extents.len() != half_spaces.len() {
        return Err(Error::mismatch(
            "hull scan: z ranges (one per face)",
            half_spaces.len(),
            z_extents.len(),
        ));
    }
    check_range(half_spaces, bbox)?;
    match backend {
        Backend::Cpu => Ok(cpu::hull_rows_culled(half_spaces, z_extents, bbox)),
        Backend::Gpu(g) => gpu::hull_rows_culled(g, half_spaces, z_extents, bbox),
    }
}

/// Every voxel of `bbox` inside / on / outside, by the per-row method
/// ([`row_spans`] expanded on the host).
pub fn classify(
    half_spaces: &[HalfSpace],
    bbox: &VoxelBox,
    backend: Backend<'_>,
) -> Result<Classification> {
    row_spans(half_spaces, bbox, backend)?.to_classification()
}

/// Every voxel of `bbox` inside / on / outside, by testing every voxel
/// against every face. CPU: [`cpu::hull_scan`]; GPU: `hull_scan` with
/// `SHADER_INT64`, else `hull_scan_i32x2`, in z slabs.
pub fn classify_voxels(
    half_spaces: &[HalfSpace],
    bbox: &VoxelBox,
    backend: Backend<'_>,
) -> Result<Classification> {
    check_range(half_spaces, bbox)?;
    match backend {
        Backend::Cpu => cpu::hull_scan(half_spaces, bbox),
        Backend::Gpu(g) => gpu::hull_scan(g, half_spaces, bbox),
    }
}
