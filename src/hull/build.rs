//! Construction: candidate points (or stored face cycles) in, a
//! [`ConvexHull`] out — the §4.1.8 start (extreme points first, initial
//! tetrahedron), the incremental run, and the flat-polygon fallback.

use super::incremental::{Builder, primitive};
use super::{ConvexHull, HalfSpace, HullFace, HullOptions, HullStats, MAX_COORD, Order};
use crate::foundation::exact::{P3, cross, dot, sub};
use crate::voxel::{CandidateKind, DigitalObject};

impl ConvexHull {
    /// Hull of `points` (combinatorial coordinates, |c| ≤ [`MAX_COORD`]).
    ///
    /// Errors: [`crate::Error::InvalidData`] for coordinates out of range,
    /// [`crate::Refusal::Collinear`] when the points are collinear (no
    /// polygon, no polyhedron).
    pub fn build(points: &[[i64; 3]], options: HullOptions) -> crate::Result<ConvexHull> {
        if let Some(i) = points
            .iter()
            .position(|p| p.iter().any(|c| c.abs() > MAX_COORD))
        {
            return Err(crate::Error::data(
                "hull points",
                "point",
                i,
                format!("{:?} exceeds the coordinate bound ±{MAX_COORD}", points[i]),
            ));
        }
        let mut pts = points.to_vec();
        pts.sort_unstable();
        pts.dedup();
        if options.order != Order::Lexicographic {
            extreme_first(&mut pts);
        }
        let Some(tet) = initial_tetrahedron(&pts) else {
            return planar_hull(&pts, options);
        };
        let mut b = Builder::new(&pts, options.coplanar, tet);
        if options.order == Order::Furthest {
            b.run_furthest()?;
        } else {
            for i in 0..pts.len() as u32 {
                if !tet.contains(&i) {
                    b.insert(i)?;
                }
            }
        }
        let vol6 = b.vol6;
        let stats = b.stats;
        let faces: Vec<_> = b.faces.into_iter().flatten().collect();
        let (vertices, faces) = compact(&pts, faces.into_iter().map(|f| (f.verts, f.n, f.d)));
        Ok(ConvexHull {
            vertices,
            faces,
            vol6,
            planar: None,
            stats,
            options,
        })
    }

    /// Hull of a digital object's candidates of `kind` (§4.1.2–4.1.3):
    /// vertices at voxel centres, or at 0-cells for
    /// [`CandidateKind::ConvexCorners`].
    pub fn of_object(
        object: &DigitalObject,
        kind: CandidateKind,
        options: HullOptions,
    ) -> crate::Result<ConvexHull> {
        ConvexHull::build(&object.candidates(kind), options)
    }

