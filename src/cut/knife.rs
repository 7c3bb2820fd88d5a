//! Knife geometry: which mesh edges a knife crosses, where, and which boxes
//! it cannot touch (seed 004 §3.1 node classification).
//!
//! Every decision is a pure function of the edge's two endpoint positions,
//! taken in canonical order (lower vertex id first), evaluated in f64. The
//! tree query and the brute-force locate call the same functions, so they agree
//! exactly; box tests are conservative (a margin of 1e-9 of the scene
//! scale), so a box declared clear never holds a crossed edge.

use glam::{DVec3, Vec3};

use crate::TriMesh;
use crate::foundation::{Aabb, Forest};

/// Largest sagitta of an interior cap edge, or of a polyhedral sphere's
/// triangle, on a sphere, relative to the radius.
pub const SPHERE_CHORD_ERROR: f64 = 1e-3;

/// A scalpel.
#[derive(Debug, Clone)]
pub enum Knife {
    /// Infinite plane through `point`; the negative side is where
    /// `normal·(p − point) < 0`.
    Plane { point: DVec3, normal: DVec3 },
    /// Bounded rectangle: centre, normal, in-plane axis `u` (made orthogonal
    /// to the normal), half extents along `u` and `v = n × u`. Cuts only
    /// where the plane crossing lies inside the rectangle.
    Rect {
        centre: DVec3,
        normal: DVec3,
        u_axis: DVec3,
        half_extents: [f64; 2],
    },
    /// Sphere; the negative side is the inside.
    Sphere { centre: DVec3, radius: f64 },
    /// A triangulated knife (open sheet reaching beyond the surface, or
    /// closed), consistently oriented, organised in its own B+ tree forest
    /// when the cut runs. The negative side is behind the knife triangles
    /// (against their right-hand normals): inside an outward closed knife.
    Mesh(TriMesh),
}

/// Which side of the knife.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// Behind the plane, inside the sphere, behind the knife triangles.
    Negative,
    /// In front of the plane, outside the sphere.
    Positive,
    /// A piece holding triangles of both sides (an open knife that does not
    /// cut through).
    Both,
}

/// A crossing of a mesh edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Where the knife meets the edge (f64, rounded to f32 for the mesh).
    pub point: DVec3,
    /// Whether the edge's first endpoint (lower vertex id) is on the negative side.
    pub first_negative: bool,
}

/// A knife ready for queries (normalised vectors, the mesh knife's forest).
#[derive(Debug)]
pub(crate) struct PreparedKnife<'a> {
    pub kind: Kind<'a>,
    margin: f64,
}

#[derive(Debug)]
pub(crate) enum Kind<'a> {
    Plane {
        p: DVec3,
        n: DVec3,
    },
    Rect {
        p: DVec3,
        n: DVec3,
        u: DVec3,
        v: DVec3,
        h: [f64; 2],
    },
    Sphere {
        c: DVec3,
        r: f64,
    },
    Mesh {
        mesh: &'a TriMesh,
        forest: Forest,
    },
}

fn check_finite(what: &str, v: DVec3) -> crate::Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(crate::Error::param(
            format!("knife {what}"),
            v,
            "must be finite",
        ))
    }
}

fn unit(what: &str, v: DVec3) -> crate::Result<DVec3> {
    check_finite(what, v)?;
    v.try_normalize()
        .ok_or_else(|| crate::Error::param(format!("knife {what}"), v, "must not have zero length"))
}

