//! The marching-cubes case table, generated once from a topological rule
//! instead of typed in (a plain Lorensen 15-case table is not crack-free).
//!
//! Cell corners `c = x + 2y + 4z` (bits of the corner's offset); corner `c`
//! is *inside* when bit `c` of the case index is set. Local edge
//! `e = 4·axis + k` runs along `axis` (0 = x, 1 = y, 2 = z) from corner
//! [`EDGE_OWNER`]`[e]` to `EDGE_OWNER[e] | 1 << axis`.
//!
//! Connectivity convention (documented choice, SPEC §5.1): the surface is
//! the boundary of a regular neighbourhood of the *lattice cubical complex*
//! of the inside samples — inside is 6-connected, outside 26-connected:
//! - **faces**: on an ambiguous face (inside corners on one diagonal) the
//!   two inside corners are always separated. The rule reads only the face's
//!   four corners, so both cells sharing the face draw the same segments and
//!   no crack can open between ambiguous cells;
//! - **cell interior**: every edge-connected group of inside corners gets one
//!   surface piece, a disk (one boundary loop, fan-triangulated) or — when
//!   the outside corners are exactly one body-diagonal pair — a tube joining
//!   the two loops (the outside stays 26-connected through the cell).
//!
//! Triangles are wound counter-clockwise seen from outside: the right-hand
//! normal points from inside (values ≥ level) to outside.

use std::sync::OnceLock;

/// Owner corner of each local edge (the end with the lower coordinate).
pub const EDGE_OWNER: [u8; 12] = [0, 2, 4, 6, 0, 1, 4, 5, 0, 1, 2, 3];

/// Axis of local edge `e`.
pub const fn edge_axis(e: usize) -> usize {
    e / 4
}

/// The two corners joined by local edge `e` (owner first).
pub const fn edge_corners(e: usize) -> (usize, usize) {
    let a = EDGE_OWNER[e] as usize;
    (a, a | 1 << edge_axis(e))
}

/// The local edge joining corners `a` and `b`, if they share a cube edge.
fn edge_between(a: usize, b: usize) -> Option<usize> {
    (0..12).find(|&e| {
        let (p, q) = edge_corners(e);
        (p == a && q == b) || (p == b && q == a)
    })
}

/// Offset of corner `c` as `[x, y, z]` in {0, 1}.
pub const fn corner_offset(c: usize) -> [usize; 3] {
    [c & 1, (c >> 1) & 1, (c >> 2) & 1]
}

/// The generated table: per case the triangles as local edge triples.
#[derive(Debug, Clone)]
pub struct CaseTable {
    /// `offsets[case]..offsets[case + 1]` indexes `triangles`.
    pub offsets: [u32; 257],
    /// Local edge triples, counter-clockwise seen from outside.
    pub triangles: Vec<[u8; 3]>,
}

impl CaseTable {
    /// Triangles of `case` (empty for 0 and 255).
    pub fn case(&self, case: usize) -> &[[u8; 3]] {
        &self.triangles[self.offsets[case] as usize..self.offsets[case + 1] as usize]
    }

    /// Largest number of triangles of any case.
    pub fn max_triangles(&self) -> usize {
        (0..256).map(|c| self.case(c).len()).max().unwrap_or(0)
    }

    /// The table flattened for the GPU: 257 offsets, then 3 local edges per
    /// triangle (`kernels/mc_classify.wgsl` and `mc_triangles.wgsl` layout).
    pub fn flat(&self) -> Vec<u32> {
        let mut out: Vec<u32> = self.offsets.to_vec();
        out.extend(self.triangles.iter().flatten().map(|&e| u32::from(e)));
        out
    }
}

/// The table, generated on first use.
pub fn table() -> &'static CaseTable {
    static TABLE: OnceLock<CaseTable> = OnceLock::new();
    TABLE.get_or_init(generate)
}

