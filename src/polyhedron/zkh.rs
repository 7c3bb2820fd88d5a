//! Background components inside the convex hull (ZKH, seed §4.2.1) and
//! their classification (Def. CO, CA, TU; §4.2.3).
//!
//! A background voxel is inside CH(S) when its centre satisfies every
//! half-space (`s ≤ 0`: voxels on the hull count, which is what the seed's
//! counts in Table 8.6 need). Inside voxels are split into 6-connected
//! components. A component's 0-cells (voxel corners) decide which hull faces
//! it touches: faces visible from some 0-cell (`s > 0`); if there are none,
//! faces coplanar with some 0-cell (`s = 0`, "coplanar contact counts as a
//! concavity"). The touched faces are split into edge-connected sets:
//! 0 sets → cavity, 1 → concavity, 2 → tunnel, more → branched tunnel.
//!
//! The inside test is the exact per-row method of [`crate::hull_scan`] on the
//! CPU (bit for bit the brute-force classification).

use std::collections::HashMap;

use crate::hull::ConvexHull;
use crate::volume::analysis::label_6_connected;
use crate::voxel::{DigitalObject, voxel_centre};

/// Kind of a ZKH by the number of edge-connected sets of hull faces it
/// touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ZkhClass {
    /// No face touched (Def. CA): a hole enclosed by S.
    Cavity,
    /// One set (Def. CO).
    Concavity,
    /// Two sets (Def. TU, unbranched).
    Tunnel,
    /// More than two sets (Def. TU, branched).
    BranchedTunnel,
}

/// One background component inside the hull.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Zkh {
    /// Number of voxels.
    pub voxels: u64,
    /// Classification.
    pub class: ZkhClass,
    /// The touched hull faces (indices into [`ConvexHull::faces`]), one
    /// sorted list per edge-connected set, sets ordered by first face.
    pub face_sets: Vec<Vec<u32>>,
    /// Inclusive voxel-index bounding box (source volume indices).
    pub bbox: ([i64; 3], [i64; 3]),
    /// The component as a digital object S' in the source volume's frame
    /// (roles swapped: its voxels are background voxels of S), ready for
    /// its own hull CH(S') (§4.4).
    #[serde(skip)]
    pub object: DigitalObject,
}

