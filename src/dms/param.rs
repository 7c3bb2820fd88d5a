//! The parametrisation (SPEC §2.1, seed §2.3.1, eq. 2.12): every mesh
//! vertex gets a point of the parameter plane, and the parameter triangles
//! must be positively oriented and must not overlap.
//!
//! - [`Projection::Cylinder`]: eq. 2.12 about a vertical (`y`) axis, `u =
//!   (R·α, y)`. The axis is the least-squares circle through the vertices'
//!   `(x, z)` (Kåsa fit; the vertex centroid folds 130 of fran_cut's
//!   triangles, the fit none, docs/design/dms.md §1), `R` its radius so
//!   both coordinates are lengths, and the seam (α = ±π) lies opposite the
//!   mean vertex direction, so it does not cut the face.
//! - [`Projection::Planar`]: onto the plane of the two largest principal
//!   axes (the axis of least extent dropped).
//! - [`Projection::Given`]: UVs that come with the mesh.
//!
//! When most parameter triangles come out negatively oriented the domain is
//! mirrored (`u.x ↦ −u.x`; the mesh's vertex order, and with it the corner
//! ↔ control-point correspondence, stays). Isolated degenerate or flipped
//! triangles are repaired (seed outlook 8): an interior vertex of one moves
//! to the mean of its neighbours when that leaves its whole star positive.
//! Anything else, and a boundary that crosses itself, is refused with the
//! triangle or edge ids ([`Refusal::FoldedParameters`],
//! [`Refusal::OverlappingParameters`]).

use std::collections::HashMap;

use glam::DVec2;

use crate::{Error, Refusal, Result, TriMesh};

/// How mesh vertices map to the parameter plane.
#[derive(Debug, Clone, PartialEq)]
pub enum Projection {
    /// Eq. 2.12 about a vertical axis, seam opposite the mean direction.
    Cylinder,
    /// Onto the plane of the two largest principal axes.
    Planar,
    /// One parameter point per vertex, given.
    Given(Vec<DVec2>),
}

/// The parameter points of a mesh and how they were made.
#[derive(Debug, Clone, PartialEq)]
pub struct Parametrisation {
    /// One parameter point per mesh vertex.
    pub uv: Vec<DVec2>,
    /// Whether `u.x` was negated to orient the triangles positively.
    pub mirrored: bool,
    /// Triangles repaired by moving a vertex (outlook 8).
    pub repaired: Vec<u32>,
    /// The map from space to the parameter plane (before repairs), for
    /// projecting further points ([`Parametrisation::project`]).
    pub map: ParamMap,
}

/// The map of a parametrisation, mirroring included.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamMap {
    /// `u = (s·R·α', y)`: axis `(x, z)` = `centre`, radius `R`, `α'` the
    /// angle about the axis from `mean`, `s` = −1 when mirrored.
    Cylinder {
        centre: DVec2,
        radius: f64,
        mean: f64,
        mirror: bool,
    },
    /// `u = (s·e₁·(p − origin), e₂·(p − origin))`.
    Planar {
        origin: glam::DVec3,
        e1: glam::DVec3,
        e2: glam::DVec3,
        mirror: bool,
    },
    /// UVs came with the mesh: no map for other points.
    Given,
}

