//! Caps: closing a cut with the knife surface (beyond the seed).
//!
//! The cut segments, directed as the negative side's triangles use them
//! and reversed, chain into loops. Loops are mapped to a plane (the knife
//! plane; for a sphere a stereographic projection from the pole opposite
//! the loops), where outer loops run counter-clockwise and holes clockwise;
//! each outer loop with the holes it contains is triangulated by ear
//! clipping after bridging the holes in. The same triangles close the
//! negative pieces (as is) and the positive pieces (reversed), so the cap
//! adds no volume: the pieces' volumes add up to the original's.
//!
//! Plane caps are flat. Sphere caps follow the sphere: the loop
//! triangulation (made in the stereographic plane, which is conformal) is
//! refined by bisecting interior edges at the sphere point over their
//! planar midpoint until each is shorter than [`sphere_max_edge`] (chord
//! error below [`SPHERE_CHORD_ERROR`]·r) or than 1.2 times the longest
//! loop edge, whichever is longer; loop edges are never split, so both sides
//! still share them. Lawson flips before and after every pass keep the
//! interior edges Delaunay in that plane, so no slivers are refined. Where
//! the surface meets the sphere at a grazing angle, the cap triangles that
//! cross it (exact test) are bisected further ([`repair_on_sphere`]).

use std::collections::HashMap;

use glam::{DVec2, DVec3};

/// Loops of cut vertices from directed segments `a → b` (as the negative
/// side's triangles use them), each returned reversed (cap orientation).
/// Chains that do not close into a loop are counted as open.
pub fn loops(segments: &[(u32, u32)]) -> (Vec<Vec<u32>>, usize) {
    let mut succ: HashMap<u32, u32> = HashMap::with_capacity(segments.len());
    let mut bad = std::collections::HashSet::new();
    for &(a, b) in segments {
        // Cap direction: b → a.
        if succ.insert(b, a).is_some() {
            bad.insert(b);
        }
    }
    let mut out = Vec::new();
    let mut seen = std::collections::HashSet::new();
    // Open chains, walked from their heads (no predecessor): one each.
    let preds: std::collections::HashSet<u32> = succ.values().copied().collect();
    let mut heads: Vec<u32> = succ
        .keys()
        .filter(|v| !preds.contains(v))
        .copied()
        .collect();
    heads.sort_unstable();
    let mut open = heads.len();
    for h in heads {
        let mut v = h;
        while seen.insert(v) {
            match succ.get(&v) {
                Some(&w) => v = w,
                None => break,
            }
        }
    }
    let mut starts: Vec<u32> = succ.keys().copied().collect();
    starts.sort_unstable();
    for s in starts {
        if seen.contains(&s) {
            continue;
        }
        let mut lp = vec![s];
        seen.insert(s);
        let mut v = s;
        let closed = loop {
            if bad.contains(&v) {
                break false;
            }
            match succ.get(&v) {
                None => break false,
                Some(&w) if w == s => break true,
                Some(&w) => {
                    if !seen.insert(w) {
                        break false;
                    }
                    lp.push(w);
                    v = w;
                }
            }
        };
        if closed && lp.len() >= 3 {
            out.push(lp);
        } else {
            open += 1;
        }
    }
    (out, open)
}

/// Maps points to the cap plane.
#[derive(Debug, Clone, Copy)]
pub enum Projection {
    /// Orthonormal `u, v` with `u × v` = the cap's outward normal for the
    /// negative side.
    Plane { origin: DVec3, u: DVec3, v: DVec3 },
    /// Stereographic from the pole `c − r·d`, plane basis `u × v = d`.
    Sphere {
        c: DVec3,
        r: f64,
        d: DVec3,
        u: DVec3,
        v: DVec3,
    },
}

/// Two unit vectors completing `n` to a right-handed frame (`u × v = n`).
pub fn frame(n: DVec3) -> (DVec3, DVec3) {
    let u = n.any_orthonormal_vector();
    (u, n.cross(u))
}

impl Projection {
    /// The point of the sphere whose image is `q` (inverse stereographic
    /// projection); `None` for the plane projection.
    pub fn unapply(&self, q: DVec2) -> Option<DVec3> {
        match *self {
            Projection::Plane { .. } => None,
            Projection::Sphere { c, r, d, u, v } => {
                let s = q.length_squared();
                let w = (u * (2.0 * q.x) + v * (2.0 * q.y) + d * (1.0 - s)) / (1.0 + s);
                Some(c + w * r)
            }
        }
    }

