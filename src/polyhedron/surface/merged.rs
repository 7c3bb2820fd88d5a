//! Building the merged surface: takes a [`Polyhedron`] whose sibling shells
//! are separated and returns its [`MergedSurface`] (boundary evaluation per
//! supporting plane, face loops, T-junctions, the closedness check and the
//! triangulation). Holds this phase's `impl Polyhedron`
//! ([`Polyhedron::merged_surface`]).

use std::cmp::Reverse;
use std::collections::{BTreeMap, HashMap};

use crate::foundation::exact::{P2, cross2, dot2, gcd, orient2, sub2};
use crate::polyhedron::{Polyhedron, Role};

use super::convex_faces::convex_faces_of;
use super::polygon::{
    area2, ccw_angle_less, clip_ears, contains, find_bridge, project, split_triangle,
    strictly_between,
};
use super::{MergedFace, MergedSurface};

impl Polyhedron {
    /// The seed's single merged surface ([module docs](super)).
    ///
    /// Errors: [`crate::Refusal::SiblingsNotSeparated`] when sibling shells
    /// are not proven separated (disjoint interiors, no common face area),
    /// and [`crate::Refusal::NotARegion`] — for a malformed tree only — when the face chain is not the boundary of a
    /// region (a multiplicity outside −1..=1, an open or crossing loop, a
    /// face that cannot be triangulated).
    pub fn merged_surface(&self) -> crate::Result<MergedSurface> {
        if !self.siblings_separated() {
            return Err(crate::Refusal::SiblingsNotSeparated.into());
        }
        // Effective faces by canonical plane: (sign relative to it, cycle),
        // and the depth of the shell each comes from.
        type Planes = BTreeMap<([i64; 3], i64), (Vec<(i64, Vec<[i64; 3]>)>, Vec<u32>)>;
        let mut planes: Planes = BTreeMap::new();
        let mut depth_of: HashMap<[i64; 3], u32> = HashMap::new();
        for s in &self.shells {
            let Some(h) = s.geometry.polytope().filter(|h| !h.is_planar()) else {
                continue;
            };
            for &v in h.vertices() {
                let d = depth_of.entry(v).or_insert(s.depth);
                *d = (*d).min(s.depth);
            }
            for f in h.faces() {
                let mut cycle: Vec<[i64; 3]> = f
                    .vertices
                    .iter()
                    .map(|&v| h.vertices()[v as usize])
                    .collect();
                let (mut n, mut d) = (f.plane.normal, f.plane.offset);
                if s.role == Role::Background {
                    cycle.reverse();
                    n = n.map(|c| -c);
                    d = -d;
                }
                let sigma = if n.iter().find(|&&c| c != 0).is_some_and(|&c| c > 0) {
                    1
                } else {
                    -1
                };
                let (polys, depths) = planes.entry((n.map(|c| c * sigma), d * sigma)).or_default();
                polys.push((sigma, cycle));
                depths.push(s.depth);
            }
        }
        let mut table = VertexTable::default();
        let mut faces = Vec::new();
        // Per face, the plane it lies in.
        let mut plane_of = Vec::new();
        for (&(n, d), (polys, depths)) in &planes {
            merge_plane(n, d, polys, &mut table, &mut faces)?;
            plane_of.resize(faces.len(), (n, polys, depths));
        }
        let vertices = table.points;
        split_t_junctions(&vertices, &mut faces);
        check_closed(&faces, &vertices)?;
        let (mut triangles, mut convex_faces) = (Vec::new(), Vec::new());
        let mut face_depth = Vec::with_capacity(faces.len());
        let mut triangle_faces = Vec::new();
        for (fi, f) in faces.iter().enumerate() {
            let tris = triangulate(f, &vertices)?;
            let (n, polys, depths) = plane_of[fi];
            face_depth.push(covering_depth(n, polys, depths, &tris, &vertices));
            convex_faces.extend(convex_faces_of(fi as u32, f.normal, &tris, &vertices));
            triangle_faces.resize(triangle_faces.len() + tris.len(), fi as u32);
            triangles.extend(tris);
        }
        let vertex_depth = vertices
            .iter()
            .map(|v| depth_of.get(v).copied().unwrap_or(0))
            .collect();
        Ok(MergedSurface {
            vertices,
            faces,
            triangles,
            vertex_depth,
            triangle_faces,
            face_depth,
            convex_faces,
        })
    }
}

fn invalid(msg: String) -> crate::Error {
    crate::Refusal::NotARegion(msg).into()
}

