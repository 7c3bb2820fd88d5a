//! Bone fragments cut free by a plan's scalpels (SPEC §5.3 "hand a piece
//! to the tissue model as a bone fragment to move"; seed 004 §3).
//!
//! A plan may open with `[[cut]]` tables. Each names a fragment, a knife
//! (plane, bounded rectangle or sphere, as `chisel cut` takes them), the
//! side of the knife whose pieces form the fragment, and optionally a
//! geometric selector the pieces' centroids must lie in:
//!
//! ```toml
//! [[cut]]
//! name = "jaw"                                  # select = { fragment = "jaw" }
//! knife = { plane = { point = [0.0, -40.0, 0.0], normal = [0.0, -1.0, 0.0] } }
//! side = "positive"                             # in front of the normal
//! within = { box = { min = [-60.0, -90.0, -10.0], max = [60.0, -40.0, 70.0] } }
//! ```
//!
//! Cuts run in order on the bone mesh before the network is built: every
//! piece of the previous cut is cut again (pieces keep the fragments they
//! belonged to), capped with the knife surface unless `cap = false`, so the
//! moved fragment's cut face is bone surface too. The resulting bone mesh
//! is the pieces one after another (vertices along a cut are duplicated,
//! one copy per side), so a fragment moves without dragging its neighbour.

use std::collections::BTreeMap;

use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

use super::selector::{Selector, point_text};
use crate::cut::{CutOptions, CutStats, Knife, Side, cut_mesh};
use crate::mesh::{ScalarField, TriMesh};
use crate::{Error, Refusal, Result};

/// Bone vertex ids of named fragments (e.g. the jaw cut off by `cut`),
/// resolved by [`Selector::Fragment`].
pub type Fragments = BTreeMap<String, Vec<u32>>;

/// A knife of a plan cut (mesh units).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum KnifeSpec {
    /// Infinite plane through `point`; positive side = where `normal` points.
    Plane { point: [f32; 3], normal: [f32; 3] },
    /// Bounded rectangle: centre, normal, in-plane axis `u`, half extents
    /// along `u` and `v = normal × u`.
    Rect {
        center: [f32; 3],
        normal: [f32; 3],
        u: [f32; 3],
        half_extents: [f32; 2],
    },
    /// Sphere; the negative side is the inside.
    Sphere { center: [f32; 3], radius: f32 },
}

impl KnifeSpec {
    /// The scalpel.
    pub fn knife(&self) -> Knife {
        let v = |a: &[f32; 3]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
        match self {
            KnifeSpec::Plane { point, normal } => Knife::Plane {
                point: v(point),
                normal: v(normal),
            },
            KnifeSpec::Rect {
                center,
                normal,
                u,
                half_extents,
            } => Knife::Rect {
                centre: v(center),
                normal: v(normal),
                u_axis: v(u),
                half_extents: half_extents.map(f64::from),
            },
            KnifeSpec::Sphere { center, radius } => Knife::Sphere {
                centre: v(center),
                radius: *radius as f64,
            },
        }
    }

    /// What is wrong with the knife's numbers, if anything.
    fn problem(&self) -> Option<&'static str> {
        let finite = |v: &[f32]| v.iter().all(|c| c.is_finite());
        match self {
            KnifeSpec::Plane { point, normal } => {
                if !finite(point) || !finite(normal) {
                    Some("the plane's point and normal must be finite")
                } else if Vec3::from_array(*normal) == Vec3::ZERO {
                    Some("the plane's normal is zero")
                } else {
                    None
                }
            }
            KnifeSpec::Rect {
                center,
                normal,
                u,
                half_extents,
            } => {
                if !finite(center) || !finite(normal) || !finite(u) || !finite(half_extents) {
                    Some("the rectangle's numbers must be finite")
                } else if half_extents.iter().any(|h| *h <= 0.0) {
                    Some("the rectangle's half extents must be > 0")
                } else if Vec3::from_array(*normal)
                    .cross(Vec3::from_array(*u))
                    .length()
                    == 0.0
                {
                    Some("the rectangle's normal or u is zero, or they are parallel")
                } else {
                    None
                }
            }
            KnifeSpec::Sphere { center, radius } => {
                if !finite(center) || !radius.is_finite() {
                    Some("the sphere's centre and radius must be finite")
                } else if *radius <= 0.0 {
                    Some("the sphere's radius must be > 0")
                } else {
                    None
                }
            }
        }
    }
}

