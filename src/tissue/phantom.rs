//! Generated inputs for the tissue model: the demo's CT-like head volume
//! (soft tissue over a skull whose mandible is fused to it at the joints)
//! with its osteotomy plan, a mesh head phantom (skin over a skull with a
//! separable jaw), example plans for `fran_cut` and `headsq`, and
//! refinement of structured scan grids (the benchmark networks).
//!
//! Conventions of the phantom: millimetres, +y up, +z anterior (the face),
//! +x the patient's left.

use std::f32::consts::PI;

use glam::Vec3;
use rayon::prelude::*;

use super::fragments::Fragments;
use super::plan::Plan;
use crate::mesh::TriMesh;
use crate::volume::{Volume, VolumeData};
use crate::{Error, Result};

/// The demo's plan on [`ct_head_phantom`]: a plane osteotomy through both
/// rami frees the mandible (`[[cut]]` "jaw"), which advances 6 mm.
pub const CT_DEMO_PLAN_TOML: &str = include_str!("plans/ct_phantom_jaw_advance.toml");
/// Chin advance on the CT head `headsq/quarter.nhdr` (skin 500, bone 1150):
/// a bounded cut frees the front of the mandible, which moves 5 mm forward.
pub const HEADSQ_CHIN_ADVANCE_TOML: &str = include_str!("plans/headsq_chin_advance.toml");

/// Jaw advance for the head phantom: the `jaw` fragment 6 mm forward in 6
/// increments, each relaxed to convergence.
pub const DEMO_PLAN_TOML: &str = include_str!("plans/phantom_jaw_advance.toml");
/// Chin advance for `fran_cut.vtk` (metres; +y up, face toward +x/−z).
pub const FRAN_CHIN_ADVANCE_TOML: &str = include_str!("plans/fran_chin_advance.toml");
/// A plan in the style of the seed's Table 2 for `fran_cut.vtk`: four
/// steps of ~60/60/150/70 bone points, 10/10/8/5 increments of 1 iteration.
pub const FRAN_TABLE2_TOML: &str = include_str!("plans/fran_table2.toml");

/// Columns and rows of the `fran_cut.vtk` scan grid (vertex i at column
/// i / 49, row i % 49).
pub const FRAN_GRID: (usize, usize) = (45, 49);

/// The demo's head: skin, skull (cranium + mandible as two closed
/// components) and the mandible's vertex ids.
#[derive(Debug, Clone)]
pub struct HeadPhantom {
    /// Closed skin surface, outward winding.
    pub skin: TriMesh,
    /// Cranium followed by the mandible, both closed, outward winding.
    pub skull: TriMesh,
    /// Skull vertex ids of the mandible (the separable jaw).
    pub jaw_vertices: Vec<u32>,
    /// Origin for the layer construction (centre of the head).
    pub origin: Vec3,
}

impl HeadPhantom {
    /// The fragments of the phantom for plan resolution: `jaw`.
    pub fn fragments(&self) -> Fragments {
        Fragments::from([("jaw".to_string(), self.jaw_vertices.clone())])
    }

    /// The demo plan (jaw advance), parsed.
    pub fn demo_plan() -> Result<Plan> {
        Plan::from_toml_str(DEMO_PLAN_TOML, "phantom_jaw_advance.toml")
    }
}

/// Unit direction for latitude `u ∈ [0, π]` (from +y) and longitude `v`
/// (0 = +z, increasing toward +x).
fn direction(u: f32, v: f32) -> Vec3 {
    Vec3::new(u.sin() * v.sin(), u.cos(), u.sin() * v.cos())
}

