//! Scene files: the iso value, the blend, the primitives and keyframes.
//!
//! ```toml
//! iso = 0.5
//! blend = "sum"                      # "sum" (default), "max" or "weighted"
//! [[primitive]]
//! skeleton = { point = [-1.0, 0.0, 0.0] }     # or segment = [[…], […]],
//!                                             # polyline = [[…], …], closed = true
//! influence = { blobby = { a = 1.0, b = 1.0 } }   # wyvill / metaball = { radius, strength }
//! # weight = 2.0                     # with blend = "weighted" (required there)
//! [[key]]
//! time = 1.0                         # > 0; the primitive itself is the pose at t = 0
//! primitive = 0                      # 0-based index
//! skeleton = { point = [-1.4, 0.0, 0.0] }     # same kind and point count
//! # influence = { blobby = { b = 0.8 } }      # same kind; unnamed parameters carry over
//! # weight = 1.5
//! ```
//!
//! Each primitive moves along its own track: its pose at t = 0, then its keys
//! in time order; a key names only what changes, the rest carries over from
//! the key before. Between keys everything is interpolated linearly, after
//! the last key it stays; the rates q̇ are the slopes of the interval being
//! entered (zero after the last key). The `[particles]` and `[network]`
//! tables configure the samplers of the `particles` room and are read there.
//!
//! Errors name the file, line and column, and the key: unknown keys, an empty
//! scene, non-finite or out-of-range numbers, a key naming a missing
//! primitive or changing its kind.

use std::path::Path;

use glam::DVec3;

mod file;

use file::SceneToml;

use super::{Blend, Influence, Primitive, Skeleton};
use crate::io::config::{line_column, toml_message};
use crate::{Error, Position, Result};

/// The example scenes in `src/implicit/scenes/`: (name, TOML text).
pub const EXAMPLES: &[(&str, &str)] = &[
    ("dumbbell", include_str!("../scenes/dumbbell.toml")),
    (
        "dumbbell_merge",
        include_str!("../scenes/dumbbell_merge.toml"),
    ),
    ("torus", include_str!("../scenes/torus.toml")),
    ("finger", include_str!("../scenes/finger.toml")),
    ("molecule", include_str!("../scenes/molecule.toml")),
];

/// A keyframe of one primitive: what it is at `time` (unset parts carry over).
#[derive(Debug, Clone, PartialEq)]
pub struct Key {
    pub time: f64,
    pub primitive: usize,
    pub skeleton: Option<Skeleton>,
    pub influence: Option<Influence>,
    pub weight: Option<f64>,
}

/// A validated scene: primitives at t = 0 and, per primitive, its keys in
/// time order (each complete, carried over from the one before).
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    pub iso: f64,
    pub blend: Blend,
    pub primitives: Vec<Primitive>,
    /// Per primitive, `(time, pose)` in increasing time, all times > 0.
    tracks: Vec<Vec<(f64, Primitive)>>,
}

/// Rates of one posed primitive: d/dt of its skeleton points, influence
/// parameters (kernel order, [`Influence::params`]) and weight.
#[derive(Debug, Clone, PartialEq)]
pub struct Rate {
    pub points: Vec<DVec3>,
    pub params: [f64; 2],
    pub weight: f64,
}

/// The scene at one time: every primitive and its rates.
#[derive(Debug, Clone, PartialEq)]
pub struct Pose {
    pub time: f64,
    pub iso: f64,
    pub blend: Blend,
    pub primitives: Vec<Primitive>,
    pub rates: Vec<Rate>,
}

