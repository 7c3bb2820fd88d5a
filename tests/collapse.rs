//! Short-edge collapse (`mesh::collapse_short_edges`): topology, border,
//! orientation and embedding kept on marching-cubes surfaces (random
//! volumes, a ball, headsq's skin) and on fran_cut; the link condition, the
//! border-pinch and non-manifold refusals on hand-made meshes.

mod common;

use chisel::mc::{IsoSpec, McOptions, marching_cubes};
use chisel::mesh::{Collapsed, Topology, collapse_short_edges, self_intersections};
use chisel::volume::{Volume, VolumeData};
use chisel::{Backend, TriMesh};
use glam::Vec3;
use proptest::prelude::*;

/// (Euler characteristic, boundary edges) per component, sorted.
fn component_figures(mesh: &TriMesh) -> Vec<(i64, usize)> {
    let mut c: Vec<(i64, usize)> = Topology::of(mesh)
        .components
        .iter()
        .map(|c| (c.euler, c.boundary_edges.min(1)))
        .collect();
    c.sort_unstable();
    c
}

fn edge_lengths(mesh: &TriMesh) -> Vec<f32> {
    chisel::tissue::network::unique_edges(&mesh.triangles)
        .iter()
        .map(|&(a, b)| mesh.positions[a as usize].distance(mesh.positions[b as usize]))
        .collect()
}

/// Everything the collapse promises for an embedded manifold input.
fn check_collapse(input: &TriMesh, min: f32, c: &Collapsed) {
    let (before, after) = (Topology::of(input), Topology::of(&c.mesh));
    assert!(after.is_manifold(), "manifold after");
    assert_eq!(after.components.len(), before.components.len());
    assert_eq!(component_figures(&c.mesh), component_figures(input));
    assert_eq!(after.boundary_loops.len(), before.boundary_loops.len());
    assert_eq!(after.closed, before.closed);
    assert!(after.consistently_oriented);
    if before.closed {
        assert_eq!(after.orientation, before.orientation);
    }
    assert_eq!(after.degenerate_triangles, 0);
    assert_eq!(c.crossing_pairs, 0);
    assert_eq!(self_intersections(&c.mesh).pairs.len(), 0, "embedded");
    // Counts add up: each collapse removes one vertex (two triangles
    // inside, one on the border).
    assert_eq!(before.used_vertices - after.used_vertices, c.collapsed);
    let short = edge_lengths(&c.mesh).iter().filter(|&&l| l < min).count();
    assert_eq!(short, c.short_edges_left);
    // Every input vertex maps to a surviving vertex, which lies close.
    for (v, &to) in c.vertex_map.iter().enumerate() {
        let moved = input.positions[v].distance(c.mesh.positions[to as usize]);
        assert!(moved < 4.0 * min, "vertex {v} moved {moved}");
    }
    // The enclosed volume barely changes.
    if before.closed {
        let (v0, v1) = (before.signed_volume, after.signed_volume);
        assert!((v1 - v0).abs() < 0.02 * v0.abs(), "{v0} → {v1}");
    }
}

fn ball(n: usize, r: f32) -> Volume {
    let c = (n as f32 - 1.0) / 2.0;
    let data = (0..n * n * n)
        .map(|i| {
            let p = Vec3::new((i % n) as f32, (i / n % n) as f32, (i / n / n) as f32);
            r - p.distance(Vec3::splat(c))
        })
        .collect();
    Volume::new([n; 3], [1.0; 3], [0.0; 3], VolumeData::F32(data)).unwrap()
}

fn surface(vol: &Volume, level: f32) -> TriMesh {
    marching_cubes(
        vol,
        IsoSpec::Level(level),
        &McOptions::default(),
        Backend::Cpu,
    )
    .unwrap()
    .mesh
}

#[test]
fn marching_cubes_ball_loses_its_slivers_and_keeps_its_shape() {
    let mesh = surface(&ball(40, 15.3), 0.0);
    let shortest = edge_lengths(&mesh).into_iter().fold(f32::MAX, f32::min);
    assert!(shortest < 0.05, "the ball has slivers: {shortest}");
    let c = collapse_short_edges(&mesh, 0.4);
    check_collapse(&mesh, 0.4, &c);
    assert!(c.collapsed > mesh.n_vertices() / 10, "{}", c.collapsed);
    assert!(c.min_edge_after > 4.0 * shortest, "{}", c.min_edge_after);
    assert!(c.short_edges_left * 20 < c.collapsed, "{c:?}");
    assert_eq!(c.rounds, 1);
    // min_length 0 leaves the mesh as it is.
    let none = collapse_short_edges(&mesh, 0.0);
    assert_eq!(none.mesh, mesh);
    assert_eq!(none.collapsed, 0);
}

#[test]
fn scalar_fields_follow_their_surviving_vertex() {
    let mut mesh = surface(&ball(20, 7.2), 0.0);
    let values: Vec<f32> = (0..mesh.n_vertices()).map(|v| v as f32).collect();
    mesh.scalars.push(chisel::mesh::ScalarField {
        name: "id".into(),
        values,
    });
    let c = collapse_short_edges(&mesh, 0.5);
    let field = &c.mesh.scalar("id").unwrap().values;
    for (v, &to) in c.vertex_map.iter().enumerate() {
        let kept = field[to as usize] as usize;
        assert_eq!(c.vertex_map[kept], to, "vertex {v}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    /// Random smoothed volumes: many components, handles and cavities,
    /// open at the volume border.
    #[test]
    fn random_marching_cubes_surfaces_keep_their_topology(
        seed in any::<u64>(),
        level in 60.0f32..190.0,
        min in 0.05f32..0.9,
    ) {
        let n = 12;
        let mut s = seed | 1;
        let mut data: Vec<f32> = (0..n * n * n)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s % 256) as f32
            })
            .collect();
        // Smooth along x once so the surface has real extent.
        for i in (1..data.len()).rev() {
            data[i] = 0.5 * (data[i] + data[i - 1]);
        }
        let vol = Volume::new([n; 3], [1.0; 3], [0.0; 3], VolumeData::F32(data)).unwrap();
        let mesh = surface(&vol, level);
        prop_assume!(mesh.n_triangles() > 0);
        let c = collapse_short_edges(&mesh, min);
        check_collapse(&mesh, min, &c);
    }
}

