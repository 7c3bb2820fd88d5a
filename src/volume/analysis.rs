//! Volume statistics (`chisel stats` on a volume) and 6-connected components
//! of voxel selections (a threshold `value ≥ T` or a label `value == L`).
//!
//! Labelling is linear-time and allocation-light: the selection is cut into
//! runs along x, runs overlapping in the row below (y − 1) or the slice below
//! (z − 1) are merged with union-find, and components are numbered in the
//! order of their first voxel in file order (x fastest, then y, then z).

use super::{ScalarType, Volume, VolumeData};
use crate::foundation::UnionFind;
use crate::{Error, Result};

/// Integer volumes with at most this many distinct values get a label
/// histogram in [`VolumeStats::labels`].
pub const MAX_LABELS: usize = 256;

/// [`ComponentCount::sizes`] lists at most this many component sizes.
pub const MAX_LISTED_SIZES: usize = 32;

/// Voxel count of one value of a label volume.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct LabelCount {
    pub value: i64,
    pub voxels: u64,
}

/// Geometry and value statistics of a volume.
#[derive(Debug, Clone, serde::Serialize)]
pub struct VolumeStats {
    /// Samples per axis `[nx, ny, nz]`.
    pub dims: [usize; 3],
    /// Sample spacing per axis (world units).
    pub spacing: [f64; 3],
    /// World position of sample (0,0,0).
    pub origin: [f64; 3],
    /// World direction of each index axis.
    pub axes: [[f64; 3]; 3],
    /// The anatomical frame of the world coordinates (`LPS`, `RAS`), when
    /// the file names one.
    pub space: Option<super::Space>,
    /// Element type, serialised by name (`u8`, `i16`, ...).
    pub scalar_type: ScalarType,
    /// `nx·ny·nz`.
    pub voxels: u64,
    /// Smallest finite value; `None` when there is none.
    pub min: Option<f64>,
    /// Largest finite value; `None` when there is none.
    pub max: Option<f64>,
    /// Mean of the finite values: exact integer sum (i128) for integer
    /// volumes, f64 accumulation for float volumes.
    pub mean: Option<f64>,
    /// Samples equal to zero.
    pub zeros: u64,
    /// NaN or infinite samples (float volumes only), left out of min/max/mean.
    pub non_finite: u64,
    /// For integer volumes with at most [`MAX_LABELS`] distinct values: the
    /// voxel count of each value, by value ascending; otherwise `None`.
    pub labels: Option<Vec<LabelCount>>,
}

/// The value part of [`VolumeStats`].
#[derive(Debug)]
struct Summary {
    min: Option<f64>,
    max: Option<f64>,
    mean: Option<f64>,
    zeros: u64,
    non_finite: u64,
    labels: Option<Vec<LabelCount>>,
}

fn integer_summary<T: Copy + Into<i64>>(data: &[T]) -> Summary {
    let (mut lo, mut hi, mut sum, mut zeros) = (i64::MAX, i64::MIN, 0i128, 0u64);
    for &x in data {
        let x: i64 = x.into();
        lo = lo.min(x);
        hi = hi.max(x);
        sum += i128::from(x);
        zeros += u64::from(x == 0);
    }
    if data.is_empty() {
        return Summary {
            min: None,
            max: None,
            mean: None,
            zeros,
            non_finite: 0,
            labels: None,
        };
    }
    Summary {
        min: Some(lo as f64),
        max: Some(hi as f64),
        mean: Some(sum as f64 / data.len() as f64),
        zeros,
        non_finite: 0,
        labels: label_histogram(data, lo, hi),
    }
}

/// Counts per distinct value, or `None` past [`MAX_LABELS`] values. A dense
/// histogram when the value span is at most 2¹⁶, else an ordered map that
/// stops as soon as it holds too many keys.
fn label_histogram<T: Copy + Into<i64>>(data: &[T], lo: i64, hi: i64) -> Option<Vec<LabelCount>> {
    let span = hi.abs_diff(lo);
    let counts: Vec<LabelCount> = if span < 1 << 16 {
        let mut bins = vec![0u64; span as usize + 1];
        for &x in data {
            bins[x.into().abs_diff(lo) as usize] += 1;
        }
        (lo..=hi)
            .zip(bins)
            .filter(|&(_, n)| n > 0)
            .map(|(value, voxels)| LabelCount { value, voxels })
            .collect()
    } else {
        let mut map = std::collections::BTreeMap::new();
        for &x in data {
            *map.entry(x.into()).or_insert(0u64) += 1;
            if map.len() > MAX_LABELS {
                return None;
            }
        }
        map.into_iter()
            .map(|(value, voxels)| LabelCount { value, voxels })
            .collect()
    };
    (counts.len() <= MAX_LABELS).then_some(counts)
}

