//! The control net (SPEC §2.4, seed §2.3.2 and outlook 7).
//!
//! - Point identification (eq. 2.13): corner controls are the vertices,
//!   edge controls the edge midpoints — a fixed linear map of the vertices
//!   ([`ControlMap::identify`]).
//! - Least squares with shared controls (outlook 7; the seed's eq. 2.14
//!   with the norm squared): the `#V + E` shared controls minimise `Σ_i
//!   |F(u_i) − x_i|² + λ Σ_(a,b) |c_a − c_b|²` over data points `(u_i,
//!   x_i)` and the edges `(a, b)` of the control net (nine per triangle:
//!   the sides and the inner triangle of the six controls). The fairing
//!   weight is given relative: `λ = W · trace(EᵀE) / trace(L)`, so `W` does
//!   not depend on the mesh's size or units. The normal equations `(EᵀE +
//!   λL) C = EᵀX` (sparse, symmetric positive definite when the data cover
//!   the controls) are solved by Jacobi-preconditioned conjugate gradients
//!   per coordinate, started from point identification; never a dense
//!   solve.
//! - Quasi-interpolation (beyond the seed; [`ControlMap::quasi`]): every
//!   vertex gets the least-squares quadratic `q_v` of its two-ring in the
//!   parameter plane, and the controls are blossoms (docs/design/dms.md
//!   §5): the vertex control `P_v(r₀, r₁)`, the edge control
//!   `½(P_a(a₀, b₀) + P_b(a₀, b₀))`. Quadratics are reproduced exactly, so the surface
//!   follows the shape the vertices sample instead of the mesh's flat
//!   facets (which identification and least squares against the
//!   piecewise-linear mesh both keep); like identification it is a fixed
//!   linear map of the vertices.
//!
//! Data without `--data`: the piecewise-linear mesh at its vertices, edge
//! midpoints and triangle centroids (`#V + E + t` points for `#V + E`
//! unknowns; the vertices alone leave the system underdetermined, seed
//! l.405). `--data` points whose parameter point lies in no parameter
//! triangle are left out and counted ([`super::spline()`]).

use glam::{DVec2, DVec3, Vec3};
use serde::Serialize;

use super::basis::dms_basis;
use super::domain::Domain;
use super::surface::SurfaceInput;
use crate::gpu::Backend;
use crate::mesh::Csr;
use crate::{Error, Refusal, Result};

/// Relative residual at which conjugate gradients stop.
pub const CG_TOLERANCE: f64 = 1e-10;

/// How well a control net fits its data.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitReport {
    /// `identify`, `quasi` or `lsq`.
    pub method: &'static str,
    /// Data points used.
    pub data_points: usize,
    /// `--data` points whose parameter point lies outside the domain (left out).
    pub outside: usize,
    /// RMS and largest `|F(u_i) − x_i|` over the data points used.
    pub rms: f64,
    pub max: f64,
    /// The relative fairing weight `W` (least squares).
    pub fairing: f64,
    /// Conjugate-gradient iterations (largest of the three coordinates).
    pub iterations: u32,
}

/// A control net that is a fixed linear map of the mesh vertices: control
/// `c` is `Σ weights[k] · vertex[rows.targets[k]]` over `rows.row(c)`.
#[derive(Debug, Clone, PartialEq)]
pub struct ControlMap {
    pub rows: Csr,
    pub weights: Vec<f64>,
}

impl ControlMap {
    /// Point identification (eq. 2.13): vertex `v` → itself, edge control
    /// `#V + e` → the midpoint of edge `e`.
    pub fn identify(domain: &Domain) -> ControlMap {
        let mut lists: Vec<Vec<u32>> = (0..domain.n_vertices as u32).map(|v| vec![v]).collect();
        let mut weights = vec![1.0; domain.n_vertices];
        for &[a, b] in &domain.edges {
            lists.push(vec![a, b]);
            weights.extend([0.5, 0.5]);
        }
        ControlMap {
            rows: Csr::from_rows(&lists),
            weights,
        }
    }

