//! The incremental hull of seed §4.1.4–4.1.8 in exact integer arithmetic.
//!
//! Points are inserted one after another. For point `p` every face `F` gets
//! `s = n·p − d` (Def. VI: `> 0` visible, `< 0` invisible, `= 0` coplanar;
//! `n` is the primitive outward integer normal, `d = n·Q` for a vertex `Q`).
//! The faces to replace form a region R (by policy, see
//! [`CoplanarPolicy`]); its boundary, the horizon, is joined to `p` by a cone
//! of new faces. Coordinates are bounded by [`MAX_COORD`], so every normal
//! (≤ 2³⁵), offset and `s` (≤ 2⁵⁴) fits `i64` without overflow; volumes are
//! accumulated in `i128`.

use std::collections::HashMap;

use super::CoplanarPolicy;

/// Largest accepted |coordinate| (combinatorial units): 2¹⁶.
pub const MAX_COORD: i64 = 1 << 16;

pub(crate) type P3 = [i64; 3];

pub(crate) fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn cross(a: P3, b: P3) -> P3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(crate) fn dot(a: P3, b: P3) -> i64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `det(a, b, c)` in `i128` (for volumes; arguments up to 2¹⁷).
pub(crate) fn det128(a: P3, b: P3, c: P3) -> i128 {
    let w = |v: P3| v.map(i128::from);
    let (a, b, c) = (w(a), w(b), w(c));
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

fn gcd(mut a: i64, mut b: i64) -> i64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a.abs()
}

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

pub(crate) struct Builder<'a> {
    pts: &'a [P3],
    policy: CoplanarPolicy,
    pub faces: Vec<Option<Face>>,
    /// `[nx, ny, nz, d]` per face slot; dead slots are `[0, 0, 0, 1]` (s = −1).
    planes: Vec<[i64; 4]>,
    free: Vec<u32>,
    edge_face: HashMap<(u32, u32), u32>,
    /// 6·volume of the current polyhedron, kept incrementally (ch. 5).
    pub vol6: i128,
    pub stats: HullStats,
    s: Vec<i64>,
    in_region: Vec<bool>,
}

impl<'a> Builder<'a> {
    /// Starts from the tetrahedron `t` (indices into `pts`, non-coplanar).
    pub fn new(pts: &'a [P3], policy: CoplanarPolicy, t: [u32; 4]) -> Builder<'a> {
        let mut b = Builder {
            pts,
            policy,
            faces: Vec::new(),
            planes: Vec::new(),
            free: Vec::new(),
            edge_face: HashMap::new(),
            vol6: 0,
            stats: HullStats {
                candidates: pts.len(),
                inserted: 4,
                ..HullStats::default()
            },
            s: Vec::new(),
            in_region: Vec::new(),
        };
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
            b.add_face(verts);
        }
        let p = |i: usize| pts[t[i] as usize];
        b.vol6 = det128(sub(p(1), p(0)), sub(p(2), p(0)), sub(p(3), p(0))).abs();
        b
    }

