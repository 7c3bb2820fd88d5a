//! Scalpel cuts: closed pieces, conserved volume, tree = brute force, the
//! tree visits fewer nodes and triangles than exist (counts, never time).

mod analytic;
#[path = "../common/mod.rs"]
mod common;
mod locate;
mod meshes;
mod triangulated;

use std::collections::HashMap;

use chisel::cut::{
    CutOptions, CutResult, Knife, Located, SPHERE_CHORD_ERROR, Side, cut, cut_brute_force,
    cut_mesh, cut_sequence, locate, locate_brute_force,
};
use chisel::foundation::Forest;
use chisel::mc::{IsoSpec, McOptions, Surface, marching_cubes};
use chisel::volume::{Volume, VolumeData};
use chisel::{Backend, TriMesh};
use glam::DVec3;

const CAP: CutOptions = CutOptions { cap: true };

/// Signed volume by the divergence theorem (f64, about `r`).
fn volume(m: &TriMesh, r: DVec3) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3() - r);
            a.dot(b.cross(c))
        })
        .sum::<f64>()
        / 6.0
}

/// Every edge used exactly twice, in opposite directions.
fn assert_closed(m: &TriMesh, what: &str) {
    let mut d: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            *d.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    for (&(a, b), &n) in &d {
        assert_eq!(n, 1, "{what}: directed edge {a}->{b} used {n} times");
        assert!(d.contains_key(&(b, a)), "{what}: edge {a}-{b} open");
    }
}

/// Closed pieces whose volumes add up to the original within `rel`.
fn assert_conserved(orig: &TriMesh, r: &CutResult, rel: f64, what: &str) {
    let c = orig
        .bounds()
        .map_or(DVec3::ZERO, |(lo, hi)| ((lo + hi) * 0.5).as_dvec3());
    let v0 = volume(orig, c);
    let mut sum = 0.0;
    for (i, p) in r.pieces.iter().enumerate() {
        assert_closed(p, &format!("{what} piece {i}"));
        sum += volume(p, c);
    }
    assert!(
        (sum - v0).abs() <= rel * v0.abs(),
        "{what}: pieces {sum} vs original {v0} (rel {:e})",
        (sum - v0).abs() / v0.abs()
    );
}

fn same_result(a: &CutResult, b: &CutResult) {
    assert_eq!(a.pieces, b.pieces, "tree and brute force differ");
    assert_eq!(a.sides, b.sides);
    assert_eq!(a.stats.triangles_split, b.stats.triangles_split);
    assert_eq!(a.stats.cut_vertices, b.stats.cut_vertices);
}

/// An n³ f32 volume of `f(p − centre)` at the grid points (unit spacing).
fn sampled(n: usize, f: impl Fn(DVec3) -> f64) -> Volume {
    let c = (n as f64 - 1.0) / 2.0;
    let mut data = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                data.push(f(DVec3::new(x as f64 - c, y as f64 - c, z as f64 - c)) as f32);
            }
        }
    }
    Volume::new([n; 3], [1.0; 3], [0.0; 3], VolumeData::F32(data)).unwrap()
}

fn ball_volume(n: usize, r: f64) -> Volume {
    sampled(n, |d| r - d.length())
}

/// A hollow ball (shell between radii r0 < r1): cuts give annular caps.
fn shell_volume(n: usize, r0: f64, r1: f64) -> Volume {
    sampled(n, |d| (d.length() - r0).min(r1 - d.length()))
}

/// The plane z = `z`, normal +z.
fn z_plane(z: f32) -> Knife {
    plane([0.0, 0.0, f64::from(z)], [0.0, 0.0, 1.0])
}

fn mc(vol: &Volume) -> Surface {
    marching_cubes(
        vol,
        IsoSpec::Level(0.0),
        &McOptions {
            close_border: true,
            ..McOptions::default()
        },
        Backend::Cpu,
    )
    .unwrap()
}

fn plane(p: [f64; 3], n: [f64; 3]) -> Knife {
    Knife::Plane {
        point: DVec3::from_array(p),
        normal: DVec3::from_array(n),
    }
}

/// No zero-area triangle and no two vertices at one position.
fn assert_clean(m: &TriMesh, what: &str) {
    let mut seen = std::collections::HashSet::new();
    for p in &m.positions {
        assert!(
            seen.insert(p.to_array().map(f32::to_bits)),
            "{what}: two vertices at {p}"
        );
    }
    for t in &m.triangles {
        let [a, b, c] = t.map(|v| m.positions[v as usize].as_dvec3());
        assert_ne!((b - a).cross(c - a), DVec3::ZERO, "{what}: zero-area {t:?}");
    }
}

/// Connected components of a mesh's vertices joined by its triangles, and
/// whether every vertex is used.
fn components(m: &TriMesh) -> (usize, bool) {
    let mut parent: Vec<usize> = (0..m.positions.len()).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    let mut used = vec![false; m.positions.len()];
    for t in &m.triangles {
        let [a, b, c] = t.map(|v| v as usize);
        used[a] = true;
        used[b] = true;
        used[c] = true;
        for y in [b, c] {
            let (ra, ry) = (find(&mut parent, a), find(&mut parent, y));
            parent[ra.max(ry)] = ra.min(ry);
        }
    }
    let n = (0..parent.len())
        .filter(|&x| find(&mut parent, x) == x)
        .count();
    (n, used.iter().all(|&u| u))
}

/// A square sheet knife in the plane z = `z` (two triangles, normal +z),
/// corners off the grid diagonals so no knife edge meets a surface edge.
fn sheet(z: f32) -> TriMesh {
    TriMesh::new(
        vec![
            glam::Vec3::new(-10.3, -9.1, z),
            glam::Vec3::new(40.7, -10.2, z),
            glam::Vec3::new(39.6, 40.9, z),
            glam::Vec3::new(-9.4, 39.8, z),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .unwrap()
}

/// Every edge used twice in opposite directions, and the volumes of the
/// pieces on each side.
fn side_volumes(r: &CutResult, c: DVec3) -> (f64, f64) {
    let mut v = (0.0, 0.0);
    for (p, s) in r.pieces.iter().zip(&r.sides) {
        match s {
            Side::Negative => v.0 += volume(p, c),
            Side::Positive => v.1 += volume(p, c),
            Side::Both => panic!("a piece on both sides"),
        }
    }
    v
}
