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
mod remesh;
mod surgery;

pub use surgery::{SURGERY_COOLDOWN, Surgery};

use std::collections::HashMap;

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
}
