//! The particle spring network (SPEC §3.3, seed 002 §4.1–4.3): the
//! particles are the vertices of a closed triangulation of the implicit
//! surface; springs along its edges pull them to their rest lengths
//! (eq. 12–13), eq. 8 keeps them on the moving surface (kernel
//! `network_update`), and the host keeps the triangulation: edge splits
//! and collapses with the seed's locks and length-change guard
//! (eq. 14–16), curvature-adaptive rest lengths (eq. 17–23).
//!
//! Local operations and χ:
//!
//! ```text
//!  split (a, b):     (a, b, c), (b, a, d) → (a, m, c), (m, b, c), (b, m, d), (m, a, d)   ΔV, ΔE, ΔF = +1, +3, +2
//!  collapse (a, b):  b merges into a at the midpoint; (a, b, c), (b, a, d) go             ΔV, ΔE, ΔF = −1, −3, −2
//! ```
//!
//! A collapse needs the link condition (the ends share exactly the two
//! apexes, which keep ≥ 3 neighbours), no surviving triangle turning by
//! more than 45°, and no new edge longer than D_max·R (so that it does not
//! cause a split at once). Vertices touched by one operation wait for the
//! next iteration (the seed's lock, rule 3).

pub mod cpu;
pub mod gpu;
mod surgery;

pub use surgery::{SURGERY_COOLDOWN, Surgery};

use std::collections::{HashMap, HashSet};

use glam::Vec3;
use rayon::prelude::*;

use super::StepOutput;
use crate::gpu::Backend;
use crate::implicit::field::FieldInput;
use crate::implicit::field::cpu::skeletal_field;
use crate::mesh::Topology;
use crate::{Error, Result, TriMesh};

/// Uniform parameters of `network_update`.
#[derive(Debug, Clone, Copy, PartialEq, encase::ShaderType)]
pub struct NetworkParams {
    pub n_vertices: u32,
    /// Step Δt.
    pub dt: f32,
    /// Scene-time advance δ of this iteration.
    pub delta: f32,
    /// Feedback κ = φΔt.
    pub kappa: f32,
    /// Spring constant ρ.
    pub rho: f32,
    /// Squared gradient guard g_min².
    pub g_min2: f32,
    /// Most |Δp| per step.
    pub step_max: f32,
}

/// One step's inputs besides the field.
#[derive(Debug, Clone, Copy)]
pub struct NetworkInput<'a> {
    pub params: NetworkParams,
    /// #V + 1 CSR row starts.
    pub offsets: &'a [u32],
    /// (neighbour, R_ij bits) per directed edge.
    pub springs: &'a [[u32; 2]],
    pub positions: &'a [[f32; 4]],
}

/// One `network_update` step on `backend`: new positions and (∇F, F − I)
/// at the old ones.
pub fn network_update(
    field: &FieldInput,
    input: &NetworkInput<'_>,
    backend: Backend<'_>,
) -> Result<StepOutput> {
    match backend {
        Backend::Cpu => Ok(cpu::network_update(field, input)),
        Backend::Gpu(g) => gpu::network_update(g, field, input),
    }
}

/// Constants of the network (the `[network]` table of a scene file).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct NetworkOptions {
    /// Spring constant ρ (1).
    pub rho: f64,
    /// Collapse below D_min·R_ij (4/5).
    pub d_min: f64,
    /// Split above D_max·R_ij (4/3).
    pub d_max: f64,
    /// Eq. 16: no split or collapse of a spring whose length changed by more
    /// than ε·R since the previous iteration (0.02).
    pub epsilon: f64,
    /// Feedback κ = φΔt (0.5).
    pub kappa: f64,
    /// Curvature-adaptive rest lengths (eq. 17–23): ϑ (0 = off).
    pub theta: f64,
    /// Rest-length bound λ_R / R (0.5).
    pub lambda: f64,
    /// Target spring length R; `--edge-length` overrides it, and without
    /// either it is the surface's bounding-box diagonal / 64.
    pub edge_length: Option<f64>,
    /// Least iterations carrying the network from one frame's time to the
    /// next (more when the surface would move over R/8 at a vertex in one).
    pub transport: u32,
    /// Iterations at each frame's time after the transport.
    pub relax: u32,
    /// Iterations relaxing the start mesh at frame 0.
    pub start_iterations: u32,
    /// The topology guard: after each frame, compare the network's
    /// components and genus with marching cubes of the field at spacing R/2
    /// and test it for self-intersections; on a mismatch rebuild it from the
    /// field (a reported `reseed` event). On (true).
    pub guard: bool,
}

