//! Exact 2-D polygon routines on `i64` points, no epsilons: projection of
//! a plane point to 2-D, loop area, point in polygon, and ear clipping of a
//! weakly simple polygon with holes bridged in. Polygons are given as vertex
//! occurrences (indices into a position list); results are indices.

use std::cmp::Reverse;

use crate::foundation::exact::{P2, cross2, dot2, orient2, sub2};

/// `p` with the dominant axis of `n` dropped, ordered so that
/// counter-clockwise about `n` is counter-clockwise in the plane.
pub(super) fn project(p: [i64; 3], n: [i64; 3]) -> P2 {
    let k = (0..3)
        .max_by_key(|&a| (n[a].abs(), Reverse(a)))
        .unwrap_or(0);
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    if n[k] > 0 { [p[i], p[j]] } else { [p[j], p[i]] }
}

/// Whether `q` lies strictly inside segment `a b`.
pub(super) fn strictly_between(a: P2, b: P2, q: P2) -> bool {
    orient2(a, b, q) == 0 && dot2(sub2(q, a), sub2(b, a)) > 0 && dot2(sub2(q, b), sub2(a, b)) > 0
}

/// Twice the signed area of a loop.
pub(super) fn area2(lp: &[usize], pos: &[P2]) -> i128 {
    (0..lp.len())
        .map(|k| {
            let (a, b) = (pos[lp[k]], pos[lp[(k + 1) % lp.len()]]);
            i128::from(a[0]) * i128::from(b[1]) - i128::from(a[1]) * i128::from(b[0])
        })
        .sum()
}

/// Whether direction `d` is in the sector from `a` counter-clockwise to
/// `b` (both ends excluded).
fn in_sector(a: [i128; 2], b: [i128; 2], d: [i128; 2]) -> bool {
    if cross2(a, b) > 0 {
        cross2(a, d) > 0 && cross2(d, b) > 0
    } else {
        !(cross2(b, d) >= 0 && cross2(d, a) >= 0)
    }
}

/// Counter-clockwise angle from `r` to `d` as a sortable class: half-turn
/// (0 for [0, π), 1 for [π, 2π)), compared within a half by cross products.
pub(super) fn ccw_angle_less(r: [i128; 2], d1: [i128; 2], d2: [i128; 2]) -> bool {
    let half = |d: [i128; 2]| {
        let c = cross2(r, d);
        u8::from(!(c > 0 || (c == 0 && dot2(r, d) > 0)))
    };
    let (h1, h2) = (half(d1), half(d2));
    h1 < h2 || (h1 == h2 && cross2(d1, d2) > 0)
}

/// Exact crossing parity of the point `t` (doubled coordinates, on no edge)
/// for the loop `lp`.
pub(super) fn contains(lp: &[usize], q: &[P2], t: P2) -> bool {
    let mut inside = false;
    for k in 0..lp.len() {
        let (a, b) = (
            q[lp[k]].map(|c| 2 * c),
            q[lp[(k + 1) % lp.len()]].map(|c| 2 * c),
        );
        if (a[1] > t[1]) != (b[1] > t[1]) {
            let o = orient2(a, b, t);
            if (b[1] > a[1]) == (o > 0) {
                inside = !inside;
            }
        }
    }
    inside
}

/// A vertex of `poly` (position in it) that the hole vertex `hole[km]` (the
/// rightmost) sees: the segment leaves both into the region and meets no
/// other edge or vertex of the polygon or of any hole.
pub(super) fn find_bridge(
    poly: &[usize],
    hole: &[usize],
    km: usize,
    rest: &[Vec<usize>],
    pos: &[P2],
) -> Option<usize> {
    let m = pos[hole[km]];
    let mut cands: Vec<usize> = (0..poly.len()).collect();
    cands.sort_by_key(|&k| {
        let d = sub2(pos[poly[k]], m);
        (dot2(d, d), k)
    });
    let ring = |l: &[usize]| -> Vec<(P2, P2)> {
        (0..l.len())
            .map(|k| (pos[l[k]], pos[l[(k + 1) % l.len()]]))
            .collect()
    };
    let mut edges = ring(poly);
    edges.extend(ring(hole));
    for h in rest {
        edges.extend(ring(h));
    }
    let (hp, hn) = (
        pos[hole[(km + hole.len() - 1) % hole.len()]],
        pos[hole[(km + 1) % hole.len()]],
    );
    cands.into_iter().find(|&k| {
        let p = pos[poly[k]];
        let (pp, pn) = (
            pos[poly[(k + poly.len() - 1) % poly.len()]],
            pos[poly[(k + 1) % poly.len()]],
        );
        p != m
            && in_sector(sub2(pn, p), sub2(pp, p), sub2(m, p))
            && in_sector(sub2(hn, m), sub2(hp, m), sub2(p, m))
            && !edges.iter().any(|&(u, w)| {
                if strictly_between(m, p, u) || strictly_between(m, p, w) {
                    return true;
                }
                if [u, w].iter().any(|&x| x == m || x == p) {
                    return false;
                }
                let proper = orient2(m, p, u).signum() * orient2(m, p, w).signum() < 0
                    && orient2(u, w, m).signum() * orient2(u, w, p).signum() < 0;
                proper || strictly_between(u, w, m) || strictly_between(u, w, p)
            })
    })
}