/// A closed UV surface `centre + shape(d)` over unit directions d, with
/// `n_lat` latitude bands and `n_lon` meridians; outward winding.
fn uv_surface(n_lat: usize, n_lon: usize, shape: impl Fn(Vec3) -> Vec3) -> TriMesh {
    let mut positions = vec![shape(Vec3::Y)];
    for k in 1..n_lat {
        let u = PI * k as f32 / n_lat as f32;
        for m in 0..n_lon {
            positions.push(shape(direction(u, 2.0 * PI * m as f32 / n_lon as f32)));
        }
    }
    positions.push(shape(-Vec3::Y));
    let ring = |k: usize, m: usize| (1 + (k - 1) * n_lon + m % n_lon) as u32;
    let bottom = (positions.len() - 1) as u32;
    let mut triangles = Vec::new();
    for m in 0..n_lon {
        triangles.push([0, ring(1, m), ring(1, m + 1)]);
        triangles.push([bottom, ring(n_lat - 1, m + 1), ring(n_lat - 1, m)]);
    }
    for k in 1..n_lat - 1 {
        for m in 0..n_lon {
            let (a, b) = (ring(k, m), ring(k, m + 1));
            let (c, d) = (ring(k + 1, m), ring(k + 1, m + 1));
            triangles.push([a, c, d]);
            triangles.push([a, d, b]);
        }
    }
    let mut mesh = TriMesh {
        positions,
        triangles,
        scalars: Vec::new(),
    };
    if signed_volume(&mesh) < 0.0 {
        mesh.flip_winding();
    }
    mesh
}