    /// Quasi-interpolation by local quadratic fits (module docs) over the
    /// parameter points `uv`. A vertex whose two-ring cannot fix a
    /// quadratic widens it to the three-ring, then falls back to a linear
    /// fit, then to itself.
    pub fn quasi(domain: &Domain, uv: &[DVec2]) -> ControlMap {
        let n = domain.n_vertices;
        let mut ring1: Vec<Vec<u32>> = vec![Vec::new(); n];
        for &[a, b] in &domain.edges {
            ring1[a as usize].push(b);
            ring1[b as usize].push(a);
        }
        // Per used vertex: its neighbourhood and the blossom weights map.
        let fits: Vec<Option<LocalFit>> = (0..n)
            .map(|v| (!ring1[v].is_empty()).then(|| LocalFit::new(v as u32, &ring1, uv)))
            .collect();
        let mut lists: Vec<Vec<u32>> = Vec::with_capacity(domain.n_controls());
        let mut weights: Vec<f64> = Vec::new();
        for (v, fit) in fits.iter().enumerate() {
            match fit {
                Some(f) => {
                    let k = domain.knots[v];
                    let w = f.blossom(k[0], k[1]);
                    lists.push(f.points.clone());
                    weights.extend(w);
                }
                None => {
                    lists.push(vec![v as u32]);
                    weights.push(1.0);
                }
            }
        }
        for &[a, b] in &domain.edges {
            let (ua, ub) = (uv[a as usize], uv[b as usize]);
            let mut row: Vec<(u32, f64)> = Vec::new();
            for v in [a, b] {
                let f = fits[v as usize]
                    .as_ref()
                    .expect("an edge's vertices are used");
                for (&p, w) in f.points.iter().zip(f.blossom(ua, ub)) {
                    row.push((p, 0.5 * w));
                }
            }
            row.sort_by_key(|e| e.0);
            let mut merged: Vec<(u32, f64)> = Vec::new();
            for (p, w) in row {
                match merged.last_mut() {
                    Some(last) if last.0 == p => last.1 += w,
                    _ => merged.push((p, w)),
                }
            }
            lists.push(merged.iter().map(|e| e.0).collect());
            weights.extend(merged.iter().map(|e| e.1));
        }
        ControlMap {
            rows: Csr::from_rows(&lists),
            weights,
        }
    }

    /// The map as `dms_surface` rows over `n_vertices` vertices (weights
    /// `[w, 0, 0, 0]`: the gather's positions are the controls).
    pub fn gather_input(&self, n_vertices: usize) -> SurfaceInput {
        SurfaceInput {
            rows: self.rows.clone(),
            weights: self
                .weights
                .iter()
                .map(|&w| [w as f32, 0.0, 0.0, 0.0])
                .collect(),
            n_sources: n_vertices,
            base: None,
        }
    }

    /// The controls of vertex positions `positions`.
    pub fn apply(&self, positions: &[Vec3]) -> Vec<DVec3> {
        (0..self.rows.n_rows())
            .map(|c| {
                let (lo, hi) = (
                    self.rows.offsets[c] as usize,
                    self.rows.offsets[c + 1] as usize,
                );
                (lo..hi)
                    .map(|k| self.weights[k] * positions[self.rows.targets[k] as usize].as_dvec3())
                    .sum()
            })
            .collect()
    }
}

/// The least-squares quadratic of one vertex's neighbourhood, kept as the
/// linear map from the neighbours' values to its coefficients.
struct LocalFit {
    centre: DVec2,
    scale: f64,
    /// The vertices fitted.
    points: Vec<u32>,
    /// `coeffs = g · values`: `terms × points`, row-major.
    g: Vec<f64>,
    terms: usize,
}

impl LocalFit {
    fn new(v: u32, ring1: &[Vec<u32>], uv: &[DVec2]) -> LocalFit {
        let mut points: Vec<u32> = vec![v];
        let mut frontier: Vec<u32> = vec![v];
        for ring in 1..=3 {
            let mut next: Vec<u32> = Vec::new();
            for &p in &frontier {
                for &q in &ring1[p as usize] {
                    if !points.contains(&q) && !next.contains(&q) {
                        next.push(q);
                    }
                }
            }
            points.extend(&next);
            frontier = next;
            if ring >= 2
                && let Some(fit) = LocalFit::solve(v, &points, uv, 6)
            {
                return fit;
            }
        }
        LocalFit::solve(v, &points, uv, 3).unwrap_or(LocalFit {
            centre: uv[v as usize],
            scale: 1.0,
            points: vec![v],
            g: vec![1.0],
            terms: 1,
        })
    }

