//! Mesh topology, orientation detection and re-winding: synthetic families
//! with known figures, brute-force references on random soups, and the real
//! meshes' figures from `../shared/data/README.md`.
//!
//! Modules: `synthetic`, `reference` (brute force), `real_data`; the mesh
//! families shared by them stay here.

#[path = "../common/mod.rs"]
mod common;

mod real_data;
mod reference;
mod synthetic;

use std::f32::consts::TAU;

use chisel::TriMesh;
use chisel::mesh::{Orientation, Topology};
use glam::Vec3;

use crate::common::icosphere;

/// Torus with major radius 2, minor radius 0.5, `n × m` quads, outward.
fn torus(n: u32, m: u32) -> TriMesh {
    let mut p = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let (u, v) = (TAU * i as f32 / n as f32, TAU * j as f32 / m as f32);
            let ring = 2.0 + 0.5 * v.cos();
            p.push(Vec3::new(ring * u.cos(), ring * u.sin(), 0.5 * v.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % n) * m + (j % m);
    let mut t = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            t.extend([[a, b, c], [a, c, d]]);
        }
    }
    TriMesh::new(p, t).unwrap()
}

/// Flat disk in z = 0: centre 0 and a ring of `n` vertices, counter-clockwise
/// seen from +z.
fn disk(n: u32) -> TriMesh {
    let mut p = vec![Vec3::ZERO];
    p.extend((0..n).map(|i| {
        let a = TAU * i as f32 / n as f32;
        Vec3::new(a.cos(), a.sin(), 0.0)
    }));
    let t = (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect();
    TriMesh::new(p, t).unwrap()
}

/// Möbius strip of `n` quads (non-orientable).
fn moebius(n: u32) -> TriMesh {
    let mut p = Vec::new();
    for i in 0..n {
        let u = TAU * i as f32 / n as f32;
        for w in [-0.3f32, 0.3] {
            let r = 1.0 + w * (u / 2.0).cos();
            p.push(Vec3::new(r * u.cos(), r * u.sin(), w * (u / 2.0).sin()));
        }
    }
    let mut t = Vec::new();
    for i in 0..n {
        let (a, d) = (2 * i, 2 * i + 1);
        // The last quad closes the strip with a half twist.
        let (b, c) = if i + 1 < n {
            (2 * i + 2, 2 * i + 3)
        } else {
            (1, 0)
        };
        t.extend([[a, b, c], [a, c, d]]);
    }
    TriMesh::new(p, t).unwrap()
}

/// Upper cap of an icosphere: the triangles whose centroid has z > 0.3.
fn cap() -> TriMesh {
    let mut m = icosphere(2);
    let p = m.positions.clone();
    m.triangles
        .retain(|t| t.iter().map(|&v| p[v as usize].z).sum::<f32>() / 3.0 > 0.3);
    m
}

/// `a` and `b` as one mesh (indices of `b` shifted).
fn union(a: &TriMesh, b: &TriMesh) -> TriMesh {
    let off = a.positions.len() as u32;
    let mut p = a.positions.clone();
    p.extend(&b.positions);
    let mut t = a.triangles.clone();
    t.extend(b.triangles.iter().map(|t| t.map(|v| v + off)));
    TriMesh::new(p, t).unwrap()
}

fn translated(m: &TriMesh, d: Vec3) -> TriMesh {
    let mut m = m.clone();
    m.positions.iter_mut().for_each(|p| *p += d);
    m
}

fn flipped(m: &TriMesh) -> TriMesh {
    let mut m = m.clone();
    m.flip_winding();
    m
}

/// Checks the figures every closed, consistently wound genus-`g` shell has.
fn assert_closed_shell(m: &TriMesh, genus: i64, orientation: Orientation) -> Topology {
    let topo = Topology::of(m);
    assert_eq!(topo.boundary_edges, 0);
    assert_eq!(topo.nonmanifold_edges, 0);
    assert_eq!(topo.nonmanifold_vertices, 0);
    assert_eq!(topo.edges, 3 * m.triangles.len() / 2);
    assert!(topo.boundary_loops.is_empty());
    assert!(topo.closed && topo.consistently_oriented && topo.is_manifold());
    assert_eq!(topo.components.len(), 1);
    let c = &topo.components[0];
    assert!(c.closed && c.manifold && c.orientable);
    assert_eq!(c.genus, Some(genus));
    assert_eq!(topo.euler, 2 - 2 * genus);
    assert_eq!(c.euler, topo.euler);
    assert_eq!(topo.orientation, orientation);
    assert_eq!(c.orientation, orientation);
    topo
}
