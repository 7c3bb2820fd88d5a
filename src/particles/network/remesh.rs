//! Remeshing of the spring network (seed 002 §4.2, eq. 14–16): edge
//! collapses below D_min and splits above D_max, with the seed's locks and
//! length-change guard, through local operations that keep the vertex →
//! triangle adjacency up to date (χ is kept: module docs of
//! [`super`]).

use std::collections::{HashMap, HashSet};

use super::{MAX_FAN_ANGLE, Network, NetworkIteration, key};

impl Network {
    /// Collapses (shortest first), then splits (longest first), skipping
    /// springs whose length changed by more than ε R (eq. 16) and vertices
    /// already touched in this iteration; compacts vertices and triangles.
    pub(super) fn remesh(&mut self, it: &mut NetworkIteration) {
        let (dmin, dmax, eps) = (
            self.opts.d_min as f32,
            self.opts.d_max as f32,
            self.opts.epsilon as f32,
        );
        let mut lens: Vec<((u32, u32), f32)> = Vec::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a < b {
                    lens.push((
                        (a, b),
                        self.positions[a as usize].distance(self.positions[b as usize]),
                    ));
                }
            }
        }
        let steady = |e: &(u32, u32), l: f32, last: &HashMap<(u32, u32), f32>, rest: f32| {
            last.get(e)
                .is_none_or(|&prev| (prev - l).abs() <= eps * rest)
        };
        let mut ops = Ops::new(self);
        let mut touched: HashSet<u32> = HashSet::new();
        let mut short: Vec<((u32, u32), f32)> = (lens.iter())
            .filter(|(e, l)| {
                *l < dmin * self.rest_length(e.0, e.1) && steady(e, *l, &self.last_len, self.rest)
            })
            .copied()
            .collect();
        short.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        for ((a, b), _) in short {
            if touched.contains(&a) || touched.contains(&b) {
                continue;
            }
            match ops.collapse(self, a, b, dmax) {
                Some(ring) => {
                    it.collapses += 1;
                    touched.extend(ring);
                    touched.extend([a, b]);
                }
                None => it.refused += 1,
            }
        }
        let mut long: Vec<((u32, u32), f32)> = (lens.iter())
            .filter(|((a, b), _)| !ops.removed[*a as usize] && !ops.removed[*b as usize])
            .filter(|(e, l)| {
                *l > dmax * self.rest_length(e.0, e.1) && steady(e, *l, &self.last_len, self.rest)
            })
            .copied()
            .collect();
        long.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        for ((a, b), _) in long {
            if touched.contains(&a) || touched.contains(&b) {
                continue;
            }
            if let Some(m) = ops.split(self, a, b) {
                it.splits += 1;
                touched.extend([a, b, m]);
            }
        }
        self.compact(&ops.removed, &ops.dead);
        self.last_len = (self.triangles.iter())
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .filter(|(a, b)| a < b)
            .map(|(a, b)| {
                (
                    (a, b),
                    self.positions[a as usize].distance(self.positions[b as usize]),
                )
            })
            .collect();
    }

    /// Splits edge (a, b) at its midpoint; returns the new vertex.
    pub fn split(&mut self, a: u32, b: u32) -> Option<u32> {
        let mut ops = Ops::new(self);
        let m = ops.split(self, a, b)?;
        self.compact(&ops.removed, &ops.dead);
        Some(m)
    }

    /// Collapses edge (a, b) into a at the midpoint when the tests pass
    /// (module docs); vertices after b are renumbered down by one.
    pub fn collapse(&mut self, a: u32, b: u32) -> bool {
        let mut ops = Ops::new(self);
        let done = ops.collapse(self, a, b, self.opts.d_max as f32).is_some();
        self.compact(&ops.removed, &ops.dead);
        done
    }

    /// Drops the triangles marked `dead` and the vertices marked
    /// `removed`, renumbering the rest in order.
    pub(super) fn compact(&mut self, removed: &[bool], dead: &[bool]) {
        if dead.iter().any(|&d| d) {
            let mut k = 0;
            self.triangles.retain(|_| {
                k += 1;
                !dead[k - 1]
            });
        }
        if !removed.iter().any(|&r| r) {
            return;
        }
        let mut map = vec![u32::MAX; removed.len()];
        let mut next = 0u32;
        let mut positions = Vec::with_capacity(self.positions.len());
        for (i, &r) in removed.iter().enumerate() {
            if !r {
                map[i] = next;
                next += 1;
                positions.push(self.positions[i]);
            }
        }
        self.positions = positions;
        for t in &mut self.triangles {
            *t = t.map(|v| map[v as usize]);
        }
        self.rest_of = (self.rest_of.drain())
            .filter(|((a, b), _)| map[*a as usize] != u32::MAX && map[*b as usize] != u32::MAX)
            .map(|((a, b), r)| (key(map[a as usize], map[b as usize]), r))
            .collect();
    }
}

/// Local operations with the vertex → triangle adjacency kept up to date;
/// triangles are marked dead and vertices removed, both dropped by
/// [`Network::compact`] afterwards.
struct Ops {
    /// Live triangles of each vertex.
    vt: Vec<Vec<usize>>,
    dead: Vec<bool>,
    removed: Vec<bool>,
}

impl Ops {
    fn new(net: &Network) -> Ops {
        let mut vt = vec![Vec::new(); net.positions.len()];
        for (i, t) in net.triangles.iter().enumerate() {
            for &v in t {
                vt[v as usize].push(i);
            }
        }
        Ops {
            vt,
            dead: vec![false; net.triangles.len()],
            removed: vec![false; net.positions.len()],
        }
    }