impl Parametrisation {
    /// The parameter point of a point in space by the same map as the
    /// mesh's vertices; `None` for given UVs.
    pub fn project(&self, p: glam::Vec3) -> Option<DVec2> {
        let sign = |m: bool| if m { -1.0 } else { 1.0 };
        match &self.map {
            ParamMap::Cylinder {
                centre,
                radius,
                mean,
                mirror,
            } => {
                let a = (p.x as f64 - centre.x).atan2(p.z as f64 - centre.y);
                let a = (a - mean + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                    - std::f64::consts::PI;
                Some(DVec2::new(sign(*mirror) * radius * a, p.y as f64))
            }
            ParamMap::Planar {
                origin,
                e1,
                e2,
                mirror,
            } => {
                let d = p.as_dvec3() - *origin;
                Some(DVec2::new(sign(*mirror) * e1.dot(d), e2.dot(d)))
            }
            ParamMap::Given => None,
        }
    }
}

/// Twice the signed area of a parameter triangle (positive counter-clockwise).
pub fn det(uv: &[DVec2], t: [u32; 3]) -> f64 {
    let [a, b, c] = t.map(|v| uv[v as usize]);
    (b - a).perp_dot(c - a)
}

/// The parametrisation of `mesh` by `projection`, oriented, repaired and
/// checked (module docs).
pub fn parametrise(mesh: &TriMesh, projection: &Projection) -> Result<Parametrisation> {
    mesh.validate()?;
    if mesh.triangles.is_empty() {
        return Err(Error::empty("parametrisation: mesh triangles"));
    }
    let (mut uv, mut map) = match projection {
        Projection::Cylinder => cylinder(mesh),
        Projection::Planar => planar(mesh),
        Projection::Given(uv) => {
            if uv.len() != mesh.n_vertices() {
                return Err(Error::mismatch(
                    "parametrisation: given UVs (one per vertex)",
                    mesh.n_vertices(),
                    uv.len(),
                ));
            }
            if let Some(v) = uv.iter().position(|p| !p.is_finite()) {
                return Err(Error::data("given UVs", "vertex", v, "not finite"));
            }
            (uv.clone(), ParamMap::Given)
        }
    };
    let negative = (mesh.triangles.iter())
        .filter(|&&t| det(&uv, t) < 0.0)
        .count();
    let mirrored = 2 * negative > mesh.triangles.len();
    if mirrored {
        uv.iter_mut().for_each(|p| p.x = -p.x);
        match &mut map {
            ParamMap::Cylinder { mirror, .. } | ParamMap::Planar { mirror, .. } => *mirror = true,
            ParamMap::Given => {}
        }
    }
    let repaired = repair(&mut uv, &mesh.triangles, mesh.n_vertices())?;
    check_boundary(&uv, &mesh.triangles)?;
    Ok(Parametrisation {
        uv,
        mirrored,
        repaired,
        map,
    })
}

/// Eq. 2.12 about the least-squares circle axis of the vertices' `(x, z)`.
fn cylinder(mesh: &TriMesh) -> (Vec<DVec2>, ParamMap) {
    let pts: Vec<DVec2> = (mesh.positions.iter())
        .map(|p| DVec2::new(p.x as f64, p.z as f64))
        .collect();
    let (centre, radius) = circle_fit(&pts).unwrap_or_else(|| {
        // Collinear (x, z): the box centre and the mean distance.
        let (lo, hi) = (pts.iter()).fold((pts[0], pts[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let c = (lo + hi) * 0.5;
        let r = pts.iter().map(|p| p.distance(c)).sum::<f64>() / pts.len() as f64;
        (c, r.max(f64::MIN_POSITIVE))
    });
    let angle = |p: DVec2| (p.x - centre.x).atan2(p.y - centre.y);
    let (s, c) = (pts.iter()).fold((0.0, 0.0), |(s, c), &p| {
        let a = angle(p);
        (s + a.sin(), c + a.cos())
    });
    let mean = s.atan2(c);
    let uv = (pts.iter().zip(&mesh.positions))
        .map(|(&p, q)| {
            let a = (angle(p) - mean + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            DVec2::new(radius * a, q.y as f64)
        })
        .collect();
    (
        uv,
        ParamMap::Cylinder {
            centre,
            radius,
            mean,
            mirror: false,
        },
    )
}

/// Kåsa's least-squares circle through `pts`: minimises
/// `Σ (x² + y² + D x + E y + F)²`; `None` when the points are collinear.
fn circle_fit(pts: &[DVec2]) -> Option<(DVec2, f64)> {
    let n = pts.len() as f64;
    let mean = pts.iter().copied().sum::<DVec2>() / n;
    // Centred coordinates keep the normal equations well conditioned.
    let (mut suu, mut svv, mut suv, mut suuu, mut svvv, mut suvv, mut svuu) =
        (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for p in pts {
        let (u, v) = (p.x - mean.x, p.y - mean.y);
        suu += u * u;
        svv += v * v;
        suv += u * v;
        suuu += u * u * u;
        svvv += v * v * v;
        suvv += u * v * v;
        svuu += v * u * u;
    }
    let det = suu * svv - suv * suv;
    if det.abs() <= 1e-12 * (suu * svv).max(f64::MIN_POSITIVE) {
        return None;
    }
    let (r1, r2) = (0.5 * (suuu + suvv), 0.5 * (svvv + svuu));
    let uc = (r1 * svv - r2 * suv) / det;
    let vc = (r2 * suu - r1 * suv) / det;
    let radius = (uc * uc + vc * vc + (suu + svv) / n).sqrt();
    radius
        .is_finite()
        .then(|| (DVec2::new(uc + mean.x, vc + mean.y), radius))
}

/// Onto the two largest principal axes (Jacobi eigenvectors of the
/// covariance), right-handed with the third.
fn planar(mesh: &TriMesh) -> (Vec<DVec2>, ParamMap) {
    use glam::DVec3;
    let pts: Vec<DVec3> = mesh.positions.iter().map(|p| p.as_dvec3()).collect();
    let mean = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
    let mut cov = [[0.0f64; 3]; 3];
    for p in &pts {
        let d = *p - mean;
        for (r, row) in cov.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x += d[r] * d[c];
            }
        }
    }
    let (values, vectors) = jacobi_eigen(cov);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
    let axis = |k: usize| DVec3::from_array(std::array::from_fn(|r| vectors[r][order[k]]));
    let (e1, e2) = (axis(0), axis(1));
    let uv = pts
        .iter()
        .map(|&p| DVec2::new(e1.dot(p - mean), e2.dot(p - mean)))
        .collect();
    (
        uv,
        ParamMap::Planar {
            origin: mean,
            e1,
            e2,
            mirror: false,
        },
    )
}

/// Eigenvalues and eigenvectors (columns) of a symmetric 3 × 3 matrix by
/// cyclic Jacobi rotations.
fn jacobi_eigen(mut a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        let off = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
        if off <= 1e-30 * (a[0][0].powi(2) + a[1][1].powi(2) + a[2][2].powi(2)).max(1e-300) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let (c, s) = (1.0 / (t * t + 1.0).sqrt(), t / (t * t + 1.0).sqrt());
            // A ← Jᵀ A J: columns p, q, then rows p, q.
            for row in &mut a {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (row_p, row_q) = (a[p], a[q]);
            a[p] = std::array::from_fn(|k| c * row_p[k] - s * row_q[k]);
            a[q] = std::array::from_fn(|k| s * row_p[k] + c * row_q[k]);
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    ([a[0][0], a[1][1], a[2][2]], v)
}

/// Undirected edge → the triangles using it.
fn edge_triangles(triangles: &[[u32; 3]]) -> HashMap<(u32, u32), Vec<u32>> {
    let mut edges: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            edges
                .entry((a.min(b), a.max(b)))
                .or_default()
                .push(t as u32);
        }
    }
    edges
}

/// The boundary edges of `triangles` (used by one triangle), directed as
/// in it (the interior on the left of a positive triangle), in triangle
/// order.
pub fn boundary_edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let edges = edge_triangles(triangles);
    let mut out = Vec::new();
    for tri in triangles {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            if edges[&(a.min(b), a.max(b))].len() == 1 {
                out.push((a, b));
            }
        }
    }
    out
}

/// Repairs isolated non-positive triangles by moving one of their interior
/// vertices to the mean of its neighbours where that leaves its star
/// positive; refuses what stays (outlook 8). Returns the repaired ids.
fn repair(uv: &mut [DVec2], triangles: &[[u32; 3]], n_vertices: usize) -> Result<Vec<u32>> {
    let bad = |uv: &[DVec2]| -> Vec<u32> {
        (0..triangles.len() as u32)
            // Not positive, NaN included.
            .filter(|&t| {
                det(uv, triangles[t as usize]).partial_cmp(&0.0)
                    != Some(std::cmp::Ordering::Greater)
            })
            .collect()
    };
    let first = bad(uv);
    if first.is_empty() {
        return Ok(Vec::new());
    }
    let mut boundary = vec![false; n_vertices];
    for (a, b) in boundary_edges(triangles) {
        boundary[a as usize] = true;
        boundary[b as usize] = true;
    }
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); n_vertices];
    for &(a, b) in edge_triangles(triangles).keys() {
        neighbours[a as usize].push(b);
        neighbours[b as usize].push(a);
    }
    let mut star: Vec<Vec<u32>> = vec![Vec::new(); n_vertices];
    for (t, tri) in triangles.iter().enumerate() {
        for &v in tri {
            star[v as usize].push(t as u32);
        }
    }
    for _ in 0..3 {
        for &t in &bad(uv) {
            for &v in &triangles[t as usize] {
                let v = v as usize;
                if boundary[v] || neighbours[v].is_empty() {
                    continue;
                }
                let old = uv[v];
                let ring = &neighbours[v];
                uv[v] = ring.iter().map(|&w| uv[w as usize]).sum::<DVec2>() / ring.len() as f64;
                if star[v]
                    .iter()
                    .all(|&s| det(uv, triangles[s as usize]) > 0.0)
                {
                    break;
                }
                uv[v] = old;
            }
        }
    }
    let left = bad(uv);
    if !left.is_empty() {
        return Err(Refusal::FoldedParameters { triangles: left }.into());
    }
    Ok(first)
}

/// Refuses a boundary that crosses itself (the parameter triangles would
/// overlap although each is positive): every pair of boundary edges that
/// share no vertex is tested with exact orientation signs.
fn check_boundary(uv: &[DVec2], triangles: &[[u32; 3]]) -> Result<()> {
    let mut boundary: Vec<(u32, u32)> = (boundary_edges(triangles).into_iter())
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    boundary.sort_unstable();
    let c = |v: u32| robust::Coord {
        x: uv[v as usize].x,
        y: uv[v as usize].y,
    };
    let orient = |a: u32, b: u32, p: u32| robust::orient2d(c(a), c(b), c(p)).signum();
    for (i, &(a, b)) in boundary.iter().enumerate() {
        for &(p, q) in &boundary[i + 1..] {
            if a == p || a == q || b == p || b == q {
                continue;
            }
            let cross = orient(a, b, p) * orient(a, b, q) <= 0.0
                && orient(p, q, a) * orient(p, q, b) <= 0.0;
            if cross {
                return Err(Refusal::OverlappingParameters {
                    edges: [[a, b], [p, q]],
                }
                .into());
            }
        }
    }
    Ok(())
}
