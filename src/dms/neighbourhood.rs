//! Which triangles contribute at a parameter point (SPEC §2.3; seed l.908:
//! "all triangles in the neighbourhood of this evaluation point can
//! contribute", not only the immediate neighbours).
//!
//! The support of every B-spline of a triangle lies in the convex hull of
//! its nine knots (docs/design/dms.md §4), so triangle `Δ` contributes at
//! `u` only if `u` lies in that closed hull. [`Supports`] keeps the hulls
//! and a uniform grid over the parameter plane holding each hull's bounding
//! box; [`Supports::candidates`] lists, per point, the triangles whose hull
//! contains it, in ascending id order, with exact orientation signs, so the
//! list equals [`Supports::brute_force`] (every triangle tested) exactly.

use glam::DVec2;

use super::oracle::orient;
use crate::mesh::Csr;

/// The knot hulls of a triangulation and a grid over their boxes.
#[derive(Debug, Clone)]
pub struct Supports {
    /// Per triangle: the counter-clockwise convex hull of its nine knots.
    hulls: Vec<Vec<DVec2>>,
    /// Per triangle: the hull's bounding box.
    boxes: Vec<(DVec2, DVec2)>,
    origin: DVec2,
    cell: f64,
    dims: [usize; 2],
    /// Cell (row-major) → triangles whose box meets it.
    grid: Csr,
}

/// Counter-clockwise convex hull (monotone chain, exact turns), without
/// collinear points.
fn convex_hull(mut pts: Vec<DVec2>) -> Vec<DVec2> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * pts.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && orient(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// Whether `u` lies in the closed convex polygon `hull` (counter-clockwise).
fn in_hull(hull: &[DVec2], u: DVec2) -> bool {
    let n = hull.len();
    n >= 3 && (0..n).all(|i| orient(hull[i], hull[(i + 1) % n], u) >= 0.0)
}

impl Supports {
    /// The hulls of `knots` (per triangle, the nine knots `r0 … t2`) and
    /// their grid.
    pub fn new(knots: &[[DVec2; 9]]) -> Supports {
        let hulls: Vec<Vec<DVec2>> = knots.iter().map(|k| convex_hull(k.to_vec())).collect();
        let boxes: Vec<(DVec2, DVec2)> = (knots.iter())
            .map(|k| {
                k.iter()
                    .fold((k[0], k[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)))
            })
            .collect();
        let (lo, hi) = (boxes.iter()).fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), b| (lo.min(b.0), hi.max(b.1)),
        );
        let (lo, hi) = if boxes.is_empty() {
            (DVec2::ZERO, DVec2::ONE)
        } else {
            (lo, hi)
        };
        // About one triangle per cell, at most 4096 cells per side.
        let extent = (hi - lo).max(DVec2::splat(f64::MIN_POSITIVE));
        let cell = ((extent.x * extent.y) / boxes.len().max(1) as f64)
            .sqrt()
            .max(extent.max_element() / 4096.0);
        let dims = [
            ((extent.x / cell).floor() as usize + 1).min(4097),
            ((extent.y / cell).floor() as usize + 1).min(4097),
        ];
        let mut supports = Supports {
            hulls,
            boxes,
            origin: lo,
            cell,
            dims,
            grid: Csr::default(),
        };
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for (t, b) in supports.boxes.iter().enumerate() {
            let (c0, c1) = (supports.cell_of(b.0), supports.cell_of(b.1));
            for y in c0[1]..=c1[1] {
                for x in c0[0]..=c1[0] {
                    pairs.push(((y * dims[0] + x) as u32, t as u32));
                }
            }
        }
        supports.grid = Csr::from_pairs(dims[0] * dims[1], pairs.into_iter());
        supports
    }

    /// The grid cell of `u`, clamped to the grid.
    fn cell_of(&self, u: DVec2) -> [usize; 2] {
        let c = (u - self.origin) / self.cell;
        let clamp = |x: f64, n: usize| (x.max(0.0) as usize).min(n - 1);
        [clamp(c.x, self.dims[0]), clamp(c.y, self.dims[1])]
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.hulls.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.hulls.is_empty()
    }

    /// Whether `u` lies in the closed knot hull of triangle `t`.
    pub fn contains(&self, t: u32, u: DVec2) -> bool {
        let (lo, hi) = self.boxes[t as usize];
        u.cmpge(lo).all() && u.cmple(hi).all() && in_hull(&self.hulls[t as usize], u)
    }

    /// The triangles whose knot hull contains `u`, ascending.
    pub fn at(&self, u: DVec2) -> Vec<u32> {
        let [x, y] = self.cell_of(u);
        let mut out: Vec<u32> = (self.grid.row(y * self.dims[0] + x).iter())
            .copied()
            .filter(|&t| self.contains(t, u))
            .collect();
        out.sort_unstable();
        out
    }

    /// Per point, the triangles whose knot hull contains it (CSR).
    pub fn candidates(&self, points: &[DVec2]) -> Csr {
        use rayon::prelude::*;
        let lists: Vec<Vec<u32>> = points.par_iter().map(|&u| self.at(u)).collect();
        Csr::from_rows(&lists)
    }

    /// [`Supports::candidates`] by testing every triangle (the reference
    /// the grid is tested equal to).
    pub fn brute_force(&self, points: &[DVec2]) -> Csr {
        let lists: Vec<Vec<u32>> = (points.iter())
            .map(|&u| {
                (0..self.hulls.len() as u32)
                    .filter(|&t| self.contains(t, u))
                    .collect()
            })
            .collect();
        Csr::from_rows(&lists)
    }
}
