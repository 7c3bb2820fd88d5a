//! Shared fixtures for the test binaries (libigl `test_common.h` style):
//! named synthetic families, the real data in `../shared/data`, and the GPU.
#![allow(dead_code, reason = "each test binary uses a different subset")]

use std::path::PathBuf;
use std::sync::OnceLock;

use chisel::gpu::Gpu;
use chisel::{TriMesh, Volume};
use glam::Vec3;

/// `../shared/data` next to the crate. With `CI=true` a missing folder
/// panics (the tests must run there); elsewhere `None` and a note to stderr.
pub fn data_dir() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data");
    if dir.is_dir() {
        return Some(dir);
    }
    if is_ci() {
        panic!(
            "CI=true but the real data folder {} is missing",
            dir.display()
        );
    }
    eprintln!("skipping real-data part: {} not found", dir.display());
    None
}

/// Whether `CI` is set to `true`/`1`.
pub fn is_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true" || v == "1")
}

/// `froggy/frogtissue.mhd`: (label, voxels) of all 26 values of the full
/// decode (`../shared/data/README.md` §4).
pub const FROG_LABELS: [(i64, u64); 26] = [
    (0, 30_803_043),
    (1, 35_279),
    (2, 19_172),
    (3, 38_129),
    (4, 37_146),
    (5, 16_085),
    (6, 37_030),
    (7, 27_807),
    (8, 39_181),
    (9, 51_297),
    (10, 204_672),
    (11, 47_626),
    (12, 24_263),
    (13, 440_722),
    (14, 3_891),
    (15, 133_880),
    (16, 252),
    (17, 38),
    (20, 29),
    (21, 4),
    (23, 6),
    (24, 239),
    (25, 121),
    (26, 16),
    (27, 32),
    (29, 40),
];

/// A real-data file, or `None` (skip) as in [`data_dir`].
pub fn data(rel: &str) -> Option<PathBuf> {
    data_dir().map(|d| d.join(rel))
}

/// A real mesh read with chisel's own reader.
pub fn real_mesh(rel: &str) -> Option<TriMesh> {
    data(rel).map(|p| chisel::io::read_mesh(&p).unwrap_or_else(|e| panic!("{e}")))
}

/// A real volume read with chisel's own reader.
pub fn real_volume(rel: &str) -> Option<Volume> {
    data(rel).map(|p| chisel::io::read_volume(&p).unwrap_or_else(|e| panic!("{e}")))
}

/// The CT head's bone (headsq ≥ 1150, largest 6-connected component),
/// when the data is there (see [`real_volume`]).
pub fn ct_bone() -> Option<chisel::voxel::DigitalObject> {
    use chisel::voxel::{Component, DigitalObject, Selection};
    let v = real_volume("headsq/quarter.nhdr")?;
    Some(DigitalObject::from_volume(&v, Selection::Threshold(1150.0), Component::Largest).unwrap())
}

/// The GPU for parity tests, one device per test process shared by all its
/// tests (as an application shares one): `None` (skip, with a note) when no
/// adapter exists on a developer machine; a panic under `CI=true`. Tests of
/// capped bindings or portable kernels take a [`Gpu::view`] of it, never a
/// second device.
pub fn gpu() -> Option<&'static Gpu> {
    static GPU: OnceLock<Option<Gpu>> = OnceLock::new();
    GPU.get_or_init(|| chisel::gpu::gpu_for_tests().unwrap_or_else(|e| panic!("{e}")))
        .as_ref()
}

/// Regular tetrahedron, outward winding, 4 vertices, 4 triangles.
pub fn tetra() -> TriMesh {
    TriMesh::new(
        vec![
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(-1.0, -1.0, 1.0),
        ],
        vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]],
    )
    .expect("valid tetra")
}

/// Unit cube [0,1]³, outward winding, 8 vertices, 12 triangles.
pub fn cube() -> TriMesh {
    let p = (0..8)
        .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
        .collect();
    let quads = [
        [0, 2, 3, 1], // z = 0, normal −z
        [4, 5, 7, 6], // z = 1, normal +z
        [0, 1, 5, 4], // y = 0, normal −y
        [2, 6, 7, 3], // y = 1, normal +y
        [0, 4, 6, 2], // x = 0, normal −x
        [1, 3, 7, 5], // x = 1, normal +x
    ];
    let t = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    TriMesh::new(p, t).expect("valid cube")
}

/// An `nx × ny` grid patch with vertex (i, j) at `at(i, j)` (vertex id
/// `j·nx + i`), each cell split along its (i, j)–(i+1, j+1) diagonal, wound
/// +z when `at` keeps i along x and j along y.
pub fn grid_mesh(nx: usize, ny: usize, at: impl Fn(usize, usize) -> Vec3) -> TriMesh {
    let p = (0..nx * ny).map(|v| at(v % nx, v / nx)).collect();
    let id = |i: usize, j: usize| (j * nx + i) as u32;
    let t = (0..ny - 1)
        .flat_map(|j| (0..nx - 1).map(move |i| (i, j)))
        .flat_map(|(i, j)| {
            [
                [id(i, j), id(i + 1, j), id(i + 1, j + 1)],
                [id(i, j), id(i + 1, j + 1), id(i, j + 1)],
            ]
        })
        .collect();
    TriMesh::new(p, t).expect("valid grid")
}

