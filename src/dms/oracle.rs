//! The f64 oracle of the DMS basis (SPEC §2.3, seed eq. 2.2–2.10): the
//! plain recursion every faster path is tested against.
//!
//! - Degree 0: `M(u | a, b, c) = χ_[a,b,c)(u) / |d(a, b, c)|` on the
//!   half-open triangle (eq. 2.2–2.3), read as the lexicographic limit
//!   `u + δ·e₁ + δ²·η ∈ int[a, b, c]` for small `δ > 0` (docs/design/dms.md
//!   §3), with exact orientation signs (`robust::orient2d`), so a knot line
//!   gives one answer whichever way round it is tested.
//! - Degree > 0: `M(u | V) = Σ_j λ_j(u | W) · M(u | V ∖ w_j)` (eq. 2.6) for
//!   the first affinely independent triple `W` of `V` (any triple gives the
//!   same value, seed l.187).
//! - The six normalised B-splines of a triangle: `N_β(u) = d(r_i, s_j, t_k)
//!   · M(u | V_β)`, `V_β = {r_0..r_i, s_0..s_j, t_0..t_k}` (eq. 2.7, 2.10),
//!   in the order of [`BETAS`].

use glam::DVec2;

use super::knots::{BETAS, knot_set};

/// `d(a, b, c)`: twice the signed area, exact in sign.
pub fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    let p = |v: DVec2| robust::Coord { x: v.x, y: v.y };
    robust::orient2d(p(a), p(b), p(c))
}

/// Whether `u` lies in the half-open triangle `[a, b, c)` (module docs).
pub fn half_open(u: DVec2, tri: [DVec2; 3]) -> bool {
    let [a, mut b, mut c] = tri;
    let d = orient(a, b, c);
    if d == 0.0 {
        return false;
    }
    if d < 0.0 {
        std::mem::swap(&mut b, &mut c);
    }
    [(a, b), (b, c), (c, a)].into_iter().all(|(p, q)| {
        let o = orient(p, q, u);
        if o != 0.0 {
            return o > 0.0;
        }
        // On the edge line: the perturbation's sign, e₁ first, then η = (0, 1).
        let e = q - p;
        if e.y != 0.0 { -e.y > 0.0 } else { e.x > 0.0 }
    })
}

/// The simplex spline `M(u | knots)` of degree `knots.len() − 3`.
pub fn simplex_spline(u: DVec2, knots: &[DVec2]) -> f64 {
    if knots.len() == 3 {
        let d = orient(knots[0], knots[1], knots[2]);
        return if half_open(u, [knots[0], knots[1], knots[2]]) {
            1.0 / d.abs()
        } else {
            0.0
        };
    }
    let Some(w) = first_independent(knots) else {
        return 0.0;
    };
    let tri = w.map(|k| knots[k]);
    let d = orient(tri[0], tri[1], tri[2]);
    (0..3)
        .map(|j| {
            let mut t = tri;
            t[j] = u;
            let lambda = orient(t[0], t[1], t[2]) / d;
            if lambda == 0.0 {
                return 0.0;
            }
            let rest: Vec<DVec2> = (0..knots.len())
                .filter(|&k| k != w[j])
                .map(|k| knots[k])
                .collect();
            lambda * simplex_spline(u, &rest)
        })
        .sum()
}

/// The first three knots (in index order) that are affinely independent.
fn first_independent(knots: &[DVec2]) -> Option<[usize; 3]> {
    let n = knots.len();
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                if orient(knots[a], knots[b], knots[c]) != 0.0 {
                    return Some([a, b, c]);
                }
            }
        }
    }
    None
}

/// The six normalised B-splines `N_β(u)` of a triangle whose corners have
/// the knot clouds `clouds = [r, s, t]` (each `[x_0, x_1, x_2]`).
pub fn bsplines(u: DVec2, clouds: [[DVec2; 3]; 3]) -> [f64; 6] {
    let knot = |k: usize| clouds[k / 3][k % 3];
    std::array::from_fn(|b| {
        let beta = BETAS[b];
        let v: Vec<DVec2> = knot_set(beta).into_iter().map(knot).collect();
        let norm = orient(clouds[0][beta[0]], clouds[1][beta[1]], clouds[2][beta[2]]);
        norm * simplex_spline(u, &v)
    })
}

/// The gradients `∇N_β(u)` of [`bsplines`]: `2 Σ_k ∇d_k(W_β) · M(u | V_β ∖
/// w_k)` with `W_β = (r_i, s_j, t_k)` (Micchelli's derivative formula).
pub fn bspline_gradients(u: DVec2, clouds: [[DVec2; 3]; 3]) -> [DVec2; 6] {
    let knot = |k: usize| clouds[k / 3][k % 3];
    std::array::from_fn(|b| {
        let beta = BETAS[b];
        let v = knot_set(beta);
        let w = [beta[0], 3 + beta[1], 6 + beta[2]];
        let [w0, w1, w2] = w.map(knot);
        let g = [
            DVec2::new(w1.y - w2.y, w2.x - w1.x),
            DVec2::new(w2.y - w0.y, w0.x - w2.x),
            DVec2::new(w0.y - w1.y, w1.x - w0.x),
        ];
        (0..3)
            .map(|j| {
                let rest: Vec<DVec2> = v.iter().filter(|&&k| k != w[j]).map(|&k| knot(k)).collect();
                2.0 * g[j] * simplex_spline(u, &rest)
            })
            .sum()
    })
}

/// Every control's weight `[N, ∂N/∂u, ∂N/∂v]` at `u` (parameter plane,
/// not centred), summed over the triangles whose knot hull holds `u`,
/// ascending by control.
pub fn weights(domain: &super::Domain, u: DVec2) -> Vec<(u32, [f64; 3])> {
    let mut out: Vec<(u32, [f64; 3])> = Vec::new();
    for t in domain.supports.at(u) {
        let tri = domain.triangles[t as usize];
        let clouds = tri.map(|v| domain.knots[v as usize]);
        let n = bsplines(u, clouds);
        let g = bspline_gradients(u, clouds);
        for b in 0..6 {
            let c = domain.control(t, b);
            let w = [n[b], g[b].x, g[b].y];
            match out.iter_mut().find(|(k, _)| *k == c) {
                Some((_, s)) => (0..3).for_each(|i| s[i] += w[i]),
                None => out.push((c, w)),
            }
        }
    }
    out.sort_by_key(|e| e.0);
    out
}
