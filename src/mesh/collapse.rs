//! Short-edge collapse: removes the slivers marching cubes leaves where the
//! surface passes close to a grid point (edges down to 2⁻¹⁰ of a voxel).
//!
//! Edges shorter than `min_length` are collapsed shortest first, each into
//! one vertex (Hoppe et al. 1993's edge collapse; the link condition of
//! Dey et al. 1999 keeps the topology):
//!
//! ```text
//!   a ●───● b   →   ● m      m = the midpoint, else a, else b (the
//!    ╱ ╲ ╱ ╲        ╱╲         first that passes the tests below); the
//!                               border vertex when only one end is on it
//! ```
//!
//! A collapse is refused, and its edge kept, when it would
//! - change the topology: N(a) ∩ N(b) must be exactly the apexes of the
//!   triangles on ab, and the merged neighbourhood must hold more than
//!   those apexes (so a tetrahedron or a lone triangle stays);
//! - pinch a border: an interior edge whose ends both lie on the border;
//! - touch a non-manifold vertex (on an edge of more than two triangles,
//!   or whose triangles form more than one fan);
//! - make a surviving triangle degenerate (flat as `Topology` counts it:
//!   height below `f32::EPSILON` times its longest edge), or turn it by
//!   more than [`MAX_TURN_DEGREES`] from both its old normal and the
//!   area-weighted normal of the two fans (the no-flip test of Hoppe et
//!   al.; a sliver's own normal is noise, so agreeing with its
//!   surroundings suffices).
//!
//! Manifold inputs stay manifold with the same Euler characteristic per
//! component and the same border loops; orientation is kept. A vertex
//! moves by less than `min_length` per collapse.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::Vec3;

use super::topology::is_flat;
use super::{ScalarField, TriMesh, self_intersections};

/// Most runs of the collapse (see [`collapse_short_edges`]).
pub const MAX_ROUNDS: usize = 8;

/// Largest turn of a surviving triangle's normal a collapse may cause
/// (against its old normal or its fans' mean normal).
pub const MAX_TURN_DEGREES: f32 = 45.0;

/// The collapsed mesh and what happened.
#[derive(Debug, Clone)]
pub struct Collapsed {
    /// Surviving vertices in input order, surviving triangles in input
    /// order; scalar fields keep the surviving vertex's value.
    pub mesh: TriMesh,
    /// Per input vertex: the output vertex it became (unused input
    /// vertices map to `u32::MAX`).
    pub vertex_map: Vec<u32>,
    /// Edges collapsed.
    pub collapsed: usize,
    /// Edges still shorter than `min_length` (collapses refused).
    pub short_edges_left: usize,
    /// Shortest edge before and after (0 for meshes without edges).
    pub min_edge_before: f32,
    pub min_edge_after: f32,
    /// Runs of the collapse (1 unless a run made triangles cross).
    pub rounds: usize,
    /// Triangle pairs of the result that meet beyond shared corners.
    pub crossing_pairs: usize,
}

/// Collapses the edges of `mesh` shorter than `min_length` (units of the
/// mesh); see the module docs. Duplicate-index triangles are dropped.
///
/// The result crosses itself in no more triangle pairs than `mesh`
/// (exact test, [`self_intersections`]): where a collapse made two
/// triangles meet, the collapse is run again with the input vertices that
/// became those triangles' corners kept, up to [`MAX_ROUNDS`] times; then
/// the remaining pairs are reported in [`Collapsed::crossing_pairs`].
pub fn collapse_short_edges(mesh: &TriMesh, min_length: f32) -> Collapsed {
    let allowed = self_intersections(mesh).pairs.len();
    let mut kept = vec![false; mesh.n_vertices()];
    let mut rounds = 0;
    loop {
        let mut out = collapse_once(mesh, min_length, &kept);
        rounds += 1;
        let pairs = self_intersections(&out.mesh).pairs;
        out.rounds = rounds;
        out.crossing_pairs = pairs.len();
        if pairs.len() <= allowed || rounds == MAX_ROUNDS {
            return out;
        }
        let mut corner = vec![false; out.mesh.n_vertices()];
        for [s, t] in pairs {
            for v in out.mesh.triangles[s as usize]
                .into_iter()
                .chain(out.mesh.triangles[t as usize])
            {
                corner[v as usize] = true;
            }
        }
        for (k, &v) in kept.iter_mut().zip(&out.vertex_map) {
            *k |= v != u32::MAX && corner[v as usize];
        }
    }
}