impl Scene {
    /// A scene from primitives and keys, validated as a scene file is
    /// (`origin` names it in errors; positions are [`Position::Item`]).
    pub fn new(iso: f64, blend: Blend, primitives: Vec<Primitive>, keys: &[Key]) -> Result<Scene> {
        let origin = "scene";
        let item = |kind, index: usize| Position::Item {
            kind,
            index: index as u64,
        };
        check_iso(iso)
            .map_err(|(e, f)| Error::format(origin, Position::Field("iso".into()), e, f))?;
        if primitives.is_empty() {
            return Err(Error::empty(format!("{origin}: primitives")));
        }
        for (i, p) in primitives.iter().enumerate() {
            check_primitive(p, blend)
                .map_err(|(e, f)| Error::format(origin, item("primitive", i), e, f))?;
        }
        let mut tracks: Vec<Vec<(f64, Primitive)>> = vec![Vec::new(); primitives.len()];
        let mut order: Vec<usize> = (0..keys.len()).collect();
        order.sort_by(|&a, &b| keys[a].time.total_cmp(&keys[b].time));
        for k in order {
            let key = &keys[k];
            let at = item("key", k);
            let prev = match tracks.get(key.primitive) {
                Some(t) => t.last().map_or(&primitives[key.primitive], |(_, p)| p),
                None => {
                    return Err(Error::format(
                        origin,
                        at,
                        format!("a primitive index below {}", primitives.len()),
                        key.primitive.to_string(),
                    ));
                }
            };
            let pose = apply_key(prev, key, blend)
                .map_err(|(e, f)| Error::format(origin, at.clone(), e, f))?;
            tracks[key.primitive].push((key.time, pose));
        }
        Ok(Scene {
            iso,
            blend,
            primitives,
            tracks,
        })
    }

    /// Reads a scene file.
    pub fn from_path(path: &Path) -> Result<Scene> {
        let text = crate::io::config::read_text(path)?;
        Scene::from_toml_str(&text, &path.display().to_string())
    }

    /// Parses and validates a TOML scene; `origin` names the source in errors.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Scene> {
        let file: SceneToml = toml::from_str(text).map_err(|e| {
            let at = e
                .span()
                .map_or(Position::Whole, |s| line_column(text, s.start));
            Error::format(origin, at, "a scene", toml_message(text, &e))
        })?;
        file.build(text, origin)
    }

    /// The last key's time (0 for a still scene).
    pub fn duration(&self) -> f64 {
        (self.tracks.iter())
            .filter_map(|t| t.last().map(|(time, _)| *time))
            .fold(0.0, f64::max)
    }

    /// The scene at time `t` (clamped to ≥ 0), with the slopes of the key
    /// intervals being entered as rates.
    pub fn pose(&self, t: f64) -> Pose {
        let t = t.max(0.0);
        let (primitives, rates) = (self.primitives.iter().zip(&self.tracks))
            .map(|(p0, track)| pose_track(p0, track, t))
            .unzip();
        Pose {
            time: t,
            iso: self.iso,
            blend: self.blend,
            primitives,
            rates,
        }
    }
}

/// Flat animatable state: points, then the two parameters, then the weight.
fn state(p: &Primitive) -> Vec<f64> {
    let mut s: Vec<f64> = p
        .skeleton
        .points()
        .iter()
        .flat_map(|q| q.to_array())
        .collect();
    s.extend(p.influence.params());
    s.push(p.weight);
    s
}

fn from_state(like: &Primitive, s: &[f64]) -> Primitive {
    let n = s.len() - 3;
    let points: Vec<DVec3> = s[..n].chunks(3).map(DVec3::from_slice).collect();
    Primitive {
        skeleton: like.skeleton.with_points(&points),
        influence: like.influence.with_params([s[n], s[n + 1]]),
        weight: s[n + 2],
    }
}

fn rate_from_state(d: &[f64]) -> Rate {
    let n = d.len() - 3;
    Rate {
        points: d[..n].chunks(3).map(DVec3::from_slice).collect(),
        params: [d[n], d[n + 1]],
        weight: d[n + 2],
    }
}

/// One primitive at `t` on its track (pose at 0, then the keys).
fn pose_track(p0: &Primitive, track: &[(f64, Primitive)], t: f64) -> (Primitive, Rate) {
    let mut prev = (0.0, p0);
    for (time, p) in track {
        if t < *time {
            let (a, b) = (state(prev.1), state(p));
            let span = time - prev.0;
            let u = (t - prev.0) / span;
            let s: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + u * (y - x)).collect();
            let d: Vec<f64> = a.iter().zip(&b).map(|(x, y)| (y - x) / span).collect();
            return (from_state(p0, &s), rate_from_state(&d));
        }
        prev = (*time, p);
    }
    let still = vec![0.0; state(prev.1).len()];
    (prev.1.clone(), rate_from_state(&still))
}

