//! Sampling a scene's time span, with Witkin–Heckbert particles or the
//! spring network: frame 0 is relaxed from marching cubes of the field;
//! every later frame carries the samples along with the moving surface
//! (scene time advancing inside eq. 8 through F_t) and relaxes them at the
//! frame's time, with fission and death (particles) or splits, collapses
//! and surgery (network) keeping the sampling and the topology.

use glam::Vec3;

use super::cells::CellList;
use super::network::{Network, NetworkOptions};
use super::wh::{Iteration, Particles, Sampler, WhOptions, sigma_for_spacing};
use crate::foundation::union_find::UnionFind;
use crate::gpu::Backend;
use crate::implicit::field::FieldInput;
use crate::implicit::field::cpu::skeletal_field;
use crate::implicit::{Pose, Scene, grid};
use crate::mesh::ScalarField;
use crate::mesh::collapse::collapse_short_edges;
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

/// `override_r` (the command line), else `table` (the scene file's), else
/// the bounding-box diagonal of the surface at t = 0 over 64.
pub fn edge_length(scene: &Scene, table: Option<f64>, override_r: Option<f64>) -> Result<f64> {
    if let Some(r) = override_r.or(table) {
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

/// Triangle quality of a mesh: minimum-angle distribution and aspect ratios.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Quality {
    /// Fraction of triangles whose smallest angle is ≥ 30°.
    pub min_angle_30: f64,
    /// 5th percentile and median of the smallest angles (degrees).
    pub min_angle_p5: f32,
    pub min_angle_median: f32,
    /// Longest edge over shortest altitude · √3/2 (1 for equilateral): max, mean.
    pub aspect_max: f32,
    pub aspect_mean: f32,
}

impl Quality {
    /// The figures of `mesh`'s triangles.
    pub fn of(mesh: &TriMesh) -> Quality {
        let mut angles = Vec::with_capacity(mesh.triangles.len());
        let mut aspects = Vec::with_capacity(mesh.triangles.len());
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            let ang = |p: Vec3, q: Vec3, r: Vec3| (q - p).angle_between(r - p).to_degrees();
            angles.push(ang(a, b, c).min(ang(b, c, a)).min(ang(c, a, b)));
            let longest = a.distance(b).max(b.distance(c)).max(c.distance(a));
            let area2 = (b - a).cross(c - a).length();
            aspects.push(if area2 > 0.0 {
                longest * longest / area2 * 3f32.sqrt() / 2.0
            } else {
                f32::INFINITY
            });
        }
        angles.sort_by(f32::total_cmp);
        let n = angles.len().max(1);
        let pick = |f: f64| {
            angles
                .get(((angles.len().saturating_sub(1)) as f64 * f) as usize)
                .copied()
                .unwrap_or(0.0)
        };
        Quality {
            min_angle_30: angles.iter().filter(|&&a| a >= 30.0).count() as f64 / n as f64,
            min_angle_p5: pick(0.05),
            min_angle_median: pick(0.5),
            aspect_max: aspects.iter().copied().fold(0.0, f32::max),
            aspect_mean: aspects.iter().sum::<f32>() / n as f32,
        }
    }
}

/// A topology change: the network's surgery, or a reseed by the guard.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Event {
    /// Scene time at the end of the iteration that made it.
    pub time: f64,
    /// Fans closing loops (two per cut neck) and strips joining loops.
    pub caps: u32,
    pub bridges: u32,
    /// Whether the guard rebuilt the network from the field (its topology
    /// or self-intersections disagreed after the local surgery; see
    /// [`NetworkOptions::guard`]).
    pub reseed: bool,
    /// Components and Σ genus after it.
    pub components: usize,
    pub genus: i64,
}

/// What the network did between two frames.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct NetworkSteps {
    pub iterations: u32,
    pub splits: u32,
    pub collapses: u32,
    /// Surgeries refused (retried at the next iteration).
    pub refused_surgeries: u32,
    /// Max |F − I|/|∇F| at the vertices before the frame's last step.
    pub residual: f32,
    pub events: Vec<Event>,
}

/// The start network of `scene` at t = 0 ([`seed_network`]).
pub fn start_network(
    scene: &Scene,
    r: f64,
    opts: NetworkOptions,
    backend: Backend<'_>,
) -> Result<Network> {
    seed_network(&scene.pose(0.0), r, opts, backend)
}

