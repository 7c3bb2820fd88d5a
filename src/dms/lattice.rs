//! The evaluation lattice (SPEC §2.5, seed §2.3.3): each parameter edge is
//! divided into `n − 1` pieces, so a triangle holds `n(n + 1)/2` points.
//! Points are numbered once for the whole mesh, not per triangle ("the
//! evaluation is organised by points, not by triangles", seed l.429):
//! vertex points first (in order of first use), then `n − 2` points per
//! edge (numbered from the edge's lower vertex id, so both triangles of an
//! edge name the same points), then `(n − 2)(n − 3)/2` interior points per
//! triangle. Each parameter triangle gives `(n − 1)²` output triangles with
//! its own orientation, so the output has no cracks and no duplicated
//! points:
//!
//! ```text
//!  points(n) = p + E(n − 2) + t(n − 2)(n − 3)/2,   triangles(n) = t(n − 1)²
//! ```
//!
//! (`p` vertices used by a triangle, `E` edges, `t` triangles.) A point
//! keeps the parameter triangle that made it and its lattice coordinates
//! `(i, j)`: `u = a + i/(n − 1)·(b − a) + j/(n − 1)·(c − a)` for the
//! triangle's corners `a, b, c`.

use std::collections::HashMap;

use crate::{Error, Result};

/// The lattice coordinates `(i, j)` of the point `k` steps along one side
/// of a triangle whose sides have `last` steps.
type SideStep = fn(k: u32, last: u32) -> (u32, u32);

/// One evaluation point: the parameter triangle that made it and its
/// lattice coordinates along the triangle's second and third corner.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LatticePoint {
    pub triangle: u32,
    pub i: u32,
    pub j: u32,
}

/// The evaluation points of a mesh at accuracy `n` and the output
/// triangles over them.
#[derive(Debug, Clone, PartialEq)]
pub struct Lattice {
    /// Points per parameter edge (≥ 2; 2 gives back the input connectivity).
    pub n: u32,
    pub points: Vec<LatticePoint>,
    /// `(n − 1)²` per parameter triangle, in triangle order, wound as it is.
    pub triangles: Vec<[u32; 3]>,
    /// The lattice point of each mesh vertex (`u32::MAX` for a vertex no
    /// triangle uses).
    pub vertex_points: Vec<u32>,
}

/// `(points, triangles)` of the lattice of `t` triangles over `p` used
/// vertices and `e` edges at accuracy `n` (the formula above; seed
/// Table 3).
pub fn lattice_counts(p: u64, e: u64, t: u64, n: u64) -> (u64, u64) {
    let m = n.saturating_sub(2);
    (
        p + e * m + t * m * m.saturating_sub(1) / 2,
        t * (n - 1) * (n - 1),
    )
}

/// The lattice of `triangles` (vertex ids below `n_vertices`) at accuracy
/// `n` (points per edge, 2..=65536).
///
/// Errors: `n` out of range ([`Error::InvalidParameter`]), a triangle that
/// names a missing vertex or one vertex twice ([`Error::InvalidData`]), more
/// points or triangles than `u32` numbers ([`Error::Limit`]).
pub fn lattice(triangles: &[[u32; 3]], n_vertices: usize, n: u32) -> Result<Lattice> {
    if !(2..=65_536).contains(&n) {
        return Err(Error::param("n", n, "points per edge must be in 2..=65536"));
    }
    for (t, tri) in triangles.iter().enumerate() {
        if let Some(&v) = tri.iter().find(|&&v| v as usize >= n_vertices) {
            return Err(Error::data(
                "parameter triangles",
                "triangle",
                t,
                format!("names vertex {v} of {n_vertices}"),
            ));
        }
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
            return Err(Error::data(
                "parameter triangles",
                "triangle",
                t,
                format!("{tri:?} names a vertex twice"),
            ));
        }
    }
    let m = u64::from(n) - 1;
    let out_triangles = triangles.len() as u64 * m * m;
    if out_triangles > u64::from(u32::MAX) {
        return Err(Error::limit("lattice triangles", out_triangles, u32::MAX));
    }
    let mut vertex_points = vec![u32::MAX; n_vertices];
    let mut points: Vec<LatticePoint> = Vec::new();
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    let inner = (n as usize - 2) * (n as usize).saturating_sub(3) / 2;
    let new_point = |points: &mut Vec<LatticePoint>, p: LatticePoint| -> Result<u32> {
        let id = u32::try_from(points.len())
            .ok()
            .filter(|&id| id < u32::MAX)
            .ok_or_else(|| Error::limit("lattice points", points.len() + 1, u32::MAX - 1))?;
        points.push(p);
        Ok(id)
    };
    // Ids per triangle, row by row: `ids[row(j) + i]` for i + j ≤ n − 1.
    let row = |j: u32| (j * n - j * (j.saturating_sub(1)) / 2) as usize;
    let per_triangle = (n * (n + 1) / 2) as usize;
    let mut ids = vec![0u32; per_triangle];
    let mut out = Vec::with_capacity(out_triangles as usize);
    let last = n - 1;
    for (t, &[a, b, c]) in triangles.iter().enumerate() {
        let t = t as u32;
        let at = |i: u32, j: u32| LatticePoint { triangle: t, i, j };
        // Corners.
        for (v, (i, j)) in [(a, (0, 0)), (b, (last, 0)), (c, (0, last))] {
            if vertex_points[v as usize] == u32::MAX {
                vertex_points[v as usize] = new_point(&mut points, at(i, j))?;
            }
            ids[row(j) + i as usize] = vertex_points[v as usize];
        }
        // Edges: (from, to, lattice point at k steps from `from`).
        let sides: [(u32, u32, SideStep); 3] = [
            (a, b, |k, _| (k, 0)),
            (b, c, |k, last| (last - k, k)),
            (a, c, |k, _| (0, k)),
        ];
        for (from, to, step) in sides {
            let key = (from.min(to), from.max(to));
            let base = match edges.get(&key) {
                Some(&base) => base,
                None => {
                    let base = points.len() as u32;
                    for s in 1..last {
                        // Numbered from the lower vertex id.
                        let k = if from < to { s } else { last - s };
                        let (i, j) = step(k, last);
                        new_point(&mut points, at(i, j))?;
                    }
                    edges.insert(key, base);
                    base
                }
            };
            for k in 1..last {
                let s = if from < to { k } else { last - k };
                let (i, j) = step(k, last);
                ids[row(j) + i as usize] = base + s - 1;
            }
        }
        // Interior.
        let first_inner = points.len();
        for j in 1..last {
            for i in 1..last - j {
                ids[row(j) + i as usize] = new_point(&mut points, at(i, j))?;
            }
        }
        debug_assert_eq!(points.len() - first_inner, inner);
        // Output triangles, wound as (a, b, c): "up" and "down" cells.
        let id = |i: u32, j: u32| ids[row(j) + i as usize];
        for j in 0..last {
            for i in 0..last - j {
                out.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                if i + j + 2 <= last {
                    out.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                }
            }
        }
    }
    Ok(Lattice {
        n,
        points,
        triangles: out,
        vertex_points,
    })
}