    /// The fit with `terms` monomials (6: quadratic, 3: linear), `None`
    /// when the points do not fix it.
    fn solve(v: u32, points: &[u32], uv: &[DVec2], terms: usize) -> Option<LocalFit> {
        let centre = uv[v as usize];
        let scale = (points.iter())
            .map(|&p| uv[p as usize].distance(centre))
            .fold(0.0, f64::max);
        if points.len() < terms || scale <= 0.0 {
            return None;
        }
        let mono = |p: DVec2| -> [f64; 6] {
            let d = (p - centre) / scale;
            [1.0, d.x, d.y, d.x * d.x, d.x * d.y, d.y * d.y]
        };
        let a: Vec<[f64; 6]> = points.iter().map(|&p| mono(uv[p as usize])).collect();
        // Normal matrix and its inverse by Gauss–Jordan with pivoting.
        let mut m = vec![0.0f64; terms * 2 * terms];
        for row in &a {
            for i in 0..terms {
                for j in 0..terms {
                    m[i * 2 * terms + j] += row[i] * row[j];
                }
            }
        }
        for i in 0..terms {
            m[i * 2 * terms + terms + i] = 1.0;
        }
        let w = 2 * terms;
        let norm = (0..terms).map(|i| m[i * w + i]).fold(0.0, f64::max);
        for col in 0..terms {
            let piv = (col..terms)
                .max_by(|&x, &y| m[x * w + col].abs().total_cmp(&m[y * w + col].abs()))?;
            if m[piv * w + col].abs() <= 1e-10 * norm {
                return None;
            }
            for k in 0..w {
                m.swap(col * w + k, piv * w + k);
            }
            let d = m[col * w + col];
            for k in 0..w {
                m[col * w + k] /= d;
            }
            for r in 0..terms {
                if r != col {
                    let f = m[r * w + col];
                    for k in 0..w {
                        m[r * w + k] -= f * m[col * w + k];
                    }
                }
            }
        }
        // g = (AᵀA)⁻¹ Aᵀ.
        let mut g = vec![0.0f64; terms * points.len()];
        for i in 0..terms {
            for (p, row) in a.iter().enumerate() {
                g[i * points.len() + p] = (0..terms).map(|j| m[i * w + terms + j] * row[j]).sum();
            }
        }
        Some(LocalFit {
            centre,
            scale,
            points: points.to_vec(),
            g,
            terms,
        })
    }

    /// The weights over `points` of the blossom `P(x, y)` of the fit.
    fn blossom(&self, x: DVec2, y: DVec2) -> Vec<f64> {
        let (a, b) = (
            (x - self.centre) / self.scale,
            (y - self.centre) / self.scale,
        );
        let phi = [
            1.0,
            (a.x + b.x) / 2.0,
            (a.y + b.y) / 2.0,
            a.x * b.x,
            (a.x * b.y + a.y * b.x) / 2.0,
            a.y * b.y,
        ];
        let n = self.points.len();
        (0..n)
            .map(|p| (0..self.terms).map(|i| phi[i] * self.g[i * n + p]).sum())
            .collect()
    }
}

/// The default data of a mesh: vertices, edge midpoints, centroids, with
/// their parameter points.
pub fn mesh_data(domain: &Domain, uv: &[DVec2], positions: &[Vec3]) -> (Vec<DVec2>, Vec<DVec3>) {
    let x = |v: u32| positions[v as usize].as_dvec3();
    let u = |v: u32| uv[v as usize];
    let used: Vec<u32> = {
        let mut seen = vec![false; positions.len()];
        for &v in domain.triangles.iter().flatten() {
            seen[v as usize] = true;
        }
        (0..positions.len() as u32)
            .filter(|&v| seen[v as usize])
            .collect()
    };
    let mut params: Vec<DVec2> = used.iter().map(|&v| u(v)).collect();
    let mut points: Vec<DVec3> = used.iter().map(|&v| x(v)).collect();
    for &[a, b] in &domain.edges {
        params.push(0.5 * (u(a) + u(b)));
        points.push(0.5 * (x(a) + x(b)));
    }
    for &[a, b, c] in &domain.triangles {
        params.push((u(a) + u(b) + u(c)) / 3.0);
        points.push((x(a) + x(b) + x(c)) / 3.0);
    }
    (params, points)
}

/// Symmetric sparse matrix, rows in CSR with ascending columns.
struct Sparse {
    pattern: Csr,
    values: Vec<f64>,
}

impl Sparse {
    fn mul(&self, x: &[f64], y: &mut [f64]) {
        for (i, yi) in y.iter_mut().enumerate() {
            let (lo, hi) = (
                self.pattern.offsets[i] as usize,
                self.pattern.offsets[i + 1] as usize,
            );
            *yi = (lo..hi)
                .map(|k| self.values[k] * x[self.pattern.targets[k] as usize])
                .sum();
        }
    }