/// A network on `pose`: marching cubes at lattice spacing R, edges shorter
/// than 0.3 R collapsed.
pub fn seed_network(
    pose: &Pose,
    r: f64,
    opts: NetworkOptions,
    backend: Backend<'_>,
) -> Result<Network> {
    let field = FieldInput::new(pose)?;
    let mc = grid::marching_cubes(pose, r, backend)?;
    let start = collapse_short_edges(&mc.mesh, 0.3 * r as f32).mesh;
    Network::new(&start, r, opts, &field)
}

/// Whether the network's components, genus and self-intersections agree
/// with the field of `pose` (marching cubes at spacing R/2).
fn topology_holds(net: &Network, pose: &Pose, backend: Backend<'_>) -> Result<bool> {
    let mesh = net.mesh();
    let topo = crate::mesh::Topology::of(&mesh);
    let mut genus: Vec<i64> = topo.components.iter().filter_map(|c| c.genus).collect();
    genus.sort_unstable();
    let field = grid::marching_cubes(pose, f64::from(net.rest) / 2.0, backend)?;
    let mut expected: Vec<i64> = field.groups.iter().filter_map(|g| g.genus).collect();
    expected.sort_unstable();
    Ok(topo.components.len() == field.groups.len()
        && genus == expected
        && crate::mesh::intersect::self_intersections(&mesh)
            .pairs
            .is_empty())
}

/// The guard after the frame at `t`: rebuilds `net` from the field (and
/// relaxes it) when [`topology_holds`] fails.
fn guard(
    net: &mut Network,
    scene: &Scene,
    t: f64,
    backend: Backend<'_>,
    steps: &mut NetworkSteps,
) -> Result<()> {
    let pose = scene.pose(t);
    if !net.opts.guard || topology_holds(net, &pose, backend)? {
        return Ok(());
    }
    *net = seed_network(&pose, f64::from(net.rest), net.opts, backend)?;
    // Relaxed without surgery: the seed has the field's topology at t.
    let field = FieldInput::new(&pose)?;
    for _ in 0..net.opts.start_iterations {
        let it = net.iterate(&field, 0.0, backend)?;
        steps.iterations += 1;
        steps.splits += it.splits;
        steps.collapses += it.collapses;
        steps.residual = it.residual;
    }
    let topo = net.check()?;
    steps.events.push(Event {
        time: t,
        caps: 0,
        bridges: 0,
        reseed: true,
        components: topo.components.len(),
        genus: topo.components.iter().filter_map(|c| c.genus).sum(),
    });
    Ok(())
}

/// One iteration and the surgery after it, with the scene at `t0` moving
/// to `t1`; events are recorded at `t1`.
fn network_step(
    net: &mut Network,
    scene: &Scene,
    t0: f64,
    t1: f64,
    backend: Backend<'_>,
    steps: &mut NetworkSteps,
) -> Result<()> {
    let it = net.iterate(
        &FieldInput::new(&scene.pose(t0))?,
        (t1 - t0) as f32,
        backend,
    )?;
    steps.iterations += 1;
    steps.splits += it.splits;
    steps.collapses += it.collapses;
    steps.residual = it.residual;
    let s = net.surgery(&FieldInput::new(&scene.pose(t1))?);
    steps.refused_surgeries += s.refused;
    if s.caps > 0 || s.bridges > 0 {
        let t = net.check()?;
        steps.events.push(Event {
            time: t1,
            caps: s.caps,
            bridges: s.bridges,
            reseed: false,
            components: t.components.len(),
            genus: t.components.iter().filter_map(|c| c.genus).sum(),
        });
    }
    Ok(())
}

/// Runs the network over `times`: frame 0 relaxes the start mesh, every
/// later frame transports it (scene time advancing in steps that move the
/// surface by at most R/8 at the vertices) and relaxes it at the frame's time,
/// then the guard checks it ([`NetworkOptions::guard`]); `on_frame` gets the
/// network after each frame.
pub fn network(
    scene: &Scene,
    times: &[f64],
    mut net: Network,
    backend: Backend<'_>,
    mut on_frame: impl FnMut(&Network, f64, &NetworkSteps) -> Result<()>,
) -> Result<()> {
    let opts = net.opts;
    let mut prev: Option<f64> = None;
    for &t in times {
        let mut steps = NetworkSteps::default();
        match prev {
            None => {
                for _ in 0..opts.start_iterations {
                    network_step(&mut net, scene, t, t, backend, &mut steps)?;
                }
            }
            Some(t0) => {
                // Sub-steps in which the surface moves by at most R/8 at the
                // vertices, at least `transport`, at most MAX_SUBSTEPS.
                let mut a = t0;
                let least = (t - t0) / f64::from(opts.transport.max(1));
                let floor = (t - t0) / f64::from(MAX_SUBSTEPS);
                while a < t {
                    let v = surface_speed(&net, &FieldInput::new(&scene.pose(a))?);
                    let by_speed = if v > 0.0 {
                        f64::from(net.rest) / 8.0 / f64::from(v)
                    } else {
                        f64::INFINITY
                    };
                    let b = (a + least.min(by_speed).max(floor)).min(t);
                    network_step(&mut net, scene, a, b, backend, &mut steps)?;
                    a = b;
                }
                for _ in 0..opts.relax {
                    network_step(&mut net, scene, t, t, backend, &mut steps)?;
                }
            }
        }
        guard(&mut net, scene, t, backend, &mut steps)?;
        prev = Some(t);
        on_frame(&net, t, &steps)?;
    }
    Ok(())
}

