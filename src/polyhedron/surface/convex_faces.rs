//! Convex faces (Theorem KE, seed 003 §4.5.6): takes a merged face's
//! triangles and returns its convex faces, merging the pieces on either
//! side of a diagonal when [`theorem_ke`] holds.

use std::collections::HashMap;

use crate::foundation::UnionFind;
use crate::foundation::exact::{P2, cross2, sub2};

use super::ConvexFace;
use super::polygon::project;

/// Theorem KE (seed 003 §4.5.6): two coplanar convex faces F1 and F2
/// sharing the edge E = P1P2 merge into a convex face when the points
/// S1 = E1 ∩ line(P1, P2) and S2 = E2 ∩ line(P1, P2) lie on the closed
/// segment [P1, P2], where E1 joins F1's other neighbour of P1 (`p1v`) to
/// F2's other neighbour of P1 (`p2n`), and E2 joins F2's other neighbour
/// of P2 (`p2v`) to F1's other neighbour of P2 (`p1n`). Planar
/// coordinates, counter-clockwise seen from outside: F1 runs
/// `p1v → p1 → p2 → p1n`, F2 runs `p2v → p2 → p1 → p2n`.
///
/// Equivalent to both ends of E staying convex or straight corners of the
/// union; S1 = P1 (`p1v`, P1, `p2n` collinear) is accepted. Exact: S1 =
/// P1 + t·(P2 − P1) with t a ratio of i128 cross products, compared with
/// 0 and 1 without division. E1 parallel to E (no intersection) refuses.
pub fn theorem_ke(
    p1: [i64; 2],
    p2: [i64; 2],
    p1v: [i64; 2],
    p1n: [i64; 2],
    p2v: [i64; 2],
    p2n: [i64; 2],
) -> bool {
    let on_edge = |a: P2, b: P2| {
        let ab = sub2(b, a);
        let (num, den) = (cross2(sub2(a, p1), ab), cross2(sub2(p2, p1), ab));
        match den.signum() {
            1 => 0 <= num && num <= den,
            -1 => den <= num && num <= 0,
            _ => false,
        }
    };
    on_edge(p1v, p2n) && on_edge(p2v, p1n)
}

/// The convex faces of face `face` (outward `normal`) from its triangles
/// (counter-clockwise about `normal`): one greedy pass over the shared
/// diagonals in triangle order, merging the two pieces on either side when
/// [`theorem_ke`] holds. Pieces are kept as cycles of half-edges, so a
/// merge relinks four pointers.
pub(super) fn convex_faces_of(
    face: u32,
    normal: [i64; 3],
    tris: &[[u32; 3]],
    vertices: &[[i64; 3]],
) -> Vec<ConvexFace> {
    // Half-edge h runs from corner h % 3 of triangle h / 3 to the next one.
    let n = 3 * tris.len();
    let from = |h: usize| tris[h / 3][h % 3];
    let to = |h: usize| tris[h / 3][(h + 1) % 3];
    let mut next: Vec<usize> = (0..n).map(|h| h / 3 * 3 + (h + 1) % 3).collect();
    let mut prev: Vec<usize> = (0..n).map(|h| h / 3 * 3 + (h + 2) % 3).collect();
    let mut piece = UnionFind::<usize>::with_len(tris.len());
    let mut by_edge: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for h in 0..n {
        by_edge.entry((from(h), to(h))).or_default().push(h);
    }
    let pos = |v: u32| project(vertices[v as usize], normal);
    let mut alive = vec![true; n];
    for h in 0..n {
        let (u, v) = (from(h), to(h));
        let (Some([_]), Some(&[g])) = (
            by_edge.get(&(u, v)).map(Vec::as_slice),
            by_edge.get(&(v, u)).map(Vec::as_slice),
        ) else {
            continue;
        };
        if u > v {
            continue;
        }
        let (ph, pg) = (piece.find(h / 3), piece.find(g / 3));
        if ph == pg {
            continue;
        }
        let (p1v, p1n) = (pos(from(prev[h])), pos(to(next[h])));
        let (p2v, p2n) = (pos(from(prev[g])), pos(to(next[g])));
        if !theorem_ke(pos(u), pos(v), p1v, p1n, p2v, p2n) {
            continue;
        }
        let (hp, hn, gp, gn) = (prev[h], next[h], prev[g], next[g]);
        next[hp] = gn;
        prev[gn] = hp;
        next[gp] = hn;
        prev[hn] = gp;
        alive[h] = false;
        alive[g] = false;
        piece.union(ph, pg);
    }
    let mut out = Vec::new();
    for start in 0..n {
        if !alive[start] {
            continue;
        }
        let mut cycle = Vec::new();
        let mut h = start;
        loop {
            alive[h] = false;
            cycle.push(from(h));
            h = next[h];
            if h == start {
                break;
            }
        }
        out.push(ConvexFace {
            face,
            vertices: cycle,
        });
    }
    out
}
