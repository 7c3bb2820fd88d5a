//! The evaluation program of one parameter triangle (docs/design/dms.md
//! §3): the six normalised B-splines of degree 2 through the recursion of
//! eq. 2.6 with the DMS choice of triples (seed §2.3.4, l.439–451), written
//! out once as tables that the f32 mirror and the WGSL kernel `dms_basis`
//! both run (`tests/dms_basis.rs` checks that the kernel's `const` tables
//! are these).
//!
//! Knots are numbered `3·corner + cloud`: `r0 r1 r2 s0 s1 s2 t0 t1 t2` =
//! `0 … 8`. A degree-1 set of four knots is evaluated from its triple `W`
//! as `M(u | V) = Σ_k λ_k(u | W) · M(u | V ∖ w_k)`; a B-spline from its
//! normalisation triangle `W_β = (r_i, s_j, t_k)` as `N_β(u) = Σ_k d_k(u |
//! W_β) · M(u | V_β ∖ w_k)` and `∇N_β = 2 Σ_k ∇d_k(W_β) · M(u | V_β ∖
//! w_k)` (Micchelli's derivative formula, degree 2), where `d_k(u | W)` is
//! `d(W)` with `w_k` replaced by `u`. Sharing the lower-degree splines
//! between the B-splines is the "evaluation network" of the seed (l.437):
//! 19 degree-0 and 12 degree-1 splines per triangle instead of 6 separate
//! recursions.

use super::knots::{BETAS, knot_set};

/// The 19 degree-0 triples (knot indices, ascending).
pub const DEGREE0: [[u32; 3]; 19] = [
    [0, 3, 6],
    [0, 1, 3],
    [0, 1, 6],
    [0, 1, 4],
    [0, 1, 2],
    [1, 2, 3],
    [1, 2, 6],
    [1, 6, 7],
    [0, 3, 4],
    [3, 4, 6],
    [3, 4, 7],
    [3, 4, 5],
    [0, 4, 5],
    [4, 5, 6],
    [0, 6, 7],
    [3, 6, 7],
    [6, 7, 8],
    [3, 7, 8],
    [0, 7, 8],
];

/// The 12 degree-1 knot sets (ascending) and their triples `W` (the DMS
/// choice: the last knot of each present cloud, completed by rule 2 or 3 of
/// l.448–451).
pub const DEGREE1: [([u32; 4], [u32; 3]); 12] = [
    ([0, 1, 3, 6], [1, 3, 6]), // M_100
    ([0, 3, 4, 6], [0, 4, 6]), // M_010
    ([0, 3, 6, 7], [0, 3, 7]), // M_001
    ([0, 1, 3, 4], [1, 4, 3]), // M_{1,1,-1}
    ([3, 4, 6, 7], [6, 4, 7]), // M_{-1,1,1}
    ([0, 1, 6, 7], [1, 0, 7]), // M_{1,-1,1}
    ([0, 1, 2, 6], [2, 0, 6]), // M_{2,-1,0}
    ([0, 1, 2, 3], [2, 3, 0]), // M_{2,0,-1}
    ([0, 3, 4, 5], [0, 5, 3]), // M_{0,2,-1}
    ([3, 4, 5, 6], [3, 5, 6]), // M_{-1,2,0}
    ([3, 6, 7, 8], [6, 3, 8]), // M_{-1,0,2}
    ([0, 6, 7, 8], [0, 6, 8]), // M_{0,-1,2}
];

/// The program with every child resolved to a table index.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Program {
    /// Per degree-1 set: `W` and the degree-0 child dropping `w_k`.
    pub degree1: [([u32; 3], [u32; 3]); 12],
    /// Per B-spline (in [`BETAS`] order): `W_β` and the degree-1 child
    /// dropping `w_k`.
    pub degree2: [([u32; 3], [u32; 3]); 6],
}

/// The index of the set `v` (ascending) in `table`.
fn find<const N: usize>(table: impl Iterator<Item = [u32; N]>, v: &[u32]) -> u32 {
    let mut pos = None;
    for (i, s) in table.enumerate() {
        if s[..] == *v {
            pos = Some(i as u32);
        }
    }
    pos.unwrap_or_else(|| panic!("dms program: the set {v:?} is missing from its table"))
}

/// `v` without `w`, ascending.
fn without(v: &[u32], w: u32) -> Vec<u32> {
    v.iter().copied().filter(|&k| k != w).collect()
}

impl Program {
    /// Resolves the children of the tables above (a missing child is a
    /// bug in the constant tables, caught by every test that evaluates).
    pub fn new() -> Program {
        let degree1 =
            DEGREE1.map(|(v, w)| (w, w.map(|wk| find(DEGREE0.into_iter(), &without(&v, wk)))));
        let degree2 = BETAS.map(|beta| {
            let v: Vec<u32> = knot_set(beta).into_iter().map(|k| k as u32).collect();
            let w = [beta[0] as u32, 3 + beta[1] as u32, 6 + beta[2] as u32];
            (
                w,
                w.map(|wk| find(DEGREE1.iter().map(|(s, _)| *s), &without(&v, wk))),
            )
        });
        Program { degree1, degree2 }
    }
}

impl Default for Program {
    fn default() -> Self {
        Program::new()
    }
}

/// The 36 knot lines `(a, b)`, `a < b`, in the order `line_index` numbers
/// them.
pub fn line_index(a: u32, b: u32) -> u32 {
    let (a, b) = (a.min(b), a.max(b));
    // Row a holds the lines (a, a+1 … 8).
    a * (17 - a) / 2 + (b - a - 1)
}

/// The knots of a triangle's lines, indexed by [`line_index`].
pub fn lines() -> [[u32; 2]; 36] {
    let mut out = [[0u32; 2]; 36];
    for a in 0..9u32 {
        for b in a + 1..9 {
            out[line_index(a, b) as usize] = [a, b];
        }
    }
    out
}
