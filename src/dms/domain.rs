//! The parameter domain the basis is evaluated over: the parameter
//! triangles, their knots, the shared control numbering and the support
//! grid, built once per parametrisation (the control net and the
//! evaluation points may change; this does not).
//!
//! Controls are shared (seed outlook 7, docs/design/dms.md §5): the corner
//! control of vertex `v` is the same in every triangle around it (id `v`),
//! and the edge control of edge `e` is the same in both triangles of the
//! edge (id `#V + e`), so a net has `#V + E` controls.

use std::collections::HashMap;

use glam::DVec2;

use super::knots::{BETAS, KnotClouds};
use super::neighbourhood::Supports;

/// The parameter triangles with their knots, controls and support grid.
#[derive(Debug, Clone)]
pub struct Domain {
    /// Parameter triangles (positively oriented).
    pub triangles: Vec<[u32; 3]>,
    /// Knot cloud of every vertex.
    pub knots: Vec<[DVec2; 3]>,
    /// Undirected edges `(a, b)`, `a < b`, numbered in order of first use.
    pub edges: Vec<[u32; 2]>,
    /// Per triangle, the edge ids of its sides `(0,1)`, `(0,2)`, `(1,2)`
    /// (the edge controls `β = 110, 101, 011`).
    pub tri_edges: Vec<[u32; 3]>,
    /// The centre of the parameter box: f32 data are relative to it.
    pub centre: DVec2,
    pub n_vertices: usize,
    pub supports: Supports,
}

impl Domain {
    /// The domain of `triangles` over `n_vertices` vertices with the knot
    /// clouds `clouds`.
    pub fn new(triangles: &[[u32; 3]], clouds: &KnotClouds) -> Domain {
        let n_vertices = clouds.knots.len();
        let mut index: HashMap<(u32, u32), u32> = HashMap::new();
        let mut edges: Vec<[u32; 2]> = Vec::new();
        let mut edge = |a: u32, b: u32| -> u32 {
            let key = (a.min(b), a.max(b));
            *index.entry(key).or_insert_with(|| {
                edges.push([key.0, key.1]);
                edges.len() as u32 - 1
            })
        };
        let tri_edges: Vec<[u32; 3]> = (triangles.iter())
            .map(|&[a, b, c]| [edge(a, b), edge(a, c), edge(b, c)])
            .collect();
        let used = || {
            triangles
                .iter()
                .flatten()
                .map(|&v| clouds.knots[v as usize][0])
        };
        let (lo, hi) = used().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(p), hi.max(p)),
        );
        let centre = if triangles.is_empty() {
            DVec2::ZERO
        } else {
            (lo + hi) * 0.5
        };
        let per_triangle: Vec<[DVec2; 9]> = (triangles.iter())
            .map(|t| std::array::from_fn(|k| clouds.knots[t[k / 3] as usize][k % 3]))
            .collect();
        Domain {
            triangles: triangles.to_vec(),
            knots: clouds.knots.clone(),
            edges,
            tri_edges,
            centre,
            n_vertices,
            supports: Supports::new(&per_triangle),
        }
    }

    /// `#V + E`.
    pub fn n_controls(&self) -> usize {
        self.n_vertices + self.edges.len()
    }

    /// The nine knots `r0 … t2` of triangle `t`.
    pub fn triangle_knots(&self, t: u32) -> [DVec2; 9] {
        let tri = self.triangles[t as usize];
        std::array::from_fn(|k| self.knots[tri[k / 3] as usize][k % 3])
    }

    /// The control of B-spline `b` (in [`BETAS`] order) of triangle `t`.
    pub fn control(&self, t: u32, b: usize) -> u32 {
        let tri = self.triangles[t as usize];
        let e = self.tri_edges[t as usize];
        let base = self.n_vertices as u32;
        match BETAS[b] {
            [2, 0, 0] => tri[0],
            [0, 2, 0] => tri[1],
            [0, 0, 2] => tri[2],
            [1, 1, 0] => base + e[0],
            [1, 0, 1] => base + e[1],
            _ => base + e[2],
        }
    }
}

impl Domain {
    /// The lowest-numbered parameter triangle whose closed triangle holds
    /// `u` (exact orientation signs), `None` outside the domain.
    pub fn locate(&self, u: DVec2) -> Option<u32> {
        use super::oracle::orient;
        self.supports.at(u).into_iter().find(|&t| {
            let [a, b, c] = self.triangles[t as usize].map(|v| self.knots[v as usize][0]);
            orient(a, b, u) >= 0.0 && orient(b, c, u) >= 0.0 && orient(c, a, u) >= 0.0
        })
    }
}