impl NetworkOptions {
    /// The `[network]` table of a scene file (defaults when absent).
    pub fn from_scene(text: &str, origin: &str) -> Result<NetworkOptions> {
        let o: NetworkOptions = super::scene_table(text, origin, "network")?;
        let positive = [
            ("rho", o.rho),
            ("d_min", o.d_min),
            ("d_max", o.d_max),
            ("epsilon", o.epsilon),
            ("kappa", o.kappa),
            ("lambda", o.lambda),
            ("edge_length", o.edge_length.unwrap_or(1.0)),
        ];
        super::check_positive(origin, "network", &positive)?;
        if o.d_min >= o.d_max || o.theta < 0.0 || o.lambda >= 1.0 {
            return Err(Error::format(
                origin,
                crate::Position::Field("network".into()),
                "d_min < d_max, theta ≥ 0, lambda < 1",
                format!(
                    "d_min {}, d_max {}, theta {}, lambda {}",
                    o.d_min, o.d_max, o.theta, o.lambda
                ),
            ));
        }
        Ok(o)
    }
}

impl Default for NetworkOptions {
    fn default() -> Self {
        NetworkOptions {
            rho: 1.0,
            d_min: 0.8,
            d_max: 4.0 / 3.0,
            epsilon: 0.02,
            kappa: 0.5,
            theta: 0.0,
            lambda: 0.5,
            edge_length: None,
            transport: 4,
            relax: 8,
            start_iterations: 40,
            guard: true,
        }
    }
}

/// Whether triangle `t` faces against the field's outward normal −∇F at
/// its centre.
fn faces_against(positions: &[Vec3], field: &FieldInput, t: &[u32; 3]) -> bool {
    let [p, q, r] = t.map(|v| positions[v as usize]);
    let (f, _) = skeletal_field(field, ((p + q + r) / 3.0).to_array());
    (q - p).cross(r - p).dot(-Vec3::from_array(f.grad)) <= 0.0
}

fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// What one iteration did.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct NetworkIteration {
    pub splits: u32,
    pub collapses: u32,
    /// Collapses refused by the link condition, the turn or the length test.
    pub refused: u32,
    /// Max |F − I|/|∇F| at the vertices before the step.
    pub residual: f32,
    /// Vertices moved back into their rings by the fold repair.
    pub repaired: u32,
    /// Spring energy ρ Σ g(l_e), g(l) = l³/(3R) − l²/2 (f64).
    pub energy: f64,
}

const REST_RECOVERY: f32 = 0.1;

/// Largest angle sum of a vertex's fan: 2π + π/2 (a saddle's excess at the
/// scale of R is far smaller; a fan wound twice has about 4π).
const MAX_FAN_ANGLE: f32 = 2.5 * std::f32::consts::PI;

/// A spring network on an implicit surface.
#[derive(Debug, Clone)]
pub struct Network {
    pub positions: Vec<Vec3>,
    /// Outward-wound triangles.
    pub triangles: Vec<[u32; 3]>,
    /// The target spring length R.
    pub rest: f32,
    /// Rest lengths R_ij that differ from R (curvature adaptation).
    rest_of: HashMap<(u32, u32), f32>,
    /// Lengths at the previous iteration (eq. 16).
    last_len: HashMap<(u32, u32), f32>,
    pub opts: NetworkOptions,
    /// Gradient guard g_min.
    pub g_min: f32,
    /// Iterations before the next surgery may run.
    cooldown: u32,
}