    /// The two triangles of edge (a, b): (the one with a → b, apex c),
    /// (the one with b → a, apex d).
    fn edge_triangles(
        &self,
        net: &Network,
        a: u32,
        b: u32,
    ) -> Option<((usize, u32), (usize, u32))> {
        let mut ab = None;
        let mut ba = None;
        for &i in &self.vt[a as usize] {
            let t = net.triangles[i];
            for k in 0..3 {
                let (x, y, z) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                if (x, y) == (a, b) {
                    ab = Some((i, z));
                } else if (x, y) == (b, a) {
                    ba = Some((i, z));
                }
            }
        }
        Some((ab?, ba?))
    }

    /// Sorted neighbours of `v`.
    fn neighbours(&self, net: &Network, v: u32) -> Vec<u32> {
        let mut n: Vec<u32> = (self.vt[v as usize].iter())
            .flat_map(|&i| net.triangles[i])
            .filter(|&u| u != v)
            .collect();
        n.sort_unstable();
        n.dedup();
        n
    }

    fn split(&mut self, net: &mut Network, a: u32, b: u32) -> Option<u32> {
        let ((t1, c), (t2, d)) = self.edge_triangles(net, a, b)?;
        let m = net.positions.len() as u32;
        net.positions
            .push(0.5 * (net.positions[a as usize] + net.positions[b as usize]));
        self.removed.push(false);
        let r = net.rest_length(a, b);
        if r != net.rest {
            net.rest_of.insert(key(a, m), r);
            net.rest_of.insert(key(m, b), r);
        }
        let (t3, t4) = (net.triangles.len(), net.triangles.len() + 1);
        net.triangles[t1] = [a, m, c];
        net.triangles[t2] = [b, m, d];
        net.triangles.push([m, b, c]);
        net.triangles.push([m, a, d]);
        self.dead.extend([false, false]);
        self.vt.push(vec![t1, t2, t3, t4]);
        self.vt[b as usize].retain(|&t| t != t1);
        self.vt[b as usize].push(t3);
        self.vt[a as usize].retain(|&t| t != t2);
        self.vt[a as usize].push(t4);
        self.vt[c as usize].push(t3);
        self.vt[d as usize].push(t4);
        Some(m)
    }

    fn collapse(&mut self, net: &mut Network, a: u32, b: u32, dmax: f32) -> Option<Vec<u32>> {
        let ((t1, c), (t2, d)) = self.edge_triangles(net, a, b)?;
        let (na, nb) = (self.neighbours(net, a), self.neighbours(net, b));
        let common: Vec<u32> = na.iter().filter(|x| nb.contains(x)).copied().collect();
        if common.len() != 2 || !common.contains(&c) || !common.contains(&d) || c == d {
            return None;
        }
        if self.vt[c as usize].len() <= 3
            || self.vt[d as usize].len() <= 3
            || na.len() + nb.len() - 4 < 3
        {
            return None;
        }
        let mid = 0.5 * (net.positions[a as usize] + net.positions[b as usize]);
        let limit = dmax * net.rest;
        if na
            .iter()
            .chain(&nb)
            .any(|&v| v != a && v != b && net.positions[v as usize].distance(mid) > limit)
        {
            return None;
        }
        // No surviving triangle of a or b turns by more than 45° or degenerates.
        let cos_max = crate::mesh::collapse::MAX_TURN_DEGREES.to_radians().cos();
        let moved = |v: u32| {
            if v == a || v == b {
                mid
            } else {
                net.positions[v as usize]
            }
        };
        for &i in self.vt[a as usize].iter().chain(&self.vt[b as usize]) {
            if i == t1 || i == t2 {
                continue;
            }
            let t = net.triangles[i];
            let [p, q, r] = t.map(|v| net.positions[v as usize]);
            let old = (q - p).cross(r - p);
            let [p, q, r] = t.map(moved);
            let new = (q - p).cross(r - p);
            if new.length() == 0.0 || old.normalize_or_zero().dot(new.normalize_or_zero()) < cos_max
            {
                return None;
            }
        }
        // The merged fan must wind once: its angles at the midpoint sum to
        // less than 2π + π/2 (a fan wound twice overlaps itself in the surface).
        let angle_sum: f32 = (self.vt[a as usize].iter().chain(&self.vt[b as usize]))
            .filter(|&&i| i != t1 && i != t2)
            .map(|&i| {
                let t = net.triangles[i];
                let k = t.iter().position(|&v| v == a || v == b).unwrap_or(0);
                let (p, q) = (moved(t[(k + 1) % 3]), moved(t[(k + 2) % 3]));
                (p - mid).angle_between(q - mid)
            })
            .sum();
        if angle_sum > MAX_FAN_ANGLE {
            return None;
        }
        net.positions[a as usize] = mid;
        let mut ring: Vec<u32> = na.iter().chain(&nb).copied().collect();
        ring.sort_unstable();
        ring.dedup();
        for i in std::mem::take(&mut self.vt[b as usize]) {
            if i == t1 || i == t2 {
                continue;
            }
            for v in net.triangles[i].iter_mut() {
                if *v == b {
                    *v = a;
                }
            }
            self.vt[a as usize].push(i);
        }
        for t in [t1, t2] {
            self.dead[t] = true;
            for v in net.triangles[t] {
                self.vt[v as usize].retain(|&x| x != t);
            }
        }
        self.removed[b as usize] = true;
        for v in ring.iter().copied().filter(|&v| v != a && v != b) {
            if let Some(r) = net.rest_of.remove(&key(b, v)) {
                net.rest_of.entry(key(a, v)).or_insert(r);
            }
        }
        Some(ring)
    }
}
