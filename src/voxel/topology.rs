//! The boundary complex ∂S of a digital object: cell counts, Euler
//! characteristic, genus (eq. 4.3), Lhuilier's counts of cavities and tunnels
//! (eq. 4.4), relevant cells (Def. RZ0–RZ1, KX0–KX1, KV0, SP0) and
//! non-manifold configurations.
//!
//! Non-manifold policy: where two voxels of S meet only along an edge (the
//! four voxels around a 1-cell alternate S, B, S, B) or only at a vertex, ∂S
//! is not a 2-manifold. Such cells are counted
//! ([`BoundaryTopology::non_manifold_edges`],
//! [`BoundaryTopology::non_manifold_vertices`]) and the boundary is *opened*
//! there: a pinched 1-cell counts as two edges, each bounding the two facets
//! of one voxel of S, and a 0-cell counts once per cycle of its link. This is
//! the boundary of S taken as the 6-connected set it is (strong connectivity,
//! §3.1) — every count below refers to that closed, orientable 2-manifold.

use std::sync::OnceLock;

use super::DigitalObject;
use crate::foundation::UnionFind;
use crate::volume::analysis::label_6_connected;

/// Counts of ∂S (opened at non-manifold cells, see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct BoundaryTopology {
    /// 0-cells of ∂S (n0).
    pub n0: u64,
    /// 1-cells of ∂S (n1).
    pub n1: u64,
    /// 2-cells of ∂S, the boundary facets (n2).
    pub n2: u64,
    /// Euler characteristic n0 − n1 + n2.
    pub euler: i64,
    /// Genus by eq. 4.3, g = 1 − (n0 − n1 + n2)/2, over the whole boundary
    /// (cavities make it smaller, the seed's cube with a cavity gives −1).
    pub genus: i64,
    /// Connected components of ∂S (closed surfaces).
    pub shells: u64,
    /// 6-connected components of S.
    pub components: u64,
    /// Cavities (bubbles) b = shells − components.
    pub cavities: u64,
    /// Tunnels t from Lhuilier's eq. 4.4 with p = 0:
    /// n0 − n1 + n2 = 2(b − t + components).
    pub tunnels: i64,
    /// Relevant 1-cells (Def. RZ1) bounding exactly one voxel of S (KX1).
    pub convex_edges: u64,
    /// Relevant 1-cells bounding exactly one background voxel (KX1).
    pub concave_edges: u64,
    /// Convex relevant 0-cells (KX0).
    pub convex_vertices: u64,
    /// Concave relevant 0-cells (KV0).
    pub concave_vertices: u64,
    /// Saddle points (SP0): relevant 0-cells that are neither.
    pub saddle_vertices: u64,
    /// 1-cells where S meets itself only along the edge (doubled).
    pub non_manifold_edges: u64,
    /// 0-cells whose link in ∂S has more than one cycle (split).
    pub non_manifold_vertices: u64,
}

/// Octant bit of voxel offset `(dx, dy, dz) ∈ {0,1}³` around a 0-cell.
fn bit(d: [usize; 3]) -> usize {
    d[0] | d[1] << 1 | d[2] << 2
}

/// The four octants around half-edge `(axis, dir)` of a vertex, in cyclic order.
fn around(axis: usize, dir: usize) -> [usize; 4] {
    let (q, r) = ((axis + 1) % 3, (axis + 2) % 3);
    [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(bq, br)| {
        let mut d = [0; 3];
        d[axis] = dir;
        d[q] = bq;
        d[r] = br;
        bit(d)
    })
}

/// Per 8-octant configuration around a 0-cell: number of cycles of its link
/// in the opened ∂S, and its relevant-cell class.
#[derive(Clone, Copy, Default)]
struct VertexClass {
    cycles: u8,
    convex_edges: u8,
    concave_edges: u8,
    relevant_edges: u8,
}

fn vertex_table() -> &'static [VertexClass; 256] {
    static TABLE: OnceLock<[VertexClass; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut t = [VertexClass::default(); 256];
        for (m, class) in t.iter_mut().enumerate() {
            let in_s = |o: usize| m >> o & 1 == 1;
            // Link nodes: (half-edge, S octant or 8 for "whole edge").
            let mut links = UnionFind::<usize>::with_len(6 * 9);
            let node = |axis: usize, dir: usize, s_oct: usize| {
                let ring = around(axis, dir);
                let n_s = ring.iter().filter(|&&o| in_s(o)).count();
                let diagonal = n_s == 2 && in_s(ring[0]) == in_s(ring[2]);
                (axis * 2 + dir) * 9 + if diagonal { s_oct } else { 8 }
            };
            let mut used = Vec::new();
            for a in 0..8usize {
                for k in 0..3 {
                    let b = a ^ (1 << k);
                    if a > b || in_s(a) == in_s(b) {
                        continue;
                    }
                    let s_oct = if in_s(a) { a } else { b };
                    let (p, q) = ((k + 1) % 3, (k + 2) % 3);
                    let n1 = node(p, a >> p & 1, s_oct);
                    let n2 = node(q, a >> q & 1, s_oct);
                    used.extend([n1, n2]);
                    links.union(n1, n2);
                }
            }
            used.sort_unstable();
            used.dedup();
            let mut roots: Vec<usize> = used.iter().map(|&n| links.find(n)).collect();
            roots.sort_unstable();
            roots.dedup();
            class.cycles = roots.len() as u8;
            for axis in 0..3 {
                for dir in 0..2 {
                    let n_s = around(axis, dir).iter().filter(|&&o| in_s(o)).count();
                    class.convex_edges += u8::from(n_s == 1);
                    class.concave_edges += u8::from(n_s == 3);
                }
            }
            class.relevant_edges = class.convex_edges + class.concave_edges;
        }
        t
    })
}