    /// The 2-D image of `p`; `None` at the projection pole.
    pub fn apply(&self, p: DVec3) -> Option<DVec2> {
        match *self {
            Projection::Plane { origin, u, v } => {
                Some(DVec2::new(u.dot(p - origin), v.dot(p - origin)))
            }
            Projection::Sphere { c, r, d, u, v } => {
                let w = (p - c) / r;
                let den = 1.0 + w.dot(d);
                (den > 1e-9).then(|| DVec2::new(w.dot(u) / den, w.dot(v) / den))
            }
        }
    }
}

fn area2(pts: &[DVec2], lp: &[usize]) -> f64 {
    let n = lp.len();
    (0..n)
        .map(|i| {
            let (a, b) = (pts[lp[i]], pts[lp[(i + 1) % n]]);
            a.x * b.y - a.y * b.x
        })
        .sum()
}

fn inside_polygon(pts: &[DVec2], lp: &[usize], q: DVec2) -> bool {
    let n = lp.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (pts[lp[i]], pts[lp[(i + 1) % n]]);
        if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y) {
            inside = !inside;
        }
    }
    inside
}

/// Whether loops mapped to the plane nest as a cap needs: every loop
/// inside an even number of others runs counter-clockwise (an outer
/// boundary) and every other loop clockwise (a hole). A sphere projected
/// from a pole inside a cap region fails this (its outermost loops come out
/// clockwise), so the caller tries another pole.
pub fn nests_as_cap(pts: &[DVec2], loops: &[Vec<usize>]) -> bool {
    loops.iter().enumerate().all(|(h, lp)| {
        let area = area2(pts, lp);
        if area == 0.0 {
            // A degenerate loop (coincident cut points) bounds nothing.
            return true;
        }
        let q = pts[lp[0]];
        let depth = loops
            .iter()
            .enumerate()
            .filter(|&(o, other)| o != h && inside_polygon(pts, other, q))
            .count();
        (depth % 2 == 0) == (area > 0.0)
    })
}

/// Triangulates loops (indices into `pts`, cap orientation) into
/// triangles of the same indices, counter-clockwise in the plane. Outer
/// loops have positive area; every hole goes to the smallest outer loop
/// containing it. Each loop edge ends up in exactly one triangle.
pub fn triangulate(pts: &[DVec2], loops: &[Vec<usize>]) -> Vec<[usize; 3]> {
    let areas: Vec<f64> = loops.iter().map(|l| area2(pts, l)).collect();
    let outers: Vec<usize> = (0..loops.len()).filter(|&i| areas[i] > 0.0).collect();
    let mut holes_of: Vec<Vec<usize>> = vec![Vec::new(); loops.len()];
    let mut orphans = Vec::new();
    for h in (0..loops.len()).filter(|&i| areas[i] <= 0.0) {
        let q = pts[loops[h][0]];
        let owner = outers
            .iter()
            .copied()
            .filter(|&o| inside_polygon(pts, &loops[o], q))
            .min_by(|&a, &b| areas[a].total_cmp(&areas[b]));
        match owner {
            Some(o) => holes_of[o].push(h),
            None => orphans.push(h),
        }
    }
    let mut tris = Vec::new();
    for &o in &outers {
        let mut poly = loops[o].clone();
        let mut holes: Vec<usize> = holes_of[o].clone();
        // Rightmost holes first (earcut order).
        holes.sort_by(|&a, &b| {
            let mx = |h: usize| loops[h].iter().map(|&i| pts[i].x).fold(f64::MIN, f64::max);
            mx(b).total_cmp(&mx(a))
        });
        for h in holes {
            poly = bridge(pts, &poly, &loops[h], loops);
        }
        ear_clip(pts, poly, &mut tris);
    }
    // A clockwise loop with no outer around it (degenerate projection):
    // still close it, so every edge is used once.
    for h in orphans {
        ear_clip_any(pts, loops[h].clone(), &mut tris);
    }
    tris
}

