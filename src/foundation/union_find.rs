//! Union-find (disjoint sets) whose representative is always the smallest
//! member of its set: one sequential and one concurrent form, and the
//! connected components of a triangle soup built on them.
//!
//! Linking the larger root under the smaller one makes the representative
//! deterministic and meaningful ("the first element of the set"): component
//! numberings (mesh topology, volume components, marching-cubes groups, cut
//! pieces) rely on it, and the concurrent form gives the same roots as the
//! sequential one whatever the thread schedule. Path halving keeps `find`
//! amortised O(log n) (Tarjan & van Leeuwen 1984); no recursion.

use std::sync::atomic::{AtomicU32, Ordering};

use rayon::prelude::*;

/// An element index of a [`UnionFind`]: `u32` where the elements are mesh
/// vertices or triangles (4 bytes a node), `usize` where they may exceed it.
pub trait Node: Copy + Ord + Send + Sync + std::fmt::Debug {
    /// The element as a slice index.
    fn index(self) -> usize;
    /// The element at slice index `i` (`i` below the forest's length, which
    /// the constructors bound by the type).
    fn at(i: usize) -> Self;
}

impl Node for u32 {
    fn index(self) -> usize {
        self as usize
    }
    fn at(i: usize) -> Self {
        i as u32
    }
}

impl Node for usize {
    fn index(self) -> usize {
        self
    }
    fn at(i: usize) -> Self {
        i
    }
}

/// Sequential union-find over `0..len`; each set's root is its smallest
/// member.
#[derive(Debug, Clone)]
pub struct UnionFind<N: Node = u32> {
    parent: Vec<N>,
}

impl<N: Node> Default for UnionFind<N> {
    fn default() -> Self {
        UnionFind { parent: Vec::new() }
    }
}

impl<N: Node> UnionFind<N> {
    /// `n` singletons.
    pub fn with_len(n: usize) -> Self {
        UnionFind {
            parent: (0..n).map(N::at).collect(),
        }
    }

    /// A new singleton; returns its id.
    pub fn push(&mut self) -> N {
        let id = N::at(self.parent.len());
        self.parent.push(id);
        id
    }

    /// Appends `other`'s sets as they are, its node `i` becoming node
    /// `self.len() + i` (stitching forests built apart, e.g. per chunk).
    pub fn append(&mut self, other: &UnionFind<N>) {
        let base = self.parent.len();
        (self.parent).extend(other.parent.iter().map(|p| N::at(base + p.index())));
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.parent.len()
    }

    /// Whether there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.parent.is_empty()
    }

    /// The smallest member of the set containing `x`.
    pub fn find(&mut self, mut x: N) -> N {
        while self.parent[x.index()] != x {
            let grand = self.parent[self.parent[x.index()].index()];
            self.parent[x.index()] = grand;
            x = grand;
        }
        x
    }

    /// Merges the sets of `a` and `b`; returns the root of the union.
    pub fn union(&mut self, a: N, b: N) -> N {
        let (ra, rb) = (self.find(a), self.find(b));
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        self.parent[hi.index()] = lo;
        lo
    }

    /// Whether `x` is the root (smallest member) of its set.
    pub fn is_root(&self, x: N) -> bool {
        self.parent[x.index()] == x
    }

    /// The root of every node, consuming the forest: one ascending pass,
    /// since a node's parent never has a higher id (a union links the higher
    /// root under the lower, halving keeps ancestors).
    pub fn roots(mut self) -> Vec<N> {
        for x in 0..self.parent.len() {
            let p = self.parent[x].index();
            self.parent[x] = self.parent[p];
        }
        self.parent
    }
}

/// Union-find that threads share: a union links the higher root under
/// the lower by compare-and-swap, so each set's root is its smallest node
/// whatever the order of the unions (the same roots as [`UnionFind`]).
#[derive(Debug)]
pub struct AtomicUnionFind {
    parent: Vec<AtomicU32>,
}

impl AtomicUnionFind {
    /// `n` singletons (`n` ≤ 2³², node ids are `u32`).
    pub fn with_len(n: usize) -> Self {
        AtomicUnionFind {
            parent: (0..n as u32).into_par_iter().map(AtomicU32::new).collect(),
        }
    }

