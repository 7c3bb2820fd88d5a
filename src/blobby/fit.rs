//! Fitting with splitting (seed 001 §3.5; Muraki 1991): start from one
//! primitive, then repeatedly split the primitive with the largest share of
//! the data error into two, optimise the new pair, then all primitives,
//! until N primitives or an energy target.
//!
//! **Optimiser**: L-BFGS (memory 7) with a Moré–Thuente line search
//! (argmin), over θ = (c, ln a, b) per primitive so that a stays positive;
//! ∂E/∂ln a = a·∂E/∂a. Energy and gradient come from `blobby_energy` on the
//! backend asked for; one evaluation serves both the cost and the gradient
//! at the same θ. The best θ evaluated is kept, so a phase never ends above
//! its start, even when the line search gives up.
//!
//! **Split**: the chosen primitive (c, a, b) becomes two at its centre with
//! b/2 each: V is unchanged, and with it every energy term (the two |b/2|
//! add up to |b|). At an optimum that split is a stationary point (both
//! children see the parent's zero gradient), so the pair's optimisation
//! starts from the children moved apart by ±0.25/√a along the principal
//! axis of the range points the parent owns, and keeps the unmoved split
//! as its baseline: the stage ends at or below the parent's E.
//!
//! **Choice**: each range point is assigned to the primitive with the
//! largest |b e^{−a s}| there; the primitive whose points carry the largest
//! sum of e_j = (V − T)² + α|n − N/|N||² is split (f64 on the host).

use std::cell::RefCell;

use argmin::core::{CostFunction, Executor, Gradient};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use glam::DVec3;

use super::energy::{Energy, energy};
use super::{Blob, Model, RangePoints, Weights};
use crate::gpu::Backend;
use crate::{Error, Result};

/// What the fit is asked for.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct FitOptions {
    /// N, the primitives of the final model.
    pub primitives: usize,
    pub weights: Weights,
    /// The iso value T.
    pub iso: f64,
    /// L-BFGS iterations for a new pair.
    pub pair_iterations: u64,
    /// L-BFGS iterations over all primitives after each split.
    pub global_iterations: u64,
    /// Stop splitting once E is at most this.
    pub energy_target: Option<f64>,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            primitives: 32,
            weights: Weights {
                alpha: 0.5,
                beta: 1e-4,
            },
            iso: 0.5,
            pair_iterations: 40,
            global_iterations: 80,
            energy_target: None,
        }
    }
}

/// The energy terms of a model, f64 on the host.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Terms {
    /// E (eq. 22).
    pub total: f64,
    /// E_value/M and E_normal/M (eq. 16, 19, divided by M).
    pub value: f64,
    pub normal: f64,
    /// E_shrink (eq. 21, unweighted).
    pub shrink: f64,
}

/// One stage of the fit: the model after optimising N primitives. The
/// terms are those of the fit's normalised frame (the points centred and
/// scaled to RMS radius 1): E_value and E_normal are the same in any
/// frame, E_shrink scales with the cube of the length unit squared.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FitStage {
    pub primitives: usize,
    pub terms: Terms,
    /// Energy evaluations (each one `blobby_energy` pass).
    pub evaluations: u64,
    pub seconds: f64,
}

/// The fitted model and the stages that led to it.
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    pub model: Model,
    pub stages: Vec<FitStage>,
}

/// E, E_value/M, E_normal/M and E_shrink in f64 (the normal term with the
/// kernel's |∇V| floor).
pub fn terms(model: &Model, points: &RangePoints, weights: Weights) -> Result<Terms> {
    let input = super::energy::EnergyInput::new(model, points, weights)?;
    let g_min = f64::from(input.params.g_min2).sqrt();
    let (mut value, mut normal) = (0.0, 0.0);
    for (x, n) in points.positions.iter().zip(&points.normals) {
        let g = model.gradient(*x);
        value += (model.value(*x) - model.iso).powi(2);
        normal += (*n + g / g.length().max(g_min)).length_squared();
    }
    let m = points.len() as f64;
    let (shrink, _) = super::energy::shrink(model);
    Ok(Terms {
        total: (value + weights.alpha * normal) / m + weights.beta * shrink,
        value: value / m,
        normal: normal / m,
        shrink,
    })
}

