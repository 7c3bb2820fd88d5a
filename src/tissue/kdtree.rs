//! A static k-d tree over points, for the nearest-bone search of eq. 4.1.
//!
//! Built once in O(n log n) (median splits by `select_nth_unstable`), queried
//! in O(log n) expected time. Ties in distance go to the smaller point index,
//! so the answer does not depend on the tree's shape.

use glam::DVec3;

/// Leaves hold at most this many points.
const LEAF: usize = 8;

/// Implicit balanced k-d tree: `order[lo..hi]` is a subtree whose median
/// `order[(lo + hi) / 2]` splits along `axis[(lo + hi) / 2]`.
#[derive(Debug, Clone)]
pub struct KdTree {
    points: Vec<DVec3>,
    order: Vec<u32>,
    axis: Vec<u8>,
}

impl KdTree {
    /// Builds the tree over `points` (indices are positions in the slice).
    pub fn new(points: Vec<DVec3>) -> Self {
        let mut order: Vec<u32> = (0..points.len() as u32).collect();
        let mut axis = vec![0u8; points.len()];
        build(&points, &mut order, &mut axis);
        KdTree {
            points,
            order,
            axis,
        }
    }

    /// Index of the point nearest to `q` (smallest index on ties); `None`
    /// when the tree is empty.
    pub fn nearest(&self, q: DVec3) -> Option<u32> {
        let mut best = (f64::INFINITY, u32::MAX);
        self.search(q, 0, self.order.len(), &mut best);
        (best.1 != u32::MAX).then_some(best.1)
    }

    fn consider(&self, q: DVec3, ix: u32, best: &mut (f64, u32)) {
        let d = self.points[ix as usize].distance_squared(q);
        if d < best.0 || (d == best.0 && ix < best.1) {
            *best = (d, ix);
        }
    }

    fn search(&self, q: DVec3, lo: usize, hi: usize, best: &mut (f64, u32)) {
        if hi - lo <= LEAF {
            for &ix in &self.order[lo..hi] {
                self.consider(q, ix, best);
            }
            return;
        }
        let mid = (lo + hi) / 2;
        let ix = self.order[mid];
        let a = self.axis[mid] as usize;
        let delta = q[a] - self.points[ix as usize][a];
        self.consider(q, ix, best);
        let (near, far) = if delta < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(q, near.0, near.1, best);
        // `<=` keeps equal-distance points on the far side reachable for the
        // smallest-index tie rule.
        if delta * delta <= best.0 {
            self.search(q, far.0, far.1, best);
        }
    }
}

fn build(points: &[DVec3], order: &mut [u32], axis: &mut [u8]) {
    if order.len() <= LEAF {
        return;
    }
    let (lo, hi) = order.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &i| (lo.min(points[i as usize]), hi.max(points[i as usize])),
    );
    let ext = hi - lo;
    let a = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |&i, &j| {
        points[i as usize][a].total_cmp(&points[j as usize][a])
    });
    axis[mid] = a as u8;
    let (left, right) = order.split_at_mut(mid);
    let (laxis, raxis) = axis.split_at_mut(mid);
    build(points, left, laxis);
    build(points, &mut right[1..], &mut raxis[1..]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_brute_force() {
        let mut s = 12345u64;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % 10_000) as f64 / 1000.0
        };
        let pts: Vec<DVec3> = (0..2000).map(|_| DVec3::new(rnd(), rnd(), rnd())).collect();
        let tree = KdTree::new(pts.clone());
        for _ in 0..500 {
            let q = DVec3::new(rnd(), rnd(), rnd());
            let brute = (0..pts.len())
                .min_by(|&a, &b| {
                    pts[a]
                        .distance_squared(q)
                        .total_cmp(&pts[b].distance_squared(q))
                        .then(a.cmp(&b))
                })
                .unwrap();
            assert_eq!(tree.nearest(q), Some(brute as u32));
        }
        assert_eq!(KdTree::new(Vec::new()).nearest(DVec3::ZERO), None);
    }
}