fn segments_cross(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let o = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let (d1, d2, d3, d4) = (o(a, b, c), o(a, b, d), o(c, d, a), o(c, d, b));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// Splices `hole` into `poly` along a visible bridge from the hole's
/// rightmost vertex to the nearest polygon vertex.
fn bridge(pts: &[DVec2], poly: &[usize], hole: &[usize], all: &[Vec<usize>]) -> Vec<usize> {
    let hm = (0..hole.len())
        .max_by(|&a, &b| pts[hole[a]].x.total_cmp(&pts[hole[b]].x))
        .unwrap_or(0);
    let m = pts[hole[hm]];
    let mut order: Vec<usize> = (0..poly.len()).collect();
    order.sort_by(|&a, &b| {
        (pts[poly[a]] - m)
            .length_squared()
            .total_cmp(&(pts[poly[b]] - m).length_squared())
    });
    let visible = |k: usize| {
        let p = pts[poly[k]];
        let crosses = |lp: &[usize]| {
            (0..lp.len()).any(|i| segments_cross(m, p, pts[lp[i]], pts[lp[(i + 1) % lp.len()]]))
        };
        !crosses(poly) && !all.iter().any(|l| crosses(l))
    };
    let k = order
        .iter()
        .copied()
        .find(|&k| visible(k))
        .unwrap_or(order[0]);
    let mut out = Vec::with_capacity(poly.len() + hole.len() + 2);
    out.extend_from_slice(&poly[..=k]);
    out.extend((0..=hole.len()).map(|i| hole[(hm + i) % hole.len()]));
    out.extend_from_slice(&poly[k..]);
    out
}

fn cross(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

fn in_triangle(a: DVec2, b: DVec2, c: DVec2, p: DVec2) -> bool {
    cross(a, b, p) >= 0.0 && cross(b, c, p) >= 0.0 && cross(c, a, p) >= 0.0
}

/// The reflex vertices of a ring in a uniform grid over its bounding box,
/// about one cell per vertex: an ear test visits only the cells under the
/// ear's box. A vertex's turn changes only when a clip makes it the
/// neighbour of another; the clip then inserts it if it has become reflex
/// (a forced clip, or collinear points and bridges), so every reflex vertex
/// is listed.
struct ReflexGrid {
    min: DVec2,
    scale: DVec2,
    side: usize,
    cells: Vec<Vec<usize>>,
    listed: Vec<bool>,
}

impl ReflexGrid {
    fn new(at: impl Fn(usize) -> DVec2, n: usize) -> Self {
        let (mut min, mut max) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for i in 0..n {
            min = min.min(at(i));
            max = max.max(at(i));
        }
        let side = (n as f64).sqrt().ceil().max(1.0) as usize;
        let extent = (max - min).max(DVec2::splat(f64::MIN_POSITIVE));
        ReflexGrid {
            min,
            scale: DVec2::splat(side as f64) / extent,
            side,
            cells: vec![Vec::new(); side * side],
            listed: vec![false; n],
        }
    }

    /// Cell coordinates of `p`, clamped to the grid.
    fn cell(&self, p: DVec2) -> (usize, usize) {
        let c = ((p - self.min) * self.scale).floor();
        let clamp = |v: f64| (v.max(0.0) as usize).min(self.side - 1);
        (clamp(c.x), clamp(c.y))
    }

    fn insert(&mut self, i: usize, p: DVec2) {
        if !self.listed[i] {
            self.listed[i] = true;
            let (x, y) = self.cell(p);
            self.cells[y * self.side + x].push(i);
        }
    }

    /// Whether `blocks(j)` holds for a listed vertex under the box of `tri`.
    fn any_under(&self, tri: [DVec2; 3], mut blocks: impl FnMut(usize) -> bool) -> bool {
        let lo = tri[0].min(tri[1]).min(tri[2]);
        let hi = tri[0].max(tri[1]).max(tri[2]);
        let ((x0, y0), (x1, y1)) = (self.cell(lo), self.cell(hi));
        (y0..=y1)
            .any(|y| (x0..=x1).any(|x| self.cells[y * self.side + x].iter().any(|&j| blocks(j))))
    }
}

/// Ear clipping of a counter-clockwise polygon (bridges allowed: repeated
/// indices) over a linked ring, walking on after each clip (earcut's
/// scheme). An ear test looks only at the reflex vertices under the ear's
/// box ([`ReflexGrid`]): O(n) per test at worst, far less on cut loops of
/// thousands of vertices. When a full turn finds no proper ear (degenerate
/// input) the most convex vertex is clipped, so it always terminates with
/// n − 2 triangles.
fn ear_clip(pts: &[DVec2], poly: Vec<usize>, out: &mut Vec<[usize; 3]>) {
    let n = poly.len();
    if n < 3 {
        return;
    }
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let mut next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
    let mut clipped = vec![false; n];
    let at = |i: usize| pts[poly[i]];
    let mut grid = ReflexGrid::new(at, n);
    for j in 0..n {
        if cross(at(prev[j]), at(j), at(next[j])) <= 0.0 {
            grid.insert(j, at(j));
        }
    }
    let mut remaining = n;
    let mut i = 0;
    let mut since = 0;
    while remaining > 3 {
        let (a, c) = (prev[i], next[i]);
        let ear = cross(at(a), at(i), at(c)) > 0.0 && {
            let (pa, pb, pc) = (at(a), at(i), at(c));
            !grid.any_under([pa, pb, pc], |j| {
                let q = at(j);
                !clipped[j]
                    && j != a
                    && j != i
                    && j != c
                    && cross(at(prev[j]), q, at(next[j])) <= 0.0
                    && q != pa
                    && q != pb
                    && q != pc
                    && in_triangle(pa, pb, pc, q)
            })
        };
        let clip = if ear {
            Some(i)
        } else {
            since += 1;
            (since >= remaining).then(|| {
                let mut best = i;
                let mut best_c = f64::NEG_INFINITY;
                let mut j = i;
                for _ in 0..remaining {
                    let cj = cross(at(prev[j]), at(j), at(next[j]));
                    if cj > best_c {
                        best_c = cj;
                        best = j;
                    }
                    j = next[j];
                }
                best
            })
        };
        match clip {
            Some(v) => {
                let (a, c) = (prev[v], next[v]);
                out.push([poly[a], poly[v], poly[c]]);
                next[a] = c;
                prev[c] = a;
                clipped[v] = true;
                remaining -= 1;
                since = 0;
                // Only the new neighbours change their turn.
                for k in [a, c] {
                    if cross(at(prev[k]), at(k), at(next[k])) <= 0.0 {
                        grid.insert(k, at(k));
                    }
                }
                i = c;
            }
            None => i = next[i],
        }
    }
    out.push([poly[prev[i]], poly[i], poly[next[i]]]);
}

/// Ear clipping of a loop of either orientation (keeps the loop's direction).
fn ear_clip_any(pts: &[DVec2], poly: Vec<usize>, out: &mut Vec<[usize; 3]>) {
    if area2(pts, &poly) >= 0.0 {
        ear_clip(pts, poly, out);
    } else {
        let flipped: Vec<DVec2> = pts.iter().map(|p| DVec2::new(p.x, -p.y)).collect();
        ear_clip(&flipped, poly, out);
    }
}

/// Largest sagitta of an interior cap edge on a sphere, relative to the radius.
pub const SPHERE_CHORD_ERROR: f64 = 1e-3;

/// Longest interior cap edge on a sphere of radius `r`: the sagitta of a
/// chord of length L is `r − √(r² − L²/4) ≈ L²/(8r)`, so `L = r·√(8ε)`.
pub fn sphere_max_edge(r: f64) -> f64 {
    r * (8.0 * SPHERE_CHORD_ERROR).sqrt()
}

/// Interior cap edges may be this many times the longest loop edge: a
/// triangle on a loop edge keeps an interior edge about as long as it.
const LOOP_EDGE_FACTOR: f64 = 1.2;

/// Refinement passes at most (each halves the longest edges; the rest are
/// triangles on loop edges that bisection cannot shorten).
const MAX_PASSES: usize = 48;

/// Per edge of `tris` (key: sorted vertex pair) its first two triangles and
/// its use count.
type EdgeUses = HashMap<(usize, usize), ([usize; 2], u32)>;

fn edge_key(a: usize, b: usize) -> (usize, usize) {
    (a.min(b), a.max(b))
}

fn edge_uses(tris: &[[usize; 3]]) -> EdgeUses {
    let mut uses: EdgeUses = HashMap::with_capacity(3 * tris.len());
    for (t, tri) in tris.iter().enumerate() {
        for e in 0..3 {
            let slot = uses
                .entry(edge_key(tri[e], tri[(e + 1) % 3]))
                .or_insert(([usize::MAX; 2], 0));
            if slot.1 < 2 {
                slot.0[slot.1 as usize] = t;
            }
            slot.1 += 1;
        }
    }
    uses
}

/// Refines cap triangles `tris` (indices into `pts`, their images in the
/// stereographic plane of `proj`, and `pos`, the points on the sphere):
/// every edge used by two triangles and longer than `max_edge` in space
/// and than [`LOOP_EDGE_FACTOR`] times the longest edge used once, is
/// bisected, longest first, at the point of the sphere over its planar
/// midpoint (appended to both); edges used once (the cut loops) are kept.
/// Before the first pass and after each, `delaunay_flips` makes the
/// interior edges Delaunay in the plane. The projection is conformal and
/// keeps orientation, so the refined triangles keep theirs. Stops after `max_triangles` or [`MAX_PASSES`].
pub fn refine_on_sphere(
    tris: &mut Vec<[usize; 3]>,
    pts: &mut Vec<DVec2>,
    pos: &mut Vec<DVec3>,
    proj: &Projection,
    max_edge: f64,
    max_triangles: usize,
) {
    let mut max_edge = max_edge;
    delaunay_flips(tris, pts);
    for _ in 0..MAX_PASSES {
        let uses = edge_uses(tris);
        let longest_loop_edge = uses
            .iter()
            .filter(|(_, (_, n))| *n == 1)
            .map(|(k, _)| (pos[k.0] - pos[k.1]).length())
            .fold(0.0, f64::max);
        max_edge = max_edge.max(LOOP_EDGE_FACTOR * longest_loop_edge);
        let long: Vec<(f64, (usize, usize), [usize; 2])> = uses
            .iter()
            .filter(|(_, (_, n))| *n == 2)
            .map(|(&k, &(ts, _))| ((pos[k.0] - pos[k.1]).length(), k, ts))
            .filter(|(l, _, _)| *l > max_edge)
            .collect();
        if long.is_empty() || tris.len() >= max_triangles {
            return;
        }
        if bisect(tris, pts, pos, proj, long, max_triangles).is_empty() {
            return;
        }
        delaunay_flips(tris, pts);
    }
}

/// A plane point for the exact predicates of `robust`.
fn coord(p: DVec2) -> robust::Coord<f64> {
    robust::Coord { x: p.x, y: p.y }
}

/// Makes the interior edges of `tris` locally Delaunay in the plane of
/// `pts` (Lawson flips, exact incircle test; edges used once are kept):
/// after a bisection pass this replaces the slivers between loop points and
/// the new midpoints by well-shaped triangles, so the next pass splits far
/// fewer edges. The projection is conformal, so shapes in the plane are
/// shapes on the sphere; each flip keeps both triangles' orientation (an
/// edge that fails the test has a convex quadrilateral).
fn delaunay_flips(tris: &mut [[usize; 3]], pts: &[DVec2]) {
    let mut uses = edge_uses(tris);
    let mut stack: Vec<(usize, usize)> = uses
        .iter()
        .filter(|(_, (_, n))| *n == 2)
        .map(|(&k, _)| k)
        .collect();
    stack.sort_unstable();
    // (p, q, c): the edge as it runs in triangle t and t's third corner.
    let around = |tri: [usize; 3], k: (usize, usize)| {
        (0..3)
            .map(|e| (tri[e], tri[(e + 1) % 3], tri[(e + 2) % 3]))
            .find(|&(p, q, _)| edge_key(p, q) == k)
    };
    while let Some(k) = stack.pop() {
        let Some(&([t0, t1], 2)) = uses.get(&k) else {
            continue;
        };
        let (Some((p, q, c)), Some((q1, p1, d))) = (around(tris[t0], k), around(tris[t1], k))
        else {
            continue;
        };
        if (p1, q1) != (p, q) || c == d {
            continue;
        }
        let turn = robust::orient2d(coord(pts[p]), coord(pts[q]), coord(pts[c]));
        let inside = robust::incircle(coord(pts[p]), coord(pts[q]), coord(pts[c]), coord(pts[d]));
        if turn == 0.0 || inside * turn <= 0.0 || uses.contains_key(&edge_key(c, d)) {
            continue;
        }
        tris[t0] = [c, p, d];
        tris[t1] = [d, q, c];
        uses.remove(&k);
        uses.insert(edge_key(c, d), ([t0, t1], 2));
        for (e, from, to) in [(edge_key(q, c), t0, t1), (edge_key(p, d), t1, t0)] {
            if let Some((ts, _)) = uses.get_mut(&e) {
                ts.iter_mut().filter(|t| **t == from).for_each(|t| *t = to);
            }
        }
        stack.extend([
            edge_key(c, p),
            edge_key(p, d),
            edge_key(d, q),
            edge_key(q, c),
        ]);
    }
}

/// Rounds of [`repair_on_sphere`] without fewer crossings before it stops.
pub const STALLED_ROUNDS: usize = 3;

/// What [`repair_on_sphere`] asks about the cut surface: per cap triangle
/// `tris[check[k]]` (corners in `pos`), the number of surface and cap
/// triangles it meets beyond shared vertices.
pub trait CapCheck {
    fn crossings(&mut self, tris: &[[usize; 3]], check: &[usize], pos: &[DVec3]) -> Vec<u32>;
}

/// Repairs a refined sphere cap where it crosses the surface: a surface
/// meeting the sphere at a grazing angle runs just inside it, closer than
/// a cap chord sags. Each round bisects, in every cap triangle that
/// crosses, its longest interior edge as [`refine_on_sphere`] does, and
/// counts again the triangles it changed. A new point can also land in the
/// thin band between a loop edge's chord and the sphere where the surface
/// runs outside the sphere, and cross it there, so the rounds can make
/// things worse (and a surface lying on the sphere to f32 precision only
/// touches more cap triangles the finer they get): the cap with the fewest
/// crossings seen is kept. Stops when nothing crosses, nothing can be
/// split, after [`STALLED_ROUNDS`] rounds without a new best, or after
/// `max_rounds`; returns the rounds made and the crossings left (summed
/// over the cap triangles: a pair of cap triangles counts twice).
pub fn repair_on_sphere(
    tris: &mut Vec<[usize; 3]>,
    pts: &mut Vec<DVec2>,
    pos: &mut Vec<DVec3>,
    proj: &Projection,
    max_triangles: usize,
    max_rounds: usize,
    surface: &mut impl CapCheck,
) -> (usize, u64) {
    let all: Vec<usize> = (0..tris.len()).collect();
    let mut count = surface.crossings(tris, &all, pos);
    let total = |count: &[u32]| count.iter().map(|&c| c as u64).sum::<u64>();
    // Points are only appended: a cap is its triangles and point count.
    let mut best = (total(&count), tris.clone(), pts.len());
    let (mut rounds, mut since_best) = (0, 0);
    while rounds < max_rounds && best.0 > 0 && since_best < STALLED_ROUNDS {
        let uses = edge_uses(tris);
        let chosen: Vec<(f64, (usize, usize), [usize; 2])> = (0..tris.len())
            .filter(|&t| count[t] > 0)
            .filter_map(|t| {
                let tri = tris[t];
                (0..3)
                    .map(|e| edge_key(tri[e], tri[(e + 1) % 3]))
                    .filter_map(|k| {
                        let &(ts, n) = uses.get(&k)?;
                        (n == 2).then(|| ((pos[k.0] - pos[k.1]).length(), k, ts))
                    })
                    .max_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)))
            })
            .collect();
        let changed = bisect(tris, pts, pos, proj, chosen, max_triangles);
        if changed.is_empty() {
            break;
        }
        rounds += 1;
        count.resize(tris.len(), 0);
        for (&t, c) in changed.iter().zip(surface.crossings(tris, &changed, pos)) {
            count[t] = c;
        }
        since_best += 1;
        if total(&count) < best.0 {
            best = (total(&count), tris.clone(), pts.len());
            since_best = 0;
        }
    }
    *tris = best.1;
    pts.truncate(best.2);
    pos.truncate(best.2);
    (rounds, best.0)
}

