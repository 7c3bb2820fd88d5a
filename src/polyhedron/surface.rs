//! The single merged surface of a polyhedron (seed 003 §4.4.1
//! "Zusammenfügen"), by exact boundary evaluation.
//!
//! When sibling shells have disjoint interiors
//! ([`super::PolyhedronSummary::volume_exact`]) the indicator of the object
//! region is `Σ sign_i·χ(H_i)` over the 3-D shells, so its boundary is the
//! 2-chain `Σ sign_i·∂H_i` (background faces reversed). Per supporting plane
//! the faces' multiplicities add up: coplanar overlapping pieces cancel (the
//! marked faces of Def. PR removed, the child's faces joined in); what is
//! left is cut into faces, each an outer loop with its holes, outward for the
//! region. Loops are then split where a neighbouring face has an edge
//! endpoint on their edge (T-junctions), so every edge is used as often in
//! one direction as in the other, and faces are triangulated by ear
//! clipping. Every face is also split into convex faces by the merges of
//! Theorem KE (§4.5.6, [`MergedSurface::convex_faces`]). Every predicate
//! is exact integer arithmetic on combinatorial coordinates (voxel centres
//! odd); no epsilons, no rounding.
//!
//! Lower-dimensional and flat shells carry no volume (they label voxels on
//! the surface) and are left out.

use std::cmp::Reverse;
use std::collections::{BTreeMap, HashMap};

use crate::foundation::UnionFind;
use crate::foundation::exact::{P2, cross2, det, dot2, gcd, orient2, sub2};
use crate::mesh::{ScalarField, TriMesh};
use crate::voxel::Frame;

use super::{Polyhedron, Role};

/// Planar coordinates: a plane point with its dominant axis dropped.

/// One face of a [`MergedSurface`]: a planar region, possibly with holes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MergedFace {
    /// Outward normal for the region, primitive (gcd 1).
    pub normal: [i64; 3],
    /// `normal·v` for every vertex `v` of the face.
    pub offset: i64,
    /// Vertex cycles (indices into [`MergedSurface::vertices`]): the outer
    /// loop first, counter-clockwise seen from outside, then the holes,
    /// clockwise. A loop may pass through a vertex twice (a pinch).
    pub loops: Vec<Vec<u32>>,
}

/// One convex piece of a [`MergedFace`] ([`MergedSurface::convex_faces`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConvexFace {
    /// Index of the merged face (into [`MergedSurface::faces`]) it lies in.
    pub face: u32,
    /// Vertex cycle (indices into [`MergedSurface::vertices`]),
    /// counter-clockwise seen from outside, at least 3 corners, every
    /// corner convex or straight (straight corners are kept: loop vertices
    /// and T-junctions that neighbouring faces share).
    pub vertices: Vec<u32>,
}

/// The merged surface: one closed, consistently oriented polyhedral
/// surface of the object region (possibly several components, e.g. around
/// a cavity; edges at pinch vertices may be used by four faces).
#[derive(Debug, Clone)]
pub struct MergedSurface {
    /// Vertices, combinatorial coordinates (voxel centres odd).
    pub vertices: Vec<[i64; 3]>,
    /// Faces, ordered by canonical supporting plane.
    pub faces: Vec<MergedFace>,
    /// Exact triangulation of the faces, outward winding (indices into
    /// [`MergedSurface::vertices`]); every face-loop vertex is a corner.
    pub triangles: Vec<[u32; 3]>,
    /// Per vertex, the smallest depth of a shell having it as a hull vertex
    /// (every merged vertex is one).
    pub vertex_depth: Vec<u32>,
    /// Per triangle, the face it triangulates (index into
    /// [`MergedSurface::faces`]).
    pub triangle_faces: Vec<u32>,
    /// Per face, the smallest depth of a shell with a face covering the
    /// centroid of the face's first triangle: the depth of the shell the
    /// face comes from, also where it shares vertices with shells of other
    /// depths (per-vertex depths blend there). Where coplanar faces of
    /// shells of different depths join into one face, that point decides.
    pub face_depth: Vec<u32>,
    /// Every face split into convex faces (Theorem KE, §4.5.6), ordered by
    /// face: starting from the face's triangles, two pieces sharing a
    /// diagonal are merged when [`theorem_ke`] says the union stays convex.
    /// The merges are greedy (Hertel–Mehlhorn style, one pass over the
    /// diagonals): every diagonal left is essential, so a face without
    /// holes with `r` reflex corners gets at most `2r + 1` convex faces,
    /// at most four times the minimum (any convex partition needs
    /// `⌈r/2⌉ + 1`). Not optimal, and no such bound is claimed for faces
    /// with holes. The convex faces of a face tile it exactly: they meet
    /// only along whole edges and their areas sum to the face's.
    pub convex_faces: Vec<ConvexFace>,
}

impl MergedSurface {
    /// Faces, a face with holes counted once (seed Table 8.7, "with holes").
    pub fn n_faces(&self) -> usize {
        self.faces.len()
    }

    /// Faces that have at least one hole.
    pub fn n_faces_with_holes(&self) -> usize {
        self.faces.iter().filter(|f| f.loops.len() > 1).count()
    }

    /// Faces when each face with `h` holes counts as `h + 1` simple faces
    /// (seed Table 8.7, "split").
    pub fn n_faces_split(&self) -> usize {
        self.faces.iter().map(|f| f.loops.len()).sum()
    }

    /// Convex faces ([`MergedSurface::convex_faces`]), at least
    /// [`MergedSurface::n_faces_split`].
    pub fn n_convex_faces(&self) -> usize {
        self.convex_faces.len()
    }