impl Network {
    /// A network on `mesh` (closed, manifold, wound outward) with target
    /// spring length `rest`; g_min = 1e-3 of the median |∇F| at the vertices.
    ///
    /// Errors: a mesh that is not a closed, consistently oriented 2-manifold,
    /// a non-positive rest length.
    pub fn new(
        mesh: &TriMesh,
        rest: f64,
        opts: NetworkOptions,
        field: &FieldInput,
    ) -> Result<Network> {
        if !(rest.is_finite() && rest > 0.0) {
            return Err(Error::param(
                "edge-length",
                rest,
                "must be positive and finite",
            ));
        }
        let net = Network {
            positions: mesh.positions.clone(),
            triangles: mesh.triangles.clone(),
            rest: rest as f32,
            rest_of: HashMap::new(),
            last_len: HashMap::new(),
            opts,
            g_min: 0.0,
            cooldown: 0,
        };
        net.check()?;
        let mut g: Vec<f32> = (net.positions.iter())
            .map(|p| Vec3::from_array(skeletal_field(field, p.to_array()).0.grad).length())
            .collect();
        g.sort_by(f32::total_cmp);
        Ok(Network {
            g_min: 1e-3 * g.get(g.len() / 2).copied().unwrap_or(1.0),
            ..net
        })
    }

    /// The network as a mesh.
    pub fn mesh(&self) -> TriMesh {
        TriMesh {
            positions: self.positions.clone(),
            triangles: self.triangles.clone(),
            scalars: Vec::new(),
        }
    }