    fn add_face(&mut self, verts: Vec<u32>) {
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
                self.planes.push([0, 0, 0, 1]);
                self.s.push(0);
                self.in_region.push(false);
                (self.faces.len() - 1) as u32
            }
        };
        for k in 0..verts.len() {
            self.edge_face
                .insert((verts[k], verts[(k + 1) % verts.len()]), id);
        }
        self.planes[id as usize] = [n[0], n[1], n[2], d];
        self.faces[id as usize] = Some(Face { verts, n, d });
    }

    fn remove_face(&mut self, id: u32) {
        if let Some(f) = self.faces[id as usize].take() {
            for k in 0..f.verts.len() {
                self.edge_face
                    .remove(&(f.verts[k], f.verts[(k + 1) % f.verts.len()]));
            }
            self.planes[id as usize] = [0, 0, 0, 1];
            self.free.push(id);
        }
    }

    fn twin(&self, u: u32, w: u32) -> crate::Result<u32> {
        self.edge_face.get(&(w, u)).copied().ok_or_else(|| {
            crate::Error::InvalidInput(format!("hull edge {u}→{w} has no twin (internal error)"))
        })
    }

    /// Inserts point `pi`; returns whether the polyhedron changed.
    pub fn insert(&mut self, pi: u32) -> crate::Result<bool> {
        let p = self.pts[pi as usize];
        let mut visible = Vec::new();
        for (f, pl) in self.planes.iter().enumerate() {
            let s = pl[0] * p[0] + pl[1] * p[1] + pl[2] * p[2] - pl[3];
            self.s[f] = s;
            if s > 0 {
                visible.push(f as u32);
            }
        }
        self.stats.visibility_tests += self.planes.len() as u64;
        if visible.is_empty() {
            self.stats.skipped += 1;
            return Ok(false);
        }
        let region = self.region(&visible, p)?;
        // Horizon: directed edges of R whose twin face is outside R.
        let mut next: HashMap<u32, u32> = HashMap::new();
        for &f in &region {
            let verts = &self.faces[f as usize]
                .as_ref()
                .map(|f| f.verts.clone())
                .unwrap_or_default();
            for k in 0..verts.len() {
                let (u, w) = (verts[k], verts[(k + 1) % verts.len()]);
                let g = self.twin(u, w)?;
                if !self.in_region[g as usize] && next.insert(u, w).is_some() {
                    return Err(crate::Error::InvalidInput(
                        "visible region of a hull point is not a disk (internal error)".into(),
                    ));
                }
            }
        }
        let Some(&start) = next.keys().min() else {
            return Err(crate::Error::InvalidInput(
                "empty horizon (internal error)".into(),
            ));
        };
        let mut cycle = vec![start];
        let mut u = start;
        loop {
            let w = *next.get(&u).ok_or_else(|| {
                crate::Error::InvalidInput("open horizon (internal error)".into())
            })?;
            if w == start {
                break;
            }
            cycle.push(w);
            u = w;
            if cycle.len() > next.len() {
                return Err(crate::Error::InvalidInput(
                    "horizon is not one cycle (internal error)".into(),
                ));
            }
        }
        if cycle.len() != next.len() {
            return Err(crate::Error::InvalidInput(
                "horizon is not one cycle (internal error)".into(),
            ));
        }
        // Incremental volume: the cone over R adds Σ vol(p, fan triangle).
        for &f in &region {
            if let Some(face) = &self.faces[f as usize] {
                let v0 = sub(self.pts[face.verts[0] as usize], p);
                for k in 1..face.verts.len() - 1 {
                    let a = sub(self.pts[face.verts[k] as usize], p);
                    let b = sub(self.pts[face.verts[k + 1] as usize], p);
                    self.vol6 -= det128(v0, a, b);
                }
            }
        }
        for &f in &region {
            self.in_region[f as usize] = false;
            self.remove_face(f);
        }
        let m = cycle.len();
        let h = |i: usize| self.pts[cycle[i % m] as usize];
        if self.policy == CoplanarPolicy::Merge {
            // Cone triangles i and i+1 are coplanar iff h_i, h_i+1, h_i+2, p are.
            let joins: Vec<bool> = (0..m)
                .map(|i| det128(sub(h(i + 1), h(i)), sub(h(i + 2), h(i)), sub(p, h(i))) == 0)
                .collect();
            let Some(first) = (0..m).find(|&i| !joins[(i + m - 1) % m]) else {
                return Err(crate::Error::InvalidInput(
                    "flat cone (internal error)".into(),
                ));
            };
            let mut i = first;
            while i < first + m {
                let mut verts = vec![cycle[i % m]];
                while joins[i % m] {
                    i += 1;
                    verts.push(cycle[i % m]);
                }
                verts.push(cycle[(i + 1) % m]);
                verts.push(pi);
                self.add_face(verts);
                i += 1;
            }
        } else {
            for i in 0..m {
                self.add_face(vec![cycle[i], cycle[(i + 1) % m], pi]);
            }
        }
        self.stats.inserted += 1;
        Ok(true)
    }

    /// The faces to replace for a point with `visible` faces (non-empty).
    fn region(&mut self, visible: &[u32], p: P3) -> crate::Result<Vec<u32>> {
        let mut region = visible.to_vec();
        for &f in visible {
            self.in_region[f as usize] = true;
        }
        match self.policy {
            CoplanarPolicy::Visible => {
                // Coplanar faces edge-connected to the visible ones join R.
                let mut k = 0;
                while k < region.len() {
                    let verts = self.face_verts(region[k]);
                    for e in 0..verts.len() {
                        let g = self.twin(verts[e], verts[(e + 1) % verts.len()])?;
                        if !self.in_region[g as usize] && self.s[g as usize] == 0 {
                            self.in_region[g as usize] = true;
                            region.push(g);
                        }
                    }
                    k += 1;
                }
            }
            CoplanarPolicy::Merge => {
                // 2-D extension: coplanar faces next to a visible face absorb p.
                for &f in visible {
                    let verts = self.face_verts(f);
                    for e in 0..verts.len() {
                        let g = self.twin(verts[e], verts[(e + 1) % verts.len()])?;
                        if !self.in_region[g as usize] && self.s[g as usize] == 0 {
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
                    let verts = self.face_verts(region[k]);
                    for e in 0..verts.len() {
                        let (u, w) = (verts[e], verts[(e + 1) % verts.len()]);
                        let g = self.twin(u, w)?;
                        if self.in_region[g as usize] || self.s[g as usize] != 0 {
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

    fn face_verts(&self, f: u32) -> Vec<u32> {
        self.faces[f as usize]
            .as_ref()
            .map(|f| f.verts.clone())
            .unwrap_or_default()
    }
}
