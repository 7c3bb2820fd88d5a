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

use std::collections::{HashMap, HashSet};

use glam::Vec3;

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
        }
    }
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

/// Iterations after a merge before the next surgery: the fresh strip
/// settles onto the surface first (right after a merge it spans a neck
/// thinner than its loops and would otherwise be cut again).
pub const SURGERY_COOLDOWN: u32 = 10;

/// Per iteration, rest lengths set by a surgery move this fraction of the
/// way back to R (when the curvature adaptation is off).
const REST_RECOVERY: f32 = 0.1;

/// Largest angle sum of a vertex's fan: 2π + π/2 (a saddle's excess at the
/// scale of R is far smaller; a fan wound twice has about 4π).
const MAX_FAN_ANGLE: f32 = 2.5 * std::f32::consts::PI;

/// A vertex's side before dilation (dilated marks, ±2, count as 0).
fn side_of(side: &[i8], v: u32) -> i8 {
    let s = side[v as usize];
    if s.abs() == 1 { s } else { 0 }
}

/// Combines the sides of a triangle's vertices: inside (1) wins, then outside (−1).
fn merge_side(m: i8, x: i8) -> i8 {
    if x == 1 || m == 1 { 1 } else { m.min(x) }
}

/// What one [`Network::surgery`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct Surgery {
    /// Triangles removed around stranded and submerged vertices.
    pub removed_triangles: u32,
    /// Loops closed by a fan.
    pub caps: u32,
    /// Pairs of loops joined by a strip.
    pub bridges: u32,
    /// Surgeries not done (loops not simple, or a result that is not a
    /// closed oriented manifold); retried at the next iteration.
    pub refused: u32,
    /// Stranded or submerged vertices moved onto the surface instead, where
    /// closing their region again would not change the topology.
    pub projected: u32,
}

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
        for _ in 0..3 {
            let mut bad = vec![false; self.positions.len()];
            let mut angle = vec![0.0f32; self.positions.len()];
            for t in &self.triangles {
                let [p, q, r] = t.map(|v| self.positions[v as usize]);
                let n = (q - p).cross(r - p);
                let (f, _) = skeletal_field(field, ((p + q + r) / 3.0).to_array());
                if n.dot(-Vec3::from_array(f.grad)) <= 0.0 {
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
            for (v, p) in fix {
                self.positions[v] = p;
            }
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

    /// Topology surgery where the surface left the network behind
    /// (`docs/design/particles.md` §4). A vertex is **stranded** when it is
    /// more than R/2 outside the surface, (I − F)/|∇F| > R/2 (a neck that
    /// broke leaves its ring in the gap), and **submerged** when more than
    /// R/2 inside, or one of a facing pair whose midpoint is inside (two
    /// parts that met, or a part touching itself). The
    /// triangles of such vertices are removed, and the boundary loops left
    /// are closed again: two loops around submerged regions that face each
    /// other (opposite mean normals, centres within 4R) are **bridged** by a
    /// strip (χ − 2, the merge the seed leaves open), every other loop is
    /// **capped** by a fan around a new centre vertex (a neck cut: χ + 2 for
    /// the two caps, the seed's step 3) when the field between any two cap
    /// centres leaves the inside somewhere. A surgery is kept only when it
    /// changes the components or their genus and leaves a closed,
    /// consistently oriented manifold; otherwise the mesh stays and the
    /// marked vertices are moved onto the surface by Newton steps.
    pub fn surgery(&mut self, field: &FieldInput) -> Surgery {
        if self.cooldown > 0 {
            self.cooldown -= 1;
            return Surgery::default();
        }
        let half = 0.5 * self.rest;
        let samples: Vec<(f32, Vec3)> = (self.positions.iter())
            .map(|p| {
                let (f, _) = skeletal_field(field, p.to_array());
                (f.value, Vec3::from_array(f.grad))
            })
            .collect();
        let mut side: Vec<i8> = (samples.iter())
            .map(|(value, grad)| {
                let d = value / grad.length().max(self.g_min);
                if d < -half {
                    -1
                } else if d > half {
                    1
                } else {
                    0
                }
            })
            .collect();
        self.mark_facing_pairs(field, &samples, &mut side);
        if side.iter().all(|&s| s == 0) {
            return Surgery::default();
        }
        let before = (self.positions.clone(), self.triangles.clone());
        let shape = |t: &Topology| {
            let mut g: Vec<Option<i64>> = t.components.iter().map(|c| c.genus).collect();
            g.sort_unstable();
            g
        };
        let topology_before = shape(&self.check().expect("the network is kept a closed manifold"));
        match self.reclose(&side, field) {
            Some(done) if self.check().is_ok_and(|t| shape(&t) != topology_before) => {
                if done.bridges > 0 {
                    self.cooldown = SURGERY_COOLDOWN;
                }
                done
            }
            result => {
                // No topology change (or none possible yet): keep the mesh
                // and move the stranded and submerged vertices onto the
                // surface instead.
                (self.positions, self.triangles) = before;
                let mut projected = 0;
                for (v, &sd) in side.iter().enumerate() {
                    if sd != 0 {
                        self.positions[v] = self.project(field, self.positions[v]);
                        projected += 1;
                    }
                }
                Surgery {
                    refused: u32::from(result.is_none()),
                    projected,
                    ..Surgery::default()
                }
            }
        }
    }

    /// `x` moved onto the surface by Newton steps along ∇F (at most R
    /// each, 20 of them).
    fn project(&self, field: &FieldInput, mut x: Vec3) -> Vec3 {
        for _ in 0..20 {
            let (f, _) = skeletal_field(field, x.to_array());
            let g = Vec3::from_array(f.grad);
            let step = -f.value / g.length_squared().max(self.g_min * self.g_min) * g;
            x += step.clamp_length_max(self.rest);
            if step.length() < 1e-4 * self.rest {
                break;
            }
        }
        x
    }

    /// Marks as submerged the vertices of **facing pairs**: i, j not joined
    /// by an edge, closer than 2R, with opposite outward normals
    /// (n_i·n_j < −½), j in front of i ((p_j − p_i)·n_i > 0), and the field
    /// inside between them (F(mid) > I): two sheets of the network that the
    /// surface has joined.
    fn mark_facing_pairs(&self, field: &FieldInput, samples: &[(f32, Vec3)], side: &mut [i8]) {
        let reach = 2.0 * self.rest;
        let Ok(cells) = super::CellList::build(&self.positions, reach, 0.0) else {
            return;
        };
        let n = self.neighbours();
        let normal = |i: usize| -samples[i].1.normalize_or_zero();
        for i in 0..self.positions.len() {
            let (pi, ni) = (self.positions[i], normal(i));
            for j in cells.candidates(i).filter(|&j| j > i) {
                let pj = self.positions[j];
                if pi.distance_squared(pj) >= reach * reach
                    || ni.dot(normal(j)) >= -0.5
                    || (pj - pi).dot(ni) <= 0.0
                    || n[i].binary_search(&(j as u32)).is_ok()
                {
                    continue;
                }
                if skeletal_field(field, (0.5 * (pi + pj)).to_array()).0.value > 0.0 {
                    side[i] = 1;
                    side[j] = 1;
                }
            }
        }
    }

    /// Removes the triangles of stranded and submerged vertices and closes
    /// the loops (see [`Network::surgery`]); `None` for loops that are not simple.
    fn reclose(&mut self, side: &[i8], field: &FieldInput) -> Option<Surgery> {
        let mut out = Surgery::default();
        // Which kind of removal each removed triangle is (inside wins).
        // Dilate by one ring: the removed region's border vertices join it,
        // so that its loops run through surface that is still well sampled.
        let mut side = side.to_vec();
        for t in &self.triangles {
            let s = t.iter().map(|&v| side_of(&side, v)).fold(0i8, merge_side);
            if s != 0 {
                for &v in t {
                    if side[v as usize] == 0 {
                        side[v as usize] = 2 * s;
                    }
                }
            }
        }
        let mut kind: Vec<i8> = (self.triangles.iter())
            .map(|t| {
                t.iter()
                    .map(|&v| side[v as usize].signum())
                    .fold(0i8, merge_side)
            })
            .collect();
        // Grow the region over pinch vertices (two boundary edges leaving
        // one vertex) until every loop is simple, at most 10 rounds.
        let mut next: HashMap<u32, u32> = HashMap::new();
        for round in 0..=10 {
            let directed: HashSet<(u32, u32)> = (self.triangles.iter().zip(&kind))
                .filter(|(_, k)| **k == 0)
                .flat_map(|(t, _)| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
                .collect();
            next.clear();
            let mut pinches: Vec<u32> = Vec::new();
            for &(u, v) in &directed {
                if !directed.contains(&(v, u)) && next.insert(u, v).is_some() {
                    pinches.push(u);
                }
            }
            if pinches.is_empty() {
                break;
            }
            if round == 10 {
                return None;
            }
            for (t, k) in self.triangles.iter().zip(kind.iter_mut()) {
                if *k == 0 && t.iter().any(|v| pinches.contains(v)) {
                    *k = -1;
                }
            }
        }
        let mut kind_of_removed: HashMap<(u32, u32), i8> = HashMap::new();
        let mut kept = Vec::with_capacity(self.triangles.len());
        for (t, &k) in self.triangles.iter().zip(&kind) {
            if k == 0 {
                kept.push(*t);
            } else {
                for e in 0..3 {
                    kind_of_removed.insert((t[e], t[(e + 1) % 3]), k);
                }
            }
        }
        out.removed_triangles = (self.triangles.len() - kept.len()) as u32;
        let mut loops: Vec<Vec<u32>> = Vec::new();
        let mut seen: HashSet<u32> = HashSet::new();
        let mut starts: Vec<u32> = next.keys().copied().collect();
        starts.sort_unstable();
        for s in starts {
            if seen.contains(&s) {
                continue;
            }
            let mut lp = vec![s];
            seen.insert(s);
            let mut v = *next.get(&s)?;
            while v != s {
                if !seen.insert(v) {
                    return None;
                }
                lp.push(v);
                v = *next.get(&v)?;
            }
            loops.push(lp);
        }
        self.triangles = kept;
        // Each loop's kind: the removed triangle across its first edge.
        let kinds: Vec<i8> = (loops.iter())
            .map(|l| {
                kind_of_removed
                    .get(&(l[1 % l.len()], l[0]))
                    .copied()
                    .unwrap_or(-1)
            })
            .collect();
        let centre =
            |l: &[u32], p: &[Vec3]| l.iter().map(|&v| p[v as usize]).sum::<Vec3>() / l.len() as f32;
        let normal = |l: &[u32], p: &[Vec3]| {
            let c = centre(l, p);
            (0..l.len())
                .map(|k| (p[l[k] as usize] - c).cross(p[l[(k + 1) % l.len()] as usize] - c))
                .sum::<Vec3>()
                .normalize_or_zero()
        };
        // Pair facing submerged loops, closest centres first.
        let inside: Vec<usize> = (0..loops.len()).filter(|&i| kinds[i] == 1).collect();
        let mut pairs: Vec<(f32, usize, usize)> = Vec::new();
        for (x, &i) in inside.iter().enumerate() {
            for &j in &inside[x + 1..] {
                let d =
                    centre(&loops[i], &self.positions).distance(centre(&loops[j], &self.positions));
                let facing = normal(&loops[i], &self.positions)
                    .dot(normal(&loops[j], &self.positions))
                    < -0.5;
                if facing && d < 4.0 * self.rest {
                    pairs.push((d, i, j));
                }
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut used = vec![false; loops.len()];
        for (_, i, j) in pairs {
            if used[i] || used[j] {
                continue;
            }
            used[i] = true;
            used[j] = true;
            let strip = self.bridge(&loops[i], &loops[j]);
            for t in strip {
                for k in 0..3 {
                    let (u, v) = (t[k], t[(k + 1) % 3]);
                    let l = self.positions[u as usize].distance(self.positions[v as usize]);
                    if l > self.rest {
                        self.rest_of.insert(key(u, v), l);
                    }
                }
            }
            out.bridges += 1;
        }
        let mut centres = Vec::new();
        for (i, l) in loops.iter().enumerate() {
            if !used[i] {
                self.cap(l, field);
                centres.push(*self.positions.last().expect("the cap's centre"));
                out.caps += 1;
            }
        }
        // A cut must follow the field: between any two cap centres the
        // segment leaves the inside somewhere (else a thin neck that still
        // exists, say a bond the network lags behind, would be cut).
        for (i, a) in centres.iter().enumerate() {
            for b in &centres[i + 1..] {
                let joined = (1..16).all(|k| {
                    let x = a.lerp(*b, k as f32 / 16.0);
                    skeletal_field(field, x.to_array()).0.value > 0.0
                });
                if joined {
                    return None;
                }
            }
        }
        // Drop vertices no triangle uses any more.
        let mut used_v = vec![false; self.positions.len()];
        for t in &self.triangles {
            for &v in t {
                used_v[v as usize] = true;
            }
        }
        let removed: Vec<bool> = used_v.iter().map(|u| !u).collect();
        self.compact(&removed, &[]);
        Some(out)
    }

    /// Closes the boundary loop `l` (in boundary direction) by a fan around
    /// a new vertex: the loop's centre, moved onto the surface by Newton
    /// steps along ∇F (at most R each, 20 of them).
    fn cap(&mut self, l: &[u32], field: &FieldInput) {
        let c = self.positions.len() as u32;
        let centre = l.iter().map(|&v| self.positions[v as usize]).sum::<Vec3>() / l.len() as f32;
        let x = self.project(field, centre);
        self.positions.push(x);
        for k in 0..l.len() {
            // The loop runs u → v on the kept side, so the cap uses v → u.
            self.triangles.push([l[(k + 1) % l.len()], l[k], c]);
        }
    }

    /// Joins the boundary loops `a` and `b` (each in boundary direction) by
    /// a strip of #a + #b triangles: walking `a` forward and `b` backward
    /// from their closest vertices, always adding the shorter diagonal.
    fn bridge(&mut self, a: &[u32], b: &[u32]) -> Vec<[u32; 3]> {
        let p = |v: u32| self.positions[v as usize];
        let (m, n) = (a.len(), b.len());
        let (mut i0, mut j0, mut best) = (0, 0, f32::INFINITY);
        for (i, &u) in a.iter().enumerate() {
            for (j, &w) in b.iter().enumerate() {
                let d = p(u).distance_squared(p(w));
                if d < best {
                    (i0, j0, best) = (i, j, d);
                }
            }
        }
        let ua = |k: usize| a[(i0 + k) % m];
        let wb = |k: usize| b[(j0 + n - k % n) % n];
        let (mut i, mut j) = (0, 0);
        let mut strip = Vec::with_capacity(m + n);
        while i < m || j < n {
            let advance_a = j == n
                || (i < m && p(ua(i + 1)).distance(p(wb(j))) <= p(ua(i)).distance(p(wb(j + 1))));
            if advance_a {
                strip.push([ua(i + 1), ua(i), wb(j)]);
                i += 1;
            } else {
                strip.push([ua(i), wb(j), wb(j + 1)]);
                j += 1;
            }
        }
        self.triangles.extend(&strip);
        strip
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