    /// Rebuilds a hull from stored vertices and face cycles (counter-clockwise
    /// from outside), e.g. a decoded cell list. Planes are recomputed
    /// exactly (`Σ vᵢ × vᵢ₊₁`, made primitive); a flat polygon is two
    /// opposite faces over the same cycle.
    ///
    /// Errors: [`crate::Error::InvalidData`] (naming the vertex or face)
    /// when a coordinate is out of range, a face has fewer than three vertices, an index is out of range,
    /// a face is not planar, or some vertex lies outside a face's plane (the
    /// faces do not bound a convex polytope).
    pub fn from_faces(vertices: Vec<[i64; 3]>, cycles: Vec<Vec<u32>>) -> crate::Result<ConvexHull> {
        let bad = |f: usize, what: String| crate::Error::data("convex polytope", "face", f, what);
        if let Some(i) = vertices
            .iter()
            .position(|p| p.iter().any(|c| c.abs() > MAX_COORD))
        {
            return Err(crate::Error::data(
                "convex polytope",
                "vertex",
                i,
                format!("{:?} exceeds ±{MAX_COORD}", vertices[i]),
            ));
        }
        let mut faces = Vec::with_capacity(cycles.len());
        for (f, cycle) in cycles.into_iter().enumerate() {
            if cycle.len() < 3 {
                return Err(bad(f, format!("has {} vertices", cycle.len())));
            }
            if let Some(v) = cycle.iter().find(|&&v| v as usize >= vertices.len()) {
                return Err(bad(f, format!("names vertex {v} of {}", vertices.len())));
            }
            let p = |k: usize| vertices[cycle[k % cycle.len()] as usize];
            // Twice the area vector; a convex face within ±MAX_COORD has
            // |n_c| < 2³⁶, which keeps every later product below 2⁶³.
            let mut n = [0i128; 3];
            for k in 0..cycle.len() {
                let c = cross(sub(p(k), p(0)), sub(p(k + 1), p(0)));
                n = std::array::from_fn(|a| n[a] + i128::from(c[a]));
            }
            if n == [0, 0, 0] {
                return Err(bad(f, "is degenerate".into()));
            }
            if n.iter().any(|c| c.abs() >= 1 << 36) {
                return Err(bad(
                    f,
                    "is not a convex polygon of the coordinate range".into(),
                ));
            }
            let normal = primitive(n.map(|c| c as i64));
            let plane = HalfSpace {
                normal,
                offset: dot(normal, p(0)),
            };
            if (0..cycle.len()).any(|k| plane.side(p(k)) != 0) {
                return Err(bad(f, "is not planar".into()));
            }
            if let Some(v) = vertices.iter().find(|&&v| plane.side(v) > 0) {
                return Err(bad(f, format!("vertex {v:?} lies outside its plane")));
            }
            faces.push(HullFace {
                vertices: cycle,
                plane,
            });
        }
        let planar = match faces.as_slice() {
            [a, b] if a.plane.normal == b.plane.normal.map(|c| -c) => Some(a.plane),
            _ => None,
        };
        let mut hull = ConvexHull {
            vertices,
            faces,
            vol6: 0,
            planar,
            stats: HullStats::default(),
            options: HullOptions::default(),
        };
        if hull.faces.len() < 4 && planar.is_none() {
            return Err(crate::Error::param(
                "convex polytope faces",
                hull.faces.len(),
                "fewer than 4 faces (and not a flat polygon's 2) bound no polytope",
            ));
        }
        hull.vol6 = hull.volume6_from_faces();
        Ok(hull)
    }
}

/// Moves the eight extreme points of §4.1.8 to the front of the
/// lexicographically sorted `pts` (duplicates among them kept once).
fn extreme_first(pts: &mut Vec<P3>) {
    if pts.is_empty() {
        return;
    }
    // (sign x, sign y, sign z): +1 prefers the maximum on that axis.
    let prefs: [[i64; 3]; 8] = [
        [-1, -1, -1],
        [1, -1, -1],
        [-1, 1, -1],
        [-1, -1, 1],
        [1, 1, 1],
        [-1, 1, 1],
        [1, -1, 1],
        [1, 1, -1],
    ];
    let mut front: Vec<usize> = Vec::new();
    for s in prefs {
        // Lexicographic extreme: axis x first, then y, then z; if only one
        // point has the extreme x and it is already taken, the next one is.
        let key = |i: usize| {
            let p = pts[i];
            (
                [s[0] * p[0], s[1] * p[1], s[2] * p[2]],
                std::cmp::Reverse(i),
            )
        };
        if let Some(i) = (0..pts.len())
            .filter(|i| !front.contains(i))
            .max_by_key(|&i| key(i))
        {
            front.push(i);
        }
    }
    let mut taken = vec![false; pts.len()];
    let mut out: Vec<P3> = front.iter().map(|&i| pts[i]).collect();
    for &i in &front {
        taken[i] = true;
    }
    out.extend(
        pts.iter()
            .enumerate()
            .filter(|(i, _)| !taken[*i])
            .map(|(_, p)| *p),
    );
    *pts = out;
}

