//! Selectors: which points a plan step (or a stiffness region, or a cut's
//! `within`) applies to, and their resolution to bone vertex ids.

use std::collections::BTreeMap;

use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

use crate::{Error, Refusal, Result};

/// Which points a step (or a stiffness region) applies to.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Selector {
    /// Points with `|x − center| ≤ radius`.
    Sphere { center: [f32; 3], radius: f32 },
    /// Points with `min ≤ x ≤ max` componentwise.
    Box { min: [f32; 3], max: [f32; 3] },
    /// Points with `(x − point) · normal ≥ 0`.
    HalfSpace { point: [f32; 3], normal: [f32; 3] },
    /// Explicit bone-layer vertex ids.
    Vertices(Vec<u32>),
    /// The bone vertices of a named fragment (see
    /// [`Fragments`](super::fragments::Fragments)).
    Fragment(String),
}

/// `(x, y, z)`, each coordinate in the shortest form that reads back as
/// the same `f32` (`1.0` prints as `1`).
pub(crate) fn point_text(v: &[f32; 3]) -> String {
    format!("({}, {}, {})", v[0], v[1], v[2])
}

pub(crate) fn finite3(v: &[f32; 3]) -> bool {
    v.iter().all(|c| c.is_finite())
}

impl Selector {
    /// Checks the parameters (finite vectors, positive radius, ordered box,
    /// non-zero normal, non-empty id list); `what` names the owner in errors.
    pub fn validate(&self, what: &str) -> Result<()> {
        let bad = |name: &str, value: String, rule: &str| {
            Err(Error::param(name, value, rule).within(what))
        };
        match self {
            Selector::Sphere { center, radius } => {
                if !finite3(center) || !radius.is_finite() || *radius <= 0.0 {
                    return bad(
                        "sphere",
                        format!("centre {}, radius {radius}", point_text(center)),
                        "needs a finite centre and a radius > 0",
                    );
                }
            }
            Selector::Box { min, max } => {
                if !finite3(min) || !finite3(max) || (0..3).any(|a| min[a] > max[a]) {
                    return bad(
                        "box",
                        format!("min {}, max {}", point_text(min), point_text(max)),
                        "needs finite corners with min ≤ max",
                    );
                }
            }
            Selector::HalfSpace { point, normal } => {
                if !finite3(point) || !finite3(normal) || Vec3::from_array(*normal).length() == 0.0
                {
                    return bad(
                        "half_space",
                        format!("point {}, normal {}", point_text(point), point_text(normal)),
                        "needs a finite point and a non-zero finite normal",
                    );
                }
            }
            Selector::Vertices(ids) => {
                if ids.is_empty() {
                    return bad("vertices", "[]".into(), "lists no id: an empty selection");
                }
            }
            Selector::Fragment(name) => {
                if name.is_empty() {
                    return bad("fragment", "\"\"".into(), "the name is empty");
                }
            }
        }
        Ok(())
    }

    /// Whether the geometric selector contains `p` (`None` for id-based ones).
    pub fn contains(&self, p: Vec3) -> Option<bool> {
        match self {
            Selector::Sphere { center, radius } => {
                Some(p.distance(Vec3::from_array(*center)) <= *radius)
            }
            Selector::Box { min, max } => {
                Some(p.cmpge(Vec3::from_array(*min)).all() && p.cmple(Vec3::from_array(*max)).all())
            }
            Selector::HalfSpace { point, normal } => {
                Some((p - Vec3::from_array(*point)).dot(Vec3::from_array(*normal)) >= 0.0)
            }
            Selector::Vertices(_) | Selector::Fragment(_) => None,
        }
    }

    /// The selector in words, for messages.
    pub fn describe(&self) -> String {
        match self {
            Selector::Sphere { center, radius } => {
                format!(
                    "sphere centred at {} with radius {radius}",
                    point_text(center)
                )
            }
            Selector::Box { min, max } => {
                format!("box from {} to {}", point_text(min), point_text(max))
            }
            Selector::HalfSpace { point, normal } => format!(
                "half_space through {} with normal {}",
                point_text(point),
                point_text(normal)
            ),
            Selector::Vertices(ids) => format!("{} vertex ids", ids.len()),
            Selector::Fragment(name) => format!("fragment `{name}`"),
        }
    }
}

/// The bone vertex ids `sel` picks on the bone layer at `bone` (sorted,
/// unique), `fragments` resolving [`Selector::Fragment`] (the plan's
/// [`Fragments`](super::fragments::Fragments)); errors name `what`: ids
/// outside the layer, an unknown fragment, an empty selection.
pub(crate) fn select(
    sel: &Selector,
    bone: &[DVec3],
    fragments: &BTreeMap<String, Vec<u32>>,
    what: &str,
) -> Result<Vec<u32>> {
    let n = bone.len();
    let checked = |ids: &[u32]| -> Result<Vec<u32>> {
        if let Some(&bad) = ids.iter().find(|&&k| k as usize >= n) {
            return Err(Error::param(
                "vertex id",
                bad,
                format!(
                    "outside the bone layer ({n} bone vertices, ids 0..{})",
                    n - 1
                ),
            )
            .within(what));
        }
        let mut v = ids.to_vec();
        v.sort_unstable();
        v.dedup();
        Ok(v)
    };
    let ids: Vec<u32> = match sel {
        Selector::Vertices(ids) => checked(ids)?,
        Selector::Fragment(name) => checked(
            fragments
                .get(name)
                .ok_or_else(|| Error::unknown("fragment", name, fragments.keys()).within(what))?,
        )?,
        _ => (0..n as u32)
            .filter(|&k| sel.contains(bone[k as usize].as_vec3()) == Some(true))
            .collect(),
    };
    if ids.is_empty() {
        let (lo, hi) = bone.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        return Err(Refusal::EmptySelection {
            what: what.to_string(),
            detail: format!(
                "the {} selects no bone vertex (the bone layer spans {} to {})",
                sel.describe(),
                point_text(&lo.as_vec3().to_array()),
                point_text(&hi.as_vec3().to_array())
            ),
        }
        .into());
    }
    Ok(ids)
}
