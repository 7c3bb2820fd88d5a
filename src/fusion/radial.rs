//! Radial functions from ray casts, and the laws that combine them.
//!
//! ρ_A(d) is the distance from H to A's surface along the unit direction d:
//! the one hit of the ray H + t·d on A. A ray with another hit count means
//! A is not star-shaped about H along d (or H is outside A, or A is open
//! there); every such ray is collected and the projection refused.

use glam::Vec3;

use super::sphere::{Project, Projected};
use crate::mesh::TriMesh;
use crate::ray_cast::{RayCaster, RayHit};
use crate::{Refusal, Result};

/// How C's radial function follows from A's and B's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law {
    /// Fusion, eq. 5: ρ³ = ρ_A³ + ρ_B³.
    Sum,
    /// Subtraction: ρ³ = ρ_A³ − ρ_B³ (defined where ρ_A > ρ_B).
    Difference,
    /// Morph, eq. 8: ρ³ = (1 − t)·ρ_A³ + t·ρ_B³.
    Morph(f64),
}

impl Law {
    /// ρ from ρ_A and ρ_B, `None` where the law is undefined.
    pub fn rho(self, ra: f64, rb: f64) -> Option<f64> {
        let (a3, b3) = (ra * ra * ra, rb * rb * rb);
        let c3 = match self {
            Law::Sum => a3 + b3,
            Law::Difference => a3 - b3,
            Law::Morph(t) => (1.0 - t) * a3 + t * b3,
        };
        (c3 > 0.0).then(|| c3.cbrt())
    }
}

/// One output frame: the centre H and the law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub center: Vec3,
    pub law: Law,
}

/// Most example rays a refusal lists.
pub(super) const EXAMPLES: usize = 8;

/// Radial projection of directions onto C for each frame: casts the rays
/// of each distinct centre against A and B.
#[derive(Debug)]
pub struct Radial<'a> {
    /// A with its caster.
    pub a: (&'a TriMesh, &'a RayCaster<'a>),
    /// B with its caster.
    pub b: (&'a TriMesh, &'a RayCaster<'a>),
    pub frames: Vec<Frame>,
    /// Rays cast so far (both meshes).
    pub rays: usize,
}

/// The distances along the unit directions `dirs` from the hits, checking
/// that every ray crossed the mesh once.
fn radii(mesh: &'static str, center: Vec3, dirs: &[[f32; 4]], hits: &[RayHit]) -> Result<Vec<f64>> {
    let failing: Vec<usize> = (0..hits.len()).filter(|&i| hits[i].count != 1).collect();
    if !failing.is_empty() {
        return Err(Refusal::NotStarShaped {
            mesh,
            center: center.as_dvec3().to_array(),
            failing: failing.len(),
            rays: hits.len(),
            examples: failing
                .iter()
                .take(EXAMPLES)
                .map(|&i| ([dirs[i][0], dirs[i][1], dirs[i][2]], hits[i].count))
                .collect(),
        }
        .into());
    }
    Ok(hits
        .iter()
        .zip(dirs)
        .map(|(h, d)| f64::from(h.far) * Vec3::new(d[0], d[1], d[2]).as_dvec3().length())
        .collect())
}

/// Unit normal of triangle `t` of `m` (0 for a zero-area one).
fn face_normal(m: &TriMesh, t: u32) -> Vec3 {
    let [a, b, c] = m.triangles[t as usize].map(|v| m.positions[v as usize]);
    (b - a).cross(c - a).normalize_or_zero()
}

/// One centre's rays: ρ_A, ρ_B and the normals of the faces crossed.
struct Radii {
    center: Vec3,
    a: Vec<f64>,
    b: Vec<f64>,
    faces: Vec<[Vec3; 2]>,
}

impl Radial<'_> {
    /// ρ_A and ρ_B along `dirs` from `center`, with the faces crossed.
    fn radii(&mut self, center: Vec3, dirs: &[[f32; 4]]) -> Result<Radii> {
        let ha = self.a.1.cast(center, dirs)?;
        let hb = self.b.1.cast(center, dirs)?;
        self.rays += ha.len() + hb.len();
        let (ra, rb) = (
            radii("A", center, dirs, &ha)?,
            radii("B", center, dirs, &hb)?,
        );
        let faces = ha
            .iter()
            .zip(&hb)
            .map(|(x, y)| {
                [
                    face_normal(self.a.0, x.near_tri),
                    face_normal(self.b.0, y.near_tri),
                ]
            })
            .collect();
        Ok(Radii {
            center,
            a: ra,
            b: rb,
            faces,
        })
    }
}

impl Project for Radial<'_> {
    fn project(&mut self, dirs: &[[f32; 4]]) -> Result<Projected> {
        let mut out = Projected::default();
        let mut cached: Option<Radii> = None;
        for k in 0..self.frames.len() {
            let Frame { center, law } = self.frames[k];
            if cached.as_ref().is_none_or(|c| c.center != center) {
                let r = self.radii(center, dirs)?;
                if k == 0 {
                    out.faces = r.faces.clone();
                }
                cached = Some(r);
            }
            let Radii { a: ra, b: rb, .. } = cached.as_ref().expect("cached above");
            let h = center.as_dvec3();
            let mut points = Vec::with_capacity(dirs.len());
            let mut failing = Vec::new();
            for (i, d) in dirs.iter().enumerate() {
                let u = Vec3::new(d[0], d[1], d[2]).as_dvec3().normalize();
                match law.rho(ra[i], rb[i]) {
                    Some(r) => points.push(h + r * u),
                    None => {
                        failing.push(i);
                        points.push(h);
                    }
                }
            }
            if !failing.is_empty() {
                return Err(Refusal::SubtractionReachesOut {
                    failing: failing.len(),
                    rays: dirs.len(),
                    examples: failing
                        .iter()
                        .take(EXAMPLES)
                        .map(|&i| [dirs[i][0], dirs[i][1], dirs[i][2]])
                        .collect(),
                }
                .into());
            }
            out.points.push(points);
        }
        Ok(out)
    }
}