/// First four non-coplanar points in order, or `None` when all are coplanar.
fn initial_tetrahedron(pts: &[P3]) -> Option<[u32; 4]> {
    let a = 0usize;
    let b = (1..pts.len()).find(|&i| pts[i] != pts[a])?;
    let c = (b + 1..pts.len())
        .find(|&i| cross(sub(pts[b], pts[a]), sub(pts[i], pts[a])) != [0, 0, 0])?;
    let n = cross(sub(pts[b], pts[a]), sub(pts[c], pts[a]));
    let d = (c + 1..pts.len()).find(|&i| dot(n, sub(pts[i], pts[a])) != 0)?;
    Some([a, b, c, d].map(|i| i as u32))
}

/// Renumbers the vertices used by `faces` in lexicographic order.
fn compact(
    pts: &[P3],
    faces: impl Iterator<Item = (Vec<u32>, P3, i64)>,
) -> (Vec<P3>, Vec<HullFace>) {
    let faces: Vec<_> = faces.collect();
    let mut used = vec![false; pts.len()];
    for (verts, _, _) in &faces {
        for &v in verts {
            used[v as usize] = true;
        }
    }
    let mut order: Vec<usize> = (0..pts.len()).filter(|&i| used[i]).collect();
    order.sort_unstable_by_key(|&i| pts[i]);
    let mut index = vec![u32::MAX; pts.len()];
    let mut vertices = Vec::with_capacity(order.len());
    for i in order {
        index[i] = vertices.len() as u32;
        vertices.push(pts[i]);
    }
    let faces = faces
        .into_iter()
        .map(|(verts, n, d)| HullFace {
            vertices: verts.iter().map(|&v| index[v as usize]).collect(),
            plane: HalfSpace {
                normal: n,
                offset: d,
            },
        })
        .collect();
    (vertices, faces)
}

/// Coplanar input: the convex polygon (monotone chain in the plane, exact),
/// stored as two opposite faces.
fn planar_hull(pts: &[P3], options: HullOptions) -> crate::Result<ConvexHull> {
    let degenerate = || crate::Error::from(crate::Refusal::Collinear { points: pts.len() });
    let a = *pts.first().ok_or_else(degenerate)?;
    let b = *pts.iter().find(|&&p| p != a).ok_or_else(degenerate)?;
    let c = *pts
        .iter()
        .find(|&&p| cross(sub(b, a), sub(p, a)) != [0, 0, 0])
        .ok_or_else(degenerate)?;
    let n = primitive(cross(sub(b, a), sub(c, a)));
    // Turn test in the plane: > 0 when o→p→q turns counter-clockwise about n.
    let turn = |o: P3, p: P3, q: P3| dot(cross(sub(p, o), sub(q, o)), n);
    let mut sorted: Vec<usize> = (0..pts.len()).collect();
    sorted.sort_unstable_by_key(|&i| pts[i]);
    let mut hull: Vec<usize> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &usize>> = if pass == 0 {
            Box::new(sorted.iter())
        } else {
            Box::new(sorted.iter().rev())
        };
        for &i in iter {
            while hull.len() >= start + 2
                && turn(pts[hull[hull.len() - 2]], pts[hull[hull.len() - 1]], pts[i]) <= 0
            {
                hull.pop();
            }
            hull.push(i);
        }
        hull.pop();
    }
    let ccw: Vec<u32> = hull.iter().map(|&i| i as u32).collect();
    let cw: Vec<u32> = ccw.iter().rev().copied().collect();
    let d = dot(n, a);
    let neg = n.map(|c| -c);
    let (vertices, faces) = compact(pts, [(ccw, n, d), (cw, neg, -d)].into_iter());
    Ok(ConvexHull {
        vertices,
        faces,
        vol6: 0,
        planar: Some(HalfSpace {
            normal: n,
            offset: d,
        }),
        stats: HullStats {
            candidates: pts.len(),
            inserted: hull.len(),
            skipped: pts.len() - hull.len(),
            ..HullStats::default()
        },
        options,
    })
}
