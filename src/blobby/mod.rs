//! Blobby models fitted to range scans (SPEC §3.5, seed 001 §3.2–3.5;
//! Muraki 1991).
//!
//! A blobby model is V(x) = Σ_k b_k exp(−a_k |x − c_k|²) with surface
//! V = T: the implicit room's blobby influence around point skeletons, so
//! a model is a scene of `Skeleton::Point` + `Influence::Blobby` primitives
//! under the sum blend. Five unknowns per primitive: c, a > 0 and b
//! (negative b carves).
//!
//! ```text
//!  range points (x_j, n_j) + Model + Weights
//!        │ energy::EnergyInput (flat rows)
//!        ▼
//!  blobby_energy (CPU mirror energy::cpu / GPU energy::gpu):
//!        per-workgroup rows of Σ e_j/M and ∂/∂(c, a, b)
//!        │ host: rows added in f64, + β E_shrink
//!        ▼
//!  Energy { total, data, shrink, gradient }
//! ```
//!
//! E = (E_value + α E_normal)/M + β E_shrink (eq. 22) with E_value =
//! Σ (V(x_j) − T)² (eq. 16), E_normal = Σ |n_j − N/|N||², N = −∇V
//! (eq. 17–19), E_shrink = (Σ a_k^{−3/2} |b_k|)² (eq. 21). Eq. 20 misprints
//! a primitive's mass: ∫ b exp(−a r²) dx = b (π/a)^{3/2}, which is what
//! eq. 21's a^{−3/2}|b| measures. Design notes: `docs/design/blobby.md`.

pub mod energy;
pub mod fit;

use glam::DVec3;

use crate::gpu::Backend;
use crate::{Error, Result, TriMesh};

/// One primitive b·exp(−a |x − c|²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blob {
    pub centre: DVec3,
    /// Decay a > 0.
    pub a: f64,
    /// Strength b (negative carves).
    pub b: f64,
}

impl Blob {
    /// b·exp(−a |x − c|²).
    pub fn value(&self, x: DVec3) -> f64 {
        self.b * (-self.a * (x - self.centre).length_squared()).exp()
    }

    /// The mass ∫ b exp(−a r²) dx = b (π/a)^{3/2}.
    pub fn mass(&self) -> f64 {
        self.b * (std::f64::consts::PI / self.a).powf(1.5)
    }
}

/// A blobby model: primitives and the iso value T.
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    pub iso: f64,
    pub blobs: Vec<Blob>,
}

impl Model {
    /// V(x).
    pub fn value(&self, x: DVec3) -> f64 {
        self.blobs.iter().map(|b| b.value(x)).sum()
    }

    /// ∇V(x).
    pub fn gradient(&self, x: DVec3) -> DVec3 {
        (self.blobs.iter())
            .map(|b| -2.0 * b.a * b.value(x) * (x - b.centre))
            .sum()
    }

    /// The model with primitive `k` split into two at its centre with
    /// b/2 each: V, and with it every energy term, is unchanged (the
    /// fitter then moves the pair apart).
    pub fn split(&self, k: usize) -> Model {
        let mut out = self.clone();
        let half = Blob {
            b: 0.5 * self.blobs[k].b,
            ..self.blobs[k]
        };
        out.blobs[k] = half;
        out.blobs.insert(k + 1, half);
        out
    }
}

impl Model {
    /// The model as a scene file of the implicit room (`chisel implicit`
    /// reads it): the iso value, the sum blend and one point primitive with
    /// a blobby influence per blob; numbers in Rust's shortest round-trip
    /// form, so reading it back gives the same f64 values.
    pub fn to_scene_toml(&self, comment: &str) -> String {
        let mut out = String::new();
        for line in comment.lines() {
            out.push_str(&format!("# {line}\n"));
        }
        out.push_str(&format!("iso = {:?}\nblend = \"sum\"\n", self.iso));
        for b in &self.blobs {
            let c = b.centre;
            out.push_str(&format!(
                "[[primitive]]\nskeleton = {{ point = [{:?}, {:?}, {:?}] }}\ninfluence = {{ blobby = {{ a = {:?}, b = {:?} }} }}\n",
                c.x, c.y, c.z, b.a, b.b
            ));
        }
        out
    }
}