/// Midpoint of local edge `e` in cell coordinates (for orientation only).
fn midpoint(e: usize) -> [f64; 3] {
    let (a, _) = edge_corners(e);
    let mut p = corner_offset(a).map(|v| v as f64);
    p[edge_axis(e)] += 0.5;
    p
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The six faces: corners in cyclic order and the outward normal.
fn faces() -> [([usize; 4], [f64; 3]); 6] {
    let mut out = [([0; 4], [0.0; 3]); 6];
    for axis in 0..3 {
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in 0..2 {
            let corner = |ub: usize, uc: usize| (side << axis) | (ub << b) | (uc << c);
            let mut n = [0.0; 3];
            n[axis] = if side == 1 { 1.0 } else { -1.0 };
            out[2 * axis + side] = ([corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)], n);
        }
    }
    out
}

/// Directed boundary segments of the inside region on the cube surface:
/// `next[e] = f` means the boundary runs from edge `e`'s crossing to `f`'s,
/// with the inside on the left seen from outside the cube.
fn boundary_segments(case: usize) -> [Option<usize>; 12] {
    let inside = |c: usize| case >> c & 1 == 1;
    let mut next = [None; 12];
    for (corners, normal) in faces() {
        let face_edge = |i: usize| edge_between(corners[i], corners[(i + 1) % 4]);
        let crossing: Vec<usize> = (0..4)
            .filter(|&i| inside(corners[i]) != inside(corners[(i + 1) % 4]))
            .collect();
        // Pairs (face-edge index i, face-edge index j, an inside corner cut off).
        let pairs: Vec<(usize, usize, usize)> = match crossing.len() {
            2 => {
                let Some(&corner) = corners.iter().find(|&&c| inside(c)) else {
                    continue;
                };
                vec![(crossing[0], crossing[1], corner)]
            }
            // Ambiguous face: each inside corner k_i is cut off by the
            // segment joining its two face edges (i − 1 and i).
            4 => (0..4)
                .filter(|&i| inside(corners[i]))
                .map(|i| ((i + 3) % 4, i, corners[i]))
                .collect(),
            _ => Vec::new(),
        };
        for (i, j, corner) in pairs {
            let (Some(ei), Some(ej)) = (face_edge(i), face_edge(j)) else {
                continue;
            };
            let (p, q) = (midpoint(ei), midpoint(ej));
            let c = corner_offset(corner).map(|v| v as f64);
            let left = dot(cross(sub(q, p), sub(c, p)), normal) > 0.0;
            if left {
                next[ei] = Some(ej);
            } else {
                next[ej] = Some(ei);
            }
        }
    }
    next
}

/// Loops of crossing edges (each a cycle of `next`).
fn loops(next: &[Option<usize>; 12]) -> Vec<Vec<usize>> {
    let mut seen = [false; 12];
    let mut out = Vec::new();
    for start in 0..12 {
        if seen[start] || next[start].is_none() {
            continue;
        }
        let mut cycle = Vec::new();
        let mut e = start;
        while !seen[e] {
            seen[e] = true;
            cycle.push(e);
            match next[e] {
                Some(f) => e = f,
                None => break,
            }
        }
        out.push(cycle);
    }
    out
}

/// Edge-connected groups of inside corners: `group[c]` for inside `c`.
fn inside_groups(case: usize) -> [usize; 8] {
    let mut group = [usize::MAX; 8];
    let inside = |c: usize| case >> c & 1 == 1;
    for start in 0..8 {
        if !inside(start) || group[start] != usize::MAX {
            continue;
        }
        let mut stack = vec![start];
        group[start] = start;
        while let Some(c) = stack.pop() {
            for axis in 0..3 {
                let d = c ^ (1 << axis);
                if inside(d) && group[d] == usize::MAX {
                    group[d] = start;
                    stack.push(d);
                }
            }
        }
    }
    group
}

