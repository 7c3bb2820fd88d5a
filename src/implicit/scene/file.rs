//! The TOML shapes of a scene file (module docs of [`super`]) and their
//! reading into a [`Scene`], with errors at the file's line and column.

use glam::DVec3;
use serde::Deserialize;
use toml::Spanned;

use super::super::{Blend, Influence, Primitive, Skeleton};
use super::{Key, Scene, apply_key, check_influence, check_iso, check_skeleton, finite, positive};
use crate::io::config::line_column;
use crate::{Error, Position, Result};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneToml {
    iso: Spanned<f64>,
    #[serde(default)]
    blend: Option<Blend>,
    #[serde(default, rename = "primitive")]
    primitives: Vec<PrimitiveToml>,
    #[serde(default, rename = "key")]
    keys: Vec<KeyToml>,
    /// Read by `particles::Settings`.
    #[serde(default, rename = "particles")]
    _particles: Option<serde::de::IgnoredAny>,
    /// Read by `particles::Settings`.
    #[serde(default, rename = "network")]
    _network: Option<serde::de::IgnoredAny>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SkeletonToml {
    point: Option<[f64; 3]>,
    segment: Option<[[f64; 3]; 2]>,
    polyline: Option<Vec<[f64; 3]>>,
    closed: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "lowercase")]
