//! Candidate vectors for the vertices of the convex hull (seed §4.1.2–4.1.3).
//!
//! Every extreme point of S is a candidate of every kind, so the hull of the
//! candidates is the hull of S; the kinds differ only in how many non-extreme
//! points survive the local test.

use super::{DigitalObject, voxel_centre, voxel_corner};

/// How candidate vertices are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CandidateKind {
    /// Local corners over the 6-neighbourhood (3 symmetric pairs, §4.1.2).
    Local6,
    /// Local corners over the 18-neighbourhood (9 pairs).
    Local18,
    /// Local corners over the 26-neighbourhood (13 pairs; fewest candidates).
    Local26,
    /// Convex 3-cells (Def. KX3): voxels incident with a convex 0-cell.
    ConvexVoxels,
    /// Convex 0-cells (Def. KX0): hull vertices at cell corners.
    ConvexCorners,
}

/// One offset of each symmetric neighbour pair: 3 face, 6 edge, 4 vertex
/// neighbours.
const PAIRS: [[i64; 3]; 13] = [
    [1, 0, 0],
    [0, 1, 0],
    [0, 0, 1],
    [1, 1, 0],
    [1, -1, 0],
    [1, 0, 1],
    [1, 0, -1],
    [0, 1, 1],
    [0, 1, -1],
    [1, 1, 1],
    [1, 1, -1],
    [1, -1, 1],
    [1, -1, -1],
];

impl CandidateKind {
    /// Whether hull vertices are 0-cells (even coordinates) rather than voxel
    /// centres (odd).
    pub fn at_corners(self) -> bool {
        self == CandidateKind::ConvexCorners
    }
}

impl DigitalObject {
    /// Candidate vertices of CH(S) in combinatorial coordinates, sorted
    /// lexicographically (x, then y, then z), without duplicates.
    pub fn candidates(&self, kind: CandidateKind) -> Vec<[i64; 3]> {
        let (dims, mask, low) = self.raw();
        let [nx, ny, nz] = dims;
        let at = |l: [usize; 3]| -> [i64; 3] { std::array::from_fn(|a| low[a] + l[a] as i64) };
        let mut out = Vec::new();
        match kind {
            CandidateKind::Local6 | CandidateKind::Local18 | CandidateKind::Local26 => {
                let n_pairs = match kind {
                    CandidateKind::Local6 => 3,
                    CandidateKind::Local18 => 9,
                    _ => 13,
                };
                let steps: Vec<isize> = PAIRS[..n_pairs]
                    .iter()
                    .map(|d| (d[0] + nx as i64 * (d[1] + ny as i64 * d[2])) as isize)
                    .collect();
                for z in 1..nz - 1 {
                    for y in 1..ny - 1 {
                        for x in 1..nx - 1 {
                            let i = (x + nx * (y + ny * z)) as isize;
                            if !mask[i as usize] {
                                continue;
                            }
                            let inner = steps
                                .iter()
                                .any(|&s| mask[(i - s) as usize] && mask[(i + s) as usize]);
                            if !inner {
                                out.push(voxel_centre(at([x, y, z])));
                            }
                        }
                    }
                }
            }
            CandidateKind::ConvexVoxels | CandidateKind::ConvexCorners => {
                for z in 1..nz {
                    for y in 1..ny {
                        for x in 1..nx {
                            let m = self.octants(x, y, z);
                            if m == 0 || m == 255 || !super::topology::is_convex_vertex(m) {
                                continue;
                            }
                            if kind == CandidateKind::ConvexCorners {
                                out.push(voxel_corner(at([x, y, z])));
                                continue;
                            }
                            for o in 0..8 {
                                if m >> o & 1 == 1 {
                                    let l = [
                                        x - 1 + (o & 1),
                                        y - 1 + (o >> 1 & 1),
                                        z - 1 + (o >> 2 & 1),
                                    ];
                                    out.push(voxel_centre(at(l)));
                                }
                            }
                        }
                    }
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }
}
