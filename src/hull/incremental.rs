//! The incremental hull of seed §4.1.4–4.1.8 in exact integer arithmetic.
//!
//! Points are inserted one after another in the given order. For point `p`
//! a face `F` has `s = n·p − d` (Def. VI: `> 0` visible, `< 0` invisible,
//! `= 0` coplanar; `n` is the primitive outward integer normal, `d = n·Q`
//! for a vertex `Q`). The faces to replace form a region R (by policy, see
//! [`CoplanarPolicy`]); its boundary, the horizon, is joined to `p` by a cone
//! of new faces.
//!
//! Visibility walk with conflict lists (Clarkson–Shor, Qhull's outside
//! sets): every waiting point keeps one face it sees; a point that sees no
//! face of the current polyhedron lies inside or on it and stays there
//! (hulls only grow), so it is dropped. Point `p` finds its visible faces by
//! walking from its face across edges (the visible set is connected), and
//! the points of replaced faces move to the first new face they see — a
//! point outside the new polyhedron that saw a replaced face sees a new
//! one. The result is identical to testing every face for every point (the
//! seed's formulation), for every order.
//!
//! Coordinates are bounded by [`MAX_COORD`], so every normal (≤ 2³⁵), offset and `s` (≤ 2⁵⁴) fits `i64` without overflow; volumes are
//! accumulated in `i128`.

use super::CoplanarPolicy;
use crate::foundation::exact::{P3, cross, det, dot, gcd, sub};

/// Largest accepted |coordinate| (combinatorial units): 2¹⁶.
pub const MAX_COORD: i64 = 1 << 16;

/// Primitive integer vector along `n` (`n ≠ 0`).
pub(crate) fn primitive(n: P3) -> P3 {
    let g = gcd(gcd(n[0], n[1]), n[2]);
    if g == 0 { n } else { n.map(|c| c / g) }
}

/// A face during construction: vertex indices into the point list, CCW seen
/// from outside; primitive outward normal `n` and offset `d = n·v`.
#[derive(Debug, Clone)]
pub(crate) struct Face {
    pub verts: Vec<u32>,
    /// `twins[k]`: the face across edge `verts[k] → verts[k+1]`.
    pub twins: Vec<u32>,
    pub n: P3,
    pub d: i64,
}

/// Counters of one construction.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct HullStats {
    /// Candidate points given.
    pub candidates: usize,
    /// Points that extended the current polyhedron.
    pub inserted: usize,
    /// Points found inside or on the current polyhedron (no visible face).
    pub skipped: usize,
    /// Coplanar faces promoted to visible so that no cone face degenerates
    /// (only with [`CoplanarPolicy::Invisible`]).
    pub promoted: usize,
    /// Visibility tests `s = n·p − d` evaluated.
    pub visibility_tests: u64,
}

const NONE: u32 = u32::MAX;

pub(crate) struct Builder<'a> {
    pts: &'a [P3],
    policy: CoplanarPolicy,
    pub faces: Vec<Option<Face>>,
    free: Vec<u32>,
    /// Waiting points assigned to each face slot (outside sets).
    outside: Vec<Vec<u32>>,
    /// Per point: the face it sees, or `NONE` (inside/on, or processed).
    witness: Vec<u32>,
    /// 6·volume of the current polyhedron, kept incrementally (ch. 5).
    pub vol6: i128,
    pub stats: HullStats,
    /// `s` of a face for the current point, valid where `stamp == cur`.
    s: Vec<i64>,
    stamp: Vec<u32>,
    cur: u32,
    in_region: Vec<bool>,
    /// Faces created by the last insertion (for [`Builder::run_furthest`]).
    touched: Vec<u32>,
}