enum InfluenceToml {
    Blobby {
        a: Option<f64>,
        b: Option<f64>,
    },
    Wyvill {
        radius: Option<f64>,
        strength: Option<f64>,
    },
    Metaball {
        radius: Option<f64>,
        strength: Option<f64>,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PrimitiveToml {
    skeleton: Spanned<SkeletonToml>,
    influence: Spanned<InfluenceToml>,
    weight: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyToml {
    time: Spanned<f64>,
    primitive: Spanned<i64>,
    skeleton: Option<Spanned<SkeletonToml>>,
    influence: Option<Spanned<InfluenceToml>>,
    weight: Option<Spanned<f64>>,
}

impl SkeletonToml {
    fn skeleton(&self) -> std::result::Result<Skeleton, (String, String)> {
        let given = [
            self.point.is_some(),
            self.segment.is_some(),
            self.polyline.is_some(),
        ];
        if given.iter().filter(|g| **g).count() != 1 {
            return Err((
                "exactly one of `point`, `segment`, `polyline` in `skeleton`".into(),
                format!("{} of them", given.iter().filter(|g| **g).count()),
            ));
        }
        if self.closed.is_some() && self.polyline.is_none() {
            return Err(("`closed` only with `polyline`".into(), "`closed`".into()));
        }
        let s = if let Some(p) = self.point {
            Skeleton::Point(DVec3::from_array(p))
        } else if let Some([a, b]) = self.segment {
            Skeleton::Segment(DVec3::from_array(a), DVec3::from_array(b))
        } else {
            Skeleton::Polyline {
                points: (self.polyline.iter().flatten())
                    .map(|p| DVec3::from_array(*p))
                    .collect(),
                closed: self.closed.unwrap_or(false),
            }
        };
        check_skeleton(&s)?;
        Ok(s)
    }
}

impl InfluenceToml {
    /// The influence, unset parameters taken from `prev` (a key) or
    /// required (`prev` = None, a primitive).
    fn influence(
        &self,
        prev: Option<&Influence>,
    ) -> std::result::Result<Influence, (String, String)> {
        let (kind, p) = match *self {
            InfluenceToml::Blobby { a, b } => ("blobby", [("a", a), ("b", b)]),
            InfluenceToml::Wyvill { radius, strength } => {
                ("wyvill", [("radius", radius), ("strength", strength)])
            }
            InfluenceToml::Metaball { radius, strength } => {
                ("metaball", [("radius", radius), ("strength", strength)])
            }
        };
        let like = match kind {
            "blobby" => Influence::Blobby { a: 0.0, b: 0.0 },
            "wyvill" => Influence::Wyvill {
                radius: 0.0,
                strength: 0.0,
            },
            _ => Influence::Metaball {
                radius: 0.0,
                strength: 0.0,
            },
        };
        let before = prev.filter(|i| i.kind() == kind).map(Influence::params);
        let mut out = [0.0; 2];
        for (k, (name, v)) in p.iter().enumerate() {
            out[k] = match (v, before) {
                (Some(v), _) => *v,
                (None, Some(b)) => b[k],
                (None, None) => {
                    return Err((format!("`influence.{kind}.{name}`"), "nothing".into()));
                }
            };
        }
        Ok(like.with_params(out))
    }
}

impl SceneToml {
    pub(super) fn build(self, text: &str, origin: &str) -> Result<Scene> {
        let at = |span: std::ops::Range<usize>| line_column(text, span.start);
        let fail = |span: std::ops::Range<usize>, ctx: &str, (e, f): (String, String)| {
            Error::format(origin, at(span), format!("{e} ({ctx})"), f)
        };
        let iso = *self.iso.get_ref();
        check_iso(iso).map_err(|e| fail(self.iso.span(), "iso", e))?;
        let blend = self.blend.unwrap_or(Blend::Sum);
        if self.primitives.is_empty() {
            return Err(Error::format(
                origin,
                Position::Whole,
                "at least one [[primitive]]",
                "an empty scene",
            ));
        }
        let mut primitives = Vec::with_capacity(self.primitives.len());
        for (i, p) in self.primitives.iter().enumerate() {
            let ctx = format!("primitive {i}");
            let skeleton =
                (p.skeleton.get_ref().skeleton()).map_err(|e| fail(p.skeleton.span(), &ctx, e))?;
            let influence = (p.influence.get_ref().influence(None))
                .map_err(|e| fail(p.influence.span(), &ctx, e))?;
            check_influence(&influence, blend).map_err(|e| fail(p.influence.span(), &ctx, e))?;
            let weight = match (&p.weight, blend) {
                (Some(w), Blend::Weighted) => {
                    finite("weight", *w.get_ref()).map_err(|e| fail(w.span(), &ctx, e))?;
                    *w.get_ref()
                }
                (Some(w), _) => {
                    return Err(fail(
                        w.span(),
                        &ctx,
                        (
                            "no `weight` unless blend = \"weighted\"".into(),
                            "`weight`".into(),
                        ),
                    ));
                }
                (None, Blend::Weighted) => {
                    return Err(fail(
                        p.skeleton.span(),
                        &ctx,
                        ("a `weight` with blend = \"weighted\"".into(), "none".into()),
                    ));
                }
                (None, _) => 1.0,
            };
            primitives.push(Primitive {
                skeleton,
                influence,
                weight,
            });
        }
        // Keys: resolved in time order per primitive so that unset
        // influence parameters carry over from the key before.
        let mut order: Vec<usize> = (0..self.keys.len()).collect();
        order
            .sort_by(|&a, &b| (self.keys[a].time.get_ref()).total_cmp(self.keys[b].time.get_ref()));
        let mut last: Vec<Primitive> = primitives.clone();
        let mut last_time = vec![0.0f64; primitives.len()];
        let mut keys = Vec::with_capacity(self.keys.len());
        for k in order {
            let key = &self.keys[k];
            let ctx = format!("key {k}");
            let time = *key.time.get_ref();
            positive("time", time).map_err(|e| fail(key.time.span(), &ctx, e))?;
            let index = *key.primitive.get_ref();
            let i = usize::try_from(index)
                .ok()
                .filter(|&i| i < primitives.len())
                .ok_or_else(|| {
                    fail(
                        key.primitive.span(),
                        &ctx,
                        (
                            format!(
                                "`primitive` naming one of the {} primitives (0-based)",
                                primitives.len()
                            ),
                            index.to_string(),
                        ),
                    )
                })?;
            if time == last_time[i] {
                return Err(fail(
                    key.time.span(),
                    &ctx,
                    (
                        format!("one key per time for primitive {i}"),
                        format!("a second key at time {time}"),
                    ),
                ));
            }
            let skeleton = match &key.skeleton {
                Some(s) => Some(
                    s.get_ref()
                        .skeleton()
                        .map_err(|e| fail(s.span(), &ctx, e))?,
                ),
                None => None,
            };
            let influence = match &key.influence {
                Some(inf) => Some(
                    (inf.get_ref().influence(Some(&last[i].influence)))
                        .map_err(|e| fail(inf.span(), &ctx, e))?,
                ),
                None => None,
            };
            let weight = match &key.weight {
                Some(w) if blend != Blend::Weighted => {
                    return Err(fail(
                        w.span(),
                        &ctx,
                        (
                            "no `weight` unless blend = \"weighted\"".into(),
                            "`weight`".into(),
                        ),
                    ));
                }
                Some(w) => Some(*w.get_ref()),
                None => None,
            };
            let key_value = Key {
                time,
                primitive: i,
                skeleton,
                influence,
                weight,
            };
            let span = (key.skeleton.as_ref().map(Spanned::span))
                .or(key.influence.as_ref().map(Spanned::span))
                .unwrap_or(key.time.span());
            last[i] = apply_key(&last[i], &key_value, blend).map_err(|e| fail(span, &ctx, e))?;
            last_time[i] = time;
            keys.push(key_value);
        }
        Scene::new(iso, blend, primitives, &keys)
    }
}