    fn diagonal(&self) -> Vec<f64> {
        (0..self.pattern.n_rows())
            .map(|i| {
                let (lo, hi) = (
                    self.pattern.offsets[i] as usize,
                    self.pattern.offsets[i + 1] as usize,
                );
                (lo..hi)
                    .find(|&k| self.pattern.targets[k] as usize == i)
                    .map_or(0.0, |k| self.values[k])
            })
            .collect()
    }
}

/// `EᵀE + λL` for data rows `rows` (weights `w`) over `n` controls and the
/// control-net edges `edges`.
fn normal_matrix(rows: &Csr, w: &[f64], n: usize, edges: &[[u32; 2]], lambda: f64) -> Sparse {
    // Columns of E: control → (data row, weight).
    let cols = Csr::from_pairs(
        n,
        (0..rows.n_rows()).flat_map(|r| {
            (rows.offsets[r]..rows.offsets[r + 1]).map(move |k| (rows.targets[k as usize], k))
        }),
    );
    let mut lap: Vec<Vec<u32>> = vec![Vec::new(); n];
    for &[a, b] in edges {
        lap[a as usize].push(b);
        lap[b as usize].push(a);
    }
    let mut acc = vec![0.0f64; n];
    let mut mark = vec![false; n];
    let mut offsets = vec![0u32];
    let mut targets: Vec<u32> = Vec::new();
    let mut values: Vec<f64> = Vec::new();
    let mut touched: Vec<u32> = Vec::new();
    for i in 0..n as u32 {
        touched.clear();
        let mut touch = |j: u32, v: f64, touched: &mut Vec<u32>| {
            if !mark[j as usize] {
                mark[j as usize] = true;
                touched.push(j);
            }
            acc[j as usize] += v;
        };
        for &k in cols.row(i as usize) {
            let wi = w[k as usize];
            let r = rows.offsets.partition_point(|&o| o <= k) - 1;
            for kk in rows.offsets[r]..rows.offsets[r + 1] {
                touch(rows.targets[kk as usize], wi * w[kk as usize], &mut touched);
            }
        }
        for &j in &lap[i as usize] {
            touch(j, -lambda, &mut touched);
            touch(i, lambda, &mut touched);
        }
        touch(i, 0.0, &mut touched);
        touched.sort_unstable();
        for &j in &touched {
            targets.push(j);
            values.push(acc[j as usize]);
            acc[j as usize] = 0.0;
            mark[j as usize] = false;
        }
        offsets.push(targets.len() as u32);
    }
    Sparse {
        pattern: Csr { offsets, targets },
        values,
    }
}

/// Jacobi-preconditioned conjugate gradients from `x`; the iterations.
fn conjugate_gradients(a: &Sparse, b: &[f64], x: &mut [f64], max_iter: u32) -> (u32, f64) {
    let n = b.len();
    let inv: Vec<f64> = a
        .diagonal()
        .iter()
        .map(|&d| if d > 0.0 { 1.0 / d } else { 1.0 })
        .collect();
    let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
    let mut r = vec![0.0; n];
    a.mul(x, &mut r);
    for i in 0..n {
        r[i] = b[i] - r[i];
    }
    let norm_b = dot(b, b).sqrt().max(f64::MIN_POSITIVE);
    let mut z: Vec<f64> = r.iter().zip(&inv).map(|(r, m)| r * m).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut ap = vec![0.0; n];
    for it in 0..max_iter {
        let res = dot(&r, &r).sqrt() / norm_b;
        if res <= CG_TOLERANCE {
            return (it, res);
        }
        a.mul(&p, &mut ap);
        let pap = dot(&p, &ap);
        if pap <= 0.0 {
            return (it, res);
        }
        let alpha = rz / pap;
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
        }
        for i in 0..n {
            z[i] = r[i] * inv[i];
        }
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
    (max_iter, dot(&r, &r).sqrt() / norm_b)
}

