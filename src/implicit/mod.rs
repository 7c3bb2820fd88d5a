//! Skeletal implicit surfaces (SPEC §3.1, seed 002 §3.1).
//!
//! A scene is a sum (or max, or weighted sum) of primitives
//! fⁱ(x) = eᵢ(dᵢ(x)²): an influence function e of the squared distance to a
//! skeleton element (point, segment, open or closed polyline). The surface
//! is A(F, I) = {x | F(x) = I}; **inside is F > I**, so the outward normal
//! is −∇F/|∇F|. Skeletons and influence parameters move by keyframes; the
//! field's time derivative F_t = F_q·q̇ at a fixed point is analytic.
//!
//! ```text
//!  SCENE.toml ──scene──▶ Scene (primitives + keyframe tracks)
//!                          │ pose(t): linear keys, slopes q̇
//!                          ▼
//!                        Pose ──field::FieldInput (rows + cull grid)──▶ implicit_field
//!                                   │ CPU: field::cpu (mirror)            (F − I, ∇F, F_t)
//!                                   │ GPU: field::gpu
//!                                   ▼
//!                        grid: samples on a lattice → the engine's marching cubes
//! ```
//!
//! Design notes, formulas and their checks: `docs/design/particles.md` §1.

pub mod field;
pub mod grid;
pub mod scene;

use glam::DVec3;

pub use scene::{Key, Pose, Rate, Scene};

/// A skeleton element: the set the distance d(x) is measured to.
#[derive(Debug, Clone, PartialEq)]
pub enum Skeleton {
    /// One point.
    Point(DVec3),
    /// A segment between two points (a point when they coincide).
    Segment(DVec3, DVec3),
    /// Segments between consecutive points (≥ 2), and from the last back to
    /// the first when `closed` (≥ 3 points). The distance is the minimum
    /// over the segments, ties to the lowest segment.
    Polyline { points: Vec<DVec3>, closed: bool },
}

impl Skeleton {
    /// The skeleton's points, in order.
    pub fn points(&self) -> Vec<DVec3> {
        match self {
            Skeleton::Point(p) => vec![*p],
            Skeleton::Segment(a, b) => vec![*a, *b],
            Skeleton::Polyline { points, .. } => points.clone(),
        }
    }

    /// The same kind of skeleton through `points` (as many as [`Skeleton::points`]).
    pub(crate) fn with_points(&self, points: &[DVec3]) -> Skeleton {
        match self {
            Skeleton::Point(_) => Skeleton::Point(points[0]),
            Skeleton::Segment(..) => Skeleton::Segment(points[0], points[1]),
            Skeleton::Polyline { closed, .. } => Skeleton::Polyline {
                points: points.to_vec(),
                closed: *closed,
            },
        }
    }

    /// Index pairs of the segments (a point is one degenerate segment).
    pub fn pieces(&self) -> Vec<[usize; 2]> {
        match self {
            Skeleton::Point(_) => vec![[0, 0]],
            Skeleton::Segment(..) => vec![[0, 1]],
            Skeleton::Polyline { points, closed } => {
                let n = points.len();
                let m = if *closed { n } else { n - 1 };
                (0..m).map(|i| [i, (i + 1) % n]).collect()
            }
        }
    }

    /// The kind's name in scene files.
    pub fn kind(&self) -> &'static str {
        match self {
            Skeleton::Point(_) => "point",
            Skeleton::Segment(..) => "segment",
            Skeleton::Polyline { .. } => "polyline",
        }
    }
}

/// An influence function e(s) of the squared distance s = d².
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Influence {
    /// Blinn's blobby model b·exp(−a s), a > 0; b < 0 carves.
    Blobby { a: f64, b: f64 },
    /// Wyvill soft objects: strength·(1 − 22/9 t + 17/9 t² − 4/9 t³),
    /// t = s/radius², zero from d = radius on (C¹ there).
    Wyvill { radius: f64, strength: f64 },
    /// Nishimura metaballs: strength·(1 − 3t) for d ≤ radius/3,
    /// (3/2)·strength·(1 − d/radius)² up to the radius, zero beyond.
    Metaball { radius: f64, strength: f64 },
}

impl Influence {
    /// Kernel code of the kind (`kind` column of the field rows).
    pub fn code(&self) -> u32 {
        match self {
            Influence::Blobby { .. } => 0,
            Influence::Wyvill { .. } => 1,
            Influence::Metaball { .. } => 2,
        }
    }

    /// The two parameters in kernel order: (a, b), (radius, strength),
    /// (radius, strength).
    pub fn params(&self) -> [f64; 2] {
        match *self {
            Influence::Blobby { a, b } => [a, b],
            Influence::Wyvill { radius, strength } | Influence::Metaball { radius, strength } => {
                [radius, strength]
            }
        }
    }

    /// The same kind with `params` in kernel order.
    pub(crate) fn with_params(&self, p: [f64; 2]) -> Influence {
        match self {
            Influence::Blobby { .. } => Influence::Blobby { a: p[0], b: p[1] },
            Influence::Wyvill { .. } => Influence::Wyvill {
                radius: p[0],
                strength: p[1],
            },
            Influence::Metaball { .. } => Influence::Metaball {
                radius: p[0],
                strength: p[1],
            },
        }
    }

    /// The strength (b for blobby): the value at the skeleton.
    pub fn strength(&self) -> f64 {
        self.params()[1]
    }

    /// The kind's name in scene files.
    pub fn kind(&self) -> &'static str {
        match self {
            Influence::Blobby { .. } => "blobby",
            Influence::Wyvill { .. } => "wyvill",
            Influence::Metaball { .. } => "metaball",
        }
    }
}

/// How the primitives' values combine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Blend {
    /// F = Σ fⁱ (the default).
    Sum,
    /// F = max fⁱ; ∇F and F_t from the winner (ties to the lowest index).
    /// Strengths must be positive (a negative primitive never wins).
    Max,
    /// F = Σ wᵢ fⁱ with a `weight` per primitive.
    Weighted,
}

/// One primitive: a skeleton, its influence and its weight (1 unless the
/// blend is [`Blend::Weighted`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Primitive {
    pub skeleton: Skeleton,
    pub influence: Influence,
    pub weight: f64,
}
