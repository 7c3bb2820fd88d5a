//! Topology surgery of the spring network (`docs/design/particles.md` §4
//! and §10): stranded, submerged and facing-pair regions are removed and
//! their loops capped (a cut) or bridged (a merge).

use std::collections::{HashMap, HashSet};

use glam::Vec3;
use rayon::prelude::*;

use super::{Network, key};
use crate::implicit::field::FieldInput;
use crate::implicit::field::cpu::skeletal_field;
use crate::mesh::Topology;

/// Iterations after a merge before the next surgery: the fresh strip
/// settles onto the surface first (right after a merge it spans a neck
/// thinner than its loops and would otherwise be cut again).
pub const SURGERY_COOLDOWN: u32 = 10;

/// Per iteration, rest lengths set by a surgery move this fraction of the
/// way back to R (when the curvature adaptation is off).
/// A vertex's side before dilation (dilated marks, ±2, count as 0).
fn side_of(side: &[i8], v: u32) -> i8 {
    let s = side[v as usize];
    if s.abs() == 1 { s } else { 0 }
}

/// Combines the sides of a triangle's vertices: inside (1) wins, then outside (−1).
fn merge_side(m: i8, x: i8) -> i8 {
    if x == 1 || m == 1 { 1 } else { m.min(x) }
}

/// What one [`Network::surgery`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct Surgery {
    /// Triangles removed around stranded and submerged vertices.
    pub removed_triangles: u32,
    /// Loops closed by a fan.
    pub caps: u32,
    /// Pairs of loops joined by a strip.
    pub bridges: u32,
    /// Surgeries not done (loops not simple, or a result that is not a
    /// closed oriented manifold); retried at the next iteration.
    pub refused: u32,
    /// Stranded or submerged vertices moved onto the surface instead, where
    /// closing their region again would not change the topology.
    pub projected: u32,
}

impl Network {
    /// Topology surgery where the surface left the network behind
    /// (`docs/design/particles.md` §4). A vertex is **stranded** when it is
    /// more than R/2 outside the surface, (I − F)/|∇F| > R/2 (a neck that
    /// broke leaves its ring in the gap), and **submerged** when more than
    /// R/2 inside, or one of a facing pair whose midpoint is inside (two
    /// parts that met, or a part touching itself). The
    /// triangles of such vertices are removed, and the boundary loops left
    /// are closed again: two loops around submerged regions that face each
    /// other (opposite mean normals, centres within 4R) are **bridged** by a
    /// strip (χ − 2, the merge the seed leaves open), every other loop is
    /// **capped** by a fan around a new centre vertex (a neck cut: χ + 2 for
    /// the two caps, the seed's step 3) when the field between any two cap
    /// centres leaves the inside somewhere. A surgery is kept only when it
    /// changes the components or their genus and leaves a closed,
    /// consistently oriented manifold; otherwise the mesh stays and the
    /// marked vertices are moved onto the surface by Newton steps.
    pub fn surgery(&mut self, field: &FieldInput) -> Surgery {
        if self.cooldown > 0 {
            self.cooldown -= 1;
            return Surgery::default();
        }
        let half = 0.5 * self.rest;
        let samples: Vec<(f32, Vec3)> = (self.positions.par_iter())
            .map(|p| {
                let (f, _) = skeletal_field(field, p.to_array());
                (f.value, Vec3::from_array(f.grad))
            })
            .collect();
        let mut side: Vec<i8> = (samples.iter())
            .map(|(value, grad)| {
                let d = value / grad.length().max(self.g_min);
                if d < -half {
                    -1
                } else if d > half {
                    1
                } else {
                    0
                }
            })
            .collect();
        self.mark_facing_pairs(field, &samples, &mut side);
        if side.iter().all(|&s| s == 0) {
            return Surgery::default();
        }
        let before = (self.positions.clone(), self.triangles.clone());
        let shape = |t: &Topology| {
            let mut g: Vec<Option<i64>> = t.components.iter().map(|c| c.genus).collect();
            g.sort_unstable();
            g
        };
        let topology_before = shape(&self.check().expect("the network is kept a closed manifold"));
        match self.reclose(&side, field) {
            Some(done) if self.check().is_ok_and(|t| shape(&t) != topology_before) => {
                if done.bridges > 0 {
                    self.cooldown = SURGERY_COOLDOWN;
                }
                done
            }
            result => {
                // No topology change (or none possible yet): keep the mesh
                // and move the stranded and submerged vertices onto the
                // surface instead.
                (self.positions, self.triangles) = before;
                let mut projected = 0;
                for (v, &sd) in side.iter().enumerate() {
                    if sd != 0 {
                        self.positions[v] = self.project(field, self.positions[v]);
                        projected += 1;
                    }
                }
                Surgery {
                    refused: u32::from(result.is_none()),
                    projected,
                    ..Surgery::default()
                }
            }
        }
    }

