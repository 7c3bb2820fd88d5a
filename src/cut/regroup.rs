//! Regrouping into pieces: takes the split surface (unsplit input
//! triangles, sub-triangles per crossed triangle, caps, cut and cap points)
//! and returns the pieces, connected components numbered by their first
//! triangle, each an indexed mesh, with each piece's side evidence.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::Located;
use crate::TriMesh;
use crate::foundation::AtomicUnionFind;

/// A sub-triangle of the split, before regrouping.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sub {
    /// Vertex ids: `< n_v` original, else `n_v + cut id`.
    pub(crate) v: [u32; 3],
    /// Side for sub-triangles of a separating split; `None` when glued.
    pub(crate) side: Option<bool>,
}

/// Slots of the few keys (pieces) that runs of triangles mostly stay in:
/// the last hit, else a hash map.
#[derive(Default)]
struct Slots {
    last: Option<(u32, usize)>,
    map: HashMap<u32, usize>,
}

impl Slots {
    /// The slot of `key`, made by `new` the first time.
    #[inline(always)]
    fn get(&mut self, key: u32, new: impl FnOnce() -> usize) -> usize {
        if let Some((k, s)) = self.last
            && k == key
        {
            return s;
        }
        let s = *self.map.entry(key).or_insert_with(new);
        self.last = Some((key, s));
        s
    }
}

/// Input triangles per chunk of the parallel regrouping passes.
const REGROUP_CHUNK: usize = 1 << 16;

/// The cut surface to regroup into pieces: input triangles in id order
/// (split ones replaced by their sub-triangles), then the negative caps,
/// then the positive caps, as triangles of vertex nodes. Passes over it run
/// in parallel chunks of input triangles (the caps last), and its pieces
/// come out the same for any number of threads.
pub(super) struct Regroup<'a> {
    pub(super) mesh: &'a TriMesh,
    pub(super) located: &'a Located,
    pub(super) subs: &'a [Vec<Sub>],
    pub(super) glued: &'a [bool],
    pub(super) caps: &'a [[u32; 3]],
    /// Cut and cap points (vertex `n_v + i` is point i).
    pub(super) points: &'a [Vec3],
    /// Per input vertex, whether it lies on the negative side (analytic
    /// knives; empty for a triangulated knife).
    pub(super) negative: Vec<bool>,
    /// Per chunk its first input triangle and first crossed triangle (index
    /// into `located.triangles`), then the ends; the caps chunk follows.
    pub(super) bounds: Vec<(usize, usize)>,
}

/// One piece's share of a chunk: its root, triangles and side evidence
/// (negative, positive).
struct Tally {
    root: u32,
    triangles: usize,
    seen: (bool, bool),
}

/// A chunk's stretch of one piece's triangles: (piece, the part of that
/// piece's triangle array the chunk fills).
type Stretch<'t> = (usize, &'t mut [[u32; 3]]);

/// Where a kept triangle of the cut surface comes from.
#[derive(Clone, Copy)]
enum Origin {
    /// An unsplit input triangle.
    Unsplit,
    /// A sub-triangle or cap (vertex ids as in [`Sub`]) with its side.
    Sub([u32; 3], Option<bool>),
}

/// Per chunk of [`REGROUP_CHUNK`] input triangles, its first triangle and
/// first crossed triangle (index into the ascending `crossed`), then the ends.
pub(super) fn chunk_bounds(n_triangles: usize, crossed: &[u32]) -> Vec<(usize, usize)> {
    ((0..n_triangles).step_by(REGROUP_CHUNK).chain([n_triangles]))
        .map(|t| (t, crossed.partition_point(|&c| (c as usize) < t)))
        .collect()
}