impl Knife {
    /// Validates and prepares the knife; `scale` is the size of the scene
    /// (for the conservative box margin).
    pub(crate) fn prepare(&self, scale: f64) -> crate::Result<PreparedKnife<'_>> {
        let margin = 1e-9 * scale.max(1e-30);
        let kind = match self {
            Knife::Plane { point, normal } => {
                check_finite("point", *point)?;
                Kind::Plane {
                    p: *point,
                    n: unit("normal", *normal)?,
                }
            }
            Knife::Rect {
                centre,
                normal,
                u_axis,
                half_extents,
            } => {
                check_finite("centre", *centre)?;
                let n = unit("normal", *normal)?;
                unit("u axis", *u_axis)?;
                let u = unit("u axis", *u_axis - n * u_axis.dot(n)).map_err(|_| {
                    crate::Error::param(
                        "knife rectangle u axis",
                        u_axis,
                        format!("must not be parallel to the normal {normal}"),
                    )
                })?;
                if half_extents.iter().any(|h| !h.is_finite() || *h <= 0.0) {
                    return Err(crate::Error::param(
                        "knife rectangle half extents",
                        format!("{half_extents:?}"),
                        "must be finite and > 0",
                    ));
                }
                Kind::Rect {
                    p: *centre,
                    n,
                    u,
                    v: n.cross(u),
                    h: *half_extents,
                }
            }
            Knife::Sphere { centre, radius } => {
                check_finite("centre", *centre)?;
                if !radius.is_finite() || *radius <= 0.0 {
                    return Err(crate::Error::param(
                        "knife sphere radius",
                        radius,
                        "must be finite and > 0",
                    ));
                }
                Kind::Sphere {
                    c: *centre,
                    r: *radius,
                }
            }
            Knife::Mesh(mesh) => {
                mesh.validate()?;
                if mesh.triangles.is_empty() {
                    return Err(crate::Error::empty("knife mesh triangles"));
                }
                // Sides come from the knife's normals: each directed edge
                // may be used once (a consistently oriented manifold).
                let mut directed = std::collections::HashSet::new();
                for (t, tri) in mesh.triangles.iter().enumerate() {
                    for e in 0..3 {
                        let (a, b) = (tri[e], tri[(e + 1) % 3]);
                        if a == b || !directed.insert((a, b)) {
                            return Err(crate::Refusal::KnifeNotManifold {
                                triangle: t as u32,
                                from: a,
                                to: b,
                            }
                            .into());
                        }
                    }
                }
                let forest = Forest::from_triangles(mesh.view()).forest;
                Kind::Mesh { mesh, forest }
            }
        };
        Ok(PreparedKnife { kind, margin })
    }

    /// The sphere as an outward triangulated knife: an icosahedron
    /// subdivided until every triangle lies within
    /// [`SPHERE_CHORD_ERROR`]·r of the
    /// sphere (the chord bound of analytic sphere caps), its vertices on the
    /// sphere (rounded to f32). `attempt` picks the orientation: a fixed
    /// irrational axis and angle per attempt, so a polyhedron that touches
    /// the surface degenerately (refused by the exact intersection) can be
    /// replaced by a turned one.
    pub fn polyhedral_sphere(centre: DVec3, radius: f64, attempt: u32) -> TriMesh {
        let (v, triangles) = (0..)
            .map(crate::mesh::unit_icosphere)
            .find(|(p, t)| crate::mesh::icosphere_sag(p, t) <= SPHERE_CHORD_ERROR)
            .expect("the sag shrinks about 4× per level");
        let golden = (1.0 + 5f64.sqrt()) / 2.0;
        let axis = DVec3::new(1.0, golden, std::f64::consts::SQRT_2).normalize();
        let turn = glam::DQuat::from_axis_angle(
            axis,
            0.25 + std::f64::consts::FRAC_1_SQRT_2 * f64::from(attempt),
        );
        let positions = v
            .iter()
            .map(|&p| (centre + turn * p * radius).as_vec3())
            .collect();
        TriMesh {
            positions,
            triangles,
            scalars: Vec::new(),
        }
    }
}

impl PreparedKnife<'_> {
    /// The analytic knife, resolved once so that a query's loops are
    /// compiled for its kind; `None` for mesh knives.
    pub fn analytic(&self) -> Option<AnalyticKnife> {
        let m = self.margin;
        match &self.kind {
            Kind::Plane { p, n } => Some(AnalyticKnife::Plane(PlaneSide { p: *p, n: *n, m })),
            Kind::Rect { p, n, u, v, h } => Some(AnalyticKnife::Rect(RectSide {
                plane: PlaneSide { p: *p, n: *n, m },
                u: *u,
                v: *v,
                h: *h,
            })),
            Kind::Sphere { c, r } => Some(AnalyticKnife::Sphere(SphereSide { c: *c, r: *r, m })),
            Kind::Mesh { .. } => None,
        }
    }

    /// The box margin (world units).
    pub fn margin(&self) -> f64 {
        self.margin
    }
}

