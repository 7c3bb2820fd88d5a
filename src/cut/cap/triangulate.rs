//! Planar cap triangulation: takes 2-D points and loops over them (outer
//! loops counter-clockwise, holes clockwise) and returns triangles over the
//! point indices, bridging the holes in and clipping ears; also tells
//! whether loops nest as a cap.

use glam::DVec2;

fn area2(pts: &[DVec2], lp: &[usize]) -> f64 {
    let n = lp.len();
    (0..n)
        .map(|i| {
            let (a, b) = (pts[lp[i]], pts[lp[(i + 1) % n]]);
            a.x * b.y - a.y * b.x
        })
        .sum()
}

/// Whether `q` lies inside the ring of `n` points `at(0..n)` (crossing
/// parity of a ray towards +x): the one `f64` point-in-polygon test of the
/// cut, for cap loops and knife faces.
pub(crate) fn point_in_ring(n: usize, at: impl Fn(usize) -> DVec2, q: DVec2) -> bool {
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (at(i), at((i + 1) % n));
        if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y) {
            inside = !inside;
        }
    }
    inside
}

fn inside_polygon(pts: &[DVec2], lp: &[usize], q: DVec2) -> bool {
    point_in_ring(lp.len(), |i| pts[lp[i]], q)
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