/// The smallest of `depths` whose convex cycle in `polys` (on the plane of
/// canonical normal `n`, oriented by its sign) holds the centroid of the
/// face's first triangle, boundary included: exact, on tripled
/// coordinates. A face's triangles are non-degenerate, so the centroid is
/// inside the face, where some contributing cycle lies (0 if none does,
/// which a valid chain never gives).
fn covering_depth(
    n: [i64; 3],
    polys: &[(i64, Vec<[i64; 3]>)],
    depths: &[u32],
    tris: &[[u32; 3]],
    vertices: &[[i64; 3]],
) -> u32 {
    let Some(t) = tris.first() else {
        return 0;
    };
    let c = t.iter().fold([0i64; 2], |acc, &v| {
        let p = project(vertices[v as usize], n);
        [acc[0] + p[0], acc[1] + p[1]]
    });
    let holds = |sigma: i64, cycle: &[[i64; 3]]| {
        (0..cycle.len()).all(|k| {
            let (a, b) = (
                project(cycle[k], n).map(|x| 3 * x),
                project(cycle[(k + 1) % cycle.len()], n).map(|x| 3 * x),
            );
            orient2(a, b, c) * i128::from(sigma) >= 0
        })
    };
    (polys.iter().zip(depths))
        .filter(|((sigma, cycle), _)| holds(*sigma, cycle))
        .map(|(_, &d)| d)
        .min()
        .unwrap_or(0)
}

/// Surface vertices, numbered in order of first use.
#[derive(Default)]
struct VertexTable {
    points: Vec<[i64; 3]>,
    index: HashMap<[i64; 3], u32>,
}

impl VertexTable {
    fn id(&mut self, p: [i64; 3]) -> u32 {
        *self.index.entry(p).or_insert_with(|| {
            self.points.push(p);
            (self.points.len() - 1) as u32
        })
    }
}

/// Boundary evaluation on one plane (canonical normal `n`, offset `d`):
/// the faces of multiplicity +1 (outward `n`) and −1 (outward `−n`).
fn merge_plane(
    n: [i64; 3],
    d: i64,
    polys: &[(i64, Vec<[i64; 3]>)],
    table: &mut VertexTable,
    out: &mut Vec<MergedFace>,
) -> crate::Result<()> {
    let mut local: HashMap<[i64; 3], usize> = HashMap::new();
    let mut p3: Vec<[i64; 3]> = Vec::new();
    let cycles: Vec<(i64, Vec<usize>)> = polys
        .iter()
        .map(|(sigma, cyc)| {
            let ids = cyc
                .iter()
                .map(|&p| {
                    *local.entry(p).or_insert_with(|| {
                        p3.push(p);
                        p3.len() - 1
                    })
                })
                .collect();
            (*sigma, ids)
        })
        .collect();
    let p2: Vec<P2> = p3.iter().map(|&p| project(p, n)).collect();
    let mut order: Vec<usize> = (0..p2.len()).collect();
    order.sort_unstable_by_key(|&i| p2[i]);
    // Elementary edges (split at every plane vertex on them), net count of
    // `lo → hi` minus `hi → lo`.
    let mut net: HashMap<(usize, usize), i64> = HashMap::new();
    for (_, c) in &cycles {
        for k in 0..c.len() {
            let chain = split_edge(c[k], c[(k + 1) % c.len()], &p2, &order);
            for w in chain.windows(2) {
                let (x, y) = (w[0], w[1]);
                if x < y {
                    *net.entry((x, y)).or_default() += 1;
                } else {
                    *net.entry((y, x)).or_default() -= 1;
                }
            }
        }
    }
    let mut edges: Vec<((usize, usize), i64)> = net.into_iter().filter(|e| e.1 != 0).collect();
    edges.sort_unstable();
    check_crossings(&edges, &p2, n, d)?;
    // [multiplicity +1, multiplicity −1], each with the region on the left
    // in its own orientation.
    let mut groups: [Vec<(usize, usize)>; 2] = Default::default();
    for &((a, b), w) in &edges {
        let left = multiplicity_left(a, b, &cycles, &p2);
        let right = left - w;
        if !(-1..=1).contains(&left) || !(-1..=1).contains(&right) {
            return Err(invalid(format!(
                "faces on plane {n:?}·x = {d} overlap with multiplicity {} at edge {:?}–{:?}: \
                 the shells do not bound a region",
                if left.abs() > 1 { left } else { right },
                p3[a],
                p3[b]
            )));
        }
        match left {
            1 => groups[0].push((a, b)),
            -1 => groups[1].push((b, a)),
            _ => {}
        }
        match right {
            1 => groups[0].push((b, a)),
            -1 => groups[1].push((a, b)),
            _ => {}
        }
    }
    for (g, s) in [(0, 1i64), (1, -1)] {
        if groups[g].is_empty() {
            continue;
        }
        let normal = n.map(|c| c * s);
        let q: Vec<P2> = p3.iter().map(|&p| project(p, normal)).collect();
        for lps in faces_of_edges(&groups[g], &q, normal, d * s)? {
            out.push(MergedFace {
                normal,
                offset: d * s,
                loops: lps
                    .iter()
                    .map(|l| l.iter().map(|&v| table.id(p3[v])).collect())
                    .collect(),
            });
        }
    }
    Ok(())
}