/// The box tests of a triangulated knife: the boxes of its own forest,
/// grown by the margin.
pub(crate) struct MeshBoxes<'a> {
    pub forest: &'a Forest,
    pub margin: f64,
}

impl BoxQuery for MeshBoxes<'_> {
    fn box_is_clear(&self, b: &Aabb) -> bool {
        !forest_touches(self.forest, &grow(b, self.margin))
    }

    fn axis_interval(&self, _: &Aabb, axis: usize) -> (f64, f64) {
        let m = self.margin;
        (self.forest.groups.iter()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), g| {
            (
                a.min(f64::from(g.bbox.min[axis]) - m),
                b.max(f64::from(g.bbox.max[axis]) + m),
            )
        })
    }
}

/// The box tests of a tree query (seed 004 §3.1 node classification).
pub(crate) trait BoxQuery {
    /// Whether the knife surface certainly misses every edge inside `b`.
    fn box_is_clear(&self, b: &Aabb) -> bool;

    /// Conservative range of coordinate `axis` over the knife surface
    /// points whose other two coordinates lie in `b`'s extent (the slab a
    /// sorted level of the tree is searched in, seed §4.3); infinite when
    /// the knife is parallel to the axis.
    fn axis_interval(&self, b: &Aabb, axis: usize) -> (f64, f64);
}

/// An analytic knife (plane, rectangle, sphere), one type per kind, so
/// that a query's loops are compiled for their knife instead of
/// dispatching per vertex and per box.
pub(crate) trait Analytic: BoxQuery + Copy + Send + Sync {
    /// Whether every edge whose ends have side values of opposite signs is
    /// crossed (plane and sphere; a rectangle also needs the crossing point
    /// inside it).
    const SIGN_CHANGE_CROSSES: bool;

    /// The side value of `q` (negative: the knife's negative side).
    fn eval(self, q: DVec3) -> f64;

    /// The crossing of edge `a → b` (endpoints in canonical order: lower
    /// vertex id first), if the knife cuts it, given the ends' side values
    /// `fa`, `fb` from [`Analytic::eval`] (each vertex evaluated once per
    /// triangle, not once per edge; tree and scan decide here).
    fn crossing_from(self, a: Vec3, b: Vec3, fa: f64, fb: f64) -> Option<Crossing>;
}

/// An analytic knife of any kind (see [`PreparedKnife::analytic`]).
#[derive(Debug, Clone, Copy)]
pub(crate) enum AnalyticKnife {
    Plane(PlaneSide),
    Rect(RectSide),
    Sphere(SphereSide),
}

impl AnalyticKnife {
    /// The side value of `q` (negative: the knife's negative side).
    pub fn eval(self, q: DVec3) -> f64 {
        match self {
            AnalyticKnife::Plane(a) => a.eval(q),
            AnalyticKnife::Rect(a) => a.eval(q),
            AnalyticKnife::Sphere(a) => a.eval(q),
        }
    }
}

/// Infinite plane: side value the signed distance `n·(q − p)`, `n` unit;
/// `m` the box margin.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PlaneSide {
    p: DVec3,
    n: DVec3,
    m: f64,
}

impl BoxQuery for PlaneSide {
    #[inline(always)]
    fn box_is_clear(&self, b: &Aabb) -> bool {
        plane_clear(b.min.as_dvec3(), b.max.as_dvec3(), self.p, self.n, self.m)
    }

    #[inline(always)]
    fn axis_interval(&self, b: &Aabb, axis: usize) -> (f64, f64) {
        let others = [(axis + 1) % 3, (axis + 2) % 3];
        plane_interval(
            b.min.as_dvec3(),
            b.max.as_dvec3(),
            self.p,
            self.n,
            axis,
            others,
            self.m,
        )
    }
}

