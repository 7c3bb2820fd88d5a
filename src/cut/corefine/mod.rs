//! Triangulated knives: where the knife surface meets the cut surface,
//! both split along the same curve, and caps from the knife (beyond the
//! seed, which only locates the crossings, §3.1).
//!
//! Topology is decided by orientation signs alone: Shewchuk's `orient3d`
//! evaluated in f64 on the f32 inputs with its static error bound; a sign
//! too close to call counts as a contact. Every sign is evaluated on
//! canonical arguments (edges lower id first, triangles as stored), so all
//! triangles sharing an edge see the same answer:
//! - surface edge `e` crosses knife triangle `K` → cut point `e×K`;
//! - knife edge `f` crosses surface triangle `T` → cut point `T×f`;
//! - a contact (a vertex on the other mesh, an edge through an edge,
//!   coplanar triangles) is an error asking to move the knife slightly.
//!
//! An intersecting pair (T, K) meets in one segment between two of these
//! points; a point lies on two segments (one at a mesh border), so the cut
//! curves are closed away from borders and shared by both meshes: a point
//! is one vertex for the surface and for the cap.
//!
//! Each split triangle (of either mesh) is cut along its chains of segments
//! into polygons (a loop inside one triangle becomes a hole plus a
//! polygon), triangulated by ear clipping in the triangle's own plane with
//! the triangle's orientation. A polygon lies left of the segments on its
//! border; from the other triangle's normal that says which side it is on
//! (surface: behind the knife = negative; knife: behind the surface =
//! inside the solid). Knife polygons and whole knife triangles joined
//! across knife edges form regions; a region inside the solid whose border
//! is cut curve only is a cap, used as is by the negative pieces and
//! reversed by the positive ones, so the cap adds no volume.
//!
//! Takes the surface, the knife and the knife's forest ([`Pair`]); returns
//! per surface triangle its segments, and the split surface with its caps
//! ([`MeshSplit`]). The exact tests are in [`intersect`], the splitting of
//! one triangle into polygons in [`face`]; the split and caps here.

mod face;
mod intersect;

use std::collections::HashMap;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::foundation::{UnionFind, vertex_components};
use crate::{Result, TriMesh};
use face::{Face, ToSplit, triangulate_face};
pub(crate) use intersect::Pair;
use intersect::canon;

/// How a cut point of a triangulated knife arises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PointOrigin {
    /// Surface edge `(lower id, higher id)` through a knife triangle.
    SurfaceEdge {
        edge: (u32, u32),
        knife_triangle: u32,
    },
    /// Knife edge `(lower id, higher id)` through a surface triangle.
    KnifeEdge { edge: (u32, u32), triangle: u32 },
}

/// One piece of the cut curve: where surface triangle `triangle` meets
/// knife triangle `knife_triangle`, between cut points `ends`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KnifeSegment {
    pub triangle: u32,
    pub knife_triangle: u32,
    pub ends: [u32; 2],
}

/// Segments of one surface triangle: (knife triangle, its two cut points),
/// ascending knife triangle.
pub(crate) type TriangleSegments = Vec<(u32, [PointOrigin; 2])>;

/// The split of a surface by a triangulated knife, ready for assembly.
#[derive(Debug, Default)]
pub(crate) struct MeshSplit {
    /// Per crossed surface triangle, its sub-triangles and whether each is
    /// on the negative side.
    pub subs: Vec<Vec<([u32; 3], bool)>>,
    /// Knife vertices used by the caps, appended after the cut points.
    pub extra_points: Vec<Vec3>,
    /// Cap triangles oriented for the negative side (ids `n_v + point`).
    pub caps: Vec<[u32; 3]>,
    /// Knife regions used as caps.
    pub regions_capped: usize,
    /// Cut curves with an end (at a surface border), and knife regions
    /// inside the solid that reach the knife's border (not capped).
    pub curves_open: usize,
}