/// (expected, found) of a failed check.
type Check = std::result::Result<(), (String, String)>;

fn finite(what: &str, v: f64) -> Check {
    if v.is_finite() {
        Ok(())
    } else {
        Err((format!("a finite number for `{what}`"), v.to_string()))
    }
}

fn positive(what: &str, v: f64) -> Check {
    finite(what, v)?;
    if v > 0.0 {
        Ok(())
    } else {
        Err((format!("a positive number for `{what}`"), v.to_string()))
    }
}

fn check_iso(iso: f64) -> Check {
    positive("iso", iso)
}

fn check_skeleton(s: &Skeleton) -> Check {
    for p in s.points() {
        if !p.is_finite() {
            return Err((
                format!("finite coordinates for `skeleton.{}`", s.kind()),
                format!("{:?}", p.to_array()),
            ));
        }
    }
    if let Skeleton::Polyline { points, closed } = s {
        let need = if *closed { 3 } else { 2 };
        if points.len() < need {
            return Err((
                format!(
                    "at least {need} points for `skeleton.polyline`{}",
                    if *closed { " with closed = true" } else { "" }
                ),
                format!("{} points", points.len()),
            ));
        }
    }
    Ok(())
}

fn check_influence(i: &Influence, blend: Blend) -> Check {
    let name = i.kind();
    match *i {
        Influence::Blobby { a, b } => {
            positive(&format!("influence.{name}.a"), a)?;
            finite(&format!("influence.{name}.b"), b)?;
        }
        Influence::Wyvill { radius, strength } | Influence::Metaball { radius, strength } => {
            positive(&format!("influence.{name}.radius"), radius)?;
            finite(&format!("influence.{name}.strength"), strength)?;
        }
    }
    if blend == Blend::Max && i.strength() <= 0.0 {
        return Err((
            format!(
                "a positive strength with blend = \"max\" (a primitive that is never positive never wins), `influence.{name}`"
            ),
            i.strength().to_string(),
        ));
    }
    Ok(())
}

fn check_primitive(p: &Primitive, blend: Blend) -> Check {
    check_skeleton(&p.skeleton)?;
    check_influence(&p.influence, blend)?;
    finite("weight", p.weight)?;
    if blend != Blend::Weighted && p.weight != 1.0 {
        return Err((
            "weight 1 unless blend = \"weighted\"".into(),
            p.weight.to_string(),
        ));
    }
    Ok(())
}

