//! CPU mirror of `kernels/dms_basis.wgsl`: the same f32 operations in the
//! same order (no fused multiply-adds), one point at a time (points in
//! parallel; each point owns its row, so the result does not depend on the
//! split).

use rayon::prelude::*;

use super::BasisInput;
use crate::dms::program::{DEGREE0, Program, line_index, lines};
use crate::parity::Tolerance;

/// Parity tolerance on the weights `[N, ∂N/∂u, ∂N/∂v]`, relative to the
/// largest of the compared values of the row (scaled by the caller): a
/// B-spline is a sum of at most 27 products of barycentric coordinates
/// whose denominators are knot triangles of quality ≥ 0.03 (the knot
/// clouds' smallest on fran_cut), each carrying a few ulp amplified by
/// 1/q ≲ 30; ≈ 27 · 4 · 30 ulp ≈ 4e-4 relative in the worst case, ≤ 1e-5
/// measured. The bound on the surface, where the errors average out
/// against the control net, is tighter ([`crate::dms::surface`]).
pub const TOL: Tolerance = Tolerance {
    abs: 2e-4,
    rel: 2e-4,
};

type V2 = [f32; 2];

/// `d(p, q, u) = (q − p) × (u − p)`.
fn orient(p: V2, q: V2, u: V2) -> f32 {
    (q[0] - p[0]) * (u[1] - p[1]) - (q[1] - p[1]) * (u[0] - p[0])
}

/// The six `N_β` and their gradients of one triangle with local knots `k`
/// at the local point `ul` (docs of [`crate::dms::program`]).
pub fn triangle_basis(program: &Program, k: &[V2; 9], ul: V2) -> [[f32; 3]; 6] {
    // One orientation per knot line, canonical (lower knot first); zero
    // when the point is one of its knots.
    let mut side = [0.0f32; 36];
    for (l, [a, b]) in lines().into_iter().enumerate() {
        let (p, q) = (k[a as usize], k[b as usize]);
        side[l] = if ul == p || ul == q {
            0.0
        } else {
            orient(p, q, ul)
        };
    }
    let mut m0 = [0.0f32; 19];
    for (i, [a, b, c]) in DEGREE0.into_iter().enumerate() {
        let d = orient(k[a as usize], k[b as usize], k[c as usize]);
        if d == 0.0 {
            continue;
        }
        let ring = if d > 0.0 { [a, b, c] } else { [a, c, b] };
        let inside = (0..3).all(|e| {
            let (p, q) = (ring[e], ring[(e + 1) % 3]);
            let s = side[line_index(p, q) as usize];
            let o = if p < q { s } else { -s };
            if o != 0.0 {
                return o > 0.0;
            }
            // On the line: the lexicographic perturbation (e₁, then up).
            let ey = k[q as usize][1] - k[p as usize][1];
            let ex = k[q as usize][0] - k[p as usize][0];
            if ey != 0.0 { ey < 0.0 } else { ex > 0.0 }
        });
        if inside {
            m0[i] = 1.0 / d.abs();
        }
    }
    let mut m1 = [0.0f32; 12];
    for (i, (w, child)) in program.degree1.iter().enumerate() {
        let [w0, w1, w2] = w.map(|j| k[j as usize]);
        let d = orient(w0, w1, w2);
        let l = [orient(ul, w1, w2), orient(w0, ul, w2), orient(w0, w1, ul)];
        let mut s = 0.0f32;
        for j in 0..3 {
            s += l[j] / d * m0[child[j] as usize];
        }
        m1[i] = s;
    }
    let mut out = [[0.0f32; 3]; 6];
    for (b, (w, child)) in program.degree2.iter().enumerate() {
        let [w0, w1, w2] = w.map(|j| k[j as usize]);
        let l = [orient(ul, w1, w2), orient(w0, ul, w2), orient(w0, w1, ul)];
        // ∇d_j: constant in u.
        let g = [
            [w1[1] - w2[1], w2[0] - w1[0]],
            [w2[1] - w0[1], w0[0] - w2[0]],
            [w0[1] - w1[1], w1[0] - w0[0]],
        ];
        let mut n = [0.0f32; 3];
        for j in 0..3 {
            let m = m1[child[j] as usize];
            n[0] += l[j] * m;
            n[1] += 2.0 * g[j][0] * m;
            n[2] += 2.0 * g[j][1] * m;
        }
        out[b] = n;
    }
    out
}

/// The nine local knots of triangle `t` and its origin.
fn knots_of(input: &BasisInput, t: usize) -> ([V2; 9], V2) {
    let q = &input.tri_knots[5 * t..5 * t + 5];
    let flat: [f32; 20] = std::array::from_fn(|i| q[i / 4][i % 4]);
    (
        std::array::from_fn(|j| [flat[2 * j], flat[2 * j + 1]]),
        [flat[18], flat[19]],
    )
}

/// The rows of points `range`, written into `out` (their entries).
fn rows_into(
    program: &Program,
    input: &BasisInput,
    range: std::ops::Range<usize>,
    out: &mut [[f32; 4]],
) {
    let first = input.rows.offsets[range.start] as usize;
    for p in range {
        for e in input.rows.offsets[p]..input.rows.offsets[p + 1] {
            out[e as usize - first] = [0.0; 4];
        }
        let u = input.points[p];
        for c in input.candidates.offsets[p]..input.candidates.offsets[p + 1] {
            let t = input.candidates.targets[c as usize] as usize;
            let (k, o) = knots_of(input, t);
            let ul = [u[0] - o[0], u[1] - o[1]];
            let n = triangle_basis(program, &k, ul);
            for (b, nb) in n.iter().enumerate() {
                let e = input.slot_entry[6 * c as usize + b] as usize - first;
                out[e][0] += nb[0];
                out[e][1] += nb[1];
                out[e][2] += nb[2];
            }
        }
    }
}

/// The weights of every row entry (module docs of [`super`]).
pub fn dms_basis(input: &BasisInput) -> Vec<[f32; 4]> {
    let program = Program::new();
    let n_points = input.points.len();
    let mut out = vec![[0.0f32; 4]; input.rows.targets.len()];
    // Chunks of points, each writing its own contiguous run of entries.
    const CHUNK: usize = 1024;
    let mut parts: Vec<(std::ops::Range<usize>, &mut [[f32; 4]])> = Vec::new();
    let mut rest: &mut [[f32; 4]] = &mut out;
    for start in (0..n_points).step_by(CHUNK) {
        let end = (start + CHUNK).min(n_points);
        let len = (input.rows.offsets[end] - input.rows.offsets[start]) as usize;
        let (head, tail) = rest.split_at_mut(len);
        parts.push((start..end, head));
        rest = tail;
    }
    parts
        .into_par_iter()
        .for_each(|(range, slice)| rows_into(&program, input, range, slice));
    out
}