fn float_summary<T: Copy + Into<f64>>(data: &[T]) -> Summary {
    let (mut lo, mut hi, mut sum) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    let (mut finite, mut zeros) = (0u64, 0u64);
    for &x in data {
        let x: f64 = x.into();
        zeros += u64::from(x == 0.0);
        if x.is_finite() {
            finite += 1;
            lo = lo.min(x);
            hi = hi.max(x);
            sum += x;
        }
    }
    let some = finite > 0;
    Summary {
        min: some.then_some(lo),
        max: some.then_some(hi),
        mean: some.then(|| sum / finite as f64),
        zeros,
        non_finite: data.len() as u64 - finite,
        labels: None,
    }
}

impl VolumeStats {
    /// Statistics of `v` in one or two linear passes (two for the label
    /// histogram of integer volumes).
    pub fn of(v: &Volume) -> VolumeStats {
        let s = match &v.data {
            VolumeData::U8(d) => integer_summary(d),
            VolumeData::I8(d) => integer_summary(d),
            VolumeData::U16(d) => integer_summary(d),
            VolumeData::I16(d) => integer_summary(d),
            VolumeData::U32(d) => integer_summary(d),
            VolumeData::I32(d) => integer_summary(d),
            VolumeData::F32(d) => float_summary(d),
            VolumeData::F64(d) => float_summary(d),
        };
        VolumeStats {
            dims: v.dims,
            spacing: v.spacing,
            origin: v.origin,
            axes: v.axes,
            space: v.space,
            scalar_type: v.data.scalar_type(),
            voxels: v.len() as u64,
            min: s.min,
            max: s.max,
            mean: s.mean,
            zeros: s.zeros,
            non_finite: s.non_finite,
            labels: s.labels,
        }
    }
}

/// A voxel selection and its 6-connected components.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ComponentCount {
    /// What was selected, e.g. `value >= 1150` or `value == 13`.
    pub selection: String,
    /// Selected voxels.
    pub voxels: u64,
    /// Number of 6-connected components.
    pub components: usize,
    /// Voxels in the largest component (0 when none).
    pub largest: u64,
    /// The first [`MAX_LISTED_SIZES`] component sizes, descending.
    pub sizes: Vec<u64>,
}

/// Components of the voxels with value `≥ t` (compared in f64, exact for
/// every element type; NaN samples are never selected).
///
/// `v` must hold `nx·ny·nz` samples (as [`Volume::new`] checks).
pub fn threshold_components(v: &Volume, t: f64) -> ComponentCount {
    count_components(v, format!("value >= {t}"), |x| x >= t)
}

/// Components of the voxels with value `== label` (compared in f64).
///
/// `v` must hold `nx·ny·nz` samples (as [`Volume::new`] checks).
pub fn label_components(v: &Volume, label: f64) -> ComponentCount {
    count_components(v, format!("value == {label}"), |x| x == label)
}

fn count_components(v: &Volume, selection: String, keep: impl Fn(f64) -> bool) -> ComponentCount {
    // No per-voxel mask: the selection is evaluated where the runs are found.
    let mut sizes = RunComponents::of(v.dims, |i| keep(v.data.get_f64(i))).sizes;
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    ComponentCount {
        selection,
        voxels: sizes.iter().sum(),
        components: sizes.len(),
        largest: sizes.first().copied().unwrap_or(0),
        sizes: sizes.into_iter().take(MAX_LISTED_SIZES).collect(),
    }
}

/// Components found through runs: `runs[r]` is `[x0, x1)` of run `r`, the
/// runs of row `y + ny·z` are `runs[row_start[row]..row_start[row + 1]]`,
/// `run_component[r]` is the 0-based component of run `r` and `sizes[c]`
/// the voxel count of component `c`.
#[derive(Debug)]
struct RunComponents {
    runs: Vec<(usize, usize)>,
    row_start: Vec<usize>,
    run_component: Vec<usize>,
    sizes: Vec<u64>,
}