/// One run of the collapse, never moving or merging the `kept` vertices.
fn collapse_once(mesh: &TriMesh, min_length: f32, kept: &[bool]) -> Collapsed {
    let mut state = State::new(mesh, kept);
    let min_edge_before = state.min_edge();
    let mut heap = BinaryHeap::new();
    for t in 0..state.tris.len() {
        for k in 0..3 {
            let (a, b) = (state.tris[t][k], state.tris[t][(k + 1) % 3]);
            state.push_if_short(&mut heap, a.min(b), a.max(b), min_length);
        }
    }
    let mut collapsed = 0;
    while let Some(Reverse((bits, a, b))) = heap.pop() {
        if !state.live_v[a as usize]
            || !state.live_v[b as usize]
            || state.length(a, b).to_bits() != bits
        {
            continue;
        }
        if let Some(m) = state.collapse_point(a, b) {
            state.collapse(a, b, m);
            collapsed += 1;
            let survivor = a.min(b);
            for n in state.neighbours(survivor) {
                state.push_if_short(&mut heap, survivor.min(n), survivor.max(n), min_length);
            }
        }
    }
    state.finish(mesh, min_length, collapsed, min_edge_before)
}

/// Edge-collapse state: live triangles and the triangles of each vertex.
struct State {
    pos: Vec<Vec3>,
    tris: Vec<[u32; 3]>,
    live_t: Vec<bool>,
    live_v: Vec<bool>,
    /// Live triangles of each vertex.
    fan: Vec<Vec<u32>>,
    border: Vec<bool>,
    locked: Vec<bool>,
    /// Per input vertex: the vertex it was merged into (itself if live).
    merged_into: Vec<u32>,
}

type Entry = Reverse<(u32, u32, u32)>;

impl State {
    fn new(mesh: &TriMesh, kept: &[bool]) -> State {
        let n = mesh.n_vertices();
        let tris: Vec<[u32; 3]> = mesh
            .triangles
            .iter()
            .copied()
            .filter(|t| !super::topology::is_collapsed(t))
            .collect();
        let mut fan = vec![Vec::new(); n];
        for (t, tri) in tris.iter().enumerate() {
            for &v in tri {
                fan[v as usize].push(t as u32);
            }
        }
        let mut state = State {
            pos: mesh.positions.clone(),
            live_t: vec![true; tris.len()],
            live_v: fan.iter().map(|f| !f.is_empty()).collect(),
            tris,
            fan,
            border: vec![false; n],
            locked: vec![false; n],
            merged_into: (0..n as u32).collect(),
        };
        for v in 0..n as u32 {
            let (border, manifold) = state.classify(v);
            state.border[v as usize] = border;
            state.locked[v as usize] = !manifold || kept[v as usize];
        }
        state
    }

    /// (on the border, manifold) for vertex `v`: its link (the edges
    /// opposite `v` in its triangles) must be one cycle or one path.
    fn classify(&self, v: u32) -> (bool, bool) {
        let fan = &self.fan[v as usize];
        let mut link: Vec<(u32, u32)> = fan.iter().map(|&t| self.opposite(t, v)).collect();
        let mut ends: Vec<u32> = link.iter().flat_map(|&(x, y)| [x, y]).collect();
        ends.sort_unstable();
        let mut degree_ok = true;
        let mut odd = 0;
        for run in ends.chunk_by(|x, y| x == y) {
            match run.len() {
                1 => odd += 1,
                2 => {}
                _ => degree_ok = false,
            }
        }
        if !degree_ok || (odd != 0 && odd != 2) || link.is_empty() {
            return (odd != 0, false);
        }
        // One connected chain: walk it from an end (or anywhere on a cycle).
        let start = if odd == 2 {
            *ends
                .chunk_by(|x, y| x == y)
                .find(|r| r.len() == 1)
                .map(|r| &r[0])
                .expect("two odd ends")
        } else {
            link[0].0
        };
        let mut at = start;
        let mut walked = 0;
        while let Some(i) = link.iter().position(|&(x, y)| x == at || y == at) {
            let (x, y) = link.swap_remove(i);
            at = if x == at { y } else { x };
            walked += 1;
        }
        (odd == 2, walked == fan.len())
    }