impl Analytic for PlaneSide {
    const SIGN_CHANGE_CROSSES: bool = true;

    #[inline(always)]
    fn eval(self, q: DVec3) -> f64 {
        self.n.dot(q - self.p)
    }

    #[inline(always)]
    fn crossing_from(self, a: Vec3, b: Vec3, fa: f64, fb: f64) -> Option<Crossing> {
        ((fa < 0.0) != (fb < 0.0)).then(|| plane_crossing(a.as_dvec3(), b.as_dvec3(), fa, fb))
    }
}

/// Bounded rectangle: the plane, its in-plane axes `u`, `v` and half
/// extents `h` along them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RectSide {
    plane: PlaneSide,
    u: DVec3,
    v: DVec3,
    h: [f64; 2],
}

impl BoxQuery for RectSide {
    #[inline(always)]
    fn box_is_clear(&self, b: &Aabb) -> bool {
        if self.plane.box_is_clear(b) {
            return true;
        }
        let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
        let (p, m, h) = (self.plane.p, self.plane.m, self.h);
        let (u0, u1) = project(lo, hi, p, self.u);
        let (v0, v1) = project(lo, hi, p, self.v);
        u1 < -h[0] - m || u0 > h[0] + m || v1 < -h[1] - m || v0 > h[1] + m
    }

    #[inline(always)]
    fn axis_interval(&self, b: &Aabb, axis: usize) -> (f64, f64) {
        let (a, z) = self.plane.axis_interval(b, axis);
        let (p, m, h) = (self.plane.p, self.plane.m, self.h);
        let ext = self.u[axis].abs() * h[0] + self.v[axis].abs() * h[1] + m;
        (a.max(p[axis] - ext), z.min(p[axis] + ext))
    }
}

impl Analytic for RectSide {
    const SIGN_CHANGE_CROSSES: bool = false;

    #[inline(always)]
    fn eval(self, q: DVec3) -> f64 {
        self.plane.eval(q)
    }

    #[inline(always)]
    fn crossing_from(self, a: Vec3, b: Vec3, fa: f64, fb: f64) -> Option<Crossing> {
        self.plane.crossing_from(a, b, fa, fb).filter(|c| {
            let d = c.point - self.plane.p;
            d.dot(self.u).abs() <= self.h[0] && d.dot(self.v).abs() <= self.h[1]
        })
    }
}

/// Sphere: side value `|q − c|² − r²`; `m` the box margin.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SphereSide {
    c: DVec3,
    r: f64,
    m: f64,
}

impl BoxQuery for SphereSide {
    #[inline(always)]
    fn box_is_clear(&self, b: &Aabb) -> bool {
        let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
        let (c, r, m) = (self.c, self.r, self.m);
        let near = c.clamp(lo, hi);
        let far = DVec3::new(
            if c.x - lo.x > hi.x - c.x { lo.x } else { hi.x },
            if c.y - lo.y > hi.y - c.y { lo.y } else { hi.y },
            if c.z - lo.z > hi.z - c.z { lo.z } else { hi.z },
        );
        let rr = r * r;
        let slack = m * (2.0 * r + m);
        (near - c).length_squared() > rr + slack || (far - c).length_squared() < rr - slack
    }

    #[inline(always)]
    fn axis_interval(&self, b: &Aabb, axis: usize) -> (f64, f64) {
        let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
        let (c, r, m) = (self.c, self.r, self.m);
        let d2: f64 = [(axis + 1) % 3, (axis + 2) % 3]
            .iter()
            .map(|&j| (c[j] - c[j].clamp(lo[j], hi[j])).powi(2))
            .sum();
        if d2 > r * r + m * (2.0 * r + m) {
            return (f64::INFINITY, f64::NEG_INFINITY);
        }
        let w = (r * r - d2).max(0.0).sqrt() + m;
        (c[axis] - w, c[axis] + w)
    }
}