/// Per triangle, whether its solid lies in front of it: on the closed
/// components when, together, they enclose a negative volume (the surface
/// is wound inward; cavities count against their outer surface, as they
/// should). Open components enclose nothing and keep the convention that
/// triangles face outward. With `closed_outward` (the surface is known to
/// be closed and wound outward, [`Forest::closed_outward`]) none does, and
/// nothing is computed.
pub(crate) fn inward_triangles(surface: &TriMesh, closed_outward: bool) -> Vec<bool> {
    if closed_outward {
        return vec![false; surface.triangles.len()];
    }
    let (comp, n) = vertex_components(surface.n_vertices(), &surface.triangles);
    // Closed: every edge used twice, once in each direction. The half-edges
    // are bucketed by their lower vertex (a counting sort, O(F)) as (higher
    // vertex << 1 | runs upward); each bucket holds a vertex's few edges to
    // higher vertices, and an edge's component is its lower vertex's.
    let half_edges = |t: &[u32; 3]| {
        let t = *t;
        (0..3).map(move |i| (t[i], t[(i + 1) % 3]))
    };
    let n_v = surface.n_vertices();
    let mut volume6 = vec![0.0f64; n];
    let mut start = vec![0usize; n_v + 1];
    let mut vertex_comp = vec![0u32; n_v];
    for (t, &c) in surface.triangles.iter().zip(&comp) {
        let [a, b, c3] = t.map(|v| surface.positions[v as usize].as_dvec3());
        volume6[c as usize] += a.dot(b.cross(c3));
        for (a, b) in half_edges(t) {
            start[a.min(b) as usize + 1] += 1;
            vertex_comp[a as usize] = c;
        }
    }
    for v in 1..start.len() {
        start[v] += start[v - 1];
    }
    let mut fill = start.clone();
    let mut bucket = vec![0u64; start[n_v]];
    for (a, b) in surface.triangles.iter().flat_map(half_edges) {
        let lo = a.min(b) as usize;
        bucket[fill[lo]] = u64::from(a.max(b)) << 1 | u64::from(a < b);
        fill[lo] += 1;
    }
    let open: Vec<u32> = start
        .par_windows(2)
        .enumerate()
        .filter_map(|(v, w)| {
            // A vertex has a few edges: sorted on the stack unless many.
            let run = &bucket[w[0]..w[1]];
            let (mut small, mut many) = ([0; 16], Vec::new());
            let edges = if run.len() <= small.len() {
                &mut small[..run.len()]
            } else {
                many.resize(run.len(), 0);
                &mut many[..]
            };
            edges.copy_from_slice(run);
            edges.sort_unstable();
            let open = (edges.chunk_by(|x, y| x >> 1 == y >> 1))
                .any(|run| !(run.len() == 2 && run[0] != run[1]));
            open.then_some(vertex_comp[v])
        })
        .collect();
    let mut closed = vec![true; n];
    for c in open {
        closed[c as usize] = false;
    }
    let enclosed: f64 = (0..n).filter(|&c| closed[c]).map(|c| volume6[c]).sum();
    comp.iter()
        .map(|&c| closed[c as usize] && enclosed < 0.0)
        .collect()
}