    /// `x` moved onto the surface by Newton steps along ∇F (at most R
    /// each, 20 of them).
    fn project(&self, field: &FieldInput, mut x: Vec3) -> Vec3 {
        for _ in 0..20 {
            let (f, _) = skeletal_field(field, x.to_array());
            let g = Vec3::from_array(f.grad);
            let step = -f.value / g.length_squared().max(self.g_min * self.g_min) * g;
            x += step.clamp_length_max(self.rest);
            if step.length() < 1e-4 * self.rest {
                break;
            }
        }
        x
    }

    /// Marks as submerged the vertices of **facing pairs**: i, j not joined
    /// by an edge, closer than 2R, with opposite outward normals
    /// (n_i·n_j < −½), j in front of i ((p_j − p_i)·n_i > 0), and the field
    /// inside between them (F(mid) > I): two sheets of the network that the
    /// surface has joined.
    fn mark_facing_pairs(&self, field: &FieldInput, samples: &[(f32, Vec3)], side: &mut [i8]) {
        let reach = 2.0 * self.rest;
        let Ok(cells) = crate::particles::CellList::build(&self.positions, reach, 0.0) else {
            return;
        };
        let n = self.neighbours();
        let normal = |i: usize| -samples[i].1.normalize_or_zero();
        for i in 0..self.positions.len() {
            let (pi, ni) = (self.positions[i], normal(i));
            for j in cells.candidates(i).filter(|&j| j > i) {
                let pj = self.positions[j];
                if pi.distance_squared(pj) >= reach * reach
                    || ni.dot(normal(j)) >= -0.5
                    || (pj - pi).dot(ni) <= 0.0
                    || n[i].binary_search(&(j as u32)).is_ok()
                {
                    continue;
                }
                if skeletal_field(field, (0.5 * (pi + pj)).to_array()).0.value > 0.0 {
                    side[i] = 1;
                    side[j] = 1;
                }
            }
        }
    }

