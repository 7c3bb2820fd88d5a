//! The control net (SPEC §2.4, seed §2.3.2 and outlook 7).
//!
//! - Point identification (eq. 2.13): corner controls are the vertices,
//!   edge controls the edge midpoints — a fixed linear map of the vertices
//!   ([`identify`]; folded into the surface rows by
//!   [`super::surface::SurfaceInput::identify`]).
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
//!
//! Data without `--data`: the piecewise-linear mesh at its vertices, edge
//! midpoints and triangle centroids (`#V + E + t` points for `#V + E`
//! unknowns; the vertices alone leave the system underdetermined, seed
//! l.405). Data points whose parameter point lies in no parameter triangle
//! are left out and counted.

use glam::{DVec2, DVec3, Vec3};
use serde::Serialize;

use super::basis::dms_basis;
use super::domain::Domain;
use crate::gpu::Backend;
use crate::mesh::Csr;
use crate::{Error, Refusal, Result};

/// Relative residual at which conjugate gradients stop.
pub const CG_TOLERANCE: f64 = 1e-10;

/// How well a control net fits its data.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitReport {
    /// `identify` or `lsq`.
    pub method: &'static str,
    /// Data points used.
    pub data_points: usize,
    /// Data points whose parameter point lies outside the domain (left out).
    pub outside: usize,
    /// RMS and largest `|F(u_i) − x_i|` over the data points used.
    pub rms: f64,
    pub max: f64,
    /// The relative fairing weight `W` (least squares).
    pub fairing: f64,
    /// Conjugate-gradient iterations (largest of the three coordinates).
    pub iterations: u32,
}

/// The controls of point identification: vertex `v` → its position, edge
/// control `#V + e` → the midpoint of edge `e`.
pub fn identify(domain: &Domain, positions: &[Vec3]) -> Vec<DVec3> {
    let p = |v: u32| positions[v as usize].as_dvec3();
    positions
        .iter()
        .map(|x| x.as_dvec3())
        .chain(domain.edges.iter().map(|&[a, b]| 0.5 * (p(a) + p(b))))
        .collect()
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
/// Errors: a negative or non-finite weight ([`Error::InvalidParameter`]),
/// no data point inside the domain ([`Error::Empty`]), conjugate gradients
/// that do not converge ([`Refusal::NoConvergence`]).
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
    let inside: Vec<usize> = (0..params.len())
        .filter(|&i| domain.locate(params[i]).is_some())
        .collect();
    if inside.is_empty() {
        return Err(Error::empty(
            "least squares: data points inside the parameter domain",
        ));
    }
    let u: Vec<DVec2> = inside.iter().map(|&i| params[i]).collect();
    let x: Vec<DVec3> = inside.iter().map(|&i| points[i]).collect();
    let basis = dms_basis(domain, &u, backend)?;
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
    let (rms, max) = residuals(&basis.rows, &w, &controls, &x);
    Ok((
        controls,
        FitReport {
            method: "lsq",
            data_points: inside.len(),
            outside: params.len() - inside.len(),
            rms,
            max,
            fairing,
            iterations,
        },
    ))
}

/// The figures of point identification against data `(params, points)`.
pub fn identify_report(
    domain: &Domain,
    params: &[DVec2],
    points: &[DVec3],
    controls: &[DVec3],
    backend: Backend<'_>,
) -> Result<FitReport> {
    let inside: Vec<usize> = (0..params.len())
        .filter(|&i| domain.locate(params[i]).is_some())
        .collect();
    let u: Vec<DVec2> = inside.iter().map(|&i| params[i]).collect();
    let x: Vec<DVec3> = inside.iter().map(|&i| points[i]).collect();
    let basis = dms_basis(domain, &u, backend)?;
    let w: Vec<f64> = basis.weights.iter().map(|q| q[0] as f64).collect();
    let (rms, max) = residuals(&basis.rows, &w, controls, &x);
    Ok(FitReport {
        method: "identify",
        data_points: inside.len(),
        outside: params.len() - inside.len(),
        rms,
        max,
        fairing: 0.0,
        iterations: 0,
    })
}
