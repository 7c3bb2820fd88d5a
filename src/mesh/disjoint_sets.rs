//! Disjoint sets (union-find) over `0..n` whose representative is always the
//! smallest member of its set.
//!
//! Linking the larger root under the smaller one makes the representative
//! deterministic and meaningful ("the first element of the set"), which the
//! component numbering in [`crate::mesh::topology`] and
//! [`crate::volume::analysis`] relies on. Path halving keeps `find` amortised
//! O(log n) (Tarjan & van Leeuwen 1984); no recursion.

/// Union-find over the elements `0..n`.
#[derive(Debug, Clone)]
pub struct DisjointSets {
    parent: Vec<usize>,
}

impl DisjointSets {
    /// `n` singleton sets.
    pub fn new(n: usize) -> Self {
        DisjointSets {
            parent: (0..n).collect(),
        }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.parent.len()
    }

    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.parent.is_empty()
    }

    /// The smallest member of the set containing `x`.
    pub fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] != x {
            let grand = self.parent[self.parent[x]];
            self.parent[x] = grand;
            x = grand;
        }
        x
    }

    /// Merges the sets of `a` and `b`; returns the representative of the union.
    pub fn union(&mut self, a: usize, b: usize) -> usize {
        let (ra, rb) = (self.find(a), self.find(b));
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        self.parent[hi] = lo;
        lo
    }

    /// Whether `x` is the representative (smallest member) of its set.
    pub fn is_root(&self, x: usize) -> bool {
        self.parent[x] == x
    }
}

#[cfg(test)]
mod tests {
    use super::DisjointSets;

    #[test]
    fn representative_is_smallest_member() {
        let mut s = DisjointSets::new(6);
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
}