impl<'a> Builder<'a> {
    /// Starts from the tetrahedron `t` (indices into `pts`, non-coplanar) and
    /// assigns every other point to a face it sees.
    pub fn new(pts: &'a [P3], policy: CoplanarPolicy, t: [u32; 4]) -> Builder<'a> {
        let mut b = Builder {
            pts,
            policy,
            faces: Vec::new(),
            free: Vec::new(),
            outside: Vec::new(),
            witness: vec![NONE; pts.len()],
            vol6: 0,
            stats: HullStats {
                candidates: pts.len(),
                inserted: 4,
                ..HullStats::default()
            },
            s: Vec::new(),
            stamp: Vec::new(),
            cur: 0,
            in_region: Vec::new(),
            touched: Vec::new(),
        };
        let mut ids = Vec::new();
        for (i, j, k, o) in [(0, 1, 2, 3), (0, 1, 3, 2), (0, 2, 3, 1), (1, 2, 3, 0)] {
            let (a, c, e) = (t[i], t[j], t[k]);
            let n = cross(
                sub(pts[c as usize], pts[a as usize]),
                sub(pts[e as usize], pts[a as usize]),
            );
            let verts = if dot(n, sub(pts[t[o] as usize], pts[a as usize])) > 0 {
                vec![a, e, c]
            } else {
                vec![a, c, e]
            };
            ids.push(b.add_face(verts, vec![NONE; 3]));
        }
        // Twins of the tetrahedron: the face holding the reversed edge.
        for &f in &ids {
            for e in 0..3 {
                let (u, w) = b.edge(f, e);
                let g = ids
                    .iter()
                    .copied()
                    .find(|&g| (0..3).any(|k| b.edge(g, k) == (w, u)));
                if let (Some(g), Some(face)) = (g, b.faces[f as usize].as_mut()) {
                    face.twins[e] = g;
                }
            }
        }
        let p = |i: usize| pts[t[i] as usize];
        b.vol6 = det(sub(p(1), p(0)), sub(p(2), p(0)), sub(p(3), p(0))).abs();
        let rest: Vec<u32> = (0..pts.len() as u32).filter(|i| !t.contains(i)).collect();
        b.assign(&rest, &ids);
        b
    }

    /// Gives each of `points` the first face of `candidates` it sees.
    fn assign(&mut self, points: &[u32], candidates: &[u32]) {
        for &q in points {
            let p = self.pts[q as usize];
            self.witness[q as usize] = NONE;
            for &f in candidates {
                self.stats.visibility_tests += 1;
                let face = self.faces[f as usize]
                    .as_ref()
                    .map(|fc| dot(fc.n, p) - fc.d);
                if face.is_some_and(|s| s > 0) {
                    self.witness[q as usize] = f;
                    self.outside[f as usize].push(q);
                    break;
                }
            }
        }
    }

    fn add_face(&mut self, verts: Vec<u32>, twins: Vec<u32>) -> u32 {
        let pt = |i: u32| self.pts[i as usize];
        let n = primitive(cross(
            sub(pt(verts[1]), pt(verts[0])),
            sub(pt(verts[verts.len() - 1]), pt(verts[0])),
        ));
        let d = dot(n, pt(verts[0]));
        let id = match self.free.pop() {
            Some(id) => id,
            None => {
                self.faces.push(None);
                self.outside.push(Vec::new());
                self.s.push(0);
                self.stamp.push(u32::MAX);
                self.in_region.push(false);
                (self.faces.len() - 1) as u32
            }
        };
        self.stamp[id as usize] = u32::MAX;
        self.faces[id as usize] = Some(Face { verts, twins, n, d });
        id
    }

    /// Removes face `id`; returns its waiting points.
    fn remove_face(&mut self, id: u32) -> Vec<u32> {
        if self.faces[id as usize].take().is_some() {
            self.free.push(id);
        }
        std::mem::take(&mut self.outside[id as usize])
    }

    /// The face across edge `e` of face `f`.
    fn twin(&self, f: u32, e: usize) -> crate::Result<u32> {
        match self.faces[f as usize].as_ref().map(|fc| fc.twins[e]) {
            Some(g) if g != NONE && self.faces[g as usize].is_some() => Ok(g),
            _ => Err(crate::Error::Internal(format!(
                "edge {e} of hull face {f} has no twin"
            ))),
        }
    }

    /// `s = n·p − d` of face `f` for the current point (cached per point).
    fn side(&mut self, f: u32, p: P3) -> i64 {
        let fi = f as usize;
        if self.stamp[fi] != self.cur {
            self.stamp[fi] = self.cur;
            self.stats.visibility_tests += 1;
            self.s[fi] = self.faces[fi].as_ref().map_or(-1, |fc| dot(fc.n, p) - fc.d);
        }
        self.s[fi]
    }

    /// Inserts point `pi`; returns whether the polyhedron changed.
    pub fn insert(&mut self, pi: u32) -> crate::Result<bool> {
        let p = self.pts[pi as usize];
        let start_face = self.witness[pi as usize];
        self.witness[pi as usize] = NONE;
        if start_face == NONE {
            self.stats.skipped += 1;
            return Ok(false);
        }
        self.cur = pi;
        if self.side(start_face, p) <= 0 {
            return Err(crate::Error::Internal("stale conflict face".into()));
        }
        // Visibility walk: the visible faces are edge-connected.
        let mut visible = vec![start_face];
        self.in_region[start_face as usize] = true;
        let mut k = 0;
        while k < visible.len() {
            let fv = visible[k];
            for e in 0..self.n_edges(fv) {
                let g = self.twin(fv, e)?;
                if !self.in_region[g as usize] && self.side(g, p) > 0 {
                    self.in_region[g as usize] = true;
                    visible.push(g);
                }
            }
            k += 1;
        }
        let region = self.region(visible, p)?;
        // Horizon: directed edges of R whose twin face is outside R.
        let mut next: Vec<(u32, u32, u32)> = Vec::new();
        for &f in &region {
            for k in 0..self.n_edges(f) {
                let (u, w) = self.edge(f, k);
                let g = self.twin(f, k)?;
                if !self.in_region[g as usize] {
                    next.push((u, w, g));
                }
            }
        }
        next.sort_unstable();
        let internal = |what: &str| crate::Error::Internal(what.into());
        if next.is_empty() || next.windows(2).any(|w| w[0].0 == w[1].0) {
            return Err(internal("visible region of a hull point is not a disk"));
        }
        let start = next[0].0;
        let mut cycle = vec![start];
        // outer[i]: the face beyond horizon edge cycle[i] → cycle[i+1].
        let mut outer = Vec::new();
        let mut u = start;
        loop {
            let (w, g) = next
                .binary_search_by_key(&u, |e| e.0)
                .map(|i| (next[i].1, next[i].2))
                .map_err(|_| internal("open horizon"))?;
            outer.push(g);
            if w == start {
                break;
            }
            cycle.push(w);
            u = w;
            if cycle.len() > next.len() {
                return Err(internal("horizon is not one cycle"));
            }
        }
        if cycle.len() != next.len() {
            return Err(internal("horizon is not one cycle"));
        }
        // Incremental volume: the cone over R adds Σ vol(p, fan triangle).
        for &f in &region {
            if let Some(face) = &self.faces[f as usize] {
                let v0 = sub(self.pts[face.verts[0] as usize], p);
                for k in 1..face.verts.len() - 1 {
                    let a = sub(self.pts[face.verts[k] as usize], p);
                    let b = sub(self.pts[face.verts[k + 1] as usize], p);
                    self.vol6 -= det(v0, a, b);
                }
            }
        }
        let mut orphans = Vec::new();
        for &f in &region {
            self.in_region[f as usize] = false;
            orphans.extend(self.remove_face(f));
        }
        let m = cycle.len();
        let h = |i: usize| self.pts[cycle[i % m] as usize];
        // Runs of horizon edges that form one new face: (first edge, count).
        let mut runs: Vec<(usize, usize)> = Vec::new();
        if self.policy == CoplanarPolicy::Merge {
            // Cone triangles i and i+1 are coplanar iff h_i, h_i+1, h_i+2, p are.
            let joins: Vec<bool> = (0..m)
                .map(|i| det(sub(h(i + 1), h(i)), sub(h(i + 2), h(i)), sub(p, h(i))) == 0)
                .collect();
            let Some(first) = (0..m).find(|&i| !joins[(i + m - 1) % m]) else {
                return Err(crate::Error::Internal("flat cone".into()));
            };
            let mut i = first;
            while i < first + m {
                let start_edge = i;
                while joins[i % m] {
                    i += 1;
                }
                runs.push((start_edge % m, i - start_edge + 1));
                i += 1;
            }
        } else {
            runs.extend((0..m).map(|i| (i, 1)));
        }
        let n_new = runs.len();
        let mut new_faces = Vec::with_capacity(n_new);
        for &(e0, len) in &runs {
            let mut verts: Vec<u32> = (0..=len).map(|j| cycle[(e0 + j) % m]).collect();
            verts.push(pi);
            let mut twins: Vec<u32> = (0..len).map(|j| outer[(e0 + j) % m]).collect();
            twins.extend([NONE, NONE]);
            new_faces.push(self.add_face(verts, twins));
        }
        for (j, &(e0, len)) in runs.iter().enumerate() {
            let f = new_faces[j];
            let (next_face, prev_face) = (
                new_faces[(j + 1) % n_new],
                new_faces[(j + n_new - 1) % n_new],
            );
            if let Some(face) = self.faces[f as usize].as_mut() {
                face.twins[len] = next_face;
                face.twins[len + 1] = prev_face;
            }
            // The outer faces now border the new face.
            for k in 0..len {
                let (u, w) = (cycle[(e0 + k) % m], cycle[(e0 + k + 1) % m]);
                let g = outer[(e0 + k) % m];
                let slot = (0..self.n_edges(g)).find(|&e| self.edge(g, e) == (w, u));
                match (slot, self.faces[g as usize].as_mut()) {
                    (Some(e), Some(face)) => face.twins[e] = f,
                    _ => return Err(internal("horizon edge missing in its outer face")),
                }
            }
        }
        orphans.retain(|&q| q != pi);
        self.assign(&orphans, &new_faces);
        self.touched.extend_from_slice(&new_faces);
        self.stats.inserted += 1;
        Ok(true)
    }

    /// The faces to replace for a point with `visible` faces (non-empty,
    /// flagged in `in_region`).
    fn region(&mut self, visible: Vec<u32>, p: P3) -> crate::Result<Vec<u32>> {
        let n_visible = visible.len();
        let mut region = visible;
        match self.policy {
            CoplanarPolicy::Visible => {
                // Coplanar faces edge-connected to the visible ones join R.
                let mut k = 0;
                while k < region.len() {
                    let fv = region[k];
                    for e in 0..self.n_edges(fv) {
                        let g = self.twin(fv, e)?;
                        if !self.in_region[g as usize] && self.side(g, p) == 0 {
                            self.in_region[g as usize] = true;
                            region.push(g);
                        }
                    }
                    k += 1;
                }
            }
            CoplanarPolicy::Merge => {
                // 2-D extension: coplanar faces next to a visible face absorb p.
                for k in 0..n_visible {
                    let fv = region[k];
                    for e in 0..self.n_edges(fv) {
                        let g = self.twin(fv, e)?;
                        if !self.in_region[g as usize] && self.side(g, p) == 0 {
                            self.in_region[g as usize] = true;
                            region.push(g);
                        }
                    }
                }
            }
            CoplanarPolicy::Invisible => {
                // Coplanar faces stay, except where p is collinear with the
                // shared edge (the cone triangle would be degenerate).
                let mut k = 0;
                while k < region.len() {
                    let fv = region[k];
                    for e in 0..self.n_edges(fv) {
                        let (u, w) = self.edge(fv, e);
                        let g = self.twin(fv, e)?;
                        if self.in_region[g as usize] || self.side(g, p) != 0 {
                            continue;
                        }
                        let (a, b) = (self.pts[u as usize], self.pts[w as usize]);
                        if cross(sub(b, a), sub(p, a)) == [0, 0, 0] {
                            self.in_region[g as usize] = true;
                            self.stats.promoted += 1;
                            region.push(g);
                        }
                    }
                    k += 1;
                }
            }
        }
        Ok(region)
    }

    /// Qhull's order: repeatedly the point of some non-empty outside set
    /// that lies furthest beyond that set's face (largest `s`, exact), until
    /// every outside set is empty.
    pub fn run_furthest(&mut self) -> crate::Result<()> {
        let mut pending: Vec<u32> = (0..self.faces.len() as u32).collect();
        while let Some(f) = pending.pop() {
            let fi = f as usize;
            let Some(face) = &self.faces[fi] else {
                continue;
            };
            let (n, d) = (face.n, face.d);
            let Some(&q) = self.outside[fi]
                .iter()
                .max_by_key(|&&q| (dot(n, self.pts[q as usize]) - d, std::cmp::Reverse(q)))
            else {
                continue;
            };
            self.insert(q)?;
            // Only the new faces can have received points.
            pending.append(&mut self.touched);
        }
        self.stats.skipped = self.stats.candidates - self.stats.inserted;
        Ok(())
    }

    /// Number of edges of face `f` (0 for a dead slot).
    fn n_edges(&self, f: u32) -> usize {
        self.faces[f as usize]
            .as_ref()
            .map_or(0, |fc| fc.verts.len())
    }

    /// Directed edge `e` of face `f` (CCW from outside).
    fn edge(&self, f: u32, e: usize) -> (u32, u32) {
        self.faces[f as usize].as_ref().map_or((0, 0), |fc| {
            (fc.verts[e], fc.verts[(e + 1) % fc.verts.len()])
        })
    }
}
