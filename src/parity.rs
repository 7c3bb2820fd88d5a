//! The parity harness (SPEC §0.4).
//!
//! Every data-parallel operation runs on [`Backend::Cpu`](crate::Backend)
//! (the readable mirror) or [`Backend::Gpu`](crate::Backend) (the WGSL
//! kernel). The comparators here are
//! what `tests/parity/` uses: floats within a declared [`Tolerance`],
//! integers exactly, and every mismatch reports the first bad index with both
//! values.

use std::fmt;

/// A float tolerance: `|a − b| ≤ abs + rel · max(|a|, |b|)`.
///
/// Each kernel declares one next to its CPU mirror, with the reason for the
/// bound (e.g. "2 ulp per sum term").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    pub abs: f32,
    pub rel: f32,
}

impl Tolerance {
    /// Bit-for-bit equality (for exact float operations such as min/max).
    pub const EXACT: Tolerance = Tolerance { abs: 0.0, rel: 0.0 };

    /// Whether `a` and `b` agree. NaN never agrees with anything (a surviving
    /// NaN sentinel is always a failure); equal infinities agree.
    pub fn accepts(&self, a: f32, b: f32) -> bool {
        if a.is_nan() || b.is_nan() {
            return false;
        }
        if a == b {
            return true;
        }
        let diff = (a - b).abs();
        diff <= self.abs + self.rel * a.abs().max(b.abs())
    }
}

/// The first disagreement between reference and candidate, and how many.
#[derive(Debug, Clone, PartialEq)]
pub struct Mismatch {
    /// What was compared (kernel and fixture).
    pub what: String,
    /// First differing element index.
    pub index: usize,
    /// Reference (CPU) value, formatted.
    pub expected: String,
    /// Candidate (GPU) value, formatted.
    pub found: String,
    /// Number of differing elements.
    pub count: usize,
    /// Total number of elements.
    pub total: usize,
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} of {} elements differ; first at index {}: cpu {} vs gpu {}",
            self.what, self.count, self.total, self.index, self.expected, self.found
        )
    }
}

impl std::error::Error for Mismatch {}

fn length_mismatch(what: &str, a: usize, b: usize) -> Mismatch {
    Mismatch {
        what: what.into(),
        index: a.min(b),
        expected: format!("length {a}"),
        found: format!("length {b}"),
        count: a.abs_diff(b),
        total: a.max(b),
    }
}

/// The one comparison loop: `bad(cpu[i], gpu[i])` marks a mismatch; the
/// first is reported with `show` of both values, and all are counted.
pub fn compare_by<T>(
    what: &str,
    cpu: &[T],
    gpu: &[T],
    bad: impl Fn(&T, &T) -> bool,
    show: impl Fn(&T) -> String,
) -> Result<(), Mismatch> {
    if cpu.len() != gpu.len() {
        return Err(length_mismatch(what, cpu.len(), gpu.len()));
    }
    let mut first = None;
    let mut count = 0;
    for (i, (a, b)) in cpu.iter().zip(gpu).enumerate() {
        if bad(a, b) {
            count += 1;
            first.get_or_insert(i);
        }
    }
    match first {
        None => Ok(()),
        Some(i) => Err(Mismatch {
            what: what.into(),
            index: i,
            expected: show(&cpu[i]),
            found: show(&gpu[i]),
            count,
            total: cpu.len(),
        }),
    }
}

/// Compares float arrays element-wise under `tol`.
pub fn compare_f32(what: &str, cpu: &[f32], gpu: &[f32], tol: Tolerance) -> Result<(), Mismatch> {
    compare_by(
        what,
        cpu,
        gpu,
        |&a, &b| !tol.accepts(a, b),
        |x| format!("{x:e}"),
    )
}

/// Compares arrays of anything that flattens to floats (e.g. `[f32; 4]`),
/// reporting the element (not component) index.
pub fn compare_vec<const N: usize>(
    what: &str,
    cpu: &[[f32; N]],
    gpu: &[[f32; N]],
    tol: Tolerance,
) -> Result<(), Mismatch> {
    compare_by(
        what,
        cpu,
        gpu,
        |a, b| a.iter().zip(b).any(|(&x, &y)| !tol.accepts(x, y)),
        |x| format!("{x:?}"),
    )
}

/// Compares integer (or any exactly comparable) arrays for equality.
pub fn compare_exact<T: PartialEq + fmt::Debug>(
    what: &str,
    cpu: &[T],
    gpu: &[T],
) -> Result<(), Mismatch> {
    compare_by(what, cpu, gpu, |a, b| a != b, |x| format!("{x:?}"))
}

/// Index of the first element still equal to the sentinel (compared by bits
/// for floats, so NaN sentinels are found).
pub fn find_sentinel<T: bytemuck::Pod>(out: &[T], sentinel: T) -> Option<usize> {
    let s = bytemuck::bytes_of(&sentinel);
    out.iter().position(|x| bytemuck::bytes_of(x) == s)
}