    /// Root of `x`, halving the path: each step points a non-root at its
    /// grandparent with a plain store. Only roots are ever linked (by
    /// [`AtomicUnionFind::union`]'s compare-and-swap), and an ancestor stays
    /// an ancestor, so a store racing another halving or a link still
    /// leaves every node under an ancestor.
    pub fn find(&self, mut x: u32) -> u32 {
        let parent = &self.parent;
        loop {
            let p = parent[x as usize].load(Ordering::Acquire);
            if p == x {
                return x;
            }
            let g = parent[p as usize].load(Ordering::Acquire);
            if g != p {
                parent[x as usize].store(g, Ordering::Release);
            }
            x = g;
        }
    }

    /// Joins the sets of `a` and `b`: the larger root is linked under the
    /// smaller one only while it is still a root, else the roots are looked
    /// up again.
    pub fn union(&self, a: u32, b: u32) {
        loop {
            let (ra, rb) = (self.find(a), self.find(b));
            if ra == rb {
                return;
            }
            let (lo, hi) = (ra.min(rb), ra.max(rb));
            if self.parent[hi as usize]
                .compare_exchange(hi, lo, Ordering::AcqRel, Ordering::Acquire)
                .is_ok()
            {
                return;
            }
        }
    }

    /// The root of every node, consuming the forest (see [`UnionFind::roots`]).
    pub fn roots(self) -> Vec<u32> {
        UnionFind {
            parent: self.parent.into_iter().map(AtomicU32::into_inner).collect(),
        }
        .roots()
    }

    /// The node array, for reuse as scratch space.
    pub fn into_inner(self) -> Vec<AtomicU32> {
        self.parent
    }
}