    /// Removes the triangles of stranded and submerged vertices and closes
    /// the loops (see [`Network::surgery`]); `None` for loops that are not simple.
    fn reclose(&mut self, side: &[i8], field: &FieldInput) -> Option<Surgery> {
        let mut out = Surgery::default();
        // Which kind of removal each removed triangle is (inside wins).
        // Dilate by one ring: the removed region's border vertices join it,
        // so that its loops run through surface that is still well sampled.
        let mut side = side.to_vec();
        for t in &self.triangles {
            let s = t.iter().map(|&v| side_of(&side, v)).fold(0i8, merge_side);
            if s != 0 {
                for &v in t {
                    if side[v as usize] == 0 {
                        side[v as usize] = 2 * s;
                    }
                }
            }
        }
        let mut kind: Vec<i8> = (self.triangles.iter())
            .map(|t| {
                t.iter()
                    .map(|&v| side[v as usize].signum())
                    .fold(0i8, merge_side)
            })
            .collect();
        // Grow the region over pinch vertices (two boundary edges leaving
        // one vertex) until every loop is simple, at most 10 rounds.
        let mut next: HashMap<u32, u32> = HashMap::new();
        for round in 0..=10 {
            let directed: HashSet<(u32, u32)> = (self.triangles.iter().zip(&kind))
                .filter(|(_, k)| **k == 0)
                .flat_map(|(t, _)| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
                .collect();
            next.clear();
            let mut pinches: Vec<u32> = Vec::new();
            for &(u, v) in &directed {
                if !directed.contains(&(v, u)) && next.insert(u, v).is_some() {
                    pinches.push(u);
                }
            }
            if pinches.is_empty() {
                break;
            }
            if round == 10 {
                return None;
            }
            for (t, k) in self.triangles.iter().zip(kind.iter_mut()) {
                if *k == 0 && t.iter().any(|v| pinches.contains(v)) {
                    *k = -1;
                }
            }
        }
        let mut kind_of_removed: HashMap<(u32, u32), i8> = HashMap::new();
        let mut kept = Vec::with_capacity(self.triangles.len());
        for (t, &k) in self.triangles.iter().zip(&kind) {
            if k == 0 {
                kept.push(*t);
            } else {
                for e in 0..3 {
                    kind_of_removed.insert((t[e], t[(e + 1) % 3]), k);
                }
            }
        }
        out.removed_triangles = (self.triangles.len() - kept.len()) as u32;
        let mut loops: Vec<Vec<u32>> = Vec::new();
        let mut seen: HashSet<u32> = HashSet::new();
        let mut starts: Vec<u32> = next.keys().copied().collect();
        starts.sort_unstable();
        for s in starts {
            if seen.contains(&s) {
                continue;
            }
            let mut lp = vec![s];
            seen.insert(s);
            let mut v = *next.get(&s)?;
            while v != s {
                if !seen.insert(v) {
                    return None;
                }
                lp.push(v);
                v = *next.get(&v)?;
            }
            loops.push(lp);
        }
        self.triangles = kept;
        // Each loop's kind: the removed triangle across its first edge.
        let kinds: Vec<i8> = (loops.iter())
            .map(|l| {
                kind_of_removed
                    .get(&(l[1 % l.len()], l[0]))
                    .copied()
                    .unwrap_or(-1)
            })
            .collect();
        let centre =
            |l: &[u32], p: &[Vec3]| l.iter().map(|&v| p[v as usize]).sum::<Vec3>() / l.len() as f32;
        let normal = |l: &[u32], p: &[Vec3]| {
            let c = centre(l, p);
            (0..l.len())
                .map(|k| (p[l[k] as usize] - c).cross(p[l[(k + 1) % l.len()] as usize] - c))
                .sum::<Vec3>()
                .normalize_or_zero()
        };
        // Pair facing submerged loops, closest centres first.
        let inside: Vec<usize> = (0..loops.len()).filter(|&i| kinds[i] == 1).collect();
        let mut pairs: Vec<(f32, usize, usize)> = Vec::new();
        for (x, &i) in inside.iter().enumerate() {
            for &j in &inside[x + 1..] {
                let d =
                    centre(&loops[i], &self.positions).distance(centre(&loops[j], &self.positions));
                let facing = normal(&loops[i], &self.positions)
                    .dot(normal(&loops[j], &self.positions))
                    < -0.5;
                if facing && d < 4.0 * self.rest {
                    pairs.push((d, i, j));
                }
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut used = vec![false; loops.len()];
        for (_, i, j) in pairs {
            if used[i] || used[j] {
                continue;
            }
            used[i] = true;
            used[j] = true;
            let strip = self.bridge(&loops[i], &loops[j]);
            for t in strip {
                for k in 0..3 {
                    let (u, v) = (t[k], t[(k + 1) % 3]);
                    let l = self.positions[u as usize].distance(self.positions[v as usize]);
                    if l > self.rest {
                        self.rest_of.insert(key(u, v), l);
                    }
                }
            }
            out.bridges += 1;
        }
        let mut centres = Vec::new();
        for (i, l) in loops.iter().enumerate() {
            if !used[i] {
                self.cap(l, field);
                centres.push(*self.positions.last().expect("the cap's centre"));
                out.caps += 1;
            }
        }
        // A cut must follow the field: between any two cap centres the
        // segment leaves the inside somewhere (else a thin neck that still
        // exists, say a bond the network lags behind, would be cut).
        for (i, a) in centres.iter().enumerate() {
            for b in &centres[i + 1..] {
                let joined = (1..16).all(|k| {
                    let x = a.lerp(*b, k as f32 / 16.0);
                    skeletal_field(field, x.to_array()).0.value > 0.0
                });
                if joined {
                    return None;
                }
            }
        }
        // Drop vertices no triangle uses any more.
        let mut used_v = vec![false; self.positions.len()];
        for t in &self.triangles {
            for &v in t {
                used_v[v as usize] = true;
            }
        }
        let removed: Vec<bool> = used_v.iter().map(|u| !u).collect();
        self.compact(&removed, &[]);
        Some(out)
    }

    /// Closes the boundary loop `l` (in boundary direction) by a fan around
    /// a new vertex: the loop's centre, moved onto the surface by Newton
    /// steps along ∇F (at most R each, 20 of them).
    fn cap(&mut self, l: &[u32], field: &FieldInput) {
        let c = self.positions.len() as u32;
        let centre = l.iter().map(|&v| self.positions[v as usize]).sum::<Vec3>() / l.len() as f32;
        let x = self.project(field, centre);
        self.positions.push(x);
        for k in 0..l.len() {
            // The loop runs u → v on the kept side, so the cap uses v → u.
            self.triangles.push([l[(k + 1) % l.len()], l[k], c]);
        }
    }

    /// Joins the boundary loops `a` and `b` (each in boundary direction) by
    /// a strip of #a + #b triangles: walking `a` forward and `b` backward
    /// from their closest vertices, always adding the shorter diagonal.
    fn bridge(&mut self, a: &[u32], b: &[u32]) -> Vec<[u32; 3]> {
        let p = |v: u32| self.positions[v as usize];
        let (m, n) = (a.len(), b.len());
        let (mut i0, mut j0, mut best) = (0, 0, f32::INFINITY);
        for (i, &u) in a.iter().enumerate() {
            for (j, &w) in b.iter().enumerate() {
                let d = p(u).distance_squared(p(w));
                if d < best {
                    (i0, j0, best) = (i, j, d);
                }
            }
        }
        let ua = |k: usize| a[(i0 + k) % m];
        let wb = |k: usize| b[(j0 + n - k % n) % n];
        let (mut i, mut j) = (0, 0);
        let mut strip = Vec::with_capacity(m + n);
        while i < m || j < n {
            let advance_a = j == n
                || (i < m && p(ua(i + 1)).distance(p(wb(j))) <= p(ua(i)).distance(p(wb(j + 1))));
            if advance_a {
                strip.push([ua(i + 1), ua(i), wb(j)]);
                i += 1;
            } else {
                strip.push([ua(i), wb(j), wb(j + 1)]);
                j += 1;
            }
        }
        self.triangles.extend(&strip);
        strip
    }
}