/// Bisects the interior edges `edges` (length, key, its two triangles),
/// longest first, each triangle at most once per call (an edge listed twice
/// is split once). Returns the triangles changed or added.
fn bisect(
    tris: &mut Vec<[usize; 3]>,
    pts: &mut Vec<DVec2>,
    pos: &mut Vec<DVec3>,
    proj: &Projection,
    mut edges: Vec<(f64, (usize, usize), [usize; 2])>,
    max_triangles: usize,
) -> Vec<usize> {
    edges.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut touched = vec![false; tris.len()];
    let mut changed = Vec::new();
    for (_, (a, b), ts) in edges {
        if ts.iter().any(|&t| touched[t]) || tris.len() + 2 > max_triangles {
            continue;
        }
        let mid = (pts[a] + pts[b]) * 0.5;
        let Some(q) = proj.unapply(mid) else {
            continue;
        };
        let m = pos.len();
        pts.push(mid);
        pos.push(q);
        for t in ts {
            touched[t] = true;
            let tri = tris[t];
            // Rotate so the split edge is (tri[0], tri[1]).
            let e = (0..3)
                .find(|&e| edge_key(tri[e], tri[(e + 1) % 3]) == (a, b))
                .unwrap_or(0);
            let (x, y, z) = (tri[e], tri[(e + 1) % 3], tri[(e + 2) % 3]);
            tris[t] = [x, m, z];
            tris.push([m, y, z]);
            touched.push(true);
            changed.extend([t, tris.len() - 1]);
        }
    }
    changed
}

