//! Sampling a scene's time span with Witkin–Heckbert particles: frame 0 is
//! relaxed from projected marching-cubes vertices; every later frame
//! carries the particles along with the moving surface (scene time
//! advancing inside eq. 8 through F_t) and relaxes them at the frame's
//! time, with fission and death keeping the density.

use glam::Vec3;

use super::cells::CellList;
use super::wh::{Iteration, Particles, Sampler, WhOptions, sigma_for_spacing};
use crate::foundation::union_find::UnionFind;
use crate::gpu::Backend;
use crate::implicit::field::FieldInput;
use crate::implicit::field::cpu::skeletal_field;
use crate::implicit::{Scene, grid};
use crate::mesh::ScalarField;
use crate::{Result, TriMesh};

/// Per-frame figures.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FrameReport {
    pub frame: u32,
    pub time: f64,
    pub particles: usize,
    pub iterations: u32,
    pub fissions: u32,
    pub deaths: u32,
    pub lost: u32,
    /// Max and mean |F − I|/|∇F| at the particles after the frame.
    pub residual_max: f32,
    pub residual_mean: f32,
    /// Σ D_i of the last iteration.
    pub energy: f64,
    /// Groups of particles linked within 3σ̂ (the parts they sample).
    pub clusters: usize,
    /// Whether frame 0's relaxation met its stopping rule (later frames
    /// run a fixed number of iterations).
    pub converged: Option<bool>,
}

/// The sampler's resolved setup.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Setup {
    pub edge_length: f64,
    pub sigma_hat: f64,
    pub dt: f32,
    pub options: WhOptions,
}

/// Frame times: `frames` evenly spaced over [0, duration], frame 0 at 0.
pub fn frame_times(scene: &Scene, frames: u32) -> Vec<f64> {
    let d = scene.duration();
    (0..frames.max(1))
        .map(|f| {
            if frames > 1 {
                d * f64::from(f) / f64::from(frames - 1)
            } else {
                0.0
            }
        })
        .collect()
}

/// The edge length of `opts` (or `override_r`), else the bounding-box
/// diagonal of the surface at t = 0 over 64.
pub fn edge_length(scene: &Scene, opts: &WhOptions, override_r: Option<f64>) -> Result<f64> {
    if let Some(r) = override_r.or(opts.edge_length) {
        if !(r.is_finite() && r > 0.0) {
            return Err(crate::Error::param(
                "edge-length",
                r,
                "must be positive and finite",
            ));
        }
        return Ok(r);
    }
    let (lo, hi) = grid::surface_bounds(&scene.pose(0.0))
        .ok_or_else(|| crate::Error::empty("implicit surface at t = 0 (F < I everywhere)"))?;
    Ok((hi - lo).length() / 64.0)
}

/// Samples `scene` at `times` with particles of spacing `r`; `on_frame`
/// gets each frame's particles and figures as soon as they are done.
pub fn sample(
    scene: &Scene,
    times: &[f64],
    r: f64,
    opts: WhOptions,
    backend: Backend<'_>,
    mut on_frame: impl FnMut(&Particles, &FieldInput, &FrameReport) -> Result<()>,
) -> Result<Setup> {
    let sh = sigma_for_spacing(r, &opts);
    let pose0 = scene.pose(times.first().copied().unwrap_or(0.0));
    let field0 = FieldInput::new(&pose0)?;
    let start = Particles::on_surface(&pose0, sh, backend)?;
    let mut sampler = Sampler::new(start, sh, opts, &field0)?;
    let setup = Setup {
        edge_length: r,
        sigma_hat: sh,
        dt: sampler.dt(),
        options: opts,
    };
    let mut prev = None;
    for (f, &t) in times.iter().enumerate() {
        let mut totals = Iteration::default();
        let mut iterations = 0u32;
        let mut converged = None;
        let mut step = |it: Iteration| {
            totals = Iteration {
                fissions: totals.fissions + it.fissions,
                deaths: totals.deaths + it.deaths,
                lost: totals.lost + it.lost,
                ..it
            };
            iterations += 1;
        };
        match prev {
            None => {
                let relax = sampler.relax(&field0, opts.start_iterations, backend)?;
                converged = Some(relax.converged);
                totals = Iteration {
                    fissions: relax.fissions,
                    deaths: relax.deaths,
                    lost: relax.lost,
                    ..relax.last
                };
                iterations = relax.adapt_iterations + relax.settle_iterations;
            }
            Some(t0) => {
                let m = opts.transport.max(1);
                let gap = (t - t0) / f64::from(m);
                for k in 0..m {
                    let field = FieldInput::new(&scene.pose(t0 + gap * f64::from(k)))?;
                    step(sampler.iterate(&field, gap as f32, true, backend)?);
                }
                let field = FieldInput::new(&scene.pose(t))?;
                for _ in 0..opts.relax {
                    step(sampler.iterate(&field, 0.0, true, backend)?);
                }
            }
        }
        prev = Some(t);
        let field = FieldInput::new(&scene.pose(t))?;
        let residuals: Vec<f32> = (sampler.particles.points.iter())
            .map(|p| {
                let (s, _) = skeletal_field(&field, [p[0], p[1], p[2]]);
                s.value.abs() / Vec3::from_array(s.grad).length().max(sampler.g_min)
            })
            .collect();
        let report = FrameReport {
            frame: f as u32,
            time: t,
            particles: sampler.particles.len(),
            iterations,
            fissions: totals.fissions,
            deaths: totals.deaths,
            lost: totals.lost,
            residual_max: residuals.iter().copied().fold(0.0, f32::max),
            residual_mean: residuals.iter().sum::<f32>() / residuals.len().max(1) as f32,
            energy: totals.energy,
            clusters: clusters(&sampler.particles, 3.0 * sh as f32)?,
            converged,
        };
        on_frame(&sampler.particles, &field, &report)?;
    }
    Ok(setup)
}

