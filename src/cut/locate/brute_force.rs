//! The brute-force locate: takes a mesh and a prepared knife, tests every triangle,
//! and returns the same [`Located`] as the tree query (numbered by
//! [`super::finish`]), without node counts.

use rayon::prelude::*;

use super::finish::{finish_locate, finish_locate_mesh};
use super::{ends, knife_reaches};
use crate::cut::corefine;
use crate::cut::knife::{Analytic, AnalyticKnife, Kind, PreparedKnife};
use crate::cut::{CutStats, Located};
use crate::{Error, Result, TriMesh};

pub(crate) fn locate_brute_force_prepared(
    mesh: &TriMesh,
    k: &PreparedKnife<'_>,
) -> Result<Located> {
    let stats = CutStats {
        triangles_total: mesh.triangles.len(),
        triangles_tested: mesh.triangles.len(),
        ..CutStats::default()
    };
    Ok(match k.analytic() {
        None => return scan_mesh_knife(mesh, k, stats),
        Some(AnalyticKnife::Plane(a)) => scan_analytic(mesh, a, stats),
        Some(AnalyticKnife::Rect(a)) => scan_analytic(mesh, a, stats),
        Some(AnalyticKnife::Sphere(a)) => scan_analytic(mesh, a, stats),
    })
}

/// The scan for an analytic knife (compiled per knife kind).
fn scan_analytic<A: Analytic>(mesh: &TriMesh, k: A, stats: CutStats) -> Located {
    // Analytic knives: one side value per vertex, then only triangles with
    // mixed signs can hold a crossed edge.
    let neg: Vec<bool> = mesh
        .positions
        .par_iter()
        .map(|q| k.eval(q.as_dvec3()) < 0.0)
        .collect();
    // In chunks, each a plain loop that keeps its mixed ids without a
    // branch (as the tree's leaf test does).
    const CHUNK: usize = 1 << 15;
    let mixed: Vec<u32> = (mesh.triangles.par_chunks(CHUNK).enumerate())
        .map(|(i, tris)| {
            let mut ids = vec![0; tris.len()];
            let mut kept = 0;
            for (tri, t) in tris.iter().zip((i * CHUNK) as u32..) {
                let [a, b, c] = tri.map(|v| neg[v as usize]);
                ids[kept] = t;
                kept += usize::from((a != b) | (b != c));
            }
            ids.truncate(kept);
            ids
        })
        .collect::<Vec<_>>()
        .concat();
    let crossed = if A::SIGN_CHANGE_CROSSES {
        mixed
    } else {
        let reaches = |&t: &u32| knife_reaches(k, ends(mesh, k, t));
        mixed.into_par_iter().filter(reaches).collect()
    };
    finish_locate(mesh, &crossed, k, stats)
}

/// The scan for a triangulated knife: corefinement of every triangle.
fn scan_mesh_knife(mesh: &TriMesh, k: &PreparedKnife<'_>, stats: CutStats) -> Result<Located> {
    let Kind::Mesh {
        mesh: knife,
        forest,
    } = &k.kind
    else {
        return Err(Error::Internal(
            "analytic knife on the mesh-knife path".into(),
        ));
    };
    let pair = corefine::Pair {
        surface: mesh,
        knife,
        forest,
        margin: k.margin(),
    };
    let all: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
    let segs = pair.segments_of(&all)?;
    let crossed = all
        .into_iter()
        .zip(segs)
        .filter(|(_, s)| !s.is_empty())
        .collect();
    Ok(finish_locate_mesh(&pair, crossed, stats))
}
