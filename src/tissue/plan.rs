//! Surgery plans (SPEC §1.3; seed 000 §5.2.1 and App. B).
//!
//! A plan is a list of steps. Each step selects bone vertices, gives a total
//! rigid motion (translation, optionally a rotation about a point), a
//! repetition count k (the motion is applied in k equal increments) and, per
//! increment, a fixed iteration count or `converge`. TOML:
//!
//! ```toml
//! name = "chin advance"
//!
//! [[step]]
//! name = "chin"
//! select = { half_space = { point = [0.0, -0.165, 0.0], normal = [0.0, -1.0, 0.0] } }
//! translate = [0.0034, 0.0, -0.0022]   # total, mesh units
//! increments = 10                      # k
//! iterations = "converge"              # or a number per increment
//! ```
//!
//! Selectors: `sphere = { center, radius }`, `box = { min, max }`,
//! `half_space = { point, normal }` (keeps `(x − point)·normal ≥ 0`),
//! `vertices = [ids]` (bone-layer vertex ids) and `fragment = "name"`
//! (bone vertex ids of a fragment freed by a `[[cut]]` of the plan, see
//! [`super::fragments`], or supplied by the caller).
//! Unknown keys are errors. Selections are made on the bone layer as it
//! stands when the step starts (after the earlier steps' moves).

use std::path::Path;

use glam::{DQuat, DVec3, Vec3};
use serde::{Deserialize, Serialize};

use super::fragments::{BoneCut, Fragments};
use super::network::SpringNetwork;
use super::selector::{Selector, finite3, point_text, select};
use crate::io::config::{line_column, toml_message};
use crate::{Error, Position, Result};

/// A rigid rotation about a point, applied before the translation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotation {
    /// Rotation axis (any non-zero length).
    pub axis: [f32; 3],
    /// Total angle in degrees (right-hand rule about `axis`).
    pub degrees: f32,
    /// The fixed point of the rotation.
    pub center: [f32; 3],
}

/// Iterations per increment: a fixed count, or until a stop criterion.
/// Written as a number or the word `"converge"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Iterations {
    /// Exactly this many iterations (the seed's Table 2 uses 1).
    Fixed(u32),
    /// Until converged / stalled / diverged / the iteration limit.
    Converge,
}

impl Serialize for Iterations {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            Iterations::Fixed(n) => s.serialize_u32(*n),
            Iterations::Converge => s.serialize_str("converge"),
        }
    }
}

impl<'de> Deserialize<'de> for Iterations {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Unexpected;
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = Iterations;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a count of iterations or \"converge\"")
            }
            fn visit_u64<E: serde::de::Error>(self, n: u64) -> std::result::Result<Iterations, E> {
                u32::try_from(n)
                    .map(Iterations::Fixed)
                    .map_err(|_| E::invalid_value(Unexpected::Unsigned(n), &self))
            }
            fn visit_i64<E: serde::de::Error>(self, n: i64) -> std::result::Result<Iterations, E> {
                u64::try_from(n)
                    .map_err(|_| E::invalid_value(Unexpected::Signed(n), &self))
                    .and_then(|n| self.visit_u64(n))
            }
            fn visit_str<E: serde::de::Error>(self, w: &str) -> std::result::Result<Iterations, E> {
                if w == "converge" {
                    Ok(Iterations::Converge)
                } else {
                    Err(E::invalid_value(Unexpected::Str(w), &self))
                }
            }
        }
        d.deserialize_any(Visitor)
    }
}

fn one() -> u32 {
    1
}

fn converge() -> Iterations {
    Iterations::Converge
}

/// One processing step of the seed's algorithm (§5.2.1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Step {
    /// Label for reports (default `step <n>`).
    #[serde(default)]
    pub name: Option<String>,
    /// Which bone vertices move.
    pub select: Selector,
    /// Total translation, mesh units (default 0).
    #[serde(default)]
    pub translate: [f32; 3],
    /// Optional total rotation, applied before the translation.
    #[serde(default)]
    pub rotate: Option<Rotation>,
    /// k: the motion is applied in this many equal increments (≥ 1).
    #[serde(default = "one")]
    pub increments: u32,
    /// Per increment: a count (≥ 1) or `"converge"` (default).
    #[serde(default = "converge")]
    pub iterations: Iterations,
    /// Zero all velocities before each increment of this step (default:
    /// velocities carry over between increments and steps).
    #[serde(default)]
    pub reset_velocities: bool,
}

