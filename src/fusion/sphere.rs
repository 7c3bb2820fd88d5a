//! The refined sphere of directions about H and its projected points.
//!
//! The start polyhedron is an icosphere; it is refined by newest-vertex
//! bisection (NVB, Mitchell 1991): every triangle `(apex, r0, r1)` (counter-
//! clockwise seen from outside) has the refinement edge `r0–r1`; bisecting
//! it at the midpoint `m` gives `(m, apex, r0)` and `(m, r1, apex)`, whose
//! refinement edges are the parent's other two edges. Marked edges are
//! closed under "a triangle with a marked edge has its refinement edge
//! marked", then each triangle is bisected until none of its marked edges
//! is left: both triangles at a marked edge split it, so the mesh stays
//! conforming (closed, no hanging vertices), and NVB keeps finitely many
//! triangle shapes, so refinement never makes slivers.
//!
//! A vertex is a unit direction (f32, exactly the ray that was cast) and
//! one projected point per frame. An edge's midpoint direction is
//! evaluated before the edge is judged, so a split reuses its rays.

use std::collections::{HashMap, HashSet};

use glam::{DVec3, Vec3};

use crate::mesh::{TriMesh, unit_icosphere};
use crate::{Error, Result};

/// Projected directions: the points of every frame, `[frame][i]`, and per
/// direction the unit normals of the faces of A and B its ray crossed (at
/// the first frame's centre), which tell where a triangle straddles a
/// crease.
#[derive(Debug, Clone, Default)]
pub struct Projected {
    pub points: Vec<Vec<DVec3>>,
    pub faces: Vec<[Vec3; 2]>,
}

/// Projects unit directions.
pub trait Project {
    fn project(&mut self, dirs: &[[f32; 4]]) -> Result<Projected>;
}

/// An edge key: its vertex ids, ascending.
pub type Edge = (u32, u32);

fn edge(a: u32, b: u32) -> Edge {
    (a.min(b), a.max(b))
}

/// One refinement pass's figures.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Pass {
    /// Triangles after the pass.
    pub triangles: usize,
    /// Rays' directions evaluated in the pass (edge midpoints).
    pub directions: usize,
    /// Edges marked for splitting (before closure).
    pub marked: usize,
    /// Largest midpoint deviation from the chord before the pass.
    pub max_deviation: f64,
}

/// The direction mesh with its points.
#[derive(Debug, Clone)]
pub struct Sphere {
    /// Unit directions `[x, y, z, 0]`, one per vertex (edge midpoints that
    /// were evaluated but not split included).
    pub dirs: Vec<[f32; 4]>,
    /// Projected points `[frame][vertex]`.
    pub points: Vec<Vec<DVec3>>,
    /// Per vertex, the normals of the faces of A and B its ray crossed.
    pub faces: Vec<[Vec3; 2]>,
    /// Triangles `(apex, r0, r1)`, counter-clockwise from outside.
    pub tris: Vec<[u32; 3]>,
    /// Evaluated midpoint vertex of each edge judged so far.
    mids: HashMap<Edge, u32>,
}

/// `normalize(a + b)` in f64, rounded to f32 and normalised again there,
/// so the ray cast is exactly the stored direction.
fn unit(v: DVec3) -> [f32; 4] {
    let d = v.normalize().as_vec3().normalize();
    [d.x, d.y, d.z, 0.0]
}

fn dir(d: [f32; 4]) -> DVec3 {
    Vec3::new(d[0], d[1], d[2]).as_dvec3()
}

impl Sphere {
    /// The icosphere of `level` projected by `project`; each triangle's
    /// refinement edge is its longest (the first on ties).
    pub fn start(level: u32, project: &mut impl Project) -> Result<Sphere> {
        let (p, t) = unit_icosphere(level);
        let dirs: Vec<[f32; 4]> = p.iter().map(|v| unit(*v)).collect();
        let Projected { points, faces } = project.project(&dirs)?;
        let tris = t
            .iter()
            .map(|&[a, b, c]| {
                let len = |u: u32, v: u32| (p[u as usize] - p[v as usize]).length();
                // (apex, r0, r1) rotations of (a, b, c): refinement edge opposite the apex.
                let rot = [[a, b, c], [b, c, a], [c, a, b]];
                let lens = [len(b, c), len(c, a), len(a, b)];
                let best = (0..3).fold(0, |k, j| if lens[j] > lens[k] { j } else { k });
                rot[best]
            })
            .collect();
        Ok(Sphere {
            dirs,
            points,
            faces,
            tris,
            mids: HashMap::new(),
        })
    }

    /// Number of frames.
    pub fn n_frames(&self) -> usize {
        self.points.len()
    }