/// Connected components of a triangle soup by shared vertices: per triangle
/// its group, groups numbered in the order of their first triangle; and the
/// number of groups.
///
/// In parallel and deterministic: the concurrent union-find roots every
/// component at its smallest vertex whatever the schedule; then each root's
/// first triangle is found (atomic minimum) and the groups are numbered in
/// the order of those first triangles (a chunked prefix count).
pub fn vertex_components(n_vertices: usize, triangles: &[[u32; 3]]) -> (Vec<u32>, usize) {
    let uf = AtomicUnionFind::with_len(n_vertices);
    triangles.par_iter().with_min_len(1 << 12).for_each(|t| {
        uf.union(t[0], t[1]);
        uf.union(t[0], t[2]);
    });
    let roots: Vec<u32> = (triangles.par_iter().with_min_len(1 << 12))
        .map(|t| uf.find(t[0]))
        .collect();
    // First triangle of each root (u32::MAX: not a root of any triangle).
    let first = uf.into_inner();
    first
        .par_iter()
        .for_each(|f| f.store(u32::MAX, Ordering::Relaxed));
    // Within a task triangles ascend, so after a root's first one there the
    // plain load already says "not smaller" (few read-modify-writes).
    (roots.par_iter().enumerate().with_min_len(1 << 12)).for_each(|(t, &r)| {
        let f = &first[r as usize];
        if f.load(Ordering::Relaxed) > t as u32 {
            f.fetch_min(t as u32, Ordering::Relaxed);
        }
    });
    let is_first = |t: usize, r: u32| first[r as usize].load(Ordering::Relaxed) == t as u32;
    const CHUNK: usize = 1 << 14;
    let counts: Vec<u32> = roots
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(c, rs)| {
            (rs.iter().enumerate())
                .filter(|&(i, &r)| is_first(c * CHUNK + i, r))
                .count() as u32
        })
        .collect();
    let mut n_groups = 0u32;
    let starts: Vec<u32> = counts
        .iter()
        .map(|&n| {
            n_groups += n;
            n_groups - n
        })
        .collect();
    // Group id of each root, set by its first triangle (one writer each).
    let id: Vec<AtomicU32> = (0..n_vertices)
        .into_par_iter()
        .map(|_| AtomicU32::new(u32::MAX))
        .collect();
    roots
        .par_chunks(CHUNK)
        .zip(&starts)
        .enumerate()
        .for_each(|(c, (rs, &start))| {
            let mut next = start;
            for (i, &r) in rs.iter().enumerate() {
                if is_first(c * CHUNK + i, r) {
                    id[r as usize].store(next, Ordering::Relaxed);
                    next += 1;
                }
            }
        });
    let groups = (roots.par_iter().with_min_len(1 << 12))
        .map(|&r| id[r as usize].load(Ordering::Relaxed))
        .collect();
    (groups, n_groups as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic xorshift draw below `n`.
    fn draws(seed: u64) -> impl FnMut(u32) -> u32 {
        let mut state = seed;
        move |n| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % u64::from(n)) as u32
        }
    }

    #[test]
    fn representative_is_smallest_member() {
        let mut s = UnionFind::<usize>::with_len(6);
        s.union(4, 2);
        s.union(5, 4);
        s.union(3, 1);
        assert_eq!(s.find(5), 2);
        assert_eq!(s.find(3), 1);
        assert_eq!(s.find(0), 0);
        s.union(5, 3);
        assert_eq!(s.find(2), 1);
        assert!(s.is_root(1) && !s.is_root(2));
        assert_eq!((0..6).filter(|&i| s.is_root(i)).count(), 2);
    }

    #[test]
    fn append_keeps_both_forests() {
        let mut a = UnionFind::<u32>::with_len(3);
        a.union(2, 1);
        let mut b = UnionFind::<u32>::default();
        let (x, y) = (b.push(), b.push());
        b.union(y, x);
        a.append(&b);
        assert_eq!(a.len(), 5);
        assert_eq!(a.clone().roots(), vec![0, 1, 1, 3, 3]);
        a.union(4, 2);
        assert_eq!(a.roots(), vec![0, 1, 1, 1, 1]);
    }

    /// Unions in parallel give the roots of the same unions in sequence
    /// (each set's smallest node), on a graph with long chains and cycles.
    #[test]
    fn atomic_union_find_equals_the_sequential_one() {
        let n = 20_000u32;
        let mut next = draws(0x2545_f491_4f6c_dd1d);
        let mut edges: Vec<(u32, u32)> = (0..n - 1)
            .filter(|i| i % 97 != 0)
            .map(|i| (i, i + 1))
            .collect();
        edges.extend((0..15_000).map(|_| (next(n), next(n))));
        let mut seq = UnionFind::with_len(n as usize);
        edges.iter().for_each(|&(a, b)| {
            seq.union(a, b);
        });
        let par = AtomicUnionFind::with_len(n as usize);
        edges.par_iter().for_each(|&(a, b)| par.union(b, a));
        let roots = par.roots();
        assert_eq!(roots, seq.roots());
        assert!(roots.iter().enumerate().all(|(x, &r)| r as usize <= x));
        assert!(roots.iter().filter(|&&r| r == 0).count() > 1);
    }

    /// The serial definition: union-find, groups numbered by first triangle.
    fn reference(n_vertices: usize, triangles: &[[u32; 3]]) -> (Vec<u32>, usize) {
        let mut uf = UnionFind::with_len(n_vertices);
        for t in triangles {
            uf.union(t[0], t[1]);
            uf.union(t[0], t[2]);
        }
        let mut id = vec![u32::MAX; n_vertices];
        let mut n = 0;
        let groups = triangles
            .iter()
            .map(|t| {
                let r = uf.find(t[0]) as usize;
                if id[r] == u32::MAX {
                    id[r] = n;
                    n += 1;
                }
                id[r]
            })
            .collect();
        (groups, n as usize)
    }

    #[test]
    fn vertex_components_numbers_groups_by_first_triangle() {
        let tris = [[5, 4, 3], [0, 1, 2], [2, 6, 7], [8, 9, 3], [10, 11, 12]];
        assert_eq!(vertex_components(13, &tris), (vec![0, 1, 1, 0, 2], 3));
        assert_eq!(vertex_components(4, &[]), (vec![], 0));
    }

    #[test]
    fn vertex_components_equal_the_serial_union_find_on_any_pool() {
        // Random triangles over few vertices (long chains, many unions per
        // root) and over many (thousands of small groups).
        let mut next = draws(0x2545_f491_4f6c_dd1d);
        for (n_vertices, n_triangles, spread) in [(60_000, 40_000, 60_000), (300_000, 150_000, 40)]
        {
            let tris: Vec<[u32; 3]> = (0..n_triangles)
                .map(|_| {
                    let a = next(n_vertices);
                    [
                        a,
                        (a + next(spread)) % n_vertices,
                        (a + next(spread)) % n_vertices,
                    ]
                })
                .collect();
            let want = reference(n_vertices as usize, &tris);
            assert!(want.1 > 10, "{} groups", want.1);
            for threads in [1, 2, 8] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let got = pool.install(|| vertex_components(n_vertices as usize, &tris));
                assert_eq!(got, want, "{threads} threads");
            }
        }
    }
}