/// Splits the surface and (with `cap`) makes the caps. `points` are the cut
/// points (f32, as in the pieces), `origins` their origins, `segments`
/// sorted by surface triangle, `crossed` the crossed surface triangles.
pub(crate) fn split(
    pair: &Pair<'_>,
    crossed: &[u32],
    points: &[Vec3],
    origins: &[PointOrigin],
    segments: &[KnifeSegment],
    cap: bool,
    closed_outward: bool,
) -> Result<MeshSplit> {
    let surface = pair.surface;
    let knife = pair.knife;
    let n_v = surface.positions.len() as u32;
    let n_p = points.len() as u32;
    let kbase = n_v + n_p;
    let pos = |v: u32| -> DVec3 {
        if v < n_v {
            surface.positions[v as usize].as_dvec3()
        } else if v < kbase {
            points[(v - n_v) as usize].as_dvec3()
        } else {
            knife.positions[(v - kbase) as usize].as_dvec3()
        }
    };
    let normal = |m: &TriMesh, t: u32| {
        let [a, b, c] = m.triangles[t as usize].map(|v| m.positions[v as usize].as_dvec3());
        (b - a).cross(c - a)
    };
    let mut out = MeshSplit::default();
    // Surface triangles.
    let mut s = 0;
    for &t in crossed {
        let tri = surface.triangles[t as usize];
        let mut edge_points: [Vec<u32>; 3] = Default::default();
        let mut segs = Vec::new();
        while s < segments.len() && segments[s].triangle == t {
            let sg = segments[s];
            for &p in &sg.ends {
                if let PointOrigin::SurfaceEdge { edge, .. } = origins[p as usize] {
                    let i = (0..3)
                        .find(|&i| canon(tri[i], tri[(i + 1) % 3]).0 == edge)
                        .unwrap_or(0);
                    if !edge_points[i].contains(&(n_v + p)) {
                        edge_points[i].push(n_v + p);
                    }
                }
            }
            segs.push((
                n_v + sg.ends[0],
                n_v + sg.ends[1],
                normal(knife, sg.knife_triangle),
            ));
            s += 1;
        }
        let what = format!("surface triangle {t}");
        let faces = ToSplit {
            corners: tri,
            edge_points,
            segments: segs,
            pos: &pos,
            what: &what,
            open_ends: false,
        }
        .faces()?;
        let n_own = normal(surface, t);
        out.subs.push(
            faces
                .iter()
                .flat_map(|f| {
                    triangulate_face(f, &pos, n_own)
                        .into_iter()
                        .map(move |v| (v, f.behind))
                })
                .collect(),
        );
    }
    // Open curve ends: points used by one segment only (surface borders).
    let mut uses = vec![0u8; points.len()];
    for sg in segments {
        for &p in &sg.ends {
            uses[p as usize] = uses[p as usize].saturating_add(1);
        }
    }
    let mut curve_uf = UnionFind::with_len(points.len());
    for sg in segments {
        curve_uf.union(sg.ends[0], sg.ends[1]);
    }
    let mut open_curve = vec![false; points.len()];
    for (p, &u) in uses.iter().enumerate() {
        if u == 1 {
            open_curve[curve_uf.find(p as u32) as usize] = true;
        }
    }
    out.curves_open = open_curve.iter().filter(|&&o| o).count();
    if !cap {
        return Ok(out);
    }
    // The solid is behind a surface triangle, or in front where its
    // component is closed and wound inward.
    let inward = inward_triangles(surface, closed_outward);
    // Knife triangles with segments, split.
    let mut by_knife: Vec<usize> = (0..segments.len()).collect();
    by_knife.sort_by_key(|&i| (segments[i].knife_triangle, segments[i].triangle));
    let mut knife_faces: Vec<(u32, Face)> = Vec::new();
    // Knife triangles cut by inward-wound surface: their caps face inward too.
    let mut knife_inward = vec![false; knife.triangles.len()];
    let mut split_knife = vec![false; knife.triangles.len()];
    let mut i = 0;
    while i < by_knife.len() {
        let kt = segments[by_knife[i]].knife_triangle;
        let tri = knife.triangles[kt as usize];
        let corners = tri.map(|v| kbase + v);
        let mut edge_points: [Vec<u32>; 3] = Default::default();
        let mut segs = Vec::new();
        while i < by_knife.len() && segments[by_knife[i]].knife_triangle == kt {
            let sg = segments[by_knife[i]];
            knife_inward[kt as usize] |= inward[sg.triangle as usize];
            for &p in &sg.ends {
                if let PointOrigin::KnifeEdge { edge, .. } = origins[p as usize] {
                    let e = (0..3)
                        .find(|&e| canon(tri[e], tri[(e + 1) % 3]).0 == edge)
                        .unwrap_or(0);
                    if !edge_points[e].contains(&(n_v + p)) {
                        edge_points[e].push(n_v + p);
                    }
                }
            }
            let n_solid = normal(surface, sg.triangle);
            segs.push((
                n_v + sg.ends[0],
                n_v + sg.ends[1],
                if inward[sg.triangle as usize] {
                    -n_solid
                } else {
                    n_solid
                },
            ));
            i += 1;
        }
        let what = format!("knife triangle {kt}");
        let faces = ToSplit {
            corners,
            edge_points,
            segments: segs,
            pos: &pos,
            what: &what,
            open_ends: true,
        }
        .faces()?;
        split_knife[kt as usize] = true;
        knife_faces.extend(faces.into_iter().map(|f| (kt, f)));
    }
    // Regions: faces and whole knife triangles joined across shared
    // non-curve edges; an edge used once lies on the knife's border.
    let whole: Vec<u32> = (0..knife.triangles.len() as u32)
        .filter(|&t| !split_knife[t as usize])
        .collect();
    let n_units = knife_faces.len() + whole.len();
    let mut uf = UnionFind::with_len(n_units);
    let curve: std::collections::HashSet<(u32, u32)> = segments
        .iter()
        .map(|sg| {
            let (a, b) = (n_v + sg.ends[0], n_v + sg.ends[1]);
            (a.min(b), a.max(b))
        })
        .collect();
    let mut first_user: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
    let mut add_cycle = |cyc: &[u32], unit: u32, uf: &mut UnionFind| {
        let n = cyc.len();
        for j in 0..n {
            let (a, b) = (cyc[j], cyc[(j + 1) % n]);
            let key = (a.min(b), a.max(b));
            if curve.contains(&key) {
                continue;
            }
            let e = first_user.entry(key).or_insert((unit, 0));
            e.1 += 1;
            uf.union(e.0, unit);
        }
    };
    for (u, (_, f)) in knife_faces.iter().enumerate() {
        add_cycle(&f.outer, u as u32, &mut uf);
        for h in &f.holes {
            add_cycle(h, u as u32, &mut uf);
        }
    }
    for (j, &t) in whole.iter().enumerate() {
        let cyc = knife.triangles[t as usize].map(|v| kbase + v);
        add_cycle(&cyc, (knife_faces.len() + j) as u32, &mut uf);
    }
    // Per region: what its faces say, and whether it reaches the knife's border.
    #[derive(Default)]
    struct Votes {
        inside: bool,
        outside: bool,
        open: bool,
        border: bool,
        inward: bool,
    }
    let mut region: HashMap<u32, Votes> = HashMap::new();
    for (u, (kt, f)) in knife_faces.iter().enumerate() {
        let r = region.entry(uf.find(u as u32)).or_default();
        r.inward |= knife_inward[*kt as usize];
        r.open |= f.open;
        r.inside |= f.behind && !f.open;
        r.outside |= !f.behind && !f.open;
    }
    for (&_key, &(unit, count)) in &first_user {
        if count == 1
            && let Some(r) = region.get_mut(&uf.find(unit))
        {
            r.border = true;
        }
    }
    // Regions at an open curve are counted with it; an inside region
    // bounded by the knife's border as well is counted here.
    let mut capped: Vec<(u32, bool)> = Vec::new();
    for (&root, r) in &region {
        if r.inside && !r.outside && !r.border && !r.open {
            capped.push((root, r.inward));
        } else if r.inside && !r.open {
            out.curves_open += 1;
        }
    }
    capped.sort_unstable();
    out.regions_capped = capped.len();
    // Whether unit `u` is in a cap, and whether that cap faces inward.
    let mut cap_of = |u: u32| {
        let root = uf.find(u);
        capped
            .binary_search_by_key(&root, |c| c.0)
            .ok()
            .map(|i| capped[i].1)
    };
    let oriented = |t: [u32; 3], inward: bool| if inward { [t[0], t[2], t[1]] } else { t };
    let mut knife_id: HashMap<u32, u32> = HashMap::new();
    let mut remap = |v: u32, extra: &mut Vec<Vec3>| -> u32 {
        if v < kbase {
            return v;
        }
        *knife_id.entry(v).or_insert_with(|| {
            extra.push(knife.positions[(v - kbase) as usize]);
            kbase + extra.len() as u32 - 1
        })
    };
    let mut caps = Vec::new();
    for (u, (kt, f)) in knife_faces.iter().enumerate() {
        if let Some(inward) = cap_of(u as u32) {
            for t in triangulate_face(f, &pos, normal(knife, *kt)) {
                caps.push(oriented(t, inward).map(|v| remap(v, &mut out.extra_points)));
            }
        }
    }
    for (j, &t) in whole.iter().enumerate() {
        if let Some(inward) = cap_of((knife_faces.len() + j) as u32) {
            let cyc = knife.triangles[t as usize].map(|v| kbase + v);
            caps.push(oriented(cyc, inward).map(|v| remap(v, &mut out.extra_points)));
        }
    }
    out.caps = caps;
    Ok(out)
}