    /// Errors unless the network is a closed, consistently oriented
    /// 2-manifold without unused vertices.
    pub fn check(&self) -> Result<Topology> {
        let t = Topology::of(&self.mesh());
        let bad = |problem: String| Error::InvalidData {
            what: "spring network".into(),
            at: crate::Position::Whole,
            problem,
        };
        if !t.closed || !t.is_manifold() || !t.consistently_oriented || t.collapsed_triangles > 0 {
            return Err(bad(format!(
                "not a closed, consistently oriented 2-manifold ({} boundary, {} non-manifold edges, {} non-manifold vertices, oriented {})",
                t.boundary_edges,
                t.nonmanifold_edges,
                t.nonmanifold_vertices,
                t.consistently_oriented
            )));
        }
        if let Some(v) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(bad(format!("vertex {v} is not finite")));
        }
        if t.used_vertices != t.vertices {
            return Err(bad(format!(
                "{} unused vertices",
                t.vertices - t.used_vertices
            )));
        }
        Ok(t)
    }

    /// Rest length of edge (a, b).
    pub fn rest_length(&self, a: u32, b: u32) -> f32 {
        self.rest_of.get(&key(a, b)).copied().unwrap_or(self.rest)
    }

    /// Sorted neighbours of every vertex.
    fn neighbours(&self) -> Vec<Vec<u32>> {
        let mut n = vec![Vec::new(); self.positions.len()];
        for t in &self.triangles {
            for k in 0..3 {
                n[t[k] as usize].push(t[(k + 1) % 3]);
                n[t[(k + 1) % 3] as usize].push(t[k]);
            }
        }
        for row in &mut n {
            row.sort_unstable();
            row.dedup();
        }
        n
    }

    /// The kernel's CSR: offsets and (neighbour, R_ij bits) rows.
    pub fn springs(&self) -> (Vec<u32>, Vec<[u32; 2]>) {
        let n = self.neighbours();
        let mut offsets = vec![0u32];
        let mut springs = Vec::new();
        for (i, row) in n.iter().enumerate() {
            for &j in row {
                springs.push([j, self.rest_length(i as u32, j).to_bits()]);
            }
            offsets.push(springs.len() as u32);
        }
        (offsets, springs)
    }

    /// Δt from a Gershgorin bound on the spring Jacobian:
    /// 0.9 / max_i Σ_j ρ·max(|1 − 2l/R|, |1 − l/R|), at most 0.3/ρ.
    fn dt(&self, offsets: &[u32], springs: &[[u32; 2]]) -> f32 {
        let rho = self.opts.rho as f32;
        let mut worst = 0.0f32;
        for i in 0..self.positions.len() {
            let mut sum = 0.0;
            for s in &springs[offsets[i] as usize..offsets[i + 1] as usize] {
                let l = self.positions[i].distance(self.positions[s[0] as usize]);
                let r = f32::from_bits(s[1]);
                sum += rho * (1.0 - 2.0 * l / r).abs().max((1.0 - l / r).abs());
            }
            worst = worst.max(sum);
        }
        (0.9 / worst.max(1e-30)).min(0.3 / rho)
    }

    /// One iteration: the step (scene time advancing by `delta` under
    /// `field`, the pose at the iteration's start), then curvature
    /// adaptation, collapses and splits.
    pub fn iterate(
        &mut self,
        field: &FieldInput,
        delta: f32,
        backend: Backend<'_>,
    ) -> Result<NetworkIteration> {
        let (offsets, springs) = self.springs();
        let positions: Vec<[f32; 4]> = self
            .positions
            .iter()
            .map(|p| [p.x, p.y, p.z, 0.0])
            .collect();
        let params = NetworkParams {
            n_vertices: u32::try_from(positions.len())
                .map_err(|_| Error::limit("network vertices", positions.len(), u32::MAX))?,
            dt: self.dt(&offsets, &springs),
            delta,
            kappa: self.opts.kappa as f32,
            rho: self.opts.rho as f32,
            g_min2: self.g_min * self.g_min,
            step_max: 0.5 * self.rest,
        };
        let input = NetworkInput {
            params,
            offsets: &offsets,
            springs: &springs,
            positions: &positions,
        };
        let (next, samples) = network_update(field, &input, backend)?;
        let mut it = NetworkIteration {
            residual: samples
                .iter()
                .map(|s| s[3].abs() / Vec3::new(s[0], s[1], s[2]).length().max(self.g_min))
                .fold(0.0, f32::max),
            ..NetworkIteration::default()
        };
        it.energy = self.energy();
        self.positions = next.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        it.repaired = self.repair_folds(field);
        if self.opts.theta > 0.0 {
            self.adapt_rest_lengths(&samples);
        } else {
            let r = self.rest;
            self.rest_of.retain(|_, v| {
                *v += REST_RECOVERY * (r - *v);
                (*v - r).abs() > 1e-3 * r
            });
        }
        self.remesh(&mut it);
        Ok(it)
    }

    /// Fold repair after the step: a vertex with a triangle facing against
    /// the field's outward normal (−∇F at its centre) or a fan wound more
    /// than once (angle sum > 2π + π/2) moves to the mean of its ring; up to
    /// three passes. Returns the vertices moved.
    fn repair_folds(&mut self, field: &FieldInput) -> u32 {
        let mut moved = 0;
        // Whether each triangle faces against −∇F at its centre; after the
        // first pass only triangles with a moved vertex are evaluated again.
        let mut against: Vec<bool> = (self.triangles.par_iter())
            .map(|t| faces_against(&self.positions, field, t))
            .collect();
        for _ in 0..3 {
            let mut bad = vec![false; self.positions.len()];
            let mut angle = vec![0.0f32; self.positions.len()];
            for (t, &wrong) in self.triangles.iter().zip(&against) {
                let [p, q, r] = t.map(|v| self.positions[v as usize]);
                if wrong {
                    for &v in t {
                        bad[v as usize] = true;
                    }
                }
                for k in 0..3 {
                    let (o, u, w) = ([p, q, r][k], [p, q, r][(k + 1) % 3], [p, q, r][(k + 2) % 3]);
                    angle[t[k] as usize] += (u - o).angle_between(w - o);
                }
            }
            let n = self.neighbours();
            let fix: Vec<(usize, Vec3)> = (0..self.positions.len())
                .filter(|&v| bad[v] || angle[v] > MAX_FAN_ANGLE)
                .map(|v| {
                    (
                        v,
                        n[v].iter()
                            .map(|&u| self.positions[u as usize])
                            .sum::<Vec3>()
                            / n[v].len().max(1) as f32,
                    )
                })
                .collect();
            if fix.is_empty() {
                break;
            }
            moved += fix.len() as u32;
            let mut touched = vec![false; self.positions.len()];
            for (v, p) in fix {
                self.positions[v] = p;
                touched[v] = true;
            }
            let positions = &self.positions;
            (self.triangles.par_iter().zip(&mut against))
                .filter(|(t, _)| t.iter().any(|&v| touched[v as usize]))
                .for_each(|(t, wrong)| *wrong = faces_against(positions, field, t));
        }
        moved
    }

    /// Spring energy ρ Σ_e (l³/(3R_e) − l²/2).
    pub fn energy(&self) -> f64 {
        let mut e = 0.0;
        for (i, row) in self.neighbours().iter().enumerate() {
            for &j in row.iter().filter(|&&j| j as usize > i) {
                let l = f64::from(self.positions[i].distance(self.positions[j as usize]));
                let r = f64::from(self.rest_length(i as u32, j));
                e += l * l * l / (3.0 * r) - l * l / 2.0;
            }
        }
        self.opts.rho * e
    }

    /// Eq. 17–23: R_ij ← clamp(R_ij + ϑΔ, R − λ_R, R + λ_R) with
    /// Δ = l(√((1 − cos θ̄)/(1 − cos θ)) − 1), θ the angle between the
    /// gradients at the spring's ends, θ̄ their mean over all springs; flat
    /// springs (1 − cos θ < 1e-6) go to R + λ_R.
    fn adapt_rest_lengths(&mut self, samples: &[[f32; 4]]) {
        let n: Vec<Vec3> = samples
            .iter()
            .map(|s| Vec3::new(s[0], s[1], s[2]).normalize_or_zero())
            .collect();
        let edges: Vec<(u32, u32)> = (self.neighbours().iter().enumerate())
            .flat_map(|(i, row)| {
                row.iter()
                    .filter(move |&&j| j as usize > i)
                    .map(move |&j| (i as u32, j))
            })
            .collect();
        if edges.is_empty() {
            return;
        }
        let cos: Vec<f64> = edges
            .iter()
            .map(|&(a, b)| f64::from(n[a as usize].dot(n[b as usize])))
            .collect();
        let mean = cos.iter().sum::<f64>() / cos.len() as f64;
        let (r, lam, theta) = (
            f64::from(self.rest),
            self.opts.lambda * f64::from(self.rest),
            self.opts.theta,
        );
        for (&(a, b), c) in edges.iter().zip(&cos) {
            let l = f64::from(self.positions[a as usize].distance(self.positions[b as usize]));
            let current = f64::from(self.rest_length(a, b));
            let target = if 1.0 - c < 1e-6 {
                r + lam
            } else {
                current + theta * l * (((1.0 - mean) / (1.0 - c)).max(0.0).sqrt() - 1.0)
            };
            self.rest_of
                .insert((a, b), target.clamp(r - lam, r + lam) as f32);
        }
    }

    /// Collapses (shortest first), then splits (longest first), skipping
    /// springs whose length changed by more than ε R (eq. 16) and vertices
    /// already touched in this iteration; compacts vertices and triangles.
    fn remesh(&mut self, it: &mut NetworkIteration) {
        let (dmin, dmax, eps) = (
            self.opts.d_min as f32,
            self.opts.d_max as f32,
            self.opts.epsilon as f32,
        );
        let mut lens: Vec<((u32, u32), f32)> = Vec::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a < b {
                    lens.push((
                        (a, b),
                        self.positions[a as usize].distance(self.positions[b as usize]),
                    ));
                }
            }
        }
        let steady = |e: &(u32, u32), l: f32, last: &HashMap<(u32, u32), f32>, rest: f32| {
            last.get(e)
                .is_none_or(|&prev| (prev - l).abs() <= eps * rest)
        };
        let mut ops = Ops::new(self);
        let mut touched: HashSet<u32> = HashSet::new();
        let mut short: Vec<((u32, u32), f32)> = (lens.iter())
            .filter(|(e, l)| {
                *l < dmin * self.rest_length(e.0, e.1) && steady(e, *l, &self.last_len, self.rest)
            })
            .copied()
            .collect();
        short.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        for ((a, b), _) in short {
            if touched.contains(&a) || touched.contains(&b) {
                continue;
            }
            match ops.collapse(self, a, b, dmax) {
                Some(ring) => {
                    it.collapses += 1;
                    touched.extend(ring);
                    touched.extend([a, b]);
                }
                None => it.refused += 1,
            }
        }
        let mut long: Vec<((u32, u32), f32)> = (lens.iter())
            .filter(|((a, b), _)| !ops.removed[*a as usize] && !ops.removed[*b as usize])
            .filter(|(e, l)| {
                *l > dmax * self.rest_length(e.0, e.1) && steady(e, *l, &self.last_len, self.rest)
            })
            .copied()
            .collect();
        long.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        for ((a, b), _) in long {
            if touched.contains(&a) || touched.contains(&b) {
                continue;
            }
            if let Some(m) = ops.split(self, a, b) {
                it.splits += 1;
                touched.extend([a, b, m]);
            }
        }
        self.compact(&ops.removed, &ops.dead);
        self.last_len = (self.triangles.iter())
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .filter(|(a, b)| a < b)
            .map(|(a, b)| {
                (
                    (a, b),
                    self.positions[a as usize].distance(self.positions[b as usize]),
                )
            })
            .collect();
    }

    /// Splits edge (a, b) at its midpoint; returns the new vertex.
    pub fn split(&mut self, a: u32, b: u32) -> Option<u32> {
        let mut ops = Ops::new(self);
        let m = ops.split(self, a, b)?;
        self.compact(&ops.removed, &ops.dead);
        Some(m)
    }

    /// Collapses edge (a, b) into a at the midpoint when the tests pass
    /// (module docs); vertices after b are renumbered down by one.
    pub fn collapse(&mut self, a: u32, b: u32) -> bool {
        let mut ops = Ops::new(self);
        let done = ops.collapse(self, a, b, self.opts.d_max as f32).is_some();
        self.compact(&ops.removed, &ops.dead);
        done
    }

    /// Drops the triangles marked `dead` and the vertices marked
    /// `removed`, renumbering the rest in order.
    fn compact(&mut self, removed: &[bool], dead: &[bool]) {
        if dead.iter().any(|&d| d) {
            let mut k = 0;
            self.triangles.retain(|_| {
                k += 1;
                !dead[k - 1]
            });
        }
        if !removed.iter().any(|&r| r) {
            return;
        }
        let mut map = vec![u32::MAX; removed.len()];
        let mut next = 0u32;
        let mut positions = Vec::with_capacity(self.positions.len());
        for (i, &r) in removed.iter().enumerate() {
            if !r {
                map[i] = next;
                next += 1;
                positions.push(self.positions[i]);
            }
        }
        self.positions = positions;
        for t in &mut self.triangles {
            *t = t.map(|v| map[v as usize]);
        }
        self.rest_of = (self.rest_of.drain())
            .filter(|((a, b), _)| map[*a as usize] != u32::MAX && map[*b as usize] != u32::MAX)
            .map(|((a, b), r)| (key(map[a as usize], map[b as usize]), r))
            .collect();
    }
}