    /// The other two corners of triangle `t`, in winding order after `v`.
    fn opposite(&self, t: u32, v: u32) -> (u32, u32) {
        let tri = self.tris[t as usize];
        let k = tri.iter().position(|&x| x == v).expect("v is a corner");
        (tri[(k + 1) % 3], tri[(k + 2) % 3])
    }

    fn length(&self, a: u32, b: u32) -> f32 {
        self.pos[a as usize].distance(self.pos[b as usize])
    }

    fn push_if_short(&self, heap: &mut BinaryHeap<Entry>, a: u32, b: u32, min_length: f32) {
        let len = self.length(a, b);
        if len < min_length {
            heap.push(Reverse((len.to_bits(), a, b)));
        }
    }

    /// Distinct neighbours of `v`, ascending.
    fn neighbours(&self, v: u32) -> Vec<u32> {
        let mut n: Vec<u32> = self.fan[v as usize]
            .iter()
            .flat_map(|&t| self.tris[t as usize])
            .filter(|&x| x != v)
            .collect();
        n.sort_unstable();
        n.dedup();
        n
    }

    fn min_edge(&self) -> f32 {
        (0..self.tris.len())
            .filter(|&t| self.live_t[t])
            .flat_map(|t| {
                let tri = self.tris[t];
                (0..3).map(move |k| (tri[k], tri[(k + 1) % 3]))
            })
            .map(|(a, b)| self.length(a, b))
            .fold(f32::INFINITY, f32::min)
    }

    /// Where `a` and `b` would merge, or `None` when the collapse is
    /// refused (module docs).
    fn collapse_point(&self, a: u32, b: u32) -> Option<Vec3> {
        let (ua, ub) = (a as usize, b as usize);
        if self.locked[ua] || self.locked[ub] {
            return None;
        }
        let shared: Vec<u32> = self.fan[ua]
            .iter()
            .copied()
            .filter(|t| self.tris[*t as usize].contains(&b))
            .collect();
        if shared.is_empty() || shared.len() > 2 {
            return None;
        }
        let mut apexes: Vec<u32> = shared
            .iter()
            .map(|&t| {
                let tri = self.tris[t as usize];
                tri.into_iter().find(|&x| x != a && x != b).expect("apex")
            })
            .collect();
        apexes.sort_unstable();
        let (na, nb) = (self.neighbours(a), self.neighbours(b));
        let common: Vec<u32> = na.iter().copied().filter(|x| nb.contains(x)).collect();
        let merged = na.iter().chain(&nb).filter(|&&x| x != a && x != b);
        let mut merged: Vec<u32> = merged.copied().collect();
        merged.sort_unstable();
        merged.dedup();
        if common != apexes || merged.len() <= apexes.len() {
            return None;
        }
        let border_edge = shared.len() == 1;
        let (pa, pb) = (self.pos[ua], self.pos[ub]);
        let mid = (pa + pb) * 0.5;
        let candidates: &[Vec3] = match (self.border[ua], self.border[ub]) {
            (true, true) if !border_edge => return None,
            (true, false) => &[pa],
            (false, true) => &[pb],
            _ => &[mid, pa, pb],
        };
        let cos_max = MAX_TURN_DEGREES.to_radians().cos();
        let normal = |q: [Vec3; 3]| (q[1] - q[0]).cross(q[2] - q[0]);
        let corners = |t: u32| self.tris[t as usize].map(|v| self.pos[v as usize]);
        let fans = || self.fan[ua].iter().chain(&self.fan[ub]);
        let mean = fans().map(|&t| normal(corners(t))).sum::<Vec3>();
        let turns_ok = |m: Vec3| {
            fans().filter(|t| !shared.contains(t)).all(|&t| {
                let tri = self.tris[t as usize];
                let q = tri.map(|v| {
                    if v == a || v == b {
                        m
                    } else {
                        self.pos[v as usize]
                    }
                });
                let (n0, n1) = (normal(corners(t)), normal(q));
                let agrees =
                    |n: Vec3| n != Vec3::ZERO && n1.dot(n) >= cos_max * n1.length() * n.length();
                !is_flat(q.map(Vec3::as_dvec3)) && (agrees(n0) || agrees(mean))
            })
        };
        candidates.iter().copied().find(|&m| turns_ok(m))
    }