/// `a`, the plane vertices strictly inside segment `a b` in order, `b`.
fn split_edge(a: usize, b: usize, p2: &[P2], order: &[usize]) -> Vec<usize> {
    let (pa, pb) = (p2[a], p2[b]);
    let (lo, hi) = (pa[0].min(pb[0]), pa[0].max(pb[0]));
    let start = order.partition_point(|&i| p2[i][0] < lo);
    let mut inner: Vec<(i128, usize)> = order[start..]
        .iter()
        .take_while(|&&i| p2[i][0] <= hi)
        .filter(|&&i| strictly_between(pa, pb, p2[i]))
        .map(|&i| (dot2(sub2(p2[i], pa), sub2(pb, pa)), i))
        .collect();
    inner.sort_unstable();
    let mut chain = Vec::with_capacity(inner.len() + 2);
    chain.push(a);
    chain.extend(inner.into_iter().map(|(_, i)| i));
    chain.push(b);
    chain
}

/// Refuses two remaining edges that cross at a point inside both (the
/// vertices would leave the lattice): impossible for nested shells with
/// disjoint siblings.
fn check_crossings(
    edges: &[((usize, usize), i64)],
    p2: &[P2],
    n: [i64; 3],
    d: i64,
) -> crate::Result<()> {
    let mut segs: Vec<(P2, P2)> = edges
        .iter()
        .map(|&((a, b), _)| (p2[a].min(p2[b]), p2[a].max(p2[b])))
        .collect();
    segs.sort_unstable();
    for (i, &(a, b)) in segs.iter().enumerate() {
        for &(c, e) in segs[i + 1..].iter().take_while(|s| s.0[0] <= b[0]) {
            let (o1, o2) = (orient2(a, b, c).signum(), orient2(a, b, e).signum());
            let (o3, o4) = (orient2(c, e, a).signum(), orient2(c, e, b).signum());
            if o1 * o2 < 0 && o3 * o4 < 0 {
                return Err(invalid(format!(
                    "faces on plane {n:?}·x = {d} cross properly: the shells do not nest"
                )));
            }
        }
    }
    Ok(())
}

/// Multiplicity of the faces on the plane just left of the midpoint of
/// `a → b` (simulation of simplicity: the point `mid + ε·L + ε²·D`, `D` the
/// edge direction, `L` its left normal).
fn multiplicity_left(a: usize, b: usize, cycles: &[(i64, Vec<usize>)], p2: &[P2]) -> i64 {
    let mid = [p2[a][0] + p2[b][0], p2[a][1] + p2[b][1]];
    let dir = sub2(p2[b], p2[a]);
    let left = [-dir[1], dir[0]];
    let mut m = 0;
    for (sigma, c) in cycles {
        let in_box = (0..2).all(|ax| {
            let (lo, hi) = c.iter().fold((i64::MAX, i64::MIN), |(lo, hi), &v| {
                (lo.min(p2[v][ax]), hi.max(p2[v][ax]))
            });
            2 * lo <= mid[ax] && mid[ax] <= 2 * hi
        });
        if !in_box {
            continue;
        }
        let inside = (0..c.len()).all(|k| {
            let (p, q) = (p2[c[k]], p2[c[(k + 1) % c.len()]]);
            let e = sub2(q, p);
            let rel = [
                i128::from(mid[0]) - 2 * i128::from(p[0]),
                i128::from(mid[1]) - 2 * i128::from(p[1]),
            ];
            let s = [cross2(e, rel), cross2(e, left), cross2(e, dir)]
                .into_iter()
                .find(|&s| s != 0)
                .unwrap_or(0);
            s * i128::from(*sigma) > 0
        });
        if inside {
            m += sigma;
        }
    }
    m
}