/// The relaxation's dynamics as a plan may set them (`[dynamics]` in TOML,
/// `"dynamics"` in JSON); every field is optional, the command line
/// overrides the plan, and what is left takes the defaults of
/// [`NetworkParams`](super::NetworkParams) and
/// [`RelaxOptions`](super::RelaxOptions). The report prints the values used.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dynamics {
    /// Node mass m (default 1).
    pub mass: Option<f32>,
    /// Damping γ (default 0.5).
    pub damping: Option<f32>,
    /// Time step Δt (default 0.9 × the stability limit).
    pub dt: Option<f32>,
    /// ε: converged when max |v| < ε (default 1e-5 × the bounding-box diagonal).
    pub epsilon: Option<f32>,
    /// δ: stalled when the nodes moved less than δ over the window
    /// (default 10 · ε · Δt).
    pub delta: Option<f32>,
    /// Stall window in iterations (default 100).
    pub window: Option<u32>,
    /// Iterations between convergence checks (default 25).
    pub check_every: Option<u32>,
    /// Iteration cap of a `converge` increment (default 100 000).
    pub max_iterations: Option<u32>,
}

impl Dynamics {
    /// `self` with every field that `over` sets replaced by `over`'s.
    pub fn overridden_by(&self, over: &Dynamics) -> Dynamics {
        Dynamics {
            mass: over.mass.or(self.mass),
            damping: over.damping.or(self.damping),
            dt: over.dt.or(self.dt),
            epsilon: over.epsilon.or(self.epsilon),
            delta: over.delta.or(self.delta),
            window: over.window.or(self.window),
            check_every: over.check_every.or(self.check_every),
            max_iterations: over.max_iterations.or(self.max_iterations),
        }
    }

    /// Sets the network's mass and damping that this names.
    pub fn apply_to_network(&self, params: &mut super::NetworkParams) {
        if let Some(m) = self.mass {
            params.mass = m;
        }
        if let Some(d) = self.damping {
            params.damping = d;
        }
    }

    /// Sets the relaxation's Δt, ε, δ, window, check interval and cap that
    /// this names.
    pub fn apply_to_options(&self, opts: &mut super::RelaxOptions) {
        opts.dt = self.dt.or(opts.dt);
        opts.epsilon = self.epsilon.or(opts.epsilon);
        opts.delta = self.delta.or(opts.delta);
        opts.window = self.window.unwrap_or(opts.window);
        opts.check_every = self.check_every.unwrap_or(opts.check_every);
        opts.max_iterations = self.max_iterations.unwrap_or(opts.max_iterations);
    }
}

/// A surgery plan: steps applied in order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    /// Label for reports.
    #[serde(default)]
    pub name: Option<String>,
    /// The relaxation's dynamics (mass, damping, Δt, ε, δ, window, check
    /// interval, iteration cap); unset fields take the defaults.
    #[serde(default)]
    pub dynamics: Dynamics,
    /// Scalpel cuts of the bone mesh that free named fragments, run
    /// before the network is built (`[[cut]]` in TOML, `"cuts"` or `"cut"`
    /// in JSON; see [`super::fragments`]).
    #[serde(default, rename = "cut", alias = "cuts")]
    pub cuts: Vec<BoneCut>,
    /// The steps (`[[step]]` in TOML, `"steps"` or `"step"` in JSON).
    #[serde(rename = "step", alias = "steps")]
    pub steps: Vec<Step>,
    /// Where the plan was read from (file name), for error messages.
    #[serde(skip)]
    pub source: Option<String>,
}

/// Most increments one step may have: each runs at least one iteration
/// and keeps a report line.
pub const MAX_INCREMENTS: u32 = 100_000;