/// The weights of eq. 22.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Weights {
    /// α, the normal term's weight.
    pub alpha: f64,
    /// β, the shrink term's weight.
    pub beta: f64,
}

/// Range points with unit normals (pointing out of the object).
#[derive(Debug, Clone, PartialEq)]
pub struct RangePoints {
    pub positions: Vec<DVec3>,
    pub normals: Vec<DVec3>,
}

impl RangePoints {
    /// Points with normals; normals are normalised.
    ///
    /// Errors: no points, different counts, a non-finite coordinate, a
    /// zero normal (with the index of the first such point).
    pub fn new(positions: Vec<DVec3>, normals: Vec<DVec3>) -> Result<RangePoints> {
        if positions.is_empty() {
            return Err(Error::empty("range points"));
        }
        if positions.len() != normals.len() {
            return Err(Error::mismatch(
                "range points: normals",
                positions.len(),
                normals.len(),
            ));
        }
        let mut unit = Vec::with_capacity(normals.len());
        for (j, (p, n)) in positions.iter().zip(&normals).enumerate() {
            let len = n.length();
            if !(p.is_finite() && len.is_finite() && len > 0.0) {
                return Err(Error::param(
                    "range points",
                    format!("point {j}: {p}, normal {n}"),
                    "finite positions and non-zero finite normals",
                ));
            }
            unit.push(*n / len);
        }
        Ok(RangePoints {
            positions,
            normals: unit,
        })
    }

    /// The vertices of `mesh` with its area-weighted vertex normals
    /// (following the winding: wind the scan outward). Vertices without
    /// area (unused, or only in degenerate triangles) are left out.
    pub fn from_mesh(mesh: &TriMesh) -> Result<RangePoints> {
        let normals = crate::vertex_normals::vertex_normals(mesh, Backend::Cpu)?;
        let (positions, normals): (Vec<DVec3>, Vec<DVec3>) = (mesh.positions.iter())
            .zip(&normals)
            .filter(|(_, n)| n[0] != 0.0 || n[1] != 0.0 || n[2] != 0.0)
            .map(|(p, n)| {
                (
                    p.as_dvec3(),
                    DVec3::new(f64::from(n[0]), f64::from(n[1]), f64::from(n[2])),
                )
            })
            .unzip();
        RangePoints::new(positions, normals)
    }

    /// Turns every normal around when most of them point towards the
    /// points' centroid: a scan of one side of an object (a face) or a
    /// closed surface then has outward normals whatever its winding.
    /// Returns whether the normals were turned.
    pub fn orient_outward(&mut self) -> bool {
        let (centre, _) = self.centroid_spread();
        let inward = (self.positions.iter().zip(&self.normals))
            .filter(|(x, n)| (**x - centre).dot(**n) < 0.0)
            .count();
        let turn = 2 * inward > self.len();
        if turn {
            for n in &mut self.normals {
                *n = -*n;
            }
        }
        turn
    }

    /// The points' centroid and their mean squared distance from it.
    pub fn centroid_spread(&self) -> (DVec3, f64) {
        let m = self.len() as f64;
        let centre = self.positions.iter().sum::<DVec3>() / m;
        let r2 = (self.positions.iter())
            .map(|p| (*p - centre).length_squared())
            .sum::<f64>()
            / m;
        (centre, r2)
    }

    /// The diagonal of the points' bounding box.
    pub fn diagonal(&self) -> f64 {
        let (lo, hi) = (self.positions.iter())
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        (hi - lo).length()
    }

    /// Number of points M.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether there are none (never, for a constructed set).
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }
}