/// The nine control-net edges of every triangle, each once.
fn net_edges(domain: &Domain) -> Vec<[u32; 2]> {
    // Control slots in BETAS order: 200 110 101 020 011 002.
    const PAIRS: [[usize; 2]; 9] = [
        [0, 1],
        [1, 3],
        [3, 4],
        [4, 5],
        [5, 2],
        [2, 0],
        [1, 2],
        [1, 4],
        [2, 4],
    ];
    let mut out: Vec<[u32; 2]> = (0..domain.triangles.len() as u32)
        .flat_map(|t| {
            PAIRS.map(|[a, b]| {
                let (a, b) = (domain.control(t, a), domain.control(t, b));
                [a.min(b), a.max(b)]
            })
        })
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// `|F(u_i) − x_i|` over the data rows for controls `c`.
fn residuals(rows: &Csr, w: &[f64], c: &[DVec3], x: &[DVec3]) -> (f64, f64) {
    let mut sum = 0.0;
    let mut max = 0.0f64;
    for (r, xr) in x.iter().enumerate() {
        let f: DVec3 = (rows.offsets[r]..rows.offsets[r + 1])
            .map(|k| w[k as usize] * c[rows.targets[k as usize] as usize])
            .sum();
        let d = f.distance(*xr);
        sum += d * d;
        max = max.max(d);
    }
    ((sum / x.len().max(1) as f64).sqrt(), max)
}

/// Least-squares controls for the data `(params, points)` with relative
/// fairing weight `fairing`, and the fit's figures; `start` = the
/// identification controls.
///
/// The data must lie in the domain (the caller leaves out the rest).
///
/// Errors: a negative or non-finite weight ([`Error::InvalidParameter`]),
/// no data point ([`Error::Empty`]), conjugate gradients that do not
/// converge ([`Refusal::NoConvergence`]).
pub fn least_squares(
    domain: &Domain,
    params: &[DVec2],
    points: &[DVec3],
    fairing: f64,
    start: Vec<DVec3>,
    backend: Backend<'_>,
) -> Result<(Vec<DVec3>, FitReport)> {
    if !(fairing.is_finite() && fairing >= 0.0) {
        return Err(Error::param(
            "fairing",
            fairing,
            "must be a finite weight ≥ 0",
        ));
    }
    if params.is_empty() {
        return Err(Error::empty(
            "least squares: data points inside the parameter domain",
        ));
    }
    let (u, x) = (params, points);
    let basis = dms_basis(domain, u, backend)?;
    let w: Vec<f64> = basis.weights.iter().map(|q| q[0] as f64).collect();
    let n = domain.n_controls();
    let edges = net_edges(domain);
    let unscaled = normal_matrix(&basis.rows, &w, n, &[], 0.0);
    let trace_e: f64 = unscaled.diagonal().iter().sum();
    let trace_l = 2.0 * edges.len() as f64;
    let lambda = if fairing > 0.0 {
        fairing * trace_e / trace_l
    } else {
        0.0
    };
    let a = normal_matrix(&basis.rows, &w, n, &edges, lambda);
    let mut controls = start;
    let mut iterations = 0;
    let max_iter = (10 * n as u32).max(100);
    for axis in 0..3 {
        let mut rhs = vec![0.0; n];
        for (r, xr) in x.iter().enumerate() {
            for k in basis.rows.offsets[r]..basis.rows.offsets[r + 1] {
                rhs[basis.rows.targets[k as usize] as usize] += w[k as usize] * xr[axis];
            }
        }
        let mut c: Vec<f64> = controls.iter().map(|p| p[axis]).collect();
        let (it, res) = conjugate_gradients(&a, &rhs, &mut c, max_iter);
        if res > CG_TOLERANCE {
            return Err(Refusal::NoConvergence {
                what: "least-squares control net (conjugate gradients)",
                iterations: it,
                residual: res,
            }
            .into());
        }
        iterations = iterations.max(it);
        for (p, v) in controls.iter_mut().zip(c) {
            p[axis] = v;
        }
    }
    let (rms, max) = residuals(&basis.rows, &w, &controls, x);
    Ok((
        controls,
        FitReport {
            method: "lsq",
            data_points: params.len(),
            outside: 0,
            rms,
            max,
            fairing,
            iterations,
        },
    ))
}

/// The figures of a control net made without the data (`method`) against
/// the data `(params, points)`.
pub fn report(
    domain: &Domain,
    method: &'static str,
    params: &[DVec2],
    points: &[DVec3],
    controls: &[DVec3],
    backend: Backend<'_>,
) -> Result<FitReport> {
    let basis = dms_basis(domain, params, backend)?;
    let w: Vec<f64> = basis.weights.iter().map(|q| q[0] as f64).collect();
    let (rms, max) = residuals(&basis.rows, &w, controls, points);
    Ok(FitReport {
        method,
        data_points: params.len(),
        outside: 0,
        rms,
        max,
        fairing: 0.0,
        iterations: 0,
    })
}
