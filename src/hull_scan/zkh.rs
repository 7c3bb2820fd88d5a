//! ZKH ("Zusammenhangskomponenten von Hintergrundvoxeln innerhalb der
//! konvexen Hülle", seed 003 §4.2): the 6-connected components of background
//! voxels inside the hull, and their classification by the edge-connected
//! sets of hull faces incident to them (Def. CO/CA/TU, §4.2.2–4.2.3).
//!
//! Rules, with the seed's words:
//! * **Inside the hull** (§4.2.1): a voxel lies inside CH(S) when no face is
//!   visible from its centre ("alle Flächen … unsichtbar"), i.e.
//!   [`Side::Inside`] or [`Side::On`]. Background voxels *on* a face belong
//!   to ZKHs: with hull vertices at voxel centres, the mouth voxels of a
//!   tunnel lie on the hull faces, and leaving them out would turn every
//!   through-hole into a cavity.
//! * **Incident faces** (§4.2.3): a ZKH S' is taken as a closed complex
//!   (Cl(S') = S', §4.2.2), so its 0-cells are all corners of its voxels
//!   (even combinatorial coordinates). A face `n·p ≤ d` is incident to S'
//!   when some 0-cell `c` of S' sees it (`n·c − d > 0`, Def. VI) or is
//!   coplanar with it (`n·c − d = 0`): §4.2.3 counts coplanar contact as
//!   incidence ("Dieser Fall gilt dann ebenfalls als Konkavität, da auch in
//!   diesem Fall Flächen der konvexen Hülle mit 0-Zellen der ZKH
//!   inzidieren"), and the face selection of §4.4.1 (i) uses the same
//!   "visible or coplanar" test.
//! * **Classes**: the incident faces split into sets connected through
//!   shared hull edges ("stark zusammenhängend", marked by flooding over
//!   common edges, §4.2.3); 0 sets → cavity (Def. CA), 1 → concavity
//!   (Def. CO), 2 → unbranched tunnel, > 2 → branched tunnel (Def. TU).
//!   As the seed notes (Fig. 4.16), a tunnel whose mouths touch one
//!   edge-connected set of faces is a concavity by these definitions.

use rayon::prelude::*;

use super::cpu::lattice_rows;
use super::{Classification, HalfSpace, Side, check_range};
use crate::volume::analysis::label_6_connected;
use crate::{Error, Result};

/// The class of a ZKH (Def. CA/CO/TU).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ZkhClass {
    /// No incident face (Def. CA, "Hohlraum").
    Cavity,
    /// One edge-connected set of incident faces (Def. CO).
    Concavity,
    /// Two sets (Def. TU, unverzweigt).
    UnbranchedTunnel,
    /// More than two sets (Def. TU, verzweigt).
    BranchedTunnel,
}

impl ZkhClass {
    /// The class of a ZKH incident to `n_sets` edge-connected face sets.
    pub fn of_face_sets(n_sets: usize) -> Self {
        match n_sets {
            0 => ZkhClass::Cavity,
            1 => ZkhClass::Concavity,
            2 => ZkhClass::UnbranchedTunnel,
            _ => ZkhClass::BranchedTunnel,
        }
    }
}

/// One ZKH.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Zkh {
    /// Its label in [`ZkhAnalysis::labels`] (1-based).
    pub label: u32,
    /// Voxels.
    pub size: u64,
    /// Class by the number of face sets.
    pub class: ZkhClass,
    /// The incident faces (indices into the face list), grouped into
    /// edge-connected sets; each set ascending, sets by their first face.
    pub face_sets: Vec<Vec<usize>>,
}

/// All ZKHs of an object inside its hull.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ZkhAnalysis {
    /// One label per voxel of the box (x fastest): 0 = object or outside
    /// the hull, `c ≥ 1` = ZKH `c` (numbered in order of first voxel).
    pub labels: Vec<u32>,
    /// The ZKHs, `components[c − 1]` for label `c`.
    pub components: Vec<Zkh>,
}

/// Finds and classifies the ZKHs.
///
/// * `object`: one flag per voxel of `classification.bbox` (x fastest),
///   true for voxels of S;
/// * `classification`: the scan of the hull over that box (the box should
///   contain the hull, or components are cut at its border);
/// * `faces`: the hull faces, the same half-spaces that were scanned;
/// * `adjacency`: `adjacency[f]`, the faces sharing an edge with face `f`.
///
/// Errors: [`Error::Mismatch`] when lengths disagree,
/// [`Error::InvalidData`] when an adjacency index is out of range, and
/// what [`super::check_range`] refuses.
pub fn analyse(
    object: &[bool],
    classification: &Classification,
    faces: &[HalfSpace],
    adjacency: &[Vec<usize>],
) -> Result<ZkhAnalysis> {
    let bbox = classification.bbox;
    check_range(faces, &bbox)?;
    let n = bbox.n_voxels()?;
    if object.len() != n || classification.sides.len() != n {
        let found = if object.len() != n {
            object.len()
        } else {
            classification.sides.len()
        };
        return Err(Error::mismatch(
            "zkh: object flags and side codes (one per voxel of the box)",
            n,
            found,
        ));
    }
    if adjacency.len() != faces.len() {
        return Err(Error::mismatch(
            "zkh: adjacency lists (one per face)",
            faces.len(),
            adjacency.len(),
        ));
    }
    if let Some((f, &g)) = adjacency
        .iter()
        .enumerate()
        .find_map(|(f, a)| a.iter().find(|&&g| g >= faces.len()).map(|g| (f, g)))
    {
        return Err(Error::data(
            "zkh adjacency",
            "face",
            f,
            format!("neighbour {g} is not one of the {} faces", faces.len()),
        ));
    }
    let labelling = label_6_connected(bbox.dims, |i| {
        !object[i] && classification.sides[i] != Side::Outside as u8
    })?;
    let incident = incident_faces(
        &labelling.labels,
        labelling.n_components(),
        faces,
        classification,
    );
    let mut stamp = vec![u32::MAX; faces.len()];
    let components = labelling
        .sizes
        .iter()
        .zip(incident)
        .enumerate()
        .map(|(c, (&size, faces_c))| {
            let face_sets = edge_connected_sets(&faces_c, adjacency, &mut stamp, c as u32);
            Zkh {
                label: c as u32 + 1,
                size,
                class: ZkhClass::of_face_sets(face_sets.len()),
                face_sets,
            }
        })
        .collect();
    Ok(ZkhAnalysis {
        labels: labelling.labels,
        components,
    })
}