/// Local operations with the vertex → triangle adjacency kept up to date;
/// triangles are marked dead and vertices removed, both dropped by
/// [`Network::compact`] afterwards.
struct Ops {
    /// Live triangles of each vertex.
    vt: Vec<Vec<usize>>,
    dead: Vec<bool>,
    removed: Vec<bool>,
}

impl Ops {
    fn new(net: &Network) -> Ops {
        let mut vt = vec![Vec::new(); net.positions.len()];
        for (i, t) in net.triangles.iter().enumerate() {
            for &v in t {
                vt[v as usize].push(i);
            }
        }
        Ops {
            vt,
            dead: vec![false; net.triangles.len()],
            removed: vec![false; net.positions.len()],
        }
    }

    /// The two triangles of edge (a, b): (the one with a → b, apex c),
    /// (the one with b → a, apex d).
    fn edge_triangles(
        &self,
        net: &Network,
        a: u32,
        b: u32,
    ) -> Option<((usize, u32), (usize, u32))> {
        let mut ab = None;
        let mut ba = None;
        for &i in &self.vt[a as usize] {
            let t = net.triangles[i];
            for k in 0..3 {
                let (x, y, z) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                if (x, y) == (a, b) {
                    ab = Some((i, z));
                } else if (x, y) == (b, a) {
                    ba = Some((i, z));
                }
            }
        }
        Some((ab?, ba?))
    }