/// Whether the 0-cell with octant mask `m` is convex with respect to S (Def.
/// KX0: relevant, bounding exactly three convex 1-cells).
pub(crate) fn is_convex_vertex(m: u8) -> bool {
    let c = vertex_table()[m as usize];
    c.relevant_edges >= 3 && c.convex_edges == 3
}

impl DigitalObject {
    /// Octant mask of the 0-cell at local corner `(x, y, z)` (touching local
    /// voxels `x−1..=x` etc.; `1 ≤ x < dims[0]`).
    pub(crate) fn octants(&self, x: usize, y: usize, z: usize) -> u8 {
        let (dims, mask, _) = self.raw();
        let mut m = 0u8;
        for dz in 0..2 {
            for dy in 0..2 {
                let row = dims[0] * (y - 1 + dy + dims[1] * (z - 1 + dz));
                for dx in 0..2 {
                    m |= u8::from(mask[row + x - 1 + dx]) << bit([dx, dy, dz]);
                }
            }
        }
        m
    }

    /// Counts of the boundary complex ∂S (see the module docs for the
    /// non-manifold policy). Linear in the bounding box.
    pub fn topology(&self) -> crate::Result<BoundaryTopology> {
        let (dims, mask, _) = self.raw();
        let [nx, ny, nz] = dims;
        let strides = [1, nx, nx * ny];
        let table = vertex_table();
        let mut t = BoundaryTopology {
            n0: 0,
            n1: 0,
            n2: 0,
            euler: 0,
            genus: 0,
            shells: 0,
            components: 0,
            cavities: 0,
            tunnels: 0,
            convex_edges: 0,
            concave_edges: 0,
            convex_vertices: 0,
            concave_vertices: 0,
            saddle_vertices: 0,
            non_manifold_edges: 0,
            non_manifold_vertices: 0,
        };
        for z in 1..nz {
            for y in 1..ny {
                for x in 1..nx {
                    let m = self.octants(x, y, z);
                    if m == 0 || m == 255 {
                        continue;
                    }
                    let c = table[m as usize];
                    t.n0 += u64::from(c.cycles);
                    t.non_manifold_vertices += u64::from(c.cycles > 1);
                    if c.relevant_edges >= 3 {
                        if c.convex_edges == 3 {
                            t.convex_vertices += 1;
                        } else if c.concave_edges == 3 {
                            t.concave_vertices += 1;
                        } else {
                            t.saddle_vertices += 1;
                        }
                    }
                }
            }
        }
        // Boundary facets, indexed 3·(lower voxel) + axis, ascending.
        let mut facets: Vec<u64> = Vec::new();
        for i in 0..mask.len() {
            for (k, s) in strides.iter().enumerate() {
                if i + s < mask.len() && mask[i] != mask[i + s] {
                    facets.push(3 * i as u64 + k as u64);
                }
            }
        }
        t.n2 = facets.len() as u64;
        let mut uf = UnionFind::<u32>::with_len(facets.len());
        let facet_id = |a: usize, b: usize, k: usize| -> u32 {
            let key = 3 * a.min(b) as u64 + k as u64;
            facets.binary_search(&key).map_or(u32::MAX, |i| i as u32)
        };
        // 1-cells along axis k: the four voxels around, in cyclic order.
        for k in 0..3 {
            let (q, r) = ((k + 1) % 3, (k + 2) % 3);
            let (sq, sr) = (strides[q], strides[r]);
            for z in 0..nz {
                for y in 0..ny {
                    for x in 0..nx {
                        let p = [x, y, z];
                        if p[q] == 0 || p[r] == 0 {
                            continue;
                        }
                        let base = x + nx * (y + ny * z) - sq - sr;
                        let ring = [base, base + sq, base + sq + sr, base + sr];
                        let axes = [q, r, q, r];
                        let s = ring.map(|v| mask[v]);
                        let trans = (0..4).filter(|&j| s[j] != s[(j + 1) % 4]).count();
                        if trans == 0 {
                            continue;
                        }
                        t.n1 += trans as u64 / 2;
                        let f = |j: usize| facet_id(ring[j], ring[(j + 1) % 4], axes[j]);
                        let n_s = s.iter().filter(|&&b| b).count();
                        t.convex_edges += u64::from(n_s == 1);
                        t.concave_edges += u64::from(n_s == 3);
                        if trans == 2 {
                            let both: Vec<u32> =
                                (0..4).filter(|&j| s[j] != s[(j + 1) % 4]).map(f).collect();
                            uf.union(both[0], both[1]);
                        } else {
                            t.non_manifold_edges += 1;
                            for j in (0..4).filter(|&j| s[j]) {
                                uf.union(f((j + 3) % 4), f(j));
                            }
                        }
                    }
                }
            }
        }
        let mut roots: Vec<u32> = (0..facets.len() as u32).map(|i| uf.find(i)).collect();
        roots.sort_unstable();
        roots.dedup();
        t.shells = roots.len() as u64;
        t.components = label_6_connected(dims, |i| mask[i])?.n_components() as u64;
        t.euler = t.n0 as i64 - t.n1 as i64 + t.n2 as i64;
        t.genus = 1 - t.euler / 2;
        t.cavities = t.shells.saturating_sub(t.components);
        t.tunnels = t.cavities as i64 + t.components as i64 - t.euler / 2;
        Ok(t)
    }
}