/// Loops of a set of directed edges with the region on their left
/// (counter-clockwise outer loops, clockwise holes), grouped into faces:
/// each outer loop first, then the holes it is the smallest container of.
fn faces_of_edges(
    edges: &[(usize, usize)],
    q: &[P2],
    n: [i64; 3],
    d: i64,
) -> crate::Result<Vec<Vec<Vec<usize>>>> {
    let mut out_of: HashMap<usize, Vec<usize>> = HashMap::new();
    for (e, &(a, _)) in edges.iter().enumerate() {
        out_of.entry(a).or_default().push(e);
    }
    // Successor: at the head, the outgoing edge turning tightest to the
    // left (first clockwise from the way back), which keeps the region's
    // sector on the left and separates loops at pinch vertices.
    let mut succ = Vec::with_capacity(edges.len());
    for &(a, b) in edges {
        let r = sub2(q[a], q[b]);
        let next = out_of
            .get(&b)
            .and_then(|outs| {
                outs.iter().copied().reduce(|best, e| {
                    let (d1, d2) = (sub2(q[edges[best].1], q[b]), sub2(q[edges[e].1], q[b]));
                    if ccw_angle_less(r, d1, d2) { e } else { best }
                })
            })
            .ok_or_else(|| invalid(format!("the face boundary on plane {n:?}·x = {d} is open")))?;
        succ.push(next);
    }
    let mut used = vec![false; edges.len()];
    let mut loops: Vec<(i128, Vec<usize>)> = Vec::new();
    for start in 0..edges.len() {
        if used[start] {
            continue;
        }
        let mut lp = Vec::new();
        let mut e = start;
        loop {
            if used[e] {
                return Err(invalid(format!(
                    "the face boundary on plane {n:?}·x = {d} branches"
                )));
            }
            used[e] = true;
            lp.push(edges[e].0);
            e = succ[e];
            if e == start {
                break;
            }
        }
        let area = area2(&lp, q);
        if area == 0 {
            return Err(invalid(format!(
                "a face loop on plane {n:?}·x = {d} has no area"
            )));
        }
        loops.push((area, lp));
    }
    let (mut outers, holes): (Vec<_>, Vec<_>) = loops.into_iter().partition(|l| l.0 > 0);
    outers.sort_by_key(|l| l.0);
    let mut faces: Vec<Vec<Vec<usize>>> = outers.iter().map(|o| vec![o.1.clone()]).collect();
    for (_, h) in holes {
        // The midpoint of a hole edge is on no outer loop (no segment is
        // used twice in one orientation), so parity decides exactly.
        let t = [q[h[0]][0] + q[h[1]][0], q[h[0]][1] + q[h[1]][1]];
        let Some(f) = outers.iter().position(|o| contains(&o.1, q, t)) else {
            return Err(invalid(format!(
                "a hole on plane {n:?}·x = {d} lies in no face"
            )));
        };
        faces[f].push(h);
    }
    Ok(faces)
}

/// Inserts into every loop edge the endpoints of the other loop edges on
/// the same line strictly inside it (T-junctions between neighbouring
/// faces). Lines are keyed by their Plücker coordinates (canonical
/// primitive direction, moment).
fn split_t_junctions(vertices: &[[i64; 3]], faces: &mut [MergedFace]) {
    type Line = ([i64; 3], [i128; 3]);
    let line = |a: u32, b: u32| -> (Line, [i128; 3]) {
        let (pa, pb) = (vertices[a as usize], vertices[b as usize]);
        let mut dir: [i64; 3] = std::array::from_fn(|k| pb[k] - pa[k]);
        let g = dir.iter().fold(0i64, |g, &c| gcd(g, c.abs())).max(1);
        let sign = if dir.iter().find(|&&c| c != 0).is_some_and(|&c| c < 0) {
            -1
        } else {
            1
        };
        dir = dir.map(|c| c / g * sign);
        let (dd, aa) = (dir.map(i128::from), pa.map(i128::from));
        let moment = [
            dd[1] * aa[2] - dd[2] * aa[1],
            dd[2] * aa[0] - dd[0] * aa[2],
            dd[0] * aa[1] - dd[1] * aa[0],
        ];
        ((dir, moment), dd)
    };
    let along = |dd: [i128; 3], v: u32| -> i128 {
        let p = vertices[v as usize].map(i128::from);
        dd[0] * p[0] + dd[1] * p[1] + dd[2] * p[2]
    };
    let mut points: HashMap<Line, Vec<(i128, u32)>> = HashMap::new();
    for f in faces.iter() {
        for lp in &f.loops {
            for k in 0..lp.len() {
                let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
                let (key, dd) = line(a, b);
                let list = points.entry(key).or_default();
                list.push((along(dd, a), a));
                list.push((along(dd, b), b));
            }
        }
    }
    for list in points.values_mut() {
        list.sort_unstable();
        list.dedup();
    }
    for f in faces.iter_mut() {
        for lp in &mut f.loops {
            let mut split = Vec::with_capacity(lp.len());
            for k in 0..lp.len() {
                let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
                split.push(a);
                let (key, dd) = line(a, b);
                let list = &points[&key];
                let (ta, tb) = (along(dd, a), along(dd, b));
                let (lo, hi) = (ta.min(tb), ta.max(tb));
                let from = list.partition_point(|p| p.0 <= lo);
                let to = list.partition_point(|p| p.0 < hi);
                if ta < tb {
                    split.extend(list[from..to].iter().map(|p| p.1));
                } else {
                    split.extend(list[from..to].iter().rev().map(|p| p.1));
                }
            }
            *lp = split;
        }
    }
}