    /// Sorted neighbours of `v`.
    fn neighbours(&self, net: &Network, v: u32) -> Vec<u32> {
        let mut n: Vec<u32> = (self.vt[v as usize].iter())
            .flat_map(|&i| net.triangles[i])
            .filter(|&u| u != v)
            .collect();
        n.sort_unstable();
        n.dedup();
        n
    }

    fn split(&mut self, net: &mut Network, a: u32, b: u32) -> Option<u32> {
        let ((t1, c), (t2, d)) = self.edge_triangles(net, a, b)?;
        let m = net.positions.len() as u32;
        net.positions
            .push(0.5 * (net.positions[a as usize] + net.positions[b as usize]));
        self.removed.push(false);
        let r = net.rest_length(a, b);
        if r != net.rest {
            net.rest_of.insert(key(a, m), r);
            net.rest_of.insert(key(m, b), r);
        }
        let (t3, t4) = (net.triangles.len(), net.triangles.len() + 1);
        net.triangles[t1] = [a, m, c];
        net.triangles[t2] = [b, m, d];
        net.triangles.push([m, b, c]);
        net.triangles.push([m, a, d]);
        self.dead.extend([false, false]);
        self.vt.push(vec![t1, t2, t3, t4]);
        self.vt[b as usize].retain(|&t| t != t1);
        self.vt[b as usize].push(t3);
        self.vt[a as usize].retain(|&t| t != t2);
        self.vt[a as usize].push(t4);
        self.vt[c as usize].push(t3);
        self.vt[d as usize].push(t4);
        Some(m)
    }