impl Plan {
    /// Parses and validates a TOML plan; `origin` names the source in errors.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Plan> {
        let plan: Plan = toml::from_str(text).map_err(|e| {
            let at = e
                .span()
                .map_or(Position::Whole, |s| line_column(text, s.start));
            Error::format(origin, at, "a surgery plan", toml_message(text, &e))
        })?;
        Plan {
            source: Some(origin.to_string()),
            ..plan
        }
        .validated()
    }

    /// Parses and validates a JSON plan; `origin` names the source in errors.
    pub fn from_json_str(text: &str, origin: &str) -> Result<Plan> {
        let plan: Plan = serde_json::from_str(text).map_err(|e| {
            let message = e.to_string();
            // serde_json appends " at line L column C"; the position says it.
            let message = match message.rfind(" at line ") {
                Some(i) => message[..i].to_string(),
                None => message,
            };
            // serde_json counts columns in bytes (0 at the end of input
            // after a newline); the position is recounted in characters.
            let line_start: usize = text
                .split_inclusive('\n')
                .take(e.line().saturating_sub(1))
                .map(str::len)
                .sum();
            Error::format(
                origin,
                line_column(text, line_start + e.column().saturating_sub(1)),
                "a surgery plan",
                message,
            )
        })?;
        Plan {
            source: Some(origin.to_string()),
            ..plan
        }
        .validated()
    }

    /// Reads a plan file: `.json` is JSON, anything else TOML.
    pub fn from_path(path: &Path) -> Result<Plan> {
        let text = crate::io::config::read_text(path)?;
        let origin = path.display().to_string();
        if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"))
        {
            Plan::from_json_str(&text, &origin)
        } else {
            Plan::from_toml_str(&text, &origin)
        }
    }

    fn validated(self) -> Result<Plan> {
        self.validate()?;
        Ok(self)
    }

    /// `plan step i `name`` for messages, after the plan's source if known.
    fn step_label(&self, i: usize) -> String {
        let step = format!("plan step {} `{}`", i + 1, self.step_name(i));
        match &self.source {
            Some(src) => format!("{src}: {step}"),
            None => step,
        }
    }

    /// The display name of step `i` (0-based).
    pub fn step_name(&self, i: usize) -> String {
        self.steps[i]
            .name
            .clone()
            .unwrap_or_else(|| format!("step {}", i + 1))
    }

    /// Checks everything that does not need the network: at least one step,
    /// k ≥ 1, fixed counts ≥ 1, finite vectors, valid selectors and axes.
    pub fn validate(&self) -> Result<()> {
        if self.steps.is_empty() {
            let e = Error::empty("plan steps");
            return Err(match self.source.as_deref() {
                Some(src) => e.within(src),
                None => e,
            });
        }
        super::fragments::validate_cuts(&self.cuts, self.source.as_deref())?;
        for (i, s) in self.steps.iter().enumerate() {
            let what = self.step_label(i);
            let bad = |name: &str, value: String, rule: String| {
                Err(Error::param(name, value, rule).within(&what))
            };
            s.select.validate(&what)?;
            if !(1..=MAX_INCREMENTS).contains(&s.increments) {
                return bad(
                    "increments",
                    s.increments.to_string(),
                    format!("k must be between 1 and {MAX_INCREMENTS}"),
                );
            }
            if s.iterations == Iterations::Fixed(0) {
                return bad(
                    "iterations",
                    "0".into(),
                    "must be ≥ 1 or \"converge\"".into(),
                );
            }
            if !finite3(&s.translate) {
                return bad(
                    "translate",
                    point_text(&s.translate),
                    "must be finite".into(),
                );
            }
            if let Some(r) = &s.rotate
                && (!finite3(&r.axis)
                    || !finite3(&r.center)
                    || !r.degrees.is_finite()
                    || Vec3::from_array(r.axis).length() == 0.0)
            {
                return bad(
                    "rotate",
                    format!(
                        "axis {}, degrees {}, center {}",
                        point_text(&r.axis),
                        r.degrees,
                        point_text(&r.center)
                    ),
                    "needs a finite non-zero axis, finite centre and angle".into(),
                );
            }
        }
        Ok(())
    }

    /// Checks that every `fragment = "name"` selector names one of the
    /// plan's `[[cut]]`s or a fragment in `supplied`, so that a typo fails
    /// before any work is done rather than in [`Plan::resolve`] after the
    /// cuts.
    pub fn check_fragments(&self, supplied: &Fragments) -> Result<()> {
        for (i, s) in self.steps.iter().enumerate() {
            if let Selector::Fragment(name) = &s.select
                && !supplied.contains_key(name)
                && !self.cuts.iter().any(|c| &c.name == name)
            {
                let known: Vec<&str> = self
                    .cuts
                    .iter()
                    .map(|c| c.name.as_str())
                    .chain(supplied.keys().map(String::as_str))
                    .collect();
                return Err(Error::unknown("fragment", name, known).within(self.step_label(i)));
            }
        }
        Ok(())
    }

    /// Resolves every step's selection on the bone layer of `network`
    /// (in step order, each on the bone as moved by the steps before it).
    /// Errors name the step: empty selection, vertex ids outside the bone
    /// layer, unknown fragments.
    pub fn resolve(&self, network: &SpringNetwork, fragments: &Fragments) -> Result<ResolvedPlan> {
        self.validate()?;
        let n_bone = network.n_bone();
        if n_bone == 0 {
            return Err(Error::empty("bone nodes of the network"));
        }
        let mut bone: Vec<DVec3> = network
            .bone_rest()
            .iter()
            .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
            .collect();
        let mut steps = Vec::with_capacity(self.steps.len());
        for (i, s) in self.steps.iter().enumerate() {
            let name = self.step_name(i);
            let what = self.step_label(i);
            let ids = select(&s.select, &bone, fragments, &what)?;
            let start: Vec<DVec3> = ids.iter().map(|&k| bone[k as usize]).collect();
            let motion = Motion::new(s);
            for (&k, &p) in ids.iter().zip(&start) {
                bone[k as usize] = motion.apply(p, 1.0);
            }
            steps.push(ResolvedStep {
                name,
                bone_vertices: ids,
                start,
                motion,
                increments: s.increments,
                iterations: s.iterations,
                reset_velocities: s.reset_velocities,
            });
        }
        Ok(ResolvedPlan {
            name: self.name.clone(),
            steps,
        })
    }
}