/// Every undirected edge is used as often in each direction (the chain is
/// closed): the exact watertightness check.
fn check_closed(faces: &[MergedFace], vertices: &[[i64; 3]]) -> crate::Result<()> {
    let mut net: HashMap<(u32, u32), i64> = HashMap::new();
    for f in faces {
        for lp in &f.loops {
            for k in 0..lp.len() {
                let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
                *net.entry((a.min(b), a.max(b))).or_default() += if a < b { 1 } else { -1 };
            }
        }
    }
    match net.iter().filter(|e| *e.1 != 0).min() {
        Some((&(a, b), _)) => Err(invalid(format!(
            "the merged surface is open at edge {:?}–{:?}",
            vertices[a as usize], vertices[b as usize]
        ))),
        None => Ok(()),
    }
}

/// Exact triangulation of a face with holes: holes bridged to the outer
/// loop, ear clipping with exact predicates, then vertices dropped as
/// straight angles put back by splitting the triangle edges they lie on.
/// Checked: every triangle counter-clockwise, areas summing to the face's.
fn triangulate(face: &MergedFace, vertices: &[[i64; 3]]) -> crate::Result<Vec<[u32; 3]>> {
    let fail = |what: &str| {
        invalid(format!(
            "face on plane {:?}·x = {}: {what}",
            face.normal, face.offset
        ))
    };
    // One entry per vertex occurrence.
    let mut pos: Vec<P2> = Vec::new();
    let mut ids: Vec<u32> = Vec::new();
    let mut loops: Vec<Vec<usize>> = face
        .loops
        .iter()
        .map(|l| {
            l.iter()
                .map(|&v| {
                    pos.push(project(vertices[v as usize], face.normal));
                    ids.push(v);
                    pos.len() - 1
                })
                .collect()
        })
        .collect();
    let target: i128 = loops.iter().map(|l| area2(l, &pos)).sum();
    let mut holes = loops.split_off(1.min(loops.len()));
    let Some(mut poly) = loops.pop() else {
        return Err(fail("no loop"));
    };
    holes.sort_by_key(|h| Reverse(h.iter().map(|&i| pos[i]).max()));
    for hi in 0..holes.len() {
        let hole = &holes[hi];
        let km = (0..hole.len())
            .max_by_key(|&k| (pos[hole[k]], Reverse(k)))
            .unwrap_or(0);
        let Some(k) = find_bridge(&poly, hole, km, &holes[hi + 1..], &pos) else {
            return Err(fail("no bridge from a hole to the outer loop"));
        };
        let mut spliced = Vec::with_capacity(poly.len() + hole.len() + 2);
        spliced.extend_from_slice(&poly[..=k]);
        spliced.extend((0..hole.len()).map(|s| hole[(km + s) % hole.len()]));
        for o in [hole[km], poly[k]] {
            pos.push(pos[o]);
            ids.push(ids[o]);
            spliced.push(pos.len() - 1);
        }
        spliced.extend_from_slice(&poly[k + 1..]);
        poly = spliced;
    }
    let (tris, mut dropped) = clip_ears(&poly, &pos).ok_or_else(|| fail("no ear left"))?;
    dropped.sort_unstable_by_key(|&i| pos[i]);
    dropped.dedup_by_key(|i| pos[*i]);
    let mut out = Vec::with_capacity(tris.len() + dropped.len());
    for t in tris {
        split_triangle(t, &dropped, &pos, &mut out);
    }
    let areas: Vec<i128> = out
        .iter()
        .map(|t| orient2(pos[t[0]], pos[t[1]], pos[t[2]]))
        .collect();
    if areas.iter().any(|&a| a <= 0) || areas.iter().sum::<i128>() != target {
        return Err(fail("the triangles do not tile the face"));
    }
    Ok(out.iter().map(|t| t.map(|i| ids[i])).collect())
}