    fn collapse(&mut self, net: &mut Network, a: u32, b: u32, dmax: f32) -> Option<Vec<u32>> {
        let ((t1, c), (t2, d)) = self.edge_triangles(net, a, b)?;
        let (na, nb) = (self.neighbours(net, a), self.neighbours(net, b));
        let common: Vec<u32> = na.iter().filter(|x| nb.contains(x)).copied().collect();
        if common.len() != 2 || !common.contains(&c) || !common.contains(&d) || c == d {
            return None;
        }
        if self.vt[c as usize].len() <= 3
            || self.vt[d as usize].len() <= 3
            || na.len() + nb.len() - 4 < 3
        {
            return None;
        }
        let mid = 0.5 * (net.positions[a as usize] + net.positions[b as usize]);
        let limit = dmax * net.rest;
        if na
            .iter()
            .chain(&nb)
            .any(|&v| v != a && v != b && net.positions[v as usize].distance(mid) > limit)
        {
            return None;
        }
        // No surviving triangle of a or b turns by more than 45° or degenerates.
        let cos_max = crate::mesh::collapse::MAX_TURN_DEGREES.to_radians().cos();
        let moved = |v: u32| {
            if v == a || v == b {
                mid
            } else {
                net.positions[v as usize]
            }
        };
        for &i in self.vt[a as usize].iter().chain(&self.vt[b as usize]) {
            if i == t1 || i == t2 {
                continue;
            }
            let t = net.triangles[i];
            let [p, q, r] = t.map(|v| net.positions[v as usize]);
            let old = (q - p).cross(r - p);
            let [p, q, r] = t.map(moved);
            let new = (q - p).cross(r - p);
            if new.length() == 0.0 || old.normalize_or_zero().dot(new.normalize_or_zero()) < cos_max
            {
                return None;
            }
        }
        // The merged fan must wind once: its angles at the midpoint sum to
        // less than 2π + π/2 (a fan wound twice overlaps itself in the surface).
        let angle_sum: f32 = (self.vt[a as usize].iter().chain(&self.vt[b as usize]))
            .filter(|&&i| i != t1 && i != t2)
            .map(|&i| {
                let t = net.triangles[i];
                let k = t.iter().position(|&v| v == a || v == b).unwrap_or(0);
                let (p, q) = (moved(t[(k + 1) % 3]), moved(t[(k + 2) % 3]));
                (p - mid).angle_between(q - mid)
            })
            .sum();
        if angle_sum > MAX_FAN_ANGLE {
            return None;
        }
        net.positions[a as usize] = mid;
        let mut ring: Vec<u32> = na.iter().chain(&nb).copied().collect();
        ring.sort_unstable();
        ring.dedup();
        for i in std::mem::take(&mut self.vt[b as usize]) {
            if i == t1 || i == t2 {
                continue;
            }
            for v in net.triangles[i].iter_mut() {
                if *v == b {
                    *v = a;
                }
            }
            self.vt[a as usize].push(i);
        }
        for t in [t1, t2] {
            self.dead[t] = true;
            for v in net.triangles[t] {
                self.vt[v as usize].retain(|&x| x != t);
            }
        }
        self.removed[b as usize] = true;
        for v in ring.iter().copied().filter(|&v| v != a && v != b) {
            if let Some(r) = net.rest_of.remove(&key(b, v)) {
                net.rest_of.entry(key(a, v)).or_insert(r);
            }
        }
        Some(ring)
    }
}
