//! Marching cubes: watertightness, orientation, welding, spacing/origin,
//! and group counts / per-group Euler characteristics against an
//! independent voxel-topology oracle (cubical complexes, below).
//!
//! Modules: `oracle` (the oracle and the checks), `synthetic`, `real_data`,
//! `field`; the fixtures stay here.

#[path = "../common/mod.rs"]
mod common;

mod field;
mod oracle;
mod real_data;
mod synthetic;

use chisel::mc::McOptions;
use chisel::volume::{Volume, VolumeData};

// ---------------------------------------------------------------- fixtures

/// Seeded random u8 volume with values 0..=255, smoothed a little so that
/// all case configurations and real components/cavities occur.
fn random_volume(seed: u64, dims: [usize; 3]) -> Volume {
    let mut next = common::xorshift(seed);
    let data: Vec<u8> = (0..dims.iter().product::<usize>())
        .map(|_| (next() % 256) as u8)
        .collect();
    Volume::new(dims, [1.0; 3], [0.0; 3], VolumeData::U8(data)).unwrap()
}

/// Signed distance-like phantom: `f(p) = r − |p − c|` sampled as f32.
fn ball(n: usize, r: f64, spacing: [f64; 3], origin: [f64; 3]) -> Volume {
    let c = (n as f64 - 1.0) / 2.0;
    let mut data = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let d = ((x as f64 - c).powi(2) + (y as f64 - c).powi(2) + (z as f64 - c).powi(2))
                    .sqrt();
                data.push((r - d) as f32);
            }
        }
    }
    Volume::new([n; 3], spacing, origin, VolumeData::F32(data)).unwrap()
}

/// Solid torus phantom around the z axis: `f = r − dist(p, circle R)`.
fn torus(n: usize, big_r: f64, r: f64) -> Volume {
    let c = (n as f64 - 1.0) / 2.0;
    let mut data = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let (dx, dy, dz) = (x as f64 - c, y as f64 - c, z as f64 - c);
                let q = ((dx * dx + dy * dy).sqrt() - big_r).hypot(dz);
                data.push((r - q) as f32);
            }
        }
    }
    Volume::new([n; 3], [1.0; 3], [0.0; 3], VolumeData::F32(data)).unwrap()
}

const CLOSE: McOptions = McOptions {
    close_border: true,
    mesh_only: false,
};