/// Most sub-steps between two frames.
pub const MAX_SUBSTEPS: u32 = 400;

/// Largest normal speed |F_t|/|∇F| of the surface at the network's
/// vertices, with |∇F| taken as at least 100 g_min (a tenth of the median
/// at the start): near a critical point the surface moves without bound,
/// and surgery, not tracking, handles it.
fn surface_speed(net: &Network, field: &FieldInput) -> f32 {
    (net.positions.iter())
        .map(|p| {
            let (s, _) = skeletal_field(field, p.to_array());
            s.rate.abs() / Vec3::from_array(s.grad).length().max(100.0 * net.g_min)
        })
        .fold(0.0, f32::max)
}

/// Per-frame figures of the network, checked against the field.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NetworkFrameReport {
    pub frame: u32,
    pub time: f64,
    pub vertices: usize,
    pub triangles: usize,
    pub components: usize,
    /// Genus per component (descending size).
    pub genus: Vec<i64>,
    pub euler: i64,
    /// Closed, consistently oriented 2-manifold.
    pub manifold: bool,
    /// Triangle pairs crossing each other (exact test).
    pub self_intersections: usize,
    pub steps: NetworkSteps,
    /// Max and mean |F − I|/|∇F| at the vertices after the frame.
    pub residual_max: f32,
    pub residual_mean: f32,
    pub quality: Quality,
    /// The marching-cubes mesh of the same surface at lattice spacing R.
    pub marching_cubes_quality: Quality,
    /// A dense marching-cubes reference (spacing R/4): its components and
    /// genus, and the symmetric Hausdorff distance over vertices to it.
    pub reference_components: usize,
    pub reference_genus: Vec<i64>,
    pub hausdorff: f64,
}

/// The figures of frame `frame` at time `t`.
pub fn network_report(
    net: &Network,
    scene: &Scene,
    frame: u32,
    t: f64,
    steps: &NetworkSteps,
    backend: Backend<'_>,
) -> Result<NetworkFrameReport> {
    let mesh = net.mesh();
    let topo = crate::mesh::Topology::of(&mesh);
    let pose = scene.pose(t);
    let field = FieldInput::new(&pose)?;
    let residuals: Vec<f32> = (mesh.positions.iter())
        .map(|p| {
            let (s, _) = skeletal_field(&field, p.to_array());
            s.value.abs() / Vec3::from_array(s.grad).length().max(net.g_min)
        })
        .collect();
    let r = f64::from(net.rest);
    let coarse = grid::marching_cubes(&pose, r, backend)?;
    let dense = grid::marching_cubes(&pose, r / 4.0, backend)?;
    let mut reference_genus: Vec<i64> = dense.groups.iter().filter_map(|g| g.genus).collect();
    reference_genus.sort_unstable_by(|a, b| b.cmp(a));
    Ok(NetworkFrameReport {
        frame,
        time: t,
        vertices: mesh.positions.len(),
        triangles: mesh.triangles.len(),
        components: topo.components.len(),
        genus: topo.components.iter().filter_map(|c| c.genus).collect(),
        euler: topo.euler,
        manifold: topo.closed && topo.is_manifold() && topo.consistently_oriented,
        self_intersections: crate::mesh::intersect::self_intersections(&mesh)
            .pairs
            .len(),
        steps: steps.clone(),
        residual_max: residuals.iter().copied().fold(0.0, f32::max),
        residual_mean: residuals.iter().sum::<f32>() / residuals.len().max(1) as f32,
        quality: Quality::of(&mesh),
        marching_cubes_quality: Quality::of(&coarse.mesh),
        reference_components: dense.groups.len(),
        reference_genus,
        hausdorff: crate::mesh::distance::hausdorff(&mesh, &dense.mesh),
    })
}
