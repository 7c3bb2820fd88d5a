//! Procedurally generated test objects, embedded so `chisel demo` needs no
//! input files.
//!
//! Coordinates are millimetres; +y is up (cranial), +z is anterior (the face
//! looks toward +z), +x is the subject's left.

pub mod voxel;

use glam::Vec3;

use crate::mesh::TriMesh;

/// A smooth gaussian bump on the unit sphere of directions.
struct Bump {
    /// Unit direction of the bump centre.
    dir: Vec3,
    /// Angular width (radians).
    width: f32,
    /// Relative radial amplitude (negative = dent).
    amplitude: f32,
}

fn head_radius(d: Vec3, bumps: &[Bump]) -> f32 {
    // Ellipsoid radii (mm): width 144, height 200, depth 176.
    let (ax, ay, az) = (72.0f32, 100.0f32, 88.0f32);
    let base = 1.0 / ((d.x / ax).powi(2) + (d.y / ay).powi(2) + (d.z / az).powi(2)).sqrt();
    let bump: f32 = bumps
        .iter()
        .map(|b| {
            let angle = d.dot(b.dir).clamp(-1.0, 1.0).acos();
            b.amplitude * (-(angle / b.width).powi(2)).exp()
        })
        .sum();
    base * (1.0 + bump)
}

/// Skin surface of a head phantom: a closed, outward-wound genus-0 mesh over
/// a latitude/longitude grid with `n_lat` rings and `n_lon` segments (poles
/// welded): `(n_lat − 1)·n_lon + 2` vertices, `2·(n_lat − 1)·n_lon` triangles.
/// Nose, chin, brow and cheek bumps and two eye sockets make the face side
/// (+z) recognisable. `n_lat ≥ 3`, `n_lon ≥ 3`.
pub fn head_skin(n_lat: u32, n_lon: u32) -> crate::Result<TriMesh> {
    if n_lat < 3 || n_lon < 3 {
        return Err(crate::Error::InvalidInput(format!(
            "head_skin needs n_lat ≥ 3 and n_lon ≥ 3, got {n_lat}×{n_lon}"
        )));
    }
    let dir = |x: f32, y: f32, z: f32| Vec3::new(x, y, z).normalize();
    let bumps = [
        Bump {
            dir: dir(0.0, -0.05, 1.0),
            width: 0.16,
            amplitude: 0.20,
        }, // nose
        Bump {
            dir: dir(0.0, -0.55, 1.0),
            width: 0.22,
            amplitude: 0.08,
        }, // chin
        Bump {
            dir: dir(0.0, 0.30, 1.0),
            width: 0.35,
            amplitude: 0.04,
        }, // brow
        Bump {
            dir: dir(0.33, 0.12, 1.0),
            width: 0.12,
            amplitude: -0.07,
        }, // eye socket
        Bump {
            dir: dir(-0.33, 0.12, 1.0),
            width: 0.12,
            amplitude: -0.07,
        },
        Bump {
            dir: dir(0.45, -0.15, 1.0),
            width: 0.25,
            amplitude: 0.04,
        }, // cheeks
        Bump {
            dir: dir(-0.45, -0.15, 1.0),
            width: 0.25,
            amplitude: 0.04,
        },
        Bump {
            dir: dir(1.0, 0.0, -0.05),
            width: 0.15,
            amplitude: 0.06,
        }, // ears
        Bump {
            dir: dir(-1.0, 0.0, -0.05),
            width: 0.15,
            amplitude: 0.06,
        },
    ];
    let mut positions = Vec::with_capacity(((n_lat - 1) * n_lon + 2) as usize);
    let mut push = |d: Vec3| positions.push(d * head_radius(d, &bumps));
    push(Vec3::Y);
    for i in 1..n_lat {
        let theta = std::f32::consts::PI * i as f32 / n_lat as f32;
        for j in 0..n_lon {
            let phi = std::f32::consts::TAU * j as f32 / n_lon as f32;
            push(Vec3::new(
                theta.sin() * phi.sin(),
                theta.cos(),
                theta.sin() * phi.cos(),
            ));
        }
    }
    push(-Vec3::Y);
    let ring = |i: u32, j: u32| 1 + (i - 1) * n_lon + j % n_lon;
    let south = (n_lat - 1) * n_lon + 1;
    let mut triangles = Vec::with_capacity(2 * ((n_lat - 1) * n_lon) as usize);
    for j in 0..n_lon {
        triangles.push([0, ring(1, j), ring(1, j + 1)]);
        triangles.push([south, ring(n_lat - 1, j + 1), ring(n_lat - 1, j)]);
    }
    for i in 1..n_lat - 1 {
        for j in 0..n_lon {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            triangles.push([a, c, d]);
            triangles.push([a, d, b]);
        }
    }
    TriMesh::new(positions, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn head_skin_counts_and_winding() {
        let m = head_skin(10, 16).unwrap();
        assert_eq!(m.n_vertices(), 9 * 16 + 2);
        assert_eq!(m.n_triangles(), 2 * 9 * 16);
        // Outward winding: positive signed volume.
        let vol: f32 = m
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!(vol > 0.0, "signed volume {vol}");
        assert!(head_skin(2, 16).is_err());
    }
}