/// The primitive after `key`, carried over from `prev`.
fn apply_key(
    prev: &Primitive,
    key: &Key,
    blend: Blend,
) -> std::result::Result<Primitive, (String, String)> {
    positive("time", key.time)?;
    let skeleton = match &key.skeleton {
        None => prev.skeleton.clone(),
        Some(s) => {
            let same = match (s, &prev.skeleton) {
                (
                    Skeleton::Polyline { points, closed },
                    Skeleton::Polyline {
                        points: p0,
                        closed: c0,
                    },
                ) => points.len() == p0.len() && closed == c0,
                _ => s.kind() == prev.skeleton.kind(),
            };
            if !same {
                let shape = |s: &Skeleton| {
                    let n = s.points().len();
                    format!("{} of {n} point{}", s.kind(), if n == 1 { "" } else { "s" })
                };
                return Err((
                    format!(
                        "a skeleton of the primitive's kind ({})",
                        shape(&prev.skeleton)
                    ),
                    shape(s),
                ));
            }
            s.clone()
        }
    };
    let influence = match key.influence {
        None => prev.influence,
        Some(i) if i.kind() == prev.influence.kind() => i,
        Some(i) => {
            return Err((
                format!(
                    "an influence of the primitive's kind ({})",
                    prev.influence.kind()
                ),
                i.kind().to_string(),
            ));
        }
    };
    let p = Primitive {
        skeleton,
        influence,
        weight: key.weight.unwrap_or(prev.weight),
    };
    check_primitive(&p, blend)?;
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    const DUMBBELL: &str = r#"
iso = 0.5
blend = "sum"
[[primitive]]
skeleton = { point = [-1.0, 0.0, 0.0] }
influence = { blobby = { a = 1.0, b = 1.0 } }
[[primitive]]
skeleton = { point = [1.0, 0.0, 0.0] }
influence = { blobby = { a = 1.0, b = 1.0 } }
[[key]]
time = 1.0
primitive = 0
skeleton = { point = [-1.4, 0.0, 0.0] }
[[key]]
time = 1.0
primitive = 1
skeleton = { point = [1.4, 0.0, 0.0] }
"#;

    #[test]
    fn the_issue_dumbbell_reads_and_interpolates() {
        let s = Scene::from_toml_str(DUMBBELL, "d.toml").unwrap();
        assert_eq!(s.duration(), 1.0);
        let p = s.pose(0.25);
        assert_eq!(
            p.primitives[0].skeleton,
            Skeleton::Point(DVec3::new(-1.1, 0.0, 0.0))
        );
        assert!((p.rates[1].points[0] - DVec3::new(0.4, 0.0, 0.0)).length() < 1e-15);
        let end = s.pose(2.0);
        assert_eq!(
            end.primitives[1].skeleton,
            Skeleton::Point(DVec3::new(1.4, 0.0, 0.0))
        );
        assert_eq!(end.rates[1].points[0], DVec3::ZERO);
    }

    #[test]
    fn partial_influence_keys_carry_over() {
        let text = r#"
iso = 0.5
[[primitive]]
skeleton = { segment = [[0, 0, 0], [1, 0, 0]] }
influence = { wyvill = { radius = 1.0, strength = 2.0 } }
[[key]]
time = 2.0
primitive = 0
influence = { wyvill = { strength = 4.0 } }
"#;
        let s = Scene::from_toml_str(text, "w.toml").unwrap();
        let p = s.pose(1.0);
        assert_eq!(
            p.primitives[0].influence,
            Influence::Wyvill {
                radius: 1.0,
                strength: 3.0
            }
        );
        assert_eq!(p.rates[0].params, [0.0, 1.0]);
    }

    fn error(text: &str) -> String {
        Scene::from_toml_str(text, "bad.toml")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn bad_scenes_name_file_line_and_key() {
        let e = error("iso = 0.5\nfoo = 1\n");
        assert!(
            e.contains("bad.toml") && e.contains("line 2") && e.contains("foo"),
            "{e}"
        );
        let e = error("iso = 0.5\n");
        assert!(e.contains("empty scene"), "{e}");
        let e = error(&DUMBBELL.replace(
            "a = 1.0, b = 1.0 } }\n[[primitive]]",
            "a = inf, b = 1.0 } }\n[[primitive]]",
        ));
        assert!(
            e.contains("line 6") && e.contains("influence.blobby.a") && e.contains("inf"),
            "{e}"
        );
        let e = error(&DUMBBELL.replace("primitive = 1", "primitive = 2"));
        assert!(
            e.contains("line 16") && e.contains("`primitive`") && e.contains("found 2"),
            "{e}"
        );
        let e = error(
            &DUMBBELL
                .replace("[-1.4, 0.0, 0.0]", "[[-1.4, 0.0, 0.0], [0, 0, 0]]")
                .replace("point = [[", "segment = [["),
        );
        assert!(
            e.contains("line 13") && e.contains("point of 1 point)"),
            "{e}"
        );
        let e = error(&DUMBBELL.replace(
            "blobby = { a = 1.0, b = 1.0 }",
            "blobby = { a = 1.0, c = 1.0 }",
        ));
        assert!(e.contains("line 6") && e.contains('c'), "{e}");
        let e = error(&DUMBBELL.replace("iso = 0.5", "iso = nan"));
        assert!(e.contains("line 2") && e.contains("iso"), "{e}");
        let e = error(
            &DUMBBELL
                .replace("\"sum\"", "\"max\"")
                .replace("b = 1.0 } }\n[[key]]", "b = -1.0 } }\n[[key]]"),
        );
        assert!(e.contains("positive strength"), "{e}");
    }
}