/// A rigid motion `x ↦ R(t·θ)(x − c) + c + t·translate` for progress `t ∈ [0, 1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    translate: DVec3,
    rotation: Option<(DVec3, f64, DVec3)>,
}

impl Motion {
    fn new(s: &Step) -> Self {
        let v = |a: [f32; 3]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
        Motion {
            translate: v(s.translate),
            rotation: s.rotate.as_ref().map(|r| {
                (
                    v(r.axis).normalize(),
                    (r.degrees as f64).to_radians(),
                    v(r.center),
                )
            }),
        }
    }

    /// Where `p` is after fraction `t` of the motion.
    pub fn apply(&self, p: DVec3, t: f64) -> DVec3 {
        let rotated = match self.rotation {
            Some((axis, angle, c)) => DQuat::from_axis_angle(axis, angle * t) * (p - c) + c,
            None => p,
        };
        rotated + self.translate * t
    }
}

/// A step with its selection resolved to bone vertex ids.
#[derive(Debug, Clone, PartialEq)]
pub struct ResolvedStep {
    pub name: String,
    /// Selected bone-layer vertex ids (sorted, unique, non-empty).
    pub bone_vertices: Vec<u32>,
    /// Their positions when the step starts.
    start: Vec<DVec3>,
    motion: Motion,
    pub increments: u32,
    pub iterations: Iterations,
    pub reset_velocities: bool,
}

impl ResolvedStep {
    /// Target positions of the selected bone vertices after increment `j`
    /// (1-based, `j ≤ increments`), computed from the step's start in f64 so
    /// increments do not accumulate rounding.
    pub fn targets(&self, j: u32) -> Vec<[f32; 4]> {
        let t = j as f64 / self.increments as f64;
        self.start
            .iter()
            .map(|&p| {
                let q = self.motion.apply(p, t);
                [q.x as f32, q.y as f32, q.z as f32, 0.0]
            })
            .collect()
    }
}

/// A plan whose selections were resolved on one network.
#[derive(Debug, Clone, PartialEq)]
pub struct ResolvedPlan {
    pub name: Option<String>,
    pub steps: Vec<ResolvedStep>,
}

impl ResolvedPlan {
    /// One surgery increment: the first increment of the first step,
    /// divided by `divide` (≥ 1), as a one-step plan of one increment
    /// relaxed to convergence (what the time-to-equilibrium benchmarks
    /// run); `None` for a plan without steps.
    pub fn first_increment(&self, divide: u32) -> Option<ResolvedPlan> {
        let s = self.steps.first()?;
        let f = 1.0 / (f64::from(s.increments) * f64::from(divide.max(1)));
        let motion = Motion {
            translate: s.motion.translate * f,
            rotation: (s.motion.rotation).map(|(axis, angle, c)| (axis, angle * f, c)),
        };
        Some(ResolvedPlan {
            name: self.name.clone(),
            steps: vec![ResolvedStep {
                name: s.name.clone(),
                bone_vertices: s.bone_vertices.clone(),
                start: s.start.clone(),
                motion,
                increments: 1,
                iterations: Iterations::Converge,
                reset_velocities: false,
            }],
        })
    }
}