    /// Merges `a` and `b` into the lower index at `m`.
    fn collapse(&mut self, a: u32, b: u32, m: Vec3) {
        let (keep, gone) = (a.min(b), a.max(b));
        let (uk, ug) = (keep as usize, gone as usize);
        for t in std::mem::take(&mut self.fan[ug]) {
            let tri = &mut self.tris[t as usize];
            if tri.contains(&keep) {
                self.live_t[t as usize] = false;
                for v in *tri {
                    self.fan[v as usize].retain(|&x| x != t);
                }
            } else {
                for v in tri.iter_mut() {
                    if *v == gone {
                        *v = keep;
                    }
                }
                self.fan[uk].push(t);
            }
        }
        self.pos[uk] = m;
        self.border[uk] |= self.border[ug];
        self.live_v[ug] = false;
        self.merged_into[ug] = keep;
    }

    fn finish(
        mut self,
        mesh: &TriMesh,
        min_length: f32,
        collapsed: usize,
        min_edge_before: f32,
    ) -> Collapsed {
        let n = self.pos.len();
        let kept: Vec<usize> = (0..n).filter(|&v| self.live_v[v]).collect();
        let mut new_id = vec![u32::MAX; n];
        for (k, &v) in kept.iter().enumerate() {
            new_id[v] = k as u32;
        }
        let vertex_map = (0..n)
            .map(|v| {
                let mut r = v;
                while self.merged_into[r] as usize != r {
                    r = self.merged_into[r] as usize;
                }
                self.merged_into[v] = r as u32;
                new_id[r]
            })
            .collect();
        let triangles: Vec<[u32; 3]> = (0..self.tris.len())
            .filter(|&t| self.live_t[t])
            .map(|t| self.tris[t].map(|v| new_id[v as usize]))
            .collect();
        let min_edge_after = self.min_edge();
        let mut short: Vec<(u32, u32)> = (0..self.tris.len())
            .filter(|&t| self.live_t[t])
            .flat_map(|t| {
                let tri = self.tris[t];
                (0..3).map(move |k| (tri[k].min(tri[(k + 1) % 3]), tri[k].max(tri[(k + 1) % 3])))
            })
            .filter(|&(a, b)| self.length(a, b) < min_length)
            .collect();
        short.sort_unstable();
        short.dedup();
        let short_edges_left = short.len();
        let out = TriMesh {
            positions: kept.iter().map(|&v| self.pos[v]).collect(),
            triangles,
            scalars: mesh
                .scalars
                .iter()
                .map(|s| ScalarField {
                    name: s.name.clone(),
                    values: kept.iter().map(|&v| s.values[v]).collect(),
                })
                .collect(),
        };
        let finite = |x: f32| if x.is_finite() { x } else { 0.0 };
        Collapsed {
            mesh: out,
            vertex_map,
            collapsed,
            short_edges_left,
            min_edge_before: finite(min_edge_before),
            min_edge_after: finite(min_edge_after),
            rounds: 1,
            crossing_pairs: 0,
        }
    }
}