/// The primitive carrying the largest share of the data error.
pub fn worst_primitive(model: &Model, points: &RangePoints, weights: Weights) -> usize {
    let mut share = vec![0.0f64; model.blobs.len()];
    for (x, n) in points.positions.iter().zip(&points.normals) {
        let owner = owner(model, *x);
        let g = model.gradient(*x);
        let e = (model.value(*x) - model.iso).powi(2)
            + weights.alpha * (*n + g / g.length().max(f64::MIN_POSITIVE)).length_squared();
        share[owner] += e;
    }
    (0..share.len())
        .max_by(|&i, &j| share[i].total_cmp(&share[j]))
        .expect("a model has primitives")
}

/// The start: one primitive at the points' centroid with V = 2T there and
/// V = T at their RMS distance from it.
pub fn start(points: &RangePoints, iso: f64) -> Model {
    let (centre, r2) = points.centroid_spread();
    Model {
        iso,
        blobs: vec![Blob {
            centre,
            a: std::f64::consts::LN_2 / r2.max(f64::MIN_POSITIVE),
            b: 2.0 * iso,
        }],
    }
}

/// The children of splitting primitive `k`: the split at its centre
/// (b/2 each; E unchanged) and the same moved apart by ±0.25/√a along the
/// principal axis of the range points `k` owns (see [`worst_primitive`]).
pub fn split_apart(model: &Model, k: usize, points: &RangePoints) -> (Model, Model) {
    let neutral = model.split(k);
    let owned: Vec<DVec3> = (points.positions.iter())
        .filter(|x| owner(model, **x) == k)
        .copied()
        .collect();
    let axis = principal_axis(&owned);
    let step = 0.25 / model.blobs[k].a.sqrt() * axis;
    let mut apart = neutral.clone();
    apart.blobs[k].centre -= step;
    apart.blobs[k + 1].centre += step;
    (neutral, apart)
}

/// The primitive with the largest |b e^{−a s}| at `x`.
fn owner(model: &Model, x: DVec3) -> usize {
    (0..model.blobs.len())
        .max_by(|&i, &j| {
            let f = |k: usize| model.blobs[k].value(x).abs();
            f(i).total_cmp(&f(j))
        })
        .expect("a model has primitives")
}

/// The unit direction of largest spread of `points` (power iteration on
/// their covariance; x when they do not spread).
fn principal_axis(points: &[DVec3]) -> DVec3 {
    if points.len() < 2 {
        return DVec3::X;
    }
    let mean = points.iter().sum::<DVec3>() / points.len() as f64;
    let mut cov = glam::DMat3::ZERO;
    for p in points {
        let d = *p - mean;
        cov += glam::DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    let mut v = DVec3::new(1.0, 0.7, 0.3).normalize();
    for _ in 0..50 {
        let w = cov * v;
        if w.length() == 0.0 {
            return DVec3::X;
        }
        v = w.normalize();
    }
    v
}

/// θ of the primitives `free` of `model`: (c, ln a, b) each.
fn theta_of(model: &Model, free: &[usize]) -> Vec<f64> {
    (free.iter())
        .flat_map(|&k| {
            let b = &model.blobs[k];
            [b.centre.x, b.centre.y, b.centre.z, b.a.ln(), b.b]
        })
        .collect()
}

/// `base` with the primitives `free` set from θ.
fn with_theta(base: &Model, free: &[usize], theta: &[f64]) -> Model {
    let mut m = base.clone();
    for (&k, t) in free.iter().zip(theta.chunks_exact(5)) {
        m.blobs[k] = Blob {
            centre: DVec3::new(t[0], t[1], t[2]),
            a: t[3].exp(),
            b: t[4],
        };
    }
    m
}

/// The best θ evaluated, its energy, and the evaluations so far.
#[derive(Debug, Default)]
struct Record {
    best: Option<(Vec<f64>, f64)>,
    evaluations: u64,
}

/// The optimisation problem over the primitives `free` of `base`.
struct Problem<'a> {
    base: &'a Model,
    free: &'a [usize],
    points: &'a RangePoints,
    weights: Weights,
    backend: Backend<'a>,
    /// The last evaluation (θ, energy): the gradient at the cost's θ.
    last: RefCell<Option<(Vec<f64>, Energy)>>,
    record: &'a RefCell<Record>,
}