impl Analytic for SphereSide {
    const SIGN_CHANGE_CROSSES: bool = true;

    #[inline(always)]
    fn eval(self, q: DVec3) -> f64 {
        (q - self.c).length_squared() - self.r * self.r
    }

    #[inline(always)]
    fn crossing_from(self, a: Vec3, b: Vec3, fa: f64, fb: f64) -> Option<Crossing> {
        ((fa < 0.0) != (fb < 0.0)).then(|| sphere_crossing(a.as_dvec3(), b.as_dvec3(), self.c, fa))
    }
}

fn grow(b: &Aabb, m: f64) -> Aabb {
    let m = m as f32;
    Aabb {
        min: b.min - Vec3::splat(m),
        max: b.max + Vec3::splat(m),
    }
}

/// Range of coordinate `axis` on the plane `n·(x − p) = 0` over the box's
/// extent on the `others` axes, widened by the margin.
#[inline(always)]
fn plane_interval(
    lo: DVec3,
    hi: DVec3,
    p: DVec3,
    n: DVec3,
    axis: usize,
    others: [usize; 2],
    m: f64,
) -> (f64, f64) {
    let na = n[axis];
    if na.abs() < 1e-9 {
        return (f64::NEG_INFINITY, f64::INFINITY);
    }
    // n_a·x_a = n·p − Σ_j n_j x_j over the box's other coordinates.
    let (mut s_lo, mut s_hi) = (n.dot(p), n.dot(p));
    for j in others {
        let (a, b) = (n[j] * lo[j], n[j] * hi[j]);
        s_lo -= a.max(b);
        s_hi -= a.min(b);
    }
    let (a, b) = (s_lo / na, s_hi / na);
    let w = m / na.abs() + 1e-12 * (a.abs() + b.abs());
    (a.min(b) - w, a.max(b) + w)
}

#[inline(always)]
fn plane_clear(lo: DVec3, hi: DVec3, p: DVec3, n: DVec3, m: f64) -> bool {
    let (d0, d1) = project(lo, hi, p, n);
    d0 > m || d1 < -m
}

/// Range of `dir·(x − p)` over the box.
#[inline(always)]
fn project(lo: DVec3, hi: DVec3, p: DVec3, dir: DVec3) -> (f64, f64) {
    let c = (lo + hi) * 0.5 - p;
    let e = (hi - lo) * 0.5;
    let mid = dir.dot(c);
    let rad = dir.abs().dot(e);
    (mid - rad, mid + rad)
}

/// Crossing of `a → b` by a plane, given side values of opposite signs.
fn plane_crossing(a: DVec3, b: DVec3, fa: f64, fb: f64) -> Crossing {
    let t = (fa / (fa - fb)).clamp(0.0, 1.0);
    Crossing {
        point: a + (b - a) * t,
        first_negative: fa < 0.0,
    }
}

/// Crossing of `a → b` by a sphere, given `fa = |a − c|² − r²` and that
/// the ends lie on opposite sides.
fn sphere_crossing(a: DVec3, b: DVec3, c: DVec3, fa: f64) -> Crossing {
    // |a + t·d − c|² = r²: A t² + 2B t + C = 0 with exactly one root in [0, 1].
    let d = b - a;
    let qa = d.length_squared();
    let qb = d.dot(a - c);
    let disc = (qb * qb - qa * fa).max(0.0);
    let s = disc.sqrt();
    // The root where the sign changes: entering (fa > 0) takes the smaller.
    let t = if fa > 0.0 {
        // (−B − √D)/A written stably.
        if qb <= 0.0 {
            fa / (-qb + s)
        } else {
            (-qb - s) / qa
        }
    } else if qb >= 0.0 {
        fa / (-qb - s)
    } else {
        (-qb + s) / qa
    };
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.5
    };
    Crossing {
        point: a + d * t,
        first_negative: fa < 0.0,
    }
}

/// Whether any knife triangle box of `forest` overlaps `b`.
fn forest_touches(forest: &Forest, b: &Aabb) -> bool {
    forest.leaves_overlapping(b).next().is_some()
}