/// Per label `c` of `n_labels` (index `c − 1`), the ascending faces seen by or coplanar with
/// some corner of its voxels. Only corners not strictly inside the hull
/// are tested: per corner row, those outside the open interval of the row
/// and within one voxel of a closed voxel interval next to it.
fn incident_faces(
    labels: &[u32],
    n_labels: usize,
    faces: &[HalfSpace],
    classification: &Classification,
) -> Vec<Vec<usize>> {
    let bbox = classification.bbox;
    let [nx, ny, nz] = bbox.dims;
    if n_labels == 0 {
        return Vec::new();
    }
    let corner_dims = [nx + 1, ny + 1, nz + 1];
    let corner_open = lattice_rows(faces, None, bbox.origin, corner_dims, 0);
    let voxel_rows = lattice_rows(faces, None, bbox.origin, bbox.dims, 1);
    let label_at = |x: usize, y: usize, z: usize| labels[x + nx * (y + ny * z)];
    let mut pairs: Vec<(u32, u32)> = (0..=nz)
        .into_par_iter()
        .flat_map_iter(|cz| {
            let mut out = Vec::new();
            for cy in 0..=ny {
                // Closed voxel intervals of the (up to 4) rows around this corner row.
                let (mut lo, mut hi) = (i64::MAX, i64::MIN);
                for vz in cz.saturating_sub(1)..(cz + 1).min(nz) {
                    for vy in cy.saturating_sub(1)..(cy + 1).min(ny) {
                        let s = voxel_rows[vy + ny * vz];
                        if s[0] <= s[1] {
                            lo = lo.min(i64::from(s[0]));
                            hi = hi.max(i64::from(s[1]) + 1);
                        }
                    }
                }
                let open = corner_open[cy + (ny + 1) * cz];
                for cx in lo.max(0)..=hi.min(nx as i64) {
                    if i64::from(open[2]) <= cx && cx <= i64::from(open[3]) {
                        continue;
                    }
                    let cx = cx as usize;
                    let mut near = [0u32; 8];
                    let mut k = 0;
                    for vz in cz.saturating_sub(1)..(cz + 1).min(nz) {
                        for vy in cy.saturating_sub(1)..(cy + 1).min(ny) {
                            for vx in cx.saturating_sub(1)..(cx + 1).min(nx) {
                                let l = label_at(vx, vy, vz);
                                if l != 0 && !near[..k].contains(&l) {
                                    near[k] = l;
                                    k += 1;
                                }
                            }
                        }
                    }
                    if k == 0 {
                        continue;
                    }
                    let c = [cx, cy, cz].map(|v| v as i64);
                    let p = std::array::from_fn(|a| 2 * (bbox.origin[a] + c[a]));
                    for (f, face) in faces.iter().enumerate() {
                        if face.side(p) >= 0 {
                            out.extend(near[..k].iter().map(|&l| (l, f as u32)));
                        }
                    }
                }
            }
            out
        })
        .collect();
    pairs.par_sort_unstable();
    pairs.dedup();
    let mut per_label = vec![Vec::new(); n_labels];
    for (l, f) in pairs {
        per_label[l as usize - 1].push(f as usize);
    }
    per_label
}

/// Splits `members` (ascending face ids) into sets connected through
/// `adjacency` restricted to `members`, by flooding (§4.2.3). `stamp` marks
/// members with `key` (no clearing between calls with distinct keys).
fn edge_connected_sets(
    members: &[usize],
    adjacency: &[Vec<usize>],
    stamp: &mut [u32],
    key: u32,
) -> Vec<Vec<usize>> {
    const DONE: u32 = u32::MAX - 1;
    for &f in members {
        stamp[f] = key;
    }
    let mut sets = Vec::new();
    for &start in members {
        if stamp[start] != key {
            continue;
        }
        stamp[start] = DONE;
        let mut set = vec![start];
        let mut next = 0;
        while next < set.len() {
            let f = set[next];
            next += 1;
            for &g in &adjacency[f] {
                if stamp[g] == key {
                    stamp[g] = DONE;
                    set.push(g);
                }
            }
        }
        set.sort_unstable();
        sets.push(set);
    }
    for &f in members {
        stamp[f] = u32::MAX;
    }
    sets
}