impl Problem<'_> {
    fn evaluate(&self, theta: &[f64]) -> Result<Energy> {
        if let Some((t, e)) = self.last.borrow().as_ref()
            && t == theta
        {
            return Ok(e.clone());
        }
        let model = with_theta(self.base, self.free, theta);
        let e = energy(&model, self.points, self.weights, self.backend)?;
        let mut record = self.record.borrow_mut();
        record.evaluations += 1;
        if e.total.is_finite() && record.best.as_ref().is_none_or(|b| e.total < b.1) {
            record.best = Some((theta.to_vec(), e.total));
        }
        *self.last.borrow_mut() = Some((theta.to_vec(), e.clone()));
        Ok(e)
    }
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, theta: &Self::Param) -> std::result::Result<f64, argmin::core::Error> {
        Ok(self.evaluate(theta)?.total)
    }
}

impl Gradient for Problem<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;

    fn gradient(&self, theta: &Self::Param) -> std::result::Result<Vec<f64>, argmin::core::Error> {
        let e = self.evaluate(theta)?;
        Ok((self.free.iter())
            .zip(theta.chunks_exact(5))
            .flat_map(|(&k, t)| {
                let g = e.gradient[k];
                [g[0], g[1], g[2], g[3] * t[3].exp(), g[4]]
            })
            .collect())
    }
}

/// Minimises E over the primitives `free` of `model` by L-BFGS for at most
/// `iterations`, starting from `from` (`model` itself when `None`; it may
/// differ from `model` in the free primitives only); returns the best
/// model evaluated, `model` included, and the evaluations.
pub fn optimise(
    model: &Model,
    from: Option<&Model>,
    free: &[usize],
    points: &RangePoints,
    weights: Weights,
    iterations: u64,
    backend: Backend<'_>,
) -> Result<(Model, u64)> {
    let record = RefCell::new(Record::default());
    let problem = Problem {
        base: model,
        free,
        points,
        weights,
        backend,
        last: RefCell::new(None),
        record: &record,
    };
    problem.evaluate(&theta_of(model, free))?;
    let theta = theta_of(from.unwrap_or(model), free);
    let line = MoreThuenteLineSearch::new()
        .with_c(1e-4, 0.9)
        .map_err(|e| Error::Internal(format!("blobby fit: line search: {e}")))?;
    let solver = LBFGS::new(line, 7)
        .with_tolerance_grad(1e-10)
        .and_then(|s| s.with_tolerance_cost(1e-12))
        .map_err(|e| Error::Internal(format!("blobby fit: L-BFGS: {e}")))?;
    let run = Executor::new(problem, solver)
        .configure(|state| state.param(theta).max_iters(iterations))
        .run();
    if let Err(e) = run {
        // Errors of the energy itself (limits, device) are the caller's;
        // when the line search or the solver gives up, the best θ stands.
        if let Ok(ours) = e.downcast::<Error>() {
            return Err(ours);
        }
    }
    let record = record.into_inner();
    let Some((best, _)) = record.best else {
        return Err(Error::Internal(
            "blobby fit: no finite energy at the start".into(),
        ));
    };
    Ok((with_theta(model, free, &best), record.evaluations))
}

