//! Knot clouds (SPEC §2.2, seed §2.2.3 and §2.3.1, l.346–382): every
//! parameter vertex `t_{i,0}` gets two more knots `t_{i,1}`, `t_{i,2}`, so
//! that every triple of knots the degree-2 recursion uses stays affinely
//! independent, and the ten DMS triangles `[r_i, s_j, t_k]` (`i + j + k ≤
//! 2`) of each parameter triangle stay positively oriented.
//!
//! The seed leaves the constants open; chosen here (docs/design/dms.md §2):
//! - candidates on the circle of radius 1/5 of the distance to the nearest
//!   neighbour (seed l.362), every [`THETA_DEG`]° (24 candidates), the
//!   step halved up to [`REFINEMENTS`] times where fewer than two of them
//!   lie in the vertex's allowed region;
//! - the quality of a triple is the normalised determinant
//!   `q = 2√3·d(a, b, c) / (|ab|² + |bc|² + |ca|²)` (1 for an equilateral
//!   triangle, scale-free, signed);
//! - the triples scored per triangle are the 37 three-knot subsets of the
//!   six knot sets `V_β` (not the seed's 27 cross triples, which miss the
//!   same-cloud triples the recursion uses); a DMS triangle scores its
//!   signed `q`, every other triple `|q|`;
//! - `t_{i,1}` is chosen first, then `t_{i,2}` given it, each maximising the
//!   smallest score over the incident triangles (maximin), vertices in id
//!   order, scoring only knots already placed;
//! - an interior vertex's knots lie strictly inside one of its triangles; a
//!   boundary vertex's strictly outside every boundary edge at it (the
//!   outer half-planes: there the terms that do not cancel between
//!   neighbouring triangles keep their support off the domain, so the
//!   partition of unity holds up to the border; the seed's "Ω_n covering the
//!   whole boundary triangle" cannot be met at a vertex of two or more
//!   triangles).
//!
//! The smallest quality reached over all triangles is reported
//! ([`KnotClouds::min_quality`]).

use glam::DVec2;

use crate::{Error, Refusal, Result};

/// Angle step of the knot candidates, degrees.
pub const THETA_DEG: f64 = 15.0;

/// Halvings of the angle step tried where fewer than two candidates lie in
/// a vertex's allowed region (Θ/64 ≈ 0.23° at the finest).
pub const REFINEMENTS: u32 = 6;

/// Knot radius as a fraction of the distance to the nearest neighbour.
pub const RADIUS_FRACTION: f64 = 0.2;

/// The knot clouds `[t_{i,0}, t_{i,1}, t_{i,2}]` of every vertex.
#[derive(Debug, Clone, PartialEq)]
pub struct KnotClouds {
    pub knots: Vec<[DVec2; 3]>,
    /// The smallest quality over every scored triple of every triangle.
    pub min_quality: f64,
}

/// Normalised determinant of `a b c` (module docs).
pub fn quality(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    let d = (b - a).perp_dot(c - a);
    let l = (b - a).length_squared() + (c - b).length_squared() + (a - c).length_squared();
    if l == 0.0 {
        return 0.0;
    }
    2.0 * 3f64.sqrt() * d / l
}

/// The knot indices of one triangle's knot set `V_β`, `β = (i, j, k)`,
/// `i + j + k = 2`: knot `3·corner + cloud` (`r_0 = 0 … t_2 = 8`).
pub fn knot_set(beta: [usize; 3]) -> Vec<usize> {
    (0..3)
        .flat_map(|corner| (0..=beta[corner]).map(move |cloud| 3 * corner + cloud))
        .collect()
}

/// The six `β` of degree 2, in the order `(2,0,0), (1,1,0), (1,0,1),
/// (0,2,0), (0,1,1), (0,0,2)`.
pub const BETAS: [[usize; 3]; 6] = [
    [2, 0, 0],
    [1, 1, 0],
    [1, 0, 1],
    [0, 2, 0],
    [0, 1, 1],
    [0, 0, 2],
];