/// The ZKHs of `object` inside `hull` (a hull of the object's voxels), in
/// order of their first voxel (x fastest within the hull's bounding box).
///
/// Errors: [`crate::Refusal::Flat`] when the hull is flat (no inside),
/// [`crate::Error::Limit`] when the bounding box is too large to label.
pub fn background_components(object: &DigitalObject, hull: &ConvexHull) -> crate::Result<Vec<Zkh>> {
    if hull.is_planar() {
        return Err(crate::Refusal::Flat { what: "the hull" }.into());
    }
    let hs = hull.half_spaces();
    let (lo, hi) = hull.voxel_bbox();
    let dims: [usize; 3] = std::array::from_fn(|a| (hi[a] - lo[a] + 1).max(0) as usize);
    let at = |x: usize, y: usize, z: usize| [lo[0] + x as i64, lo[1] + y as i64, lo[2] + z as i64];
    let bbox = crate::hull_scan::VoxelBox { origin: lo, dims };
    let sides = hull
        .row_spans(&bbox, crate::gpu::Backend::Cpu)?
        .to_classification()?;
    let mut inside = Vec::with_capacity(dims.iter().product());
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let k = inside.len();
                inside.push(sides.in_closed_hull(k) && !object.contains(at(x, y, z)));
            }
        }
    }
    let lab = label_6_connected(dims, |i| inside[i])?;
    let n = lab.n_components();
    // Per component: bbox and the faces its 0-cells see / touch.
    let mut bbox = vec![([i64::MAX; 3], [i64::MIN; 3]); n];
    let reach: Vec<i64> = hs
        .iter()
        .map(|h| h.normal.iter().map(|c| c.abs()).sum())
        .collect();
    let mut visible: Vec<Vec<bool>> = vec![vec![false; hs.len()]; n];
    let mut coplanar: Vec<Vec<bool>> = vec![vec![false; hs.len()]; n];
    let label = |x: i64, y: i64, z: i64| -> u32 {
        if x < 0
            || y < 0
            || z < 0
            || x >= dims[0] as i64
            || y >= dims[1] as i64
            || z >= dims[2] as i64
        {
            return 0;
        }
        lab.labels[x as usize + dims[0] * (y as usize + dims[1] * z as usize)]
    };
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let l = label(x as i64, y as i64, z as i64);
                if l == 0 {
                    continue;
                }
                let c = (l - 1) as usize;
                let v = at(x, y, z);
                for (a, &va) in v.iter().enumerate() {
                    bbox[c].0[a] = bbox[c].0[a].min(va);
                    bbox[c].1[a] = bbox[c].1[a].max(va);
                }
                // A corner shared by 8 voxels of the component is a convex
                // combination of their centres: inside, nothing to learn.
                let (xi, yi, zi) = (x as i64, y as i64, z as i64);
                let interior = (-1..=1).all(|dz| {
                    (-1..=1).all(|dy| (-1..=1).all(|dx| label(xi + dx, yi + dy, zi + dz) == l))
                });
                if interior {
                    continue;
                }
                // Corners are the centre ± 1 per axis (combinatorial), so
                // a corner's side is the centre's plus Σ ±n_a: one product
                // per face, and the eight sums only near the plane.
                let centre = voxel_centre(v);
                for (f, h) in hs.iter().enumerate() {
                    let s = h.side(centre);
                    if s + reach[f] < 0 {
                        continue;
                    }
                    for o in 0..8i64 {
                        let d = [o & 1, o >> 1 & 1, o >> 2 & 1].map(|b| 2 * b - 1);
                        match s + h.normal[0] * d[0] + h.normal[1] * d[1] + h.normal[2] * d[2] {
                            t if t > 0 => visible[c][f] = true,
                            0 => coplanar[c][f] = true,
                            _ => {}
                        }
                    }
                }
            }
        }
    }
    let adjacency = face_adjacency(hull);
    let mut out = Vec::with_capacity(n);
    for c in 0..n {
        let (blo, bhi) = bbox[c];
        let bdims: [usize; 3] = std::array::from_fn(|a| (bhi[a] - blo[a] + 1) as usize);
        let mut mask = Vec::with_capacity(bdims.iter().product());
        for z in blo[2]..=bhi[2] {
            for y in blo[1]..=bhi[1] {
                for x in blo[0]..=bhi[0] {
                    mask.push(label(x - lo[0], y - lo[1], z - lo[2]) == c as u32 + 1);
                }
            }
        }
        let sub_object = DigitalObject::from_mask(bdims, &mask, object.frame())?.shifted(blo);
        let touched = if visible[c].iter().any(|&b| b) {
            &visible[c]
        } else {
            &coplanar[c]
        };
        let face_sets = edge_connected_sets(touched, &adjacency);
        let class = match face_sets.len() {
            0 => ZkhClass::Cavity,
            1 => ZkhClass::Concavity,
            2 => ZkhClass::Tunnel,
            _ => ZkhClass::BranchedTunnel,
        };
        out.push(Zkh {
            voxels: lab.sizes[c],
            class,
            face_sets,
            bbox: bbox[c],
            object: sub_object,
        });
    }
    Ok(out)
}

/// For every face, the faces sharing an edge with it.
fn face_adjacency(hull: &ConvexHull) -> Vec<Vec<u32>> {
    let mut by_edge: HashMap<(u32, u32), u32> = HashMap::new();
    for (f, face) in hull.faces().iter().enumerate() {
        let k = face.vertices.len();
        for j in 0..k {
            by_edge.insert((face.vertices[j], face.vertices[(j + 1) % k]), f as u32);
        }
    }
    hull.faces()
        .iter()
        .map(|face| {
            let k = face.vertices.len();
            (0..k)
                .filter_map(|j| {
                    by_edge
                        .get(&(face.vertices[(j + 1) % k], face.vertices[j]))
                        .copied()
                })
                .collect()
        })
        .collect()
}

/// Edge-connected components of the flagged faces, each sorted.
fn edge_connected_sets(flagged: &[bool], adjacency: &[Vec<u32>]) -> Vec<Vec<u32>> {
    let mut seen = vec![false; flagged.len()];
    let mut sets = Vec::new();
    for start in 0..flagged.len() {
        if !flagged[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        let mut set = vec![start as u32];
        let mut k = 0;
        while k < set.len() {
            for &g in &adjacency[set[k] as usize] {
                if flagged[g as usize] && !seen[g as usize] {
                    seen[g as usize] = true;
                    set.push(g);
                }
            }
            k += 1;
        }
        set.sort_unstable();
        sets.push(set);
    }
    sets
}