/// Ear clipping of the weakly simple polygon `poly` (occurrences into
/// `pos`, counter-clockwise). Returns the triangles (occurrences) and the
/// occurrences dropped as straight angles, spikes or repeats; `None` when
/// no ear is found.
pub(super) fn clip_ears(poly: &[usize], pos: &[P2]) -> Option<(Vec<[usize; 3]>, Vec<usize>)> {
    let n = poly.len();
    let mut next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let p = |i: usize| pos[poly[i]];
    let (mut tris, mut dropped) = (Vec::new(), Vec::new());
    let (mut remaining, mut cur, mut stall) = (n, 0usize, 0usize);
    while remaining >= 3 {
        let (a, c) = (prev[cur], next[cur]);
        let o = orient2(p(a), p(cur), p(c));
        let ear = o > 0 && (remaining == 3 || is_ear(a, cur, c, &next, &prev, &p));
        if o == 0 || ear {
            if ear {
                tris.push([poly[a], poly[cur], poly[c]]);
            } else {
                dropped.push(poly[cur]);
            }
            next[a] = c;
            prev[c] = a;
            remaining -= 1;
            cur = a;
            stall = 0;
            continue;
        }
        cur = c;
        stall += 1;
        if stall > remaining {
            return None;
        }
    }
    Some((tris, dropped))
}

/// Whether `a b c` (counter-clockwise) is an ear: no other remaining
/// vertex in the closed triangle, and no edge leaving a repeat of a corner
/// into it or along the diagonal.
fn is_ear(
    a: usize,
    b: usize,
    c: usize,
    next: &[usize],
    prev: &[usize],
    p: &impl Fn(usize) -> P2,
) -> bool {
    let (pa, pb, pc) = (p(a), p(b), p(c));
    let corners = [(pa, pb, pc), (pb, pc, pa), (pc, pa, pb)];
    let mut j = next[c];
    while j != a {
        let q = p(j);
        if let Some(&(x, y, z)) = corners.iter().find(|k| k.0 == q) {
            let (u, w) = (sub2(y, x), sub2(z, x));
            for d in [sub2(p(prev[j]), q), sub2(p(next[j]), q)] {
                let along = |e: [i128; 2]| cross2(e, d) == 0 && dot2(e, d) > 0;
                let diagonal = (x == pa && along(w)) || (x == pc && along(u));
                if diagonal || (cross2(u, d) > 0 && cross2(d, w) > 0) {
                    return false;
                }
            }
        } else if orient2(pa, pb, q) >= 0 && orient2(pb, pc, q) >= 0 && orient2(pc, pa, q) >= 0 {
            return false;
        }
        j = next[j];
    }
    true
}

/// Splits triangle `t` at the dropped vertices strictly inside its edges.
pub(super) fn split_triangle(
    t: [usize; 3],
    dropped: &[usize],
    pos: &[P2],
    out: &mut Vec<[usize; 3]>,
) {
    for k in 0..3 {
        let (u, w, o) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        if let Some(&x) = dropped
            .iter()
            .find(|&&x| strictly_between(pos[u], pos[w], pos[x]))
        {
            split_triangle([u, x, o], dropped, pos, out);
            split_triangle([x, w, o], dropped, pos, out);
            return;
        }
    }
    out.push(t);
}