/// The scored triples of one triangle: `(knots, signed)`, `signed` for the
/// ten DMS triangles `[r_i, s_j, t_k]`, `i + j + k ≤ 2` (37 in all).
pub fn scored_triples() -> Vec<([usize; 3], bool)> {
    let mut out: Vec<([usize; 3], bool)> = Vec::new();
    for beta in BETAS {
        let v = knot_set(beta);
        for a in 0..v.len() {
            for b in a + 1..v.len() {
                for c in b + 1..v.len() {
                    let t = [v[a], v[b], v[c]];
                    let corners = t.map(|k| k / 3);
                    let dms = corners == [0, 1, 2];
                    if !out.iter().any(|(u, _)| *u == t) {
                        out.push((t, dms));
                    }
                }
            }
        }
    }
    out
}

/// The knot clouds of the positively oriented parameter triangles
/// `triangles` over the points `uv` (module docs).
///
/// Errors: [`Refusal::NoKnotPosition`] when no candidate of a vertex lies
/// in its allowed region (a star too thin for the angle step).
pub fn knot_clouds(uv: &[DVec2], triangles: &[[u32; 3]]) -> Result<KnotClouds> {
    let n = uv.len();
    let mut star: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (t, tri) in triangles.iter().enumerate() {
        for &v in tri {
            star[v as usize].push(t as u32);
        }
    }
    // Directed boundary edges at each vertex (interior on the left).
    let mut boundary: Vec<Vec<(u32, u32)>> = vec![Vec::new(); n];
    for (a, b) in super::param::boundary_edges(triangles) {
        boundary[a as usize].push((a, b));
        boundary[b as usize].push((a, b));
    }
    let triples = scored_triples();
    // Per knot of a triangle (3·corner + cloud), the scored triples that
    // contain it: placing that knot changes only their scores.
    let with_knot: Vec<Vec<([usize; 3], bool)>> = (0..9)
        .map(|k| {
            triples
                .iter()
                .copied()
                .filter(|(t, _)| t.contains(&k))
                .collect()
        })
        .collect();
    // Knot k of vertex v: None until placed.
    let mut knots: Vec<[Option<DVec2>; 3]> = uv.iter().map(|&p| [Some(p), None, None]).collect();
    // The smallest score of triangle t's triples with the knot `need`,
    // folded into `worst`; stops once it is at or below `bound` (a
    // candidate that low cannot win the maximin). `own` overrides the
    // knots of the vertex being placed.
    let score = |knots: &[[Option<DVec2>; 3]],
                 own: &[Option<DVec2>; 3],
                 t: u32,
                 need: (usize, usize),
                 worst: &mut f64,
                 bound: f64| {
        let tri = triangles[t as usize];
        let Some(corner) = tri.iter().position(|&w| w as usize == need.0) else {
            return;
        };
        let get = |w: u32, c: usize| {
            if w as usize == need.0 {
                own[c]
            } else {
                knots[w as usize][c]
            }
        };
        for &(ks, signed) in &with_knot[3 * corner + need.1] {
            let pts = ks.map(|k| get(tri[k / 3], k % 3));
            let [Some(a), Some(b), Some(c)] = pts else {
                continue;
            };
            let q = quality(a, b, c);
            *worst = worst.min(if signed { q } else { q.abs() });
            if *worst <= bound {
                return;
            }
        }
    };
    let steps = (360.0 / THETA_DEG).round() as usize;
    // The two extra knots of vertex v, given the knots placed so far
    // (`None` when no candidate fits).
    let place = |v: usize, knots: &[[Option<DVec2>; 3]]| -> Option<[DVec2; 2]> {
        let p = uv[v];
        let nearest = (star[v].iter())
            .flat_map(|&t| triangles[t as usize])
            .filter(|&w| w as usize != v)
            .map(|w| uv[w as usize].distance(p))
            .fold(f64::INFINITY, f64::min);
        let radius = RADIUS_FRACTION * nearest;
        let allowed = |q: DVec2| -> bool {
            if boundary[v].is_empty() {
                star[v].iter().any(|&t| {
                    let [a, b, c] = triangles[t as usize].map(|w| uv[w as usize]);
                    (b - a).perp_dot(q - a) > 0.0
                        && (c - b).perp_dot(q - b) > 0.0
                        && (a - c).perp_dot(q - c) > 0.0
                })
            } else {
                boundary[v].iter().all(|&(a, b)| {
                    let (a, b) = (uv[a as usize], uv[b as usize]);
                    (b - a).perp_dot(q - a) < 0.0
                })
            }
        };
        // The candidates every Θ; where fewer than two of them lie in the
        // allowed region (a sharp boundary corner, a thin star), every
        // Θ/2, Θ/4, … down to Θ/64.
        let mut candidates: Vec<DVec2> = Vec::new();
        for refine in 0..=REFINEMENTS {
            let n_steps = steps << refine;
            let step = THETA_DEG / f64::from(1u32 << refine);
            candidates = (0..n_steps)
                .map(|s| {
                    let angle = (s as f64 * step).to_radians();
                    p + radius * DVec2::new(angle.cos(), angle.sin())
                })
                .filter(|&q| allowed(q))
                .collect();
            if candidates.len() >= 2 {
                break;
            }
        }
        let mut own: [Option<DVec2>; 3] = [Some(p), None, None];
        for cloud in 1..3 {
            let mut best: Option<(f64, DVec2)> = None;
            for &q in &candidates {
                if own[..cloud].iter().flatten().any(|&k| k == q) {
                    continue;
                }
                own[cloud] = Some(q);
                // Branch and bound: the maximin only needs to know whether
                // this candidate beats the best so far (same choice as
                // scoring every triple).
                let bound = best.map_or(f64::NEG_INFINITY, |(b, _)| b);
                let mut s = f64::INFINITY;
                for &t in &star[v] {
                    score(knots, &own, t, (v, cloud), &mut s, bound);
                    if s <= bound {
                        break;
                    }
                }
                own[cloud] = None;
                if best.is_none_or(|(b, _)| s > b) {
                    best = Some((s, q));
                }
            }
            own[cloud] = Some(best?.1);
        }
        Some([own[1]?, own[2]?])
    };
    // Vertices are placed in id order, each seeing the knots of its
    // lower-numbered neighbours only. Vertex v depends on those alone, so
    // the vertices of one level (1 + the largest level of a lower-numbered
    // neighbour) are independent and placed in parallel, with the same
    // result as the sequential order.
    let mut level = vec![0u32; n];
    for v in 0..n {
        for &t in &star[v] {
            for w in triangles[t as usize] {
                if (w as usize) < v {
                    level[v] = level[v].max(level[w as usize] + 1);
                }
            }
        }
    }
    let mut by_level: Vec<Vec<usize>> = Vec::new();
    for v in (0..n).filter(|&v| !star[v].is_empty()) {
        let l = level[v] as usize;
        if by_level.len() <= l {
            by_level.resize(l + 1, Vec::new());
        }
        by_level[l].push(v);
    }
    let mut failed: Option<usize> = None;
    for vertices in &by_level {
        use rayon::prelude::*;
        let placed: Vec<Option<[DVec2; 2]>> = vertices
            .par_iter()
            .with_min_len(64)
            .map(|&v| place(v, &knots))
            .collect();
        for (&v, k) in vertices.iter().zip(placed) {
            match k {
                Some([a, b]) => {
                    knots[v][1] = Some(a);
                    knots[v][2] = Some(b);
                }
                None => failed = Some(failed.map_or(v, |f| f.min(v))),
            }
        }
    }
    if let Some(v) = failed {
        return Err(Refusal::NoKnotPosition { vertex: v as u32 }.into());
    }
    let mut min_quality = f64::INFINITY;
    for tri in triangles {
        for &(ks, signed) in &triples {
            let [a, b, c] = ks.map(|k| knots[tri[k / 3] as usize][k % 3]);
            let (Some(a), Some(b), Some(c)) = (a, b, c) else {
                return Err(Error::Internal("a knot of a used vertex is missing".into()));
            };
            let q = quality(a, b, c);
            min_quality = min_quality.min(if signed { q } else { q.abs() });
        }
    }
    Ok(KnotClouds {
        knots: knots
            .into_iter()
            .zip(uv)
            .map(|(k, &p)| [p, k[1].unwrap_or(p), k[2].unwrap_or(p)])
            .collect(),
        min_quality,
    })
}