impl std::fmt::Display for KnifeSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            KnifeSpec::Plane { point, normal } => write!(
                f,
                "plane through {} with normal {}",
                point_text(point),
                point_text(normal)
            ),
            KnifeSpec::Rect {
                center,
                normal,
                u,
                half_extents,
            } => write!(
                f,
                "rectangle centred at {} with normal {}, u {}, half extents {} × {}",
                point_text(center),
                point_text(normal),
                point_text(u),
                half_extents[0],
                half_extents[1]
            ),
            KnifeSpec::Sphere { center, radius } => {
                write!(
                    f,
                    "sphere centred at {} with radius {radius}",
                    point_text(center)
                )
            }
        }
    }
}

/// Which side of the knife a fragment takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum KeepSide {
    /// In front of the plane / rectangle normal, outside the sphere.
    Positive,
    /// Behind the plane / rectangle, inside the sphere.
    Negative,
}

impl std::fmt::Display for KeepSide {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            KeepSide::Positive => "positive",
            KeepSide::Negative => "negative",
        })
    }
}

fn yes() -> bool {
    true
}

/// One `[[cut]]` of a plan: a knife and the fragment it frees.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoneCut {
    /// Fragment name (for `select = { fragment = "name" }`), unique in the plan.
    pub name: String,
    /// The scalpel.
    pub knife: KnifeSpec,
    /// The side whose pieces form the fragment.
    pub side: KeepSide,
    /// Only pieces whose area centroid lies in this sphere, box or half-space.
    #[serde(default)]
    pub within: Option<Selector>,
    /// Close the pieces with the knife surface (default true).
    #[serde(default = "yes")]
    pub cap: bool,
}

impl BoneCut {
    /// Checks the name, the knife's numbers and the `within` selector;
    /// `what` names the cut in errors.
    pub fn validate(&self, what: &str) -> Result<()> {
        if self.name.trim().is_empty() {
            return Err(Error::param("name", "\"\"", "must not be empty").within(what));
        }
        if let Some(problem) = self.knife.problem() {
            return Err(Error::param("knife", &self.knife, problem).within(what));
        }
        if let Some(w) = &self.within {
            w.validate(&format!("{what} `within`"))?;
            if w.contains(Vec3::ZERO).is_none() {
                return Err(Error::param(
                    "within",
                    w.describe(),
                    "takes a sphere, box or half_space",
                )
                .within(what));
            }
        }
        Ok(())
    }
}

/// One piece of the cut bone.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PieceInfo {
    /// Its vertices in the bone mesh: `first_vertex..first_vertex + vertices`.
    pub first_vertex: u32,
    pub vertices: u32,
    pub triangles: u32,
    /// Area-weighted centroid (mesh units).
    pub centroid: [f32; 3],
    /// Fragments it belongs to (plan cut names).
    pub fragments: Vec<String>,
}

/// The bone after a plan's cuts.
#[derive(Debug, Clone)]
pub struct CutBone {
    /// The pieces one after another, with a per-vertex scalar `fragment`
    /// (1 + index of the last plan cut whose fragment holds the vertex, 0 = none).
    pub mesh: TriMesh,
    /// Fragment name → bone vertex ids (ascending).
    pub fragments: Fragments,
    /// Per piece, in mesh order.
    pub pieces: Vec<PieceInfo>,
    /// Per cut, what the scalpel did (tree nodes and triangles tested, caps).
    pub stats: Vec<CutStats>,
}

fn centroid(mesh: &TriMesh) -> DVec3 {
    let (mut sum, mut area) = (DVec3::ZERO, 0.0);
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
        let w = (b - a).cross(c - a).length();
        sum += (a + b + c) * (w / 3.0);
        area += w;
    }
    if area > 0.0 {
        sum / area
    } else {
        mesh.positions.iter().map(|p| p.as_dvec3()).sum::<DVec3>()
            / mesh.positions.len().max(1) as f64
    }
}

