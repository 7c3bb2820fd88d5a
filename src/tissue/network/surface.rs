//! The input surface's own geometry and topology: takes a triangle list (or
//! mesh) and returns its default origin, unique edges, bend-spring apexes
//! and 1-rings, as the network construction needs them.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::mesh::{Csr, TriMesh};
use crate::{Error, Result};

/// The SPEC §1.1 default origin: for an open surface, the centre of the
/// back face of the bounding box along the axis of least extent, on the
/// side the surface bulges away from. The side is decided by the surface's
/// own curvature (vertex normals oriented so most point away from the
/// centroid's side), not by the file's winding, which is not trusted
/// (`fran_cut` is wound inward). For a closed surface (no boundary edge)
/// the bounding-box centre, so the layers nest.
pub fn default_origin(mesh: &TriMesh) -> Result<Vec3> {
    let (lo, hi) = mesh
        .bounds()
        .ok_or_else(|| Error::empty("epidermis mesh vertices"))?;
    let centre = (lo + hi) * 0.5;
    let edges = unique_edges(&mesh.triangles);
    let closed = !edges.is_empty() && edge_use_all_even(&mesh.triangles, &edges);
    if closed {
        return Ok(centre);
    }
    let ext = hi - lo;
    let axis = if ext.x <= ext.y && ext.x <= ext.z {
        0
    } else if ext.y <= ext.z {
        1
    } else {
        2
    };
    // Area-weighted normals by the file's winding, then orientation by
    // curvature: outward normals of a bulging patch point away from its
    // centroid on average.
    let centroid = mesh.positions.iter().copied().sum::<Vec3>() / mesh.n_vertices() as f32;
    let mut normal_sum = Vec3::ZERO;
    let mut outwardness = 0.0f64;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let n = (b - a).cross(c - a);
        normal_sum += n;
        outwardness += n.dot((a + b + c) / 3.0 - centroid) as f64;
    }
    if outwardness < 0.0 {
        normal_sum = -normal_sum;
    }
    let mut o = centre;
    o[axis] = if normal_sum[axis] >= 0.0 {
        lo[axis]
    } else {
        hi[axis]
    };
    Ok(o)
}

/// Whether every edge is used by an even number (≥ 2) of triangles.
fn edge_use_all_even(triangles: &[[u32; 3]], edges: &[(u32, u32)]) -> bool {
    let mut uses = vec![0u32; edges.len()];
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a != b {
                let key = (a.min(b), a.max(b));
                if let Ok(ix) = edges.binary_search(&key) {
                    uses[ix] += 1;
                }
            }
        }
    }
    uses.iter().all(|&u| u >= 2 && u % 2 == 0)
}

/// Sorted unique undirected edges `(min, max)` of a triangle list
/// (self-edges of degenerate triangles are skipped).
pub fn unique_edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut e: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter(|(a, b)| a != b)
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    e.par_sort_unstable();
    e.dedup();
    e
}

/// The two apexes of each edge shared by exactly two triangles, as
/// `(min, max)` pairs in edge order (edges whose apexes coincide skipped).
pub(super) fn edge_apexes(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut corners: Vec<(u32, u32, u32)> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3], t[(k + 2) % 3])))
        .filter(|&(a, b, c)| a != b && b != c && a != c)
        .map(|(a, b, c)| (a.min(b), a.max(b), c))
        .collect();
    corners.par_sort_unstable();
    corners
        .chunk_by(|x, y| (x.0, x.1) == (y.0, y.1))
        .filter(|run| run.len() == 2 && run[0].2 != run[1].2)
        .map(|run| (run[0].2, run[1].2))
        .collect()
}

/// 1-ring neighbours (sorted) of `n` vertices from unique edges.
pub(super) fn one_rings(n: usize, edges: &[(u32, u32)]) -> Csr {
    let mut csr = Csr::from_pairs(n, edges.iter().flat_map(|&(a, b)| [(a, b), (b, a)]));
    for i in 0..n {
        let (s, e) = (csr.offsets[i] as usize, csr.offsets[i + 1] as usize);
        csr.targets[s..e].sort_unstable();
    }
    csr
}

pub(super) fn dvec(p: [f32; 4]) -> DVec3 {
    DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}
