//! Cut points of the crossed triangles: takes them in ascending id order
//! (analytic knife: their corners, evaluated against the knife;
//! triangulated knife: their segments from corefinement) and returns a
//! [`Located`] with one cut vertex per crossed edge, numbered by first use.

use std::collections::HashMap;

use glam::Vec3;

use super::{End, ends};
use crate::TriMesh;
use crate::cut::corefine;
use crate::cut::knife::Analytic;
use crate::cut::{CutStats, KnifeSegment, Located, PointOrigin};
use crate::foundation::UnionFind;

/// Cut points of a triangulated knife, numbered by first use in ascending
/// (surface triangle, knife triangle) order (tree and scan agree).
pub(super) fn finish_locate_mesh(
    pair: &corefine::Pair<'_>,
    crossed: Vec<(u32, corefine::TriangleSegments)>,
    mut stats: CutStats,
) -> Located {
    let mut ids: HashMap<PointOrigin, u32> = HashMap::new();
    let mut out = Located::default();
    for (t, segs) in crossed {
        for (kt, ends) in segs {
            let ends = ends.map(|o| {
                *ids.entry(o).or_insert_with(|| {
                    out.points.push(pair.point(o).as_vec3());
                    out.lower_negative.push(pair.lower_behind(o));
                    out.edges.push(match o {
                        PointOrigin::SurfaceEdge { edge, .. }
                        | PointOrigin::KnifeEdge { edge, .. } => edge,
                    });
                    out.origins.push(o);
                    out.points.len() as u32 - 1
                })
            });
            out.segments.push(KnifeSegment {
                triangle: t,
                knife_triangle: kt,
                ends,
            });
        }
        out.triangles.push(t);
    }
    stats.triangles_split = out.triangles.len();
    stats.cut_vertices = out.points.len();
    out.stats = stats;
    out
}

/// Cut-vertex ids of crossed edges: open addressing with linear probing
/// in one flat table of at least 1.5 times as many slots as edges can be
/// inserted (so a probe always ends at the key or at an empty slot). A slot
/// holds a cut-vertex id; its key is that vertex's edge in
/// [`Located::edges`]. Keys are vertex-id pairs, not attacker controlled; a
/// multiplicative hash spreads them.
struct EdgeTable {
    slots: Vec<u32>,
    shift: u32,
}

impl EdgeTable {
    const EMPTY: u32 = u32::MAX;

    /// A table for up to `n` edges (load factor at most 2/3).
    fn with_capacity(n: usize) -> EdgeTable {
        let len = (n + n / 2 + 1).next_power_of_two().max(16);
        EdgeTable {
            slots: vec![Self::EMPTY; len],
            shift: 64 - len.trailing_zeros(),
        }
    }

    /// The id stored for `edge` (`Ok`), or the free slot to store it in.
    #[inline(always)]
    fn find(&self, edge: (u32, u32), edges: &[(u32, u32)]) -> Result<u32, usize> {
        let mask = self.slots.len() - 1;
        let key = (u64::from(edge.0) << 32) | u64::from(edge.1);
        let mut i = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> self.shift) as usize;
        loop {
            let id = self.slots[i];
            if id == Self::EMPTY {
                return Err(i);
            }
            if edges[id as usize] == edge {
                return Ok(id);
            }
            i = (i + 1) & mask;
        }
    }
}

/// The two edges a triangle's side signs change along, ascending (edge e
/// joins corners e and e + 1), indexed by the corners' negative bits
/// (`1 << c`); the other edge is opposite the corner on its own side.
#[rustfmt::skip]
const CROSSED_EDGES: [(usize, usize); 8] = [
    (0, 0), // no corner negative: not crossed
    (0, 2), // corner 0 alone
    (0, 1), // corner 1 alone
    (1, 2), // corner 2 alone (0 and 1 negative)
    (1, 2), // corner 2 alone
    (0, 1), // corner 1 alone (0 and 2 negative)
    (0, 2), // corner 0 alone (1 and 2 negative)
    (0, 0), // all negative: not crossed
];