/// Groups of particles linked by pairs closer than `link`.
pub fn clusters(p: &Particles, link: f32) -> Result<usize> {
    let pos = p.positions();
    let cells = CellList::build(&pos, link, 0.0)?;
    let mut uf: UnionFind = UnionFind::with_len(pos.len());
    for i in 0..pos.len() {
        for j in cells.candidates(i) {
            if j > i && pos[i].distance_squared(pos[j]) < link * link {
                uf.union(i as u32, j as u32);
            }
        }
    }
    let roots = uf.roots();
    Ok(roots
        .iter()
        .enumerate()
        .filter(|(i, r)| **r as usize == *i)
        .count())
}

/// The particles as a point set with outward normals (`nx ny nz`) and
/// their radii (`sigma`).
pub fn point_set(p: &Particles, field: &FieldInput) -> TriMesh {
    let normals: Vec<Vec3> = (p.points.iter())
        .map(|q| {
            let (s, _) = skeletal_field(field, [q[0], q[1], q[2]]);
            -Vec3::from_array(s.grad).normalize_or_zero()
        })
        .collect();
    let field_of = |name: &str, values: Vec<f32>| ScalarField {
        name: name.into(),
        values,
    };
    TriMesh {
        positions: p.positions(),
        triangles: Vec::new(),
        scalars: vec![
            field_of("nx", normals.iter().map(|n| n.x).collect()),
            field_of("ny", normals.iter().map(|n| n.y).collect()),
            field_of("nz", normals.iter().map(|n| n.z).collect()),
            field_of("sigma", p.points.iter().map(|q| q[3]).collect()),
        ],
    }
}

/// Discs for pictures: a hexagon of radius `scale`·σ in each particle's
/// tangent plane (six triangles, wound outward), with `sigma` per vertex.
pub fn splats(points: &TriMesh, scale: f32) -> TriMesh {
    let get = |name: &str| {
        &points
            .scalars
            .iter()
            .find(|s| s.name == name)
            .expect("point set field")
            .values
    };
    let (nx, ny, nz, sigma) = (get("nx"), get("ny"), get("nz"), get("sigma"));
    let mut out = TriMesh::default();
    let mut sig = Vec::new();
    for (i, p) in points.positions.iter().enumerate() {
        let n = Vec3::new(nx[i], ny[i], nz[i]).normalize_or(Vec3::Z);
        let t1 = n.any_orthonormal_vector();
        let t2 = n.cross(t1);
        let c = out.positions.len() as u32;
        out.positions.push(*p);
        sig.push(sigma[i]);
        for k in 0..6 {
            let a = std::f32::consts::TAU * k as f32 / 6.0;
            out.positions
                .push(*p + scale * sigma[i] * (a.cos() * t1 + a.sin() * t2));
            sig.push(sigma[i]);
            out.triangles.push([c, c + 1 + k, c + 1 + (k + 1) % 6]);
        }
    }
    out.scalars.push(ScalarField {
        name: "sigma".into(),
        values: sig,
    });
    out
}