#[test]
fn a_tetrahedron_and_a_lone_triangle_stay() {
    let tetra = common::tetra();
    let c = collapse_short_edges(&tetra, 100.0);
    assert_eq!(c.collapsed, 0);
    assert_eq!(c.mesh, tetra);
    assert_eq!(c.short_edges_left, 6);
    let tri = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
    assert_eq!(collapse_short_edges(&tri, 100.0).collapsed, 0);
}

/// A strip one cell wide with rungs of 0.1: every vertex is on the
/// border, so the inner rungs would pinch it; only the two end rungs (on
/// the border) may go.
#[test]
fn border_pinches_are_refused() {
    let mut p = Vec::new();
    for i in 0..6 {
        p.push(Vec3::new(i as f32, 0.0, 0.0));
        p.push(Vec3::new(i as f32, 0.1, 0.0));
    }
    let t: Vec<[u32; 3]> = (0..5u32)
        .flat_map(|i| {
            [
                [2 * i, 2 * i + 2, 2 * i + 1],
                [2 * i + 1, 2 * i + 2, 2 * i + 3],
            ]
        })
        .collect();
    let strip = TriMesh::new(p, t).unwrap();
    let c = collapse_short_edges(&strip, 0.2);
    check_collapse(&strip, 0.2, &c);
    assert_eq!(c.collapsed, 2, "only the end rungs");
    assert_eq!(c.short_edges_left, 4);
}

/// An edge whose two triangles wind the same way (both ends on the
/// border, so it stays) is counted once.
#[test]
fn short_edges_are_counted_once_whatever_the_winding() {
    let mesh = TriMesh::new(
        vec![Vec3::ZERO, Vec3::new(0.01, 0.0, 0.0), Vec3::Y, -Vec3::Y],
        vec![[0, 1, 2], [0, 1, 3]],
    )
    .unwrap();
    let c = collapse_short_edges(&mesh, 0.1);
    assert_eq!(c.collapsed, 0);
    assert_eq!(c.short_edges_left, 1);
}

/// Collapsing a short border edge keeps the border (and the vertex on it).
#[test]
fn open_grid_keeps_its_border_loop() {
    let n = 8;
    // Column 3 squeezed against column 2: short edges across the grid.
    let grid = common::grid_mesh(n, n, |i, j| {
        let x = if i >= 3 { i as f32 - 0.9 } else { i as f32 };
        Vec3::new(x, j as f32, 0.05 * (i * j % 3) as f32)
    });
    let c = collapse_short_edges(&grid, 0.3);
    check_collapse(&grid, 0.3, &c);
    assert!(c.collapsed >= n - 2, "{}", c.collapsed);
    // Border vertices stay on the grid's outline.
    let (lo, hi) = grid.bounds().unwrap();
    let topo = Topology::of(&c.mesh);
    assert_eq!(topo.boundary_loops, vec![2 * (n - 1) + 2 * (n - 2)]);
    assert_eq!(c.mesh.bounds().unwrap(), (lo, hi));
}

/// Two fans sharing one vertex (a bowtie): that vertex is not manifold and
/// never moves.
#[test]
fn non_manifold_vertices_are_kept() {
    let mesh = TriMesh::new(
        vec![
            Vec3::ZERO,
            Vec3::new(1.0, 0.05, 0.0),
            Vec3::new(1.0, -0.05, 0.0),
            Vec3::new(-1.0, 0.05, 0.0),
            Vec3::new(-1.0, -0.05, 0.0),
        ],
        vec![[0, 2, 1], [0, 3, 4]],
    )
    .unwrap();
    let c = collapse_short_edges(&mesh, 0.5);
    assert_eq!(c.mesh.positions[c.vertex_map[0] as usize], Vec3::ZERO);
    assert_eq!(c.mesh.n_triangles(), 2);
}

#[test]
fn fran_cut_keeps_its_topology() {
    let Some(face) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    // The shortest 5 % of the edges.
    let mut lengths = edge_lengths(&face);
    lengths.sort_by(f32::total_cmp);
    let min = lengths[lengths.len() / 20];
    let c = collapse_short_edges(&face, min);
    check_collapse(&face, min, &c);
    assert!(c.collapsed > lengths.len() / 100, "{}", c.collapsed);
}

/// headsq's skin at 500 (open at the volume border, 26 groups): the
/// default CT threshold removes most vertices and keeps every group's
/// topology; a larger one needs the embedding guard's second run.
#[test]
fn headsq_skin_keeps_its_topology_and_stays_embedded() {
    let Some(vol) = common::real_volume("headsq/quarter.nhdr") else {
        return;
    };
    let skin = surface(&vol, 500.0);
    assert_eq!(self_intersections(&skin).pairs.len(), 0);
    let c = collapse_short_edges(&skin, 1.92);
    check_collapse(&skin, 1.92, &c);
    assert!(c.mesh.n_vertices() < skin.n_vertices() / 2);
    // At 2.24 mm a first run makes triangles cross; the guard re-runs
    // with their vertices kept.
    let c = collapse_short_edges(&skin, 2.24);
    assert!(c.rounds >= 2, "rounds {}", c.rounds);
    check_collapse(&skin, 2.24, &c);
}