/// `source: plan cut i `name`` for messages (`source` names the plan file).
fn cut_label(source: Option<&str>, i: usize, name: &str) -> String {
    let cut = format!("plan cut {} `{name}`", i + 1);
    match source {
        Some(src) => format!("{src}: {cut}"),
        None => cut,
    }
}

/// Validates every cut and checks that names are unique; `source` (the
/// plan file) prefixes errors.
pub fn validate_cuts(cuts: &[BoneCut], source: Option<&str>) -> Result<()> {
    for (i, c) in cuts.iter().enumerate() {
        let what = cut_label(source, i, &c.name);
        c.validate(&what)?;
        if cuts[..i].iter().any(|d| d.name == c.name) {
            return Err(Error::param("name", &c.name, "is used by an earlier cut").within(what));
        }
    }
    Ok(())
}

/// Runs `cuts` in order on `bone` (each cuts every piece of the previous
/// one) and names the fragments. Errors: invalid or duplicate cut names, a
/// cut whose fragment is empty (names the knife, side and `within`);
/// `source` (the plan file) prefixes them.
pub fn cut_bone(bone: &TriMesh, cuts: &[BoneCut], source: Option<&str>) -> Result<CutBone> {
    bone.validate()?;
    validate_cuts(cuts, source)?;
    // (piece, indices of the cuts whose fragment holds it, area centroid)
    let mut pieces: Vec<(TriMesh, Vec<usize>, DVec3)> =
        vec![(bone.clone(), Vec::new(), centroid(bone))];
    let mut stats = Vec::with_capacity(cuts.len());
    for (ci, c) in cuts.iter().enumerate() {
        let knife = c.knife.knife();
        let opts = CutOptions { cap: c.cap };
        let want = match c.side {
            KeepSide::Positive => Side::Positive,
            KeepSide::Negative => Side::Negative,
        };
        let mut next = Vec::with_capacity(pieces.len());
        let mut total = CutStats::default();
        let mut taken = 0usize;
        for (mesh, member, _) in &pieces {
            let r = cut_mesh(mesh, &knife, &opts)?;
            total.accumulate(&r.stats);
            for (p, side) in r.pieces.into_iter().zip(r.sides) {
                let mut m = member.clone();
                let at = centroid(&p);
                let inside = c
                    .within
                    .as_ref()
                    .is_none_or(|w| w.contains(at.as_vec3()) == Some(true));
                if side == want && inside {
                    m.push(ci);
                    taken += 1;
                }
                next.push((p, m, at));
            }
        }
        if taken == 0 {
            let what = cut_label(source, ci, &c.name);
            let detail = match &c.within {
                None => format!(
                    "no bone piece lies on the {} side of the {}",
                    c.side, c.knife
                ),
                Some(w) => format!(
                    "no bone piece on the {} side of the {} has its centroid in the {}",
                    c.side,
                    c.knife,
                    w.describe()
                ),
            };
            return Err(Refusal::EmptySelection { what, detail }.into());
        }
        stats.push(total);
        pieces = next;
    }

    let mut mesh = TriMesh::default();
    let mut label = Vec::new();
    let mut ids: BTreeMap<String, Vec<u32>> = BTreeMap::new();
    let mut infos = Vec::with_capacity(pieces.len());
    for (p, member, at) in &pieces {
        let first = mesh.positions.len() as u32;
        let n = p.positions.len() as u32;
        mesh.positions.extend_from_slice(&p.positions);
        mesh.triangles
            .extend(p.triangles.iter().map(|t| t.map(|i| i + first)));
        label.extend(std::iter::repeat_n(
            member.last().map_or(0.0, |&c| (c + 1) as f32),
            n as usize,
        ));
        for &c in member {
            ids.entry(cuts[c].name.clone())
                .or_default()
                .extend(first..first + n);
        }
        infos.push(PieceInfo {
            first_vertex: first,
            vertices: n,
            triangles: p.triangles.len() as u32,
            centroid: at.as_vec3().to_array(),
            fragments: member.iter().map(|&c| cuts[c].name.clone()).collect(),
        });
    }
    mesh.scalars.push(ScalarField {
        name: "fragment".into(),
        values: label,
    });
    Ok(CutBone {
        mesh,
        fragments: ids,
        pieces: infos,
        stats,
    })
}