/// Triangles of one case, wound with the boundary loops (inside on the
/// left seen from outside the cube).
fn case_triangles(case: usize) -> Vec<[usize; 3]> {
    let next = boundary_segments(case);
    let cycles = loops(&next);
    let group = inside_groups(case);
    // Each loop borders the group of the inside end of any of its edges.
    let loop_group = |cycle: &[usize]| {
        let (a, b) = edge_corners(cycle[0]);
        if case >> a & 1 == 1 {
            group[a]
        } else {
            group[b]
        }
    };
    let mut tris = Vec::new();
    let mut done = vec![false; cycles.len()];
    for i in 0..cycles.len() {
        if done[i] {
            continue;
        }
        done[i] = true;
        let partner = (i + 1..cycles.len())
            .find(|&j| !done[j] && loop_group(&cycles[j]) == loop_group(&cycles[i]));
        match partner {
            None => tris.extend(disk(&cycles[i])),
            Some(j) => {
                done[j] = true;
                tris.extend(tube(&cycles[i], &cycles[j]));
            }
        }
    }
    tris
}

/// Faces (2·axis + side) containing local edge `e`, as a bitmask.
fn edge_faces(e: usize) -> u32 {
    let (o, _) = edge_corners(e);
    let off = corner_offset(o);
    (0..3)
        .filter(|&b| b != edge_axis(e))
        .map(|b| 1u32 << (2 * b + off[b]))
        .sum()
}