/// Icosphere of radius 1 with `n` subdivisions, outward winding:
/// 10·4ⁿ + 2 vertices, 20·4ⁿ triangles.
pub fn icosphere(n: u32) -> TriMesh {
    let (p, t) = chisel::mesh::unit_icosphere(n);
    TriMesh::new(p.iter().map(|q| q.as_vec3()).collect(), t).expect("valid icosphere")
}

/// A seeded random soup of `n` triangles over `n_vertices` points in
/// [-1, 1]³ (xorshift; reproducible, no external RNG).
pub fn random_mesh(seed: u64, n_vertices: usize, n: usize) -> TriMesh {
    let mut next = xorshift(seed);
    let p = (0..n_vertices)
        .map(|_| {
            let mut c = || (next() % 2_000_001) as f32 / 1_000_000.0 - 1.0;
            Vec3::new(c(), c(), c())
        })
        .collect();
    let t = (0..n)
        .map(|_| {
            let mut v = || (next() % n_vertices as u64) as u32;
            [v(), v(), v()]
        })
        .collect();
    TriMesh::new(p, t).expect("valid random mesh")
}

/// Runs the `chisel` binary with `--quiet` (for the CLI test binaries;
/// `bin` is `env!("CARGO_BIN_EXE_chisel")` of the caller).
pub fn run_chisel(bin: &str, args: &[&str]) -> std::process::Output {
    std::process::Command::new(bin)
        .args(args)
        .arg("--quiet")
        .output()
        .expect("run chisel")
}

/// A `n³` cube of voxels (one background voxel around it) minus the voxels
/// where `hole(x, y, z)` holds (`1 ≤ x, y, z ≤ n`).
pub fn carved(
    n: usize,
    hole: impl Fn(usize, usize, usize) -> bool,
) -> chisel::voxel::DigitalObject {
    let d = n + 2;
    let mut mask = vec![false; d * d * d];
    for z in 1..=n {
        for y in 1..=n {
            for x in 1..=n {
                mask[x + d * (y + d * z)] = !hole(x, y, z);
            }
        }
    }
    chisel::voxel::DigitalObject::from_mask([d; 3], &mask, chisel::voxel::Frame::default()).unwrap()
}

/// A fixed xorshift64 sequence (shifts 13, 7, 17) from `seed`: test inputs
/// that are the same on every run, and the one generator of the test
/// fixtures. A zero seed, xorshift's fixed point, is taken as 1.
pub fn xorshift(seed: u64) -> impl FnMut() -> u64 {
    let mut s = seed.max(1);
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

/// The 20 random carvings of an 11³ cube (a fixed xorshift sequence; about
/// one voxel in 7 removed): staircase pits, grooves, cavities, islands.
pub fn random_carvings() -> Vec<chisel::voxel::DigitalObject> {
    let mut next = xorshift(0x2545_f491_4f6c_dd1d);
    (0..20)
        .map(|_| {
            let holes: Vec<bool> = (0..13 * 13 * 13)
                .map(|_| next().is_multiple_of(7))
                .collect();
            carved(11, |x, y, z| holes[x + 13 * (y + 13 * z)])
        })
        .collect()
}

/// `m` points of the unit sphere on a Fibonacci lattice (each its own
/// outward normal).
pub fn fibonacci_sphere(m: usize) -> Vec<glam::DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..m)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / m as f64;
            let r = (1.0 - z * z).sqrt();
            let t = golden * i as f64;
            glam::DVec3::new(r * t.cos(), r * t.sin(), z)
        })
        .collect()
}

/// A torus about the z axis: core radius `big`, tube radius `small`,
/// outward.
pub fn torus(big: f32, small: f32, nu: u32, nv: u32) -> TriMesh {
    let mut m = TriMesh::default();
    for i in 0..nu {
        let u = i as f32 / nu as f32 * std::f32::consts::TAU;
        for j in 0..nv {
            let v = j as f32 / nv as f32 * std::f32::consts::TAU;
            let r = big + small * v.cos();
            m.positions
                .push(Vec3::new(r * u.cos(), r * u.sin(), small * v.sin()));
        }
    }
    let at = |i: u32, j: u32| (i % nu) * nv + (j % nv);
    for i in 0..nu {
        for j in 0..nv {
            let [a, b, c, d] = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            m.triangles.push([a, b, c]);
            m.triangles.push([a, c, d]);
        }
    }
    m
}