#[cfg(test)]
mod tests {
    use super::*;

    fn signed_area(t: [usize; 3], p: &[DVec2]) -> f64 {
        robust::orient2d(coord(p[t[0]]), coord(p[t[1]]), coord(p[t[2]]))
    }

    /// A band 40 long and 1 wide with 0.25 spacing along its long sides:
    /// ear clipping fans it into slivers; the flips leave a triangulation of
    /// the same region and boundary, every triangle still counter-clockwise,
    /// every interior edge locally Delaunay and no sliver spanning the band
    /// lengthwise.
    #[test]
    fn delaunay_flips_keep_the_region_and_make_edges_delaunay() {
        let mut pts: Vec<DVec2> = (0..=160)
            .map(|i| DVec2::new(i as f64 * 0.25, 0.0))
            .collect();
        pts.extend((0..=160).rev().map(|i| DVec2::new(i as f64 * 0.25, 1.0)));
        let lp: Vec<usize> = (0..pts.len()).collect();
        let mut tris = triangulate(&pts, &[lp]);
        let boundary = |tris: &[[usize; 3]]| {
            let mut b: Vec<(usize, usize)> = edge_uses(tris)
                .into_iter()
                .filter(|(_, (_, n))| *n == 1)
                .map(|(k, _)| k)
                .collect();
            b.sort_unstable();
            b
        };
        let area = |tris: &[[usize; 3]]| tris.iter().map(|&t| signed_area(t, &pts)).sum::<f64>();
        let pts_ref = &pts;
        let longest = |tris: &[[usize; 3]]| {
            tris.iter()
                .flat_map(|t| {
                    (0..3).map(move |e| (pts_ref[t[e]] - pts_ref[t[(e + 1) % 3]]).length())
                })
                .fold(0.0, f64::max)
        };
        let (b0, a0, n0) = (boundary(&tris), area(&tris), tris.len());
        assert!(
            longest(&tris) > 5.0,
            "the fan has no sliver: the test shows nothing"
        );
        delaunay_flips(&mut tris, &pts);
        assert_eq!(tris.len(), n0);
        assert_eq!(boundary(&tris), b0);
        assert!((area(&tris) - a0).abs() < 1e-9 * a0.abs());
        assert!(tris.iter().all(|&t| signed_area(t, &pts) > 0.0));
        assert!(longest(&tris) < 1.1, "a sliver is left: {}", longest(&tris));
        for (&(a, b), &([t0, t1], n)) in &edge_uses(&tris) {
            if n != 2 {
                continue;
            }
            let third = |t: [usize; 3]| t.into_iter().find(|&v| v != a && v != b).unwrap();
            let (c, d) = (third(tris[t0]), third(tris[t1]));
            let [p, q, r] = tris[t0];
            assert!(
                robust::incircle(coord(pts[p]), coord(pts[q]), coord(pts[r]), coord(pts[d])) <= 0.0,
                "edge ({a}, {b}) with opposite corners {c} and {d} is not Delaunay"
            );
        }
    }
}