impl Regroup<'_> {
    fn n_v(&self) -> u32 {
        self.mesh.positions.len() as u32
    }

    /// Vertex nodes: originals, then two copies per cut vertex (negative,
    /// positive); a glued cut vertex uses its negative copy on both sides.
    fn n_nodes(&self) -> usize {
        self.mesh.positions.len() + 2 * self.points.len()
    }

    /// The node of vertex `v` in a triangle of side `side`. A cut at mesh
    /// vertex `a` is `a` itself on a's side (and when glued), so the
    /// sub-triangles it flattens repeat a node and are dropped.
    fn node(&self, v: u32, side: Option<bool>) -> u32 {
        let n_v = self.n_v();
        if v < n_v {
            return v;
        }
        let c = (v - n_v) as usize;
        let glued = self.glued[c];
        if let Some(&(a, b)) = self.located.edges.get(c)
            && a == b
            && (glued || side == Some(self.located.lower_negative[c]))
        {
            return a;
        }
        n_v + 2 * c as u32 + u32::from(!glued && side == Some(false))
    }

    /// Chunks, the caps last.
    fn chunks(&self) -> std::ops::Range<usize> {
        0..self.bounds.len()
    }

    /// Every triangle of chunk `i` that is not flat, as vertex nodes, in
    /// output order.
    #[inline(always)]
    fn for_each_kept(&self, i: usize, mut f: impl FnMut([u32; 3], Origin)) {
        let flat = |k3: &[u32; 3]| k3[0] == k3[1] || k3[1] == k3[2] || k3[2] == k3[0];
        let sub = |v: [u32; 3], side: Option<bool>, f: &mut dyn FnMut([u32; 3], Origin)| {
            let k3 = v.map(|x| self.node(x, side));
            if !flat(&k3) {
                f(k3, Origin::Sub(v, side));
            }
        };
        if i + 1 == self.bounds.len() {
            for &c in self.caps {
                sub(c, Some(true), &mut f);
            }
            for &c in self.caps {
                sub([c[0], c[2], c[1]], Some(false), &mut f);
            }
            return;
        }
        let ((t0, c0), (t1, c1)) = (self.bounds[i], self.bounds[i + 1]);
        let mut next = t0;
        let crossed = self.located.triangles[c0..c1]
            .iter()
            .zip(&self.subs[c0..c1]);
        for (t, s) in crossed
            .map(|(&t, s)| (t as usize, &s[..]))
            .chain([(t1, &[][..])])
        {
            for k3 in self.mesh.triangles[next..t].iter().filter(|t| !flat(t)) {
                f(*k3, Origin::Unsplit);
            }
            for x in s {
                sub(x.v, x.side, &mut f);
            }
            next = t + 1;
        }
    }

    /// The pieces (connected components of the vertex nodes), numbered by
    /// their first triangle in output order, each with its vertices in
    /// node order (input vertices, then cut and cap points) and its
    /// triangles in output order; and per piece whether it holds triangles
    /// of the negative / positive side.
    pub(super) fn pieces(&self) -> (Vec<TriMesh>, Vec<(bool, bool)>) {
        let n_nodes = self.n_nodes();
        // Every triangle joins its vertices. Cut vertices separate because
        // each side uses its own copy; glued cut vertices have one copy and
        // join both sides.
        let uf = AtomicUnionFind::with_len(n_nodes);
        let used: Vec<AtomicBool> = (0..n_nodes)
            .into_par_iter()
            .map(|_| AtomicBool::new(false))
            .collect();
        self.chunks().into_par_iter().for_each(|i| {
            self.for_each_kept(i, |k3, _| {
                k3.iter()
                    .for_each(|&x| used[x as usize].store(true, Ordering::Relaxed));
                uf.union(k3[0], k3[1]);
                uf.union(k3[0], k3[2]);
            });
        });
        let root = uf.roots();
        // Per chunk, the roots of its pieces in order of first triangle, with
        // their triangle counts and side evidence; then, in chunk order, the
        // pieces numbered by first triangle and each chunk's share of each.
        let tallies: Vec<Vec<Tally>> = (self.chunks().into_par_iter())
            .map(|i| {
                let (mut slots, mut tally) = (Slots::default(), Vec::<Tally>::new());
                self.for_each_kept(i, |k3, origin| {
                    let root = root[k3[0] as usize];
                    let s = slots.get(root, || {
                        tally.push(Tally {
                            root,
                            triangles: 0,
                            seen: (false, false),
                        });
                        tally.len() - 1
                    });
                    let (e, t) = (self.evidence(k3, origin), &mut tally[s]);
                    t.triangles += 1;
                    t.seen = (t.seen.0 | e.0, t.seen.1 | e.1);
                });
                tally
            })
            .collect();
        let mut piece_of_root = vec![u32::MAX; n_nodes];
        let (mut n_triangles, mut sides) = (Vec::<usize>::new(), Vec::<(bool, bool)>::new());
        let chunk_pieces: Vec<Vec<(usize, usize)>> = (tallies.into_iter())
            .map(|tally| {
                (tally.into_iter())
                    .map(|t| {
                        let p = &mut piece_of_root[t.root as usize];
                        if *p == u32::MAX {
                            *p = n_triangles.len() as u32;
                            n_triangles.push(0);
                            sides.push((false, false));
                        }
                        let p = *p as usize;
                        n_triangles[p] += t.triangles;
                        sides[p] = (sides[p].0 | t.seen.0, sides[p].1 | t.seen.1);
                        (p, t.triangles)
                    })
                    .collect()
            })
            .collect();
        // Vertices in node order; every node belongs to exactly one piece
        // (all triangles using it were united), so one node → local index
        // table serves all pieces.
        let n_v = self.n_v();
        let mut positions: Vec<Vec<Vec3>> = (n_triangles.iter())
            .map(|&n| Vec::with_capacity(n / 2 + 64))
            .collect();
        let mut local = vec![0u32; n_nodes];
        for (x, slot) in local.iter_mut().enumerate() {
            if used[x].load(Ordering::Relaxed) {
                let p = &mut positions[piece_of_root[root[x] as usize] as usize];
                *slot = p.len() as u32;
                p.push(if (x as u32) < n_v {
                    self.mesh.positions[x]
                } else {
                    self.points[(x - n_v as usize) / 2]
                });
            }
        }
        // Triangles: each chunk writes its stretch of each of its pieces.
        let mut triangles: Vec<Vec<[u32; 3]>> =
            (n_triangles.iter()).map(|&n| vec![[0; 3]; n]).collect();
        let mut rest: Vec<&mut [[u32; 3]]> = triangles.iter_mut().map(|t| &mut t[..]).collect();
        let stretches: Vec<Vec<Stretch<'_>>> = (chunk_pieces.iter())
            .map(|pieces| {
                (pieces.iter())
                    .map(|&(p, n)| {
                        let (mine, after) = std::mem::take(&mut rest[p]).split_at_mut(n);
                        rest[p] = after;
                        (p, mine)
                    })
                    .collect()
            })
            .collect();
        (self.chunks().into_par_iter().zip(stretches)).for_each(|(i, mut stretches)| {
            let mut slots = Slots::default();
            let mut filled = vec![0; stretches.len()];
            self.for_each_kept(i, |k3, _| {
                let p = piece_of_root[root[k3[0] as usize] as usize] as usize;
                let s = slots.get(p as u32, || {
                    (stretches.iter().position(|(q, _)| *q == p))
                        .expect("each piece of a chunk has its stretch")
                });
                stretches[s].1[filled[s]] = k3.map(|x| local[x as usize]);
                filled[s] += 1;
            });
        });
        let pieces = (positions.into_iter().zip(triangles))
            .map(|(positions, triangles)| TriMesh {
                positions,
                triangles,
                scalars: Vec::new(),
            })
            .collect();
        (pieces, sides)
    }

    /// The side evidence (negative, positive) of a kept triangle `k3`.
    fn evidence(&self, k3: [u32; 3], origin: Origin) -> (bool, bool) {
        let of = |neg: Option<bool>| neg.map_or((false, false), |n| (n, !n));
        let n_v = self.n_v();
        match origin {
            // Unsplit triangles of a triangulated knife say nothing about
            // their side.
            Origin::Unsplit => of(self.negative.get(k3[0] as usize).copied()),
            // Glued sub-triangles (an open knife or a rectangle's border
            // ends there) touch both sides.
            Origin::Sub(v, None) if v.iter().any(|&x| x >= n_v) => (true, true),
            Origin::Sub(_, Some(n)) => of(Some(n)),
            Origin::Sub(v, None) => {
                let first = v.iter().find(|&&x| x < n_v);
                of(first.and_then(|&x| self.negative.get(x as usize).copied()))
            }
        }
    }
}