/// Fits `opts.primitives` primitives to `points` (see the module doc);
/// `on_stage` sees every stage as it ends.
///
/// Errors: no primitives asked, non-finite weights or iso, the energy's
/// errors (limits, device).
pub fn fit(
    points: &RangePoints,
    opts: &FitOptions,
    backend: Backend<'_>,
    mut on_stage: impl FnMut(&FitStage),
) -> Result<Fit> {
    if opts.primitives == 0 {
        return Err(Error::param("primitives", 0, "at least 1"));
    }
    let w = opts.weights;
    if !(w.alpha.is_finite() && w.alpha >= 0.0 && w.beta.is_finite() && w.beta >= 0.0) {
        return Err(Error::param(
            "weights",
            format!("alpha {}, beta {}", w.alpha, w.beta),
            "finite and ≥ 0",
        ));
    }
    if !(opts.iso.is_finite() && opts.iso > 0.0) {
        return Err(Error::param("iso", opts.iso, "positive and finite"));
    }
    let clock = std::time::Instant::now();
    let (frame, points) = Frame::of(points);
    let points = &points;
    let mut stages = Vec::new();
    let mut model = start(points, opts.iso);
    let (m, evaluations) = optimise(
        &model,
        None,
        &[0],
        points,
        w,
        opts.global_iterations,
        backend,
    )?;
    model = m;
    let mut stage = |model: &Model, evaluations: u64| -> Result<FitStage> {
        let s = FitStage {
            primitives: model.blobs.len(),
            terms: terms(model, points, w)?,
            evaluations,
            seconds: clock.elapsed().as_secs_f64(),
        };
        on_stage(&s);
        Ok(s)
    };
    stages.push(stage(&model, evaluations)?);
    while model.blobs.len() < opts.primitives {
        if opts
            .energy_target
            .is_some_and(|t| stages.last().is_some_and(|s: &FitStage| s.terms.total <= t))
        {
            break;
        }
        let k = worst_primitive(&model, points, w);
        let (neutral, apart) = split_apart(&model, k, points);
        let pair = [k, k + 1];
        let (pair, e1) = optimise(
            &neutral,
            Some(&apart),
            &pair,
            points,
            w,
            opts.pair_iterations,
            backend,
        )?;
        let all: Vec<usize> = (0..pair.blobs.len()).collect();
        let (next, e2) = optimise(
            &pair,
            None,
            &all,
            points,
            w,
            opts.global_iterations,
            backend,
        )?;
        model = next;
        stages.push(stage(&model, e1 + e2)?);
    }
    Ok(Fit {
        model: frame.to_world(&model),
        stages,
    })
}

/// The normalised frame the fit works in: the points centred on their
/// centroid and scaled to RMS radius 1, so that α, β and the start do not
/// depend on the scan's units or placement.
#[derive(Debug, Clone, Copy)]
struct Frame {
    centre: DVec3,
    scale: f64,
}

impl Frame {
    /// The frame of `points` and the points in it.
    fn of(points: &RangePoints) -> (Frame, RangePoints) {
        let (centre, r2) = points.centroid_spread();
        let scale = if r2 > 0.0 { r2.sqrt() } else { 1.0 };
        let local = RangePoints {
            positions: (points.positions.iter())
                .map(|p| (*p - centre) / scale)
                .collect(),
            normals: points.normals.clone(),
        };
        (Frame { centre, scale }, local)
    }

    /// A model of the frame in world coordinates: c·s + centre, a/s².
    fn to_world(self, model: &Model) -> Model {
        Model {
            iso: model.iso,
            blobs: (model.blobs.iter())
                .map(|b| Blob {
                    centre: self.centre + self.scale * b.centre,
                    a: b.a / (self.scale * self.scale),
                    b: b.b,
                })
                .collect(),
        }
    }
}