    /// 6·volume enclosed, combinatorial units (one voxel = 8 units, so
    /// 48 per voxel), exact from the triangles.
    pub fn volume6(&self) -> i128 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| self.vertices[v as usize]);
                det(a, b, c)
            })
            .sum()
    }

    /// Enclosed volume in voxel units (`volume6 / 48`: combinatorial
    /// coordinates are doubled), exact up to the final division.
    pub fn volume_voxels(&self) -> f64 {
        self.volume6() as f64 / 48.0
    }

    /// Surface area in voxel units: Σ |(b − a) × (c − a)| / 8 over the
    /// triangles (exact `i128` cross products, one square root each).
    pub fn area_voxels(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| self.vertices[v as usize].map(i128::from));
                let (u, w) = (
                    [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                    [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
                );
                let n = [
                    u[1] * w[2] - u[2] * w[1],
                    u[2] * w[0] - u[0] * w[2],
                    u[0] * w[1] - u[1] * w[0],
                ];
                ((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) as f64).sqrt() / 8.0
            })
            .sum()
    }

    /// The triangles as a mesh in world units (`frame`), outward winding;
    /// scalar `depth` per vertex ([`MergedSurface::vertex_depth`]).
    pub fn to_mesh(&self, frame: &Frame) -> crate::Result<TriMesh> {
        let positions = self.vertices.iter().map(|&v| frame.world_f32(v)).collect();
        let mut mesh = TriMesh::new(positions, self.triangles.clone())?;
        mesh.scalars.push(ScalarField {
            name: "depth".into(),
            values: self.vertex_depth.iter().map(|&d| d as f32).collect(),
        });
        mesh.validate()?;
        Ok(mesh)
    }

    /// The triangles as a mesh for pictures: each with its own three
    /// vertices and the scalar `depth` of its face
    /// ([`MergedSurface::face_depth`]), so colours do not blend across
    /// faces. Not welded: write [`MergedSurface::to_mesh`] instead.
    pub fn to_face_mesh(&self, frame: &Frame) -> crate::Result<TriMesh> {
        let positions = (self.triangles.iter())
            .flat_map(|t| t.map(|v| frame.world_f32(self.vertices[v as usize])))
            .collect();
        let triangles = (0..self.triangles.len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        let mut mesh = TriMesh::new(positions, triangles)?;
        mesh.scalars.push(ScalarField {
            name: "depth".into(),
            values: (self.triangle_faces.iter())
                .flat_map(|&f| [self.face_depth[f as usize] as f32; 3])
                .collect(),
        });
        mesh.validate()?;
        Ok(mesh)
    }
}

impl Polyhedron {
    /// The seed's single merged surface (module docs).
    ///
    /// Errors: [`crate::Error::InvalidInput`] when sibling shells are not
    /// proven separated (disjoint interiors, no common face area), and — for a
    /// malformed tree only — when the face chain is not the boundary of a
    /// region (a multiplicity outside −1..=1, an open or crossing loop, a
    /// face that cannot be triangulated).
    pub fn merged_surface(&self) -> crate::Result<MergedSurface> {
        if !self.siblings_separated() {
            return Err(invalid(
                "the merged surface needs sibling shells with disjoint interiors \
                 and no common face area"
                    .into(),
            ));
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
    crate::Error::InvalidInput(msg)
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

/// `p` with the dominant axis of `n` dropped, ordered so that
/// counter-clockwise about `n` is counter-clockwise in the plane.
fn project(p: [i64; 3], n: [i64; 3]) -> P2 {
    let k = (0..3)
        .max_by_key(|&a| (n[a].abs(), Reverse(a)))
        .unwrap_or(0);
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    if n[k] > 0 { [p[i], p[j]] } else { [p[j], p[i]] }
}


/// Whether `q` lies strictly inside segment `a b`.
fn strictly_between(a: P2, b: P2, q: P2) -> bool {
    orient2(a, b, q) == 0 && dot2(sub2(q, a), sub2(b, a)) > 0 && dot2(sub2(q, b), sub2(a, b)) > 0
}

/// Twice the signed area of a loop.
fn area2(lp: &[usize], pos: &[P2]) -> i128 {
    (0..lp.len())
        .map(|k| {
            let (a, b) = (pos[lp[k]], pos[lp[(k + 1) % lp.len()]]);
            i128::from(a[0]) * i128::from(b[1]) - i128::from(a[1]) * i128::from(b[0])
        })
        .sum()
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
fn ccw_angle_less(r: [i128; 2], d1: [i128; 2], d2: [i128; 2]) -> bool {
    let half = |d: [i128; 2]| {
        let c = cross2(r, d);
        u8::from(!(c > 0 || (c == 0 && dot2(r, d) > 0)))
    };
    let (h1, h2) = (half(d1), half(d2));
    h1 < h2 || (h1 == h2 && cross2(d1, d2) > 0)
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

/// Exact crossing parity of the point `t` (doubled coordinates, on no edge)
/// for the loop `lp`.
fn contains(lp: &[usize], q: &[P2], t: P2) -> bool {
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

/// A vertex of `poly` (position in it) that the hole vertex `hole[km]` (the
/// rightmost) sees: the segment leaves both into the region and meets no
/// other edge or vertex of the polygon or of any hole.
fn find_bridge(
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
fn clip_ears(poly: &[usize], pos: &[P2]) -> Option<(Vec<[usize; 3]>, Vec<usize>)> {
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
fn split_triangle(t: [usize; 3], dropped: &[usize], pos: &[P2], out: &mut Vec<[usize; 3]>) {
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
fn convex_faces_of(
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