/// Signed volume (positive for an outward-wound closed surface).
pub fn signed_volume(mesh: &TriMesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// A Gaussian bump of `height` (mm) around unit direction `at` with angular
/// width `width` (radians).
fn bump(d: Vec3, at: Vec3, width: f32, height: f32) -> f32 {
    let angle = d.dot(at.normalize()).clamp(-1.0, 1.0).acos();
    height * (-(angle / width).powi(2)).exp()
}

/// The head phantom at `resolution` (≥ 8; the skin has `resolution`
/// latitude bands and `4/3 · resolution` meridians). Skin: an ellipsoid of
/// half-axes 75 × 110 × 95 mm with nose and chin; cranium: ellipsoid
/// 52 × 70 × 62 mm centred at (0, 14, −6); mandible: ellipsoid
/// 38 × 11 × 20 mm centred at (0, −58, 28), lying between the subcutis
/// (0.8) and the 0.7 shell of the skin so every layer nests.
pub fn head_phantom(resolution: usize) -> Result<HeadPhantom> {
    if resolution < 8 {
        return Err(Error::param("resolution", resolution, "must be ≥ 8"));
    }
    let n_lat = resolution;
    let n_lon = resolution * 4 / 3;
    let skin = uv_surface(n_lat, n_lon, |d| {
        let r = Vec3::new(75.0, 110.0, 95.0) * d;
        let bumps = bump(d, Vec3::new(0.0, 0.05, 1.0), 0.16, 14.0)
            + bump(d, Vec3::new(0.0, -0.75, 0.66), 0.22, 6.0);
        r + d * bumps
    });
    let cranium = uv_surface((n_lat / 2).max(6), (n_lon / 2).max(8), |d| {
        Vec3::new(0.0, 14.0, -6.0) + Vec3::new(52.0, 70.0, 62.0) * d
    });
    let mandible = uv_surface((n_lat / 4).max(4), (n_lon / 2).max(8), |d| {
        Vec3::new(0.0, -58.0, 28.0) + Vec3::new(38.0, 11.0, 20.0) * d
    });
    let offset = cranium.n_vertices() as u32;
    let jaw_vertices: Vec<u32> = (offset..offset + mandible.n_vertices() as u32).collect();
    let mut skull = cranium;
    skull.positions.extend_from_slice(&mandible.positions);
    skull
        .triangles
        .extend(mandible.triangles.iter().map(|t| t.map(|i| i + offset)));
    Ok(HeadPhantom {
        skin,
        skull,
        jaw_vertices,
        origin: Vec3::ZERO,
    })
}

/// Refines a structured scan grid of `cols × rows` vertices (vertex i at
/// column i / rows, row i % rows, like `fran_cut`) by `factor` per cell
/// side: (cols−1)·f+1 × (rows−1)·f+1 vertices, bilinear within each cell,
/// two triangles per cell with the diagonal and winding of the input's
/// first cell. `fran_cut` with f = 1, 8, 13 gives 6.6k, 408k and 1.07M
/// network nodes (the benchmark sizes).
pub fn refine_grid(mesh: &TriMesh, cols: usize, rows: usize, factor: usize) -> Result<TriMesh> {
    if cols < 2 || rows < 2 || factor == 0 {
        return Err(Error::param(
            "refine_grid: cols, rows, factor",
            format!("{cols}, {rows}, {factor}"),
            "need cols, rows ≥ 2 and factor ≥ 1",
        ));
    }
    if mesh.n_vertices() != cols * rows {
        return Err(Error::mismatch(
            format!("refine_grid: vertices of a {cols} × {rows} grid mesh"),
            cols * rows,
            mesh.n_vertices(),
        ));
    }
    let first = mesh
        .triangles
        .first()
        .ok_or_else(|| Error::empty("refine_grid: mesh triangles"))?;
    let cell = |i: u32| ((i as usize / rows) as i64, (i as usize % rows) as i64);
    let [a, b, c] = first.map(cell);
    let orient = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
    // Diagonal of cell (0, 0): does a triangle hold both (0,0) and (1,1)?
    let main_diagonal = mesh
        .triangles
        .iter()
        .any(|t| t.contains(&0) && t.contains(&(rows as u32 + 1)));
    let (nc, nr) = ((cols - 1) * factor + 1, (rows - 1) * factor + 1);
    let at = |c: usize, r: usize| mesh.positions[c * rows + r];
    let mut positions = Vec::with_capacity(nc * nr);
    for c in 0..nc {
        let (c0, fc) = ((c / factor).min(cols - 2), c as f32 / factor as f32);
        let tc = fc - c0 as f32;
        for r in 0..nr {
            let (r0, fr) = ((r / factor).min(rows - 2), r as f32 / factor as f32);
            let tr = fr - r0 as f32;
            let p = at(c0, r0) * (1.0 - tc) * (1.0 - tr)
                + at(c0 + 1, r0) * tc * (1.0 - tr)
                + at(c0, r0 + 1) * (1.0 - tc) * tr
                + at(c0 + 1, r0 + 1) * tc * tr;
            positions.push(p);
        }
    }
    let id = |c: usize, r: usize| (c * nr + r) as u32;
    let mut triangles = Vec::with_capacity(2 * (nc - 1) * (nr - 1));
    for c in 0..nc - 1 {
        for r in 0..nr - 1 {
            let (p00, p10, p01, p11) = (id(c, r), id(c + 1, r), id(c, r + 1), id(c + 1, r + 1));
            let (t1, t2) = if main_diagonal {
                ([p00, p10, p11], [p00, p11, p01])
            } else {
                ([p00, p10, p01], [p10, p11, p01])
            };
            // Both candidate triangles are counter-clockwise in (col, row);
            // flip when the input winds the other way.
            if orient > 0 {
                triangles.push(t1);
                triangles.push(t2);
            } else {
                triangles.push([t1[0], t1[2], t1[1]]);
                triangles.push([t2[0], t2[2], t2[1]]);
            }
        }
    }
    TriMesh::new(positions, triangles)
}

/// CT numbers of [`ct_head_phantom`]: air, soft tissue and bone (the
/// levels 500 and 1150 of the VTK CT head separate them as in `headsq`).
pub const CT_AIR: f32 = 0.0;
pub const CT_SOFT_TISSUE: f32 = 1000.0;
pub const CT_BONE: f32 = 2000.0;

/// Approximate signed distance to the ellipsoid `centre`, half-axes `a`
/// (exact on the axes; negative inside).
fn sd_ellipsoid(p: Vec3, centre: Vec3, a: Vec3) -> f32 {
    ((p - centre) / a)
        .length()
        .mul_add(a.min_element(), -a.min_element())
}

/// Signed distance to the capsule (segment `a`–`b`, radius `r`).
fn sd_capsule(p: Vec3, a: Vec3, b: Vec3, r: f32) -> f32 {
    let (pa, ba) = (p - a, b - a);
    let t = (pa.dot(ba) / ba.length_squared()).clamp(0.0, 1.0);
    (pa - ba * t).length() - r
}

/// Polynomial smooth minimum of two signed distances (blend width `k`).
fn smin(a: f32, b: f32, k: f32) -> f32 {
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

/// Signed distance of the mandible: the front half of a torus (centre
/// (0, −72, 8), radii 38 / 8 mm) and two rami (capsules of radius 7 mm)
/// up to the skull base.
fn sd_mandible(p: Vec3) -> f32 {
    let q = p - Vec3::new(0.0, -72.0, 8.0);
    let arch = if q.z >= 0.0 {
        let ring = Vec3::new(q.x, 0.0, q.z).length() - 38.0;
        (ring * ring + q.y * q.y).sqrt() - 8.0
    } else {
        f32::INFINITY
    };
    let ramus = |side: f32| {
        sd_capsule(
            p,
            Vec3::new(38.0 * side, -72.0, 8.0),
            Vec3::new(40.0 * side, -28.0, -6.0),
            7.0,
        )
    };
    arch.min(ramus(1.0)).min(ramus(-1.0))
}

/// Signed distance of the skin: a head ellipsoid (72 × 90 × 90 mm about
/// (0, 20, −5)) blended with 12 mm of soft tissue around the mandible and
/// with a neck (capsule of radius 48 mm down to y = −100), plus a nose.
fn sd_skin(p: Vec3) -> f32 {
    let head = sd_ellipsoid(p, Vec3::new(0.0, 20.0, -5.0), Vec3::new(72.0, 90.0, 90.0));
    let jaw = sd_mandible(p) - 12.0;
    let neck = sd_capsule(
        p,
        Vec3::new(0.0, -40.0, -12.0),
        Vec3::new(0.0, -100.0, -12.0),
        48.0,
    );
    let nose = sd_ellipsoid(p, Vec3::new(0.0, 2.0, 85.0), Vec3::new(11.0, 20.0, 15.0));
    smin(smin(head, jaw, 16.0), neck, 20.0).min(nose)
}

/// Signed distance of the skull: a 6 mm cranial shell (outer ellipsoid
/// 64 × 72 × 80 mm about (0, 28, −8), bottom at y = −44), the mandible
/// (see [`sd_mandible`]), whose rami fuse with the skull base as the joints
/// do at a bone threshold, and a cervical spine (capsule of radius 9 mm
/// from the skull base down the neck), fused to the skull base too.
fn sd_bone(p: Vec3) -> f32 {
    let outer = sd_ellipsoid(p, Vec3::new(0.0, 28.0, -8.0), Vec3::new(64.0, 72.0, 80.0));
    let cranium = (outer + 3.0).abs() - 3.0;
    let spine = sd_capsule(
        p,
        Vec3::new(0.0, -36.0, -38.0),
        Vec3::new(0.0, -130.0, -32.0),
        9.0,
    );
    cranium.min(sd_mandible(p)).min(spine)
}

/// A CT-like head volume with `voxel` mm isotropic samples (1 ≤ voxel ≤
/// 8): air [`CT_AIR`], soft tissue [`CT_SOFT_TISSUE`] inside the skin,
/// [`CT_BONE`] inside the skull, each boundary a one-voxel linear ramp
/// (partial-volume blur), so marching cubes at 500 / 1150 finds the skin
/// and the bone like on `headsq`. Millimetres, +y up, +z anterior (the
/// face), +x the patient's left; the volume spans the head with two
/// samples of air around it, `i16` samples.
pub fn ct_head_phantom(voxel: f32) -> Result<Volume> {
    if !(voxel.is_finite() && (1.0..=8.0).contains(&voxel)) {
        return Err(Error::param("voxel", voxel, "must be in [1, 8] mm"));
    }
    let lo = Vec3::new(-75.0, -150.0, -97.0) - 2.0 * voxel;
    let hi = Vec3::new(75.0, 112.0, 102.0) + 2.0 * voxel;
    let dims = ((hi - lo) / voxel).ceil().as_uvec3() + 1;
    let [nx, ny, nz] = dims.to_array().map(|d| d as usize);
    let ramp = |sd: f32| (0.5 - sd / voxel).clamp(0.0, 1.0);
    let mut data = vec![0i16; nx * ny * nz];
    data.par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(z, slab)| {
            for (k, v) in slab.iter_mut().enumerate() {
                let p = lo + Vec3::new((k % nx) as f32, (k / nx) as f32, z as f32) * voxel;
                let value = CT_AIR
                    + (CT_SOFT_TISSUE - CT_AIR) * ramp(sd_skin(p))
                    + (CT_BONE - CT_SOFT_TISSUE) * ramp(sd_bone(p));
                *v = value.round() as i16;
            }
        });
    Volume::new(
        [nx, ny, nz],
        [voxel as f64; 3],
        lo.as_dvec3().to_array(),
        VolumeData::I16(data),
    )
}

/// The demo plan on [`ct_head_phantom`], parsed.
pub fn ct_demo_plan() -> Result<Plan> {
    Plan::from_toml_str(CT_DEMO_PLAN_TOML, "ct_phantom_jaw_advance.toml")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phantom_is_closed_outward_and_nested() {
        let h = head_phantom(16).unwrap();
        assert!(signed_volume(&h.skin) > 0.0);
        assert!(signed_volume(&h.skull) > 0.0);
        assert!(!h.jaw_vertices.is_empty());
        // Every skull vertex lies inside the subcutis shell (0.8 · skin).
        let skin_radius = |d: Vec3| {
            h.skin
                .positions
                .iter()
                .filter(|p| p.normalize().dot(d) > 0.995)
                .map(|p| p.length())
                .fold(f32::INFINITY, f32::min)
        };
        for p in h.skull.positions.iter().step_by(7) {
            let r = skin_radius(p.normalize());
            if r.is_finite() {
                assert!(p.length() < 0.8 * r + 2.0, "{p} vs skin {r}");
            }
        }
    }

    #[test]
    fn refine_grid_counts_and_interpolates() {
        let mut pos = Vec::new();
        for c in 0..3 {
            for r in 0..4 {
                pos.push(Vec3::new(c as f32, r as f32, 0.0));
            }
        }
        let mut tri = Vec::new();
        for c in 0..2u32 {
            for r in 0..3u32 {
                let (a, b, cc, d) = (
                    c * 4 + r,
                    (c + 1) * 4 + r,
                    c * 4 + r + 1,
                    (c + 1) * 4 + r + 1,
                );
                tri.push([a, b, cc]);
                tri.push([b, d, cc]);
            }
        }
        let m = TriMesh::new(pos, tri).unwrap();
        let r = refine_grid(&m, 3, 4, 2).unwrap();
        assert_eq!(r.n_vertices(), 5 * 7);
        assert_eq!(r.n_triangles(), 2 * 4 * 6);
        assert_eq!(r.positions[7 + 1], Vec3::new(0.5, 0.5, 0.0));
        // Same winding as the input: +z normals.
        let [a, b, c] = r.triangles[0].map(|i| r.positions[i as usize]);
        assert!((b - a).cross(c - a).z > 0.0);
        assert!(matches!(
            refine_grid(&m, 4, 4, 2),
            Err(Error::Mismatch { expected: 16, .. })
        ));
    }
}