/// Triangulates one loop as a disk. No diagonal may join two vertices on a
/// common cell face: the neighbour cell sharing that face could draw the
/// same edge, and the surface would stop being a manifold there. Among the
/// admissible triangulations (interval dynamic programme) the one with the
/// shortest total diagonal length is taken.
fn disk(c: &[usize]) -> Vec<[usize; 3]> {
    let n = c.len();
    let ok = |i: usize, j: usize| {
        (i + 1) % n == j || (j + 1) % n == i || edge_faces(c[i]) & edge_faces(c[j]) == 0
    };
    let len = |i: usize, j: usize| {
        let d = sub(midpoint(c[i]), midpoint(c[j]));
        dot(d, d).sqrt()
    };
    // cost[i][j]: best triangulation of the sub-polygon c[i..=j] (j > i + 1).
    let mut cost = vec![vec![f64::INFINITY; n]; n];
    let mut apex = vec![vec![usize::MAX; n]; n];
    for i in 0..n - 1 {
        cost[i][i + 1] = 0.0;
    }
    for span in 2..n {
        for i in 0..n - span {
            let j = i + span;
            if !ok(i, j) {
                continue;
            }
            for k in i + 1..j {
                let c2 = cost[i][k] + cost[k][j];
                let extra = if span == n - 1 { 0.0 } else { len(i, j) };
                if c2 + extra < cost[i][j] {
                    cost[i][j] = c2 + extra;
                    apex[i][j] = k;
                }
            }
        }
    }
    let mut tris = Vec::with_capacity(n - 2);
    let mut stack = vec![(0usize, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j <= i + 1 {
            continue;
        }
        let k = apex[i][j];
        if k == usize::MAX {
            // No admissible triangulation: leave it to the table test to fail.
            return Vec::new();
        }
        tris.push([c[i], c[k], c[j]]);
        stack.push((i, k));
        stack.push((k, j));
    }
    tris
}

/// A band of triangles joining loops `a` and `b` (equal lengths), keeping
/// each loop edge in its loop's direction so the band is oriented with them.
///
/// Each edge of `a` gets an apex on `b` and each edge of `b` one on `a`;
/// the rotation of `b` against `a` is the one with the shortest cross edges.
/// For the body-diagonal tube that is the zigzag whose apexes lie between
/// their edge's ends seen along the diagonal; a rotation by one (which an
/// equally short pairing of the loops' vertices allows) twists the band so
/// that it crosses itself for any unequal crossing parameters.
fn tube(a: &[usize], b: &[usize]) -> Vec<[usize; 3]> {
    let n = a.len();
    let rev: Vec<usize> = b.iter().rev().copied().collect();
    let len = |p: usize, q: usize| {
        let d = sub(midpoint(p), midpoint(q));
        dot(d, d).sqrt()
    };
    // Cross edges of rotation k: a_i–b_i' and a_(i+1)–b_i' for every i.
    let cross_length = |k: usize| -> f64 {
        (0..n)
            .map(|i| len(a[i], rev[(i + k) % n]) + len(a[(i + 1) % n], rev[(i + k) % n]))
            .sum()
    };
    let best = (0..n)
        .min_by(|&x, &y| cross_length(x).total_cmp(&cross_length(y)))
        .unwrap_or(0);
    let mut tris = Vec::with_capacity(2 * n);
    for i in 0..n {
        let (a0, a1) = (a[i], a[(i + 1) % n]);
        let (b0, b1) = (rev[(i + best) % n], rev[(i + 1 + best) % n]);
        tris.push([a0, a1, b0]);
        tris.push([a1, b1, b0]);
    }
    tris
}

/// Generates the full table and fixes the global winding so that normals
/// point from inside to outside (checked on case 1: corner 0 alone inside).
fn generate() -> CaseTable {
    let per_case: Vec<Vec<[usize; 3]>> = (0..256).map(case_triangles).collect();
    let outward = per_case[1].first().is_none_or(|t| {
        let n = cross(
            sub(midpoint(t[1]), midpoint(t[0])),
            sub(midpoint(t[2]), midpoint(t[0])),
        );
        dot(n, [1.0, 1.0, 1.0]) > 0.0
    });
    let mut offsets = [0u32; 257];
    let mut triangles = Vec::new();
    for (case, tris) in per_case.iter().enumerate() {
        for t in tris {
            let t = if outward { *t } else { [t[0], t[2], t[1]] };
            triangles.push(t.map(|e| e as u8));
        }
        offsets[case + 1] = triangles.len() as u32;
    }
    CaseTable { offsets, triangles }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No triangle edge inside a cell may join two vertices on one cell face
    /// unless it is a boundary segment of the piece (used once in the cell).
    #[test]
    fn no_interior_edge_lies_in_a_cell_face() {
        let t = table();
        for case in 0..256 {
            let mut directed = std::collections::HashSet::new();
            for tri in t.case(case) {
                for k in 0..3 {
                    directed.insert((tri[k], tri[(k + 1) % 3]));
                }
            }
            for &(a, b) in &directed {
                if directed.contains(&(b, a)) {
                    assert_eq!(
                        edge_faces(a as usize) & edge_faces(b as usize),
                        0,
                        "case {case}: interior edge {a}-{b} lies in a face"
                    );
                }
            }
        }
    }

    #[test]
    fn empty_and_full_cases_have_no_triangles() {
        let t = table();
        assert!(t.case(0).is_empty());
        assert!(t.case(255).is_empty());
    }

    #[test]
    fn every_crossing_edge_is_used_and_no_other() {
        let t = table();
        for case in 0..256 {
            let mut used = [false; 12];
            for tri in t.case(case) {
                for &e in tri {
                    used[e as usize] = true;
                }
            }
            for (e, &u) in used.iter().enumerate() {
                let (a, b) = edge_corners(e);
                let crossing = (case >> a & 1) != (case >> b & 1);
                assert_eq!(u, crossing, "case {case} edge {e}");
            }
        }
    }

    /// Within a cell each triangle edge between two local edges on the same
    /// face is a boundary segment (used once); all others are used twice in
    /// opposite directions — each piece is an oriented surface with boundary
    /// on the cube faces.
    #[test]
    fn pieces_are_oriented_with_boundary_on_faces() {
        let t = table();
        for case in 0..256 {
            let mut directed = std::collections::HashMap::new();
            for tri in t.case(case) {
                for k in 0..3 {
                    *directed.entry((tri[k], tri[(k + 1) % 3])).or_insert(0) += 1;
                }
            }
            for (&(a, b), &n) in &directed {
                assert_eq!(n, 1, "case {case}: directed edge {a}->{b} twice");
                if !directed.contains_key(&(b, a)) {
                    let (pa, qa) = edge_corners(a as usize);
                    let (pb, qb) = edge_corners(b as usize);
                    let shared = [pa, qa, pb, qb]
                        .iter()
                        .fold(0xff, |m, &c| m & corner_mask(c));
                    assert_ne!(shared, 0, "case {case}: boundary {a}->{b} not on a face");
                }
            }
        }
    }

    /// Bitmask of the six faces (axis·2 + side) containing corner `c`.
    fn corner_mask(c: usize) -> u32 {
        let o = corner_offset(c);
        (0..3).map(|ax| 1u32 << (2 * ax + o[ax])).sum()
    }

    #[test]
    fn complementary_tube_cases_exist_and_table_is_small() {
        let t = table();
        // Inside = the six-corner ring around a body diagonal: a tube (6 triangles).
        for (a, b) in [(0usize, 7usize), (1, 6), (2, 5), (3, 4)] {
            let case = 0xff & !(1 << a) & !(1 << b);
            assert_eq!(t.case(case).len(), 6, "case {case:#x}");
        }
        assert!(t.max_triangles() <= 8, "max {}", t.max_triangles());
    }

    /// One cell's triangles as a mesh, a vertex on each local edge at
    /// `k[e] / 1024` of the edge from its owner corner (exact in f32).
    fn cell_mesh(tris: &[[u8; 3]], k: &[u32; 12]) -> crate::TriMesh {
        let positions = (0..12)
            .map(|e| {
                let (a, _) = edge_corners(e);
                let mut p = corner_offset(a).map(|v| v as f32);
                p[edge_axis(e)] += k[e] as f32 / 1024.0;
                glam::Vec3::from(p)
            })
            .collect();
        let triangles = tris.iter().map(|t| t.map(u32::from)).collect();
        crate::TriMesh::new(positions, triangles).unwrap()
    }

    /// Crossing parameters at the clamp ends, near them and in between.
    fn parameter_sets() -> Vec<[u32; 12]> {
        let mut seed = 0x9e37_79b9_u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        };
        let mut sets = vec![[1; 12], [1023; 12], [512; 12]];
        for _ in 0..400 {
            sets.push(std::array::from_fn(|_| match next() % 4 {
                0 => 1 + next() % 32,
                1 => 1023 - next() % 32,
                2 => [1, 1023][(next() % 2) as usize],
                _ => 1 + next() % 1023,
            }));
        }
        sets
    }

    /// No two triangles of a cell meet beyond their shared vertices and
    /// edges, for any crossing parameters (exact test); the surface of
    /// neighbouring cells only meets on the shared face segments, so
    /// marching-cubes surfaces cannot cross themselves.
    #[test]
    fn no_case_crosses_itself() {
        let t = table();
        let sets = parameter_sets();
        for case in 1..255 {
            for k in &sets {
                let hits = crate::mesh::self_intersections(&cell_mesh(t.case(case), k));
                assert!(hits.degenerate.is_empty(), "case {case} {k:?}");
                assert!(hits.pairs.is_empty(), "case {case} {k:?}: {:?}", hits.pairs);
            }
        }
    }

    /// Negative control: the tube band rotated by one against the chosen
    /// one (as the table built it before) crosses itself.
    #[test]
    fn a_twisted_tube_crosses_itself() {
        let case = 0xff & !1 & !(1 << 7);
        let good = table().case(case).to_vec();
        // Rotate every apex taken from the second loop one step along it.
        let tube: Vec<usize> = good.iter().flatten().map(|&e| e as usize).collect();
        let second = [3usize, 7, 11];
        assert!(second.iter().all(|e| tube.contains(e)));
        let step = |e: u8| match e {
            3 => 11,
            11 => 7,
            7 => 3,
            e => e,
        };
        let twisted: Vec<[u8; 3]> = good.iter().map(|t| t.map(step)).collect();
        let k = [700, 1, 1, 1, 300, 1, 1, 1, 40, 1, 1, 1].map(|v: u32| v.max(1));
        let mut k = k;
        (k[3], k[7], k[11]) = (900, 100, 500);
        assert!(
            crate::mesh::self_intersections(&cell_mesh(&good, &k))
                .pairs
                .is_empty()
        );
        assert!(
            !crate::mesh::self_intersections(&cell_mesh(&twisted, &k))
                .pairs
                .is_empty()
        );
    }

    #[test]
    fn case_one_points_away_from_corner_zero() {
        let tri = table().case(1)[0].map(|e| midpoint(e as usize));
        let n = cross(sub(tri[1], tri[0]), sub(tri[2], tri[0]));
        assert!(dot(n, [1.0, 1.0, 1.0]) > 0.0);
    }
}
