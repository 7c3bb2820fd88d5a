//! A disk-like patch of a closed surface to spline: the DMS room needs a
//! parameter domain without folds, and a closed skin (a CT's, a phantom's)
//! has none as a whole. [`facing_patch`] keeps the triangles that face a
//! direction (the face of a head) and maps them onto the plane across it:
//! a triangle whose normal points within `acos(min_cos)` of `front`
//! projects with positive area, so the map cannot fold.

use std::collections::HashMap;

use glam::{DVec2, Vec3};

use crate::{Error, Result, TriMesh};

/// A patch of a mesh with its parameter points.
#[derive(Debug, Clone)]
pub struct FacingPatch {
    /// The patch, vertices renumbered.
    pub mesh: TriMesh,
    /// Patch vertex → mesh vertex.
    pub vertices: Vec<u32>,
    /// Parameter point per patch vertex: `(right·p, up·p)`.
    pub uv: Vec<DVec2>,
}

/// The largest edge-connected set of triangles of `mesh` whose unit normal
/// has a component ≥ `min_cos` along `front`, mapped onto the plane
/// spanned by `right = up × front` and `up` (`up` made orthogonal to
/// `front`).
///
/// Errors: zero or parallel directions, `min_cos` outside (0, 1)
/// ([`Error::InvalidParameter`]), no triangle facing `front`
/// ([`Error::Empty`]).
pub fn facing_patch(mesh: &TriMesh, front: Vec3, up: Vec3, min_cos: f32) -> Result<FacingPatch> {
    mesh.validate()?;
    let f = front.normalize_or_zero();
    let u = (up - up.dot(f) * f).normalize_or_zero();
    if f == Vec3::ZERO || u == Vec3::ZERO {
        return Err(Error::param(
            "facing patch: front and up",
            format!("{front} and {up}"),
            "must be non-zero and not parallel",
        ));
    }
    if !(min_cos > 0.0 && min_cos < 1.0) {
        return Err(Error::param(
            "facing patch: min_cos",
            min_cos,
            "must lie in (0, 1)",
        ));
    }
    let right = u.cross(f);
    let keep: Vec<bool> = (mesh.triangles.iter())
        .map(|t| {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            (b - a).cross(c - a).normalize_or_zero().dot(f) >= min_cos
        })
        .collect();
    let mut keep = largest_component(&mesh.triangles, &keep);
    if !keep.iter().any(|&k| k) {
        return Err(Error::empty(format!(
            "facing patch: triangles facing {front}"
        )));
    }
    // A vertex where two fans of the patch touch (more than two boundary
    // edges) has no outer side for its knots: keep its largest fan.
    loop {
        let pinched = pinched_vertices(&mesh.triangles, &keep);
        if pinched.is_empty() {
            break;
        }
        for v in pinched {
            let fan: Vec<usize> = (0..mesh.triangles.len())
                .filter(|&t| keep[t] && mesh.triangles[t].contains(&v))
                .collect();
            let sub: Vec<[u32; 3]> = fan.iter().map(|&t| mesh.triangles[t]).collect();
            let largest = largest_component(&sub, &vec![true; sub.len()]);
            for (k, &t) in fan.iter().enumerate() {
                keep[t] = largest[k];
            }
        }
        keep = largest_component(&mesh.triangles, &keep);
    }
    let mut new_id = vec![u32::MAX; mesh.n_vertices()];
    let mut vertices: Vec<u32> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if keep[t] {
            triangles.push(tri.map(|v| {
                if new_id[v as usize] == u32::MAX {
                    new_id[v as usize] = vertices.len() as u32;
                    vertices.push(v);
                }
                new_id[v as usize]
            }));
        }
    }
    let positions: Vec<Vec3> = vertices
        .iter()
        .map(|&v| mesh.positions[v as usize])
        .collect();
    let uv = positions
        .iter()
        .map(|p| DVec2::new(right.dot(*p) as f64, u.dot(*p) as f64))
        .collect();
    Ok(FacingPatch {
        mesh: TriMesh::new(positions, triangles)?,
        vertices,
        uv,
    })
}

/// The largest edge-connected set of the triangles with `keep` set (ties:
/// the one with the lowest triangle), as a mask.
fn largest_component(triangles: &[[u32; 3]], keep: &[bool]) -> Vec<bool> {
    fn root(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    let mut parent: Vec<u32> = (0..triangles.len() as u32).collect();
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for (t, tri) in triangles.iter().enumerate() {
        if !keep[t] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            match edges.get(&(a.min(b), a.max(b))) {
                Some(&o) => {
                    let (x, y) = (root(&mut parent, o), root(&mut parent, t as u32));
                    let (lo, hi) = (x.min(y), x.max(y));
                    parent[hi as usize] = lo;
                }
                None => {
                    edges.insert((a.min(b), a.max(b)), t as u32);
                }
            }
        }
    }
    let mut size = vec![0usize; triangles.len()];
    for t in 0..triangles.len() {
        if keep[t] {
            size[root(&mut parent, t as u32) as usize] += 1;
        }
    }
    let best = (0..size.len()).max_by_key(|&r| (size[r], std::cmp::Reverse(r)));
    (0..triangles.len())
        .map(|t| keep[t] && Some(root(&mut parent, t as u32) as usize) == best)
        .collect()
}

/// Vertices of the kept triangles with more than two boundary edges.
fn pinched_vertices(triangles: &[[u32; 3]], keep: &[bool]) -> Vec<u32> {
    let kept: Vec<[u32; 3]> = (0..triangles.len())
        .filter(|&t| keep[t])
        .map(|t| triangles[t])
        .collect();
    let mut count: HashMap<u32, u32> = HashMap::new();
    for (a, b) in crate::dms::param::boundary_edges(&kept) {
        *count.entry(a).or_default() += 1;
        *count.entry(b).or_default() += 1;
    }
    let mut out: Vec<u32> = count
        .into_iter()
        .filter(|&(_, c)| c > 2)
        .map(|(v, _)| v)
        .collect();
    out.sort_unstable();
    out
}