impl RunComponents {
    /// O(N) for N voxels plus near-linear union-find over the runs.
    fn of(dims: [usize; 3], inside: impl Fn(usize) -> bool) -> Self {
        let [nx, ny, nz] = dims;
        let rows = ny * nz;
        let mut runs = Vec::new();
        let mut row_start = Vec::with_capacity(rows + 1);
        row_start.push(0);
        for row in 0..rows {
            let base = row * nx;
            let mut x = 0;
            while x < nx {
                if inside(base + x) {
                    let x0 = x;
                    while x < nx && inside(base + x) {
                        x += 1;
                    }
                    runs.push((x0, x));
                } else {
                    x += 1;
                }
            }
            row_start.push(runs.len());
        }
        let mut sets = UnionFind::<usize>::with_len(runs.len());
        let row_runs = |row: usize| row_start[row]..row_start[row + 1];
        for row in 0..rows {
            let (y, z) = (row % ny, row / ny);
            let below = [(y > 0).then(|| row - 1), (z > 0).then(|| row - ny)];
            for other in below.into_iter().flatten() {
                let (mut i, mut j) = (row_start[row], row_start[other]);
                let (i_end, j_end) = (row_runs(row).end, row_runs(other).end);
                while i < i_end && j < j_end {
                    let (a, b) = (runs[i], runs[j]);
                    if a.0 < b.1 && b.0 < a.1 {
                        sets.union(i, j);
                    }
                    if a.1 < b.1 { i += 1 } else { j += 1 }
                }
            }
        }
        // A set's representative is its first run, so components are numbered
        // in order of their first voxel.
        let mut run_component = vec![0; runs.len()];
        let mut sizes: Vec<u64> = Vec::new();
        for r in 0..runs.len() {
            let root = sets.find(r);
            let c = if root == r {
                sizes.push(0);
                sizes.len() - 1
            } else {
                run_component[root]
            };
            run_component[r] = c;
            sizes[c] += (runs[r].1 - runs[r].0) as u64;
        }
        RunComponents {
            runs,
            row_start,
            run_component,
            sizes,
        }
    }
}

/// A 6-connected labelling of a voxel selection.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Labelling {
    /// `nx·ny·nz` labels in file order: 0 = not selected, `c ≥ 1` = component
    /// `c`. Components are numbered 1, 2, … in order of their first voxel in
    /// file order (x fastest, then y, then z).
    pub labels: Vec<u32>,
    /// `sizes[c − 1]`: voxels of component `c`.
    pub sizes: Vec<u64>,
}

impl Labelling {
    /// Number of components.
    pub fn n_components(&self) -> usize {
        self.sizes.len()
    }
}

/// Labels the 6-connected components of the voxels `i` (linear index
/// `x + nx·(y + ny·z)`) where `inside(i)` holds, for a grid of `dims`.
/// Linear time; `inside` is called at most twice per voxel.
///
/// Errors: [`Error::InvalidParameter`] when `nx·ny·nz` overflows,
/// [`Error::Limit`] at `u32::MAX` components or more.
pub fn label_6_connected(dims: [usize; 3], inside: impl Fn(usize) -> bool) -> Result<Labelling> {
    let n = dims
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .ok_or_else(|| {
            Error::param(
                "dims",
                format!("{dims:?}"),
                "the sample count overflows usize",
            )
        })?;
    let found = RunComponents::of(dims, inside);
    if found.sizes.len() >= u32::MAX as usize {
        return Err(Error::limit(
            "6-connected components (32-bit labels)",
            found.sizes.len(),
            u32::MAX - 1,
        ));
    }
    let mut labels =
        crate::foundation::alloc::filled("6-connected labels (one u32 per voxel)", n, 0u32)?;
    let nx = dims[0];
    for row in 0..found.row_start.len() - 1 {
        for r in found.row_start[row]..found.row_start[row + 1] {
            let (x0, x1) = found.runs[r];
            let label = found.run_component[r] as u32 + 1;
            labels[row * nx + x0..row * nx + x1].fill(label);
        }
    }
    Ok(Labelling {
        labels,
        sizes: found.sizes,
    })
}