    /// Evaluates the midpoints of the edges that have none yet; returns
    /// how many directions were projected.
    pub fn evaluate_midpoints(&mut self, project: &mut impl Project) -> Result<usize> {
        let mut new: Vec<Edge> = Vec::new();
        let mut seen = HashSet::new();
        for t in &self.tris {
            for k in 0..3 {
                let e = edge(t[k], t[(k + 1) % 3]);
                if !self.mids.contains_key(&e) && seen.insert(e) {
                    new.push(e);
                }
            }
        }
        let dirs: Vec<[f32; 4]> = new
            .iter()
            .map(|&(a, b)| unit(dir(self.dirs[a as usize]) + dir(self.dirs[b as usize])))
            .collect();
        let Projected { points, faces } = project.project(&dirs)?;
        let base = self.dirs.len() as u32;
        for (i, e) in new.iter().enumerate() {
            self.mids.insert(*e, base + i as u32);
        }
        self.dirs.extend_from_slice(&dirs);
        self.faces.extend(faces);
        for (frame, p) in self.points.iter_mut().zip(points) {
            frame.extend(p);
        }
        Ok(new.len())
    }

    /// Largest distance, over frames, of edge `e`'s projected midpoint from
    /// the midpoint of its chord.
    pub fn deviation(&self, e: Edge) -> f64 {
        let m = self.mids[&e] as usize;
        self.points
            .iter()
            .map(|p| (p[m] - (p[e.0 as usize] + p[e.1 as usize]) * 0.5).length())
            .fold(0.0, f64::max)
    }

    /// Whether edge `e` straddles a crease of A or B: its end rays crossed
    /// faces of one mesh whose normals differ by more than the angle whose
    /// cosine is `cos_max`.
    pub fn straddles_crease(&self, e: Edge, cos_max: f32) -> bool {
        let (fa, fb) = (self.faces[e.0 as usize], self.faces[e.1 as usize]);
        fa[0].dot(fb[0]) < cos_max || fa[1].dot(fb[1]) < cos_max
    }

    /// Longest chord of edge `e` over the frames.
    pub fn chord(&self, e: Edge) -> f64 {
        self.points
            .iter()
            .map(|p| (p[e.0 as usize] - p[e.1 as usize]).length())
            .fold(0.0, f64::max)
    }

    /// The current triangles' edges (each once).
    pub fn edges(&self) -> Vec<Edge> {
        let mut seen = HashSet::new();
        let mut out = Vec::new();
        for t in &self.tris {
            for k in 0..3 {
                let e = edge(t[k], t[(k + 1) % 3]);
                if seen.insert(e) {
                    out.push(e);
                }
            }
        }
        out
    }

    /// Splits every edge of `marked` (and, by closure, the refinement edges
    /// of triangles that have one), keeping the mesh conforming.
    ///
    /// Errors: a marked edge whose midpoint was not evaluated.
    pub fn refine(&mut self, mut marked: HashSet<Edge>) -> Result<()> {
        loop {
            let mut grew = false;
            for t in &self.tris {
                let r = edge(t[1], t[2]);
                if marked.contains(&r) {
                    continue;
                }
                if marked.contains(&edge(t[0], t[1])) || marked.contains(&edge(t[2], t[0])) {
                    marked.insert(r);
                    grew = true;
                }
            }
            if !grew {
                break;
            }
        }
        if let Some(e) = marked.iter().find(|e| !self.mids.contains_key(e)) {
            return Err(Error::Internal(format!(
                "fusion: edge {e:?} marked before its midpoint was evaluated"
            )));
        }
        let mut out = Vec::with_capacity(self.tris.len() * 2);
        let mut stack = Vec::new();
        for &t in &self.tris {
            stack.push(t);
            while let Some([apex, r0, r1]) = stack.pop() {
                let r = edge(r0, r1);
                if !marked.contains(&r) {
                    out.push([apex, r0, r1]);
                    continue;
                }
                let m = self.mids[&r];
                stack.push([m, r1, apex]);
                stack.push([m, apex, r0]);
            }
        }
        self.tris = out;
        Ok(())
    }

    /// Frame `frame` as a mesh: the points the triangles use, renumbered in
    /// first-use order; the triangles keep their order (triangle `i` of
    /// the mesh is `tris[i]`).
    pub fn mesh(&self, frame: usize) -> TriMesh {
        let mut map = vec![u32::MAX; self.dirs.len()];
        let mut positions = Vec::new();
        let triangles = self
            .tris
            .iter()
            .map(|t| {
                t.map(|v| {
                    if map[v as usize] == u32::MAX {
                        map[v as usize] = positions.len() as u32;
                        positions.push(self.points[frame][v as usize].as_vec3());
                    }
                    map[v as usize]
                })
            })
            .collect();
        TriMesh {
            positions,
            triangles,
            scalars: Vec::new(),
        }
    }
}