/// Cut vertices of the crossed triangles `crossed` (ids into `mesh`), in
/// ascending id order, numbered by first use in that order (so tree and
/// scan number them identically). Only the two edges whose ends change side
/// are looked up; a triangle none of whose edges the knife reaches (a
/// rectangle's border) is dropped.
pub(super) fn finish_locate<A: Analytic>(
    mesh: &TriMesh,
    crossed: &[u32],
    k: A,
    mut stats: CutStats,
) -> Located {
    let n = crossed.len();
    // A mixed triangle has exactly two edges whose ends change side.
    let mut ids = EdgeTable::with_capacity(2 * n);
    let mut coincident: Vec<(u32, u32)> = Vec::new();
    let mut out = Located {
        triangles: Vec::with_capacity(n),
        edge_cuts: Vec::with_capacity(n),
        points: Vec::with_capacity(n),
        lower_negative: Vec::with_capacity(n),
        edges: Vec::with_capacity(n),
        ..Located::default()
    };
    for &t in crossed {
        let ends = ends(mesh, k, t);
        let signs = (0..3).fold(0, |s, c| s | usize::from(ends[c].2 < 0.0) << c);
        if signs == 0 || signs == 7 {
            continue;
        }
        let (e0, e1) = CROSSED_EDGES[signs];
        let x = cut_edge(&mut ids, &mut out, k, &ends, e0);
        let y = cut_edge(&mut ids, &mut out, k, &ends, e1);
        if x & y == u32::MAX {
            continue;
        }
        // Two crossings of one triangle that round to one f32 point (on a
        // sliver, or near a corner) are one cut vertex.
        if x != u32::MAX
            && y != u32::MAX
            && x != y
            && same(out.points[x as usize], out.points[y as usize])
        {
            coincident.push(if e1 == 2 && e0 == 0 { (y, x) } else { (x, y) });
        }
        // Without a branch: which edges are crossed is data, not a pattern.
        let pick = |c: bool, a: u32, b: u32| b ^ ((a ^ b) & u32::from(c).wrapping_neg());
        let cuts = [
            pick(e0 == 0, x, u32::MAX),
            pick(e0 == 1, x, pick(e1 == 1, y, u32::MAX)),
            pick(e1 == 2, y, u32::MAX),
        ];
        out.triangles.push(t);
        out.edge_cuts.push(cuts);
    }
    if !coincident.is_empty() {
        merge_cut_vertices(&mut out, &coincident);
    }
    stats.triangles_split = out.triangles.len();
    stats.cut_vertices = out.points.len();
    out.stats = stats;
    out
}

/// The cut vertex of edge `e` of a triangle (corners e, e + 1 of `ends`),
/// whose ends change side (made at its first use, from its lower-id end),
/// or `u32::MAX` when the knife does not reach the crossing.
///
/// A crossing that lands on an end (a vertex on the knife, or rounded onto
/// it) is that vertex's cut, shared by all its crossed edges: no two cut
/// vertices coincide, no piece gets a zero-area triangle. It is recorded as
/// the edge `(v, v)` with v's side (and found under that key, not under the
/// edge's).
#[inline(always)]
fn cut_edge<A: Analytic>(
    ids: &mut EdgeTable,
    out: &mut Located,
    k: A,
    ends: &[End; 3],
    e: usize,
) -> u32 {
    let (c0, c1) = (e, if e == 2 { 0 } else { e + 1 });
    // The lower-id end first, chosen by index (no branch on the data).
    let lower = if ends[c0].0 < ends[c1].0 { c0 } else { c1 };
    let upper = c0 + c1 - lower;
    let ((i, a, fa), (j, b, fb)) = (ends[lower], ends[upper]);
    let slot = match ids.find((i, j), &out.edges) {
        Ok(id) => return id,
        Err(slot) => slot,
    };
    let Some(cross) = k.crossing_from(a, b, fa, fb) else {
        return u32::MAX;
    };
    let q = cross.point.as_vec3();
    let (at_a, at_b) = (same(q, a), same(q, b));
    let (edge, slot, lower_negative) = if at_a | at_b {
        let (v, fv) = if at_a { (i, fa) } else { (j, fb) };
        match ids.find((v, v), &out.edges) {
            Ok(id) => return id,
            Err(slot) => ((v, v), slot, fv < 0.0),
        }
    } else {
        ((i, j), slot, cross.first_negative)
    };
    let id = out.points.len() as u32;
    out.points.push(q);
    out.lower_negative.push(lower_negative);
    out.edges.push(edge);
    ids.slots[slot] = id;
    id
}

/// Whether two points are equal (`==` on each coordinate), without a
/// branch per coordinate: on a cut along a grid plane, one coordinate of a
/// crossing often equals its end's and the next decides.
#[inline(always)]
fn same(p: Vec3, q: Vec3) -> bool {
    (p.x == q.x) & (p.y == q.y) & (p.z == q.z)
}

/// Joins the cut vertices of each pair in `pairs` (equal positions) into
/// one and renumbers all by first use, keeping the tree's and the scan's
/// numbering equal. A cut at a mesh vertex (edge `(v, v)`) survives a join;
/// two such at different vertices (coincident mesh vertices) stay apart.
fn merge_cut_vertices(out: &mut Located, pairs: &[(u32, u32)]) {
    let n = out.points.len();
    let at_vertex = |c: u32, out: &Located| {
        let (a, b) = out.edges[c as usize];
        a == b
    };
    let mut uf = UnionFind::with_len(n);
    let mut has_vertex: Vec<bool> = (0..n as u32).map(|c| at_vertex(c, out)).collect();
    for &(x, y) in pairs {
        let (rx, ry) = (uf.find(x), uf.find(y));
        if rx == ry || (has_vertex[rx as usize] && has_vertex[ry as usize]) {
            continue;
        }
        let either = has_vertex[rx as usize] || has_vertex[ry as usize];
        let r = uf.union(rx, ry);
        has_vertex[r as usize] = either;
    }
    // Per class its survivor: a vertex cut if there is one, else the first.
    let mut survivor = vec![u32::MAX; n];
    for c in 0..n as u32 {
        let r = uf.find(c) as usize;
        if survivor[r] == u32::MAX || (at_vertex(c, out) && !at_vertex(survivor[r], out)) {
            survivor[r] = c;
        }
    }
    let mut new_id = vec![u32::MAX; n];
    let mut next = 0u32;
    let mut located = Located {
        triangles: std::mem::take(&mut out.triangles),
        edge_cuts: Vec::with_capacity(out.edge_cuts.len()),
        ..Located::default()
    };
    for cuts in &out.edge_cuts {
        located.edge_cuts.push(cuts.map(|c| {
            if c == u32::MAX {
                return c;
            }
            let s = survivor[uf.find(c) as usize] as usize;
            if new_id[s] == u32::MAX {
                new_id[s] = next;
                next += 1;
                located.points.push(out.points[s]);
                located.lower_negative.push(out.lower_negative[s]);
                located.edges.push(out.edges[s]);
            }
            new_id[s]
        }));
    }
    *out = located;
}

#[cfg(test)]
mod tests {
    use super::CROSSED_EDGES;

    /// Each mixed sign pattern lists exactly the edges whose ends differ,
    /// ascending; the two uniform patterns list none.
    #[test]
    fn crossed_edges_are_the_sign_changes() {
        for (signs, &listed) in CROSSED_EDGES.iter().enumerate() {
            let neg = |c: usize| signs >> c & 1 == 1;
            let changes: Vec<usize> = (0..3).filter(|&e| neg(e) != neg((e + 1) % 3)).collect();
            match changes[..] {
                [] => assert!(signs == 0 || signs == 7),
                [e0, e1] => assert_eq!(listed, (e0, e1), "signs {signs:03b}"),
                _ => unreachable!("a triangle changes side along 0 or 2 edges"),
            }
        }
    }
}
