//! Synthetic families with known figures: shells, tori, disks, caps, strips,
//! non-manifold edges and vertices, degenerate and empty meshes.

use std::f64::consts::{PI, TAU as TAU64};

use chisel::TriMesh;
use chisel::mesh::{Orientation, Topology, orient_consistently, orient_outward};
use glam::Vec3;

use crate::common::{cube, icosphere, tetra};
use crate::{assert_closed_shell, cap, disk, flipped, moebius, torus, translated, union};

#[test]
fn platonic_and_sphere_shells_are_genus_zero_and_outward() {
    let t = assert_closed_shell(&tetra(), 0, Orientation::Outward);
    assert!(
        (t.signed_volume - 8.0 / 3.0).abs() < 1e-6,
        "{}",
        t.signed_volume
    );
    let c = assert_closed_shell(&cube(), 0, Orientation::Outward);
    assert!((c.signed_volume - 1.0).abs() < 1e-9);
    assert!((c.area - 6.0).abs() < 1e-9);
    assert_eq!(c.bounds.unwrap().max.to_array(), [1.0, 1.0, 1.0]);
    let s = assert_closed_shell(&icosphere(3), 0, Orientation::Outward);
    let ball = 4.0 / 3.0 * std::f64::consts::PI;
    assert!(s.signed_volume < ball && s.signed_volume > 0.97 * ball);
}

#[test]
fn flipped_shells_are_inward_and_orient_outward_restores_them() {
    for m in [tetra(), cube(), icosphere(2), torus(16, 8)] {
        let genus = Topology::of(&m).components[0].genus.unwrap();
        let mut f = flipped(&m);
        let topo = assert_closed_shell(&f, genus, Orientation::Inward);
        assert!(topo.signed_volume < 0.0);
        assert_eq!(orient_outward(&mut f), 1);
        assert_eq!(f, m, "re-flipping restores the original winding exactly");
        assert_eq!(orient_outward(&mut f), 0);
    }
}

#[test]
fn torus_has_genus_one() {
    let t = assert_closed_shell(&torus(24, 12), 1, Orientation::Outward);
    assert_eq!(t.euler, 0);
    // Pappus with polygons: a 12-gon cross-section of area (12/2π)·sin(2π/12)·πr²
    // swept along a 24-gon of perimeter (24/2π)·sin(2π/24)·2πR.
    let polygon = |n: f64| n / TAU64 * (TAU64 / n).sin();
    let pappus = polygon(12.0) * PI * 0.25 * polygon(24.0) * TAU64 * 2.0;
    assert!(
        (t.signed_volume / pappus - 1.0).abs() < 2e-3,
        "{} vs {pappus}",
        t.signed_volume
    );
}

#[test]
fn flat_disk_is_open_with_one_loop_and_undetermined() {
    let topo = Topology::of(&disk(12));
    assert_eq!(
        (topo.edges, topo.boundary_edges, topo.manifold_edges),
        (24, 12, 12)
    );
    assert_eq!(topo.boundary_loops, vec![12]);
    assert!(topo.open_boundary_chains.is_empty());
    assert_eq!(topo.euler, 1);
    assert!(!topo.closed && topo.consistently_oriented && topo.is_manifold());
    let c = &topo.components[0];
    assert_eq!((c.closed, c.genus, c.boundary_edges), (false, None, 12));
    assert_eq!(topo.orientation, Orientation::Undetermined);
    assert_eq!(
        Topology::of(&flipped(&disk(12))).orientation,
        Orientation::Undetermined
    );
    let mut d = disk(12);
    assert_eq!(orient_outward(&mut d), 0);
}

#[test]
fn open_cap_orientation_follows_its_curvature() {
    let cap = cap();
    let topo = Topology::of(&cap);
    assert!(topo.used_vertices < topo.vertices);
    assert_eq!(topo.components.len(), 1);
    assert_eq!(topo.boundary_loops.len(), 1);
    assert_eq!(topo.euler, 1);
    assert_eq!(topo.orientation, Orientation::Outward);
    let mut inward = flipped(&cap);
    assert_eq!(Topology::of(&inward).orientation, Orientation::Inward);
    assert_eq!(orient_outward(&mut inward), 1);
    assert_eq!(inward, cap);
}

#[test]
fn disjoint_cubes_are_two_components() {
    let small = translated(&flipped(&tetra()), Vec3::new(10.0, 0.0, 0.0));
    let m = union(
        &small,
        &union(&cube(), &translated(&cube(), Vec3::splat(3.0))),
    );
    let topo = Topology::of(&m);
    assert_eq!(topo.components.len(), 3);
    let tris: Vec<usize> = topo.components.iter().map(|c| c.triangles).collect();
    assert_eq!(tris, vec![12, 12, 4], "by size descending");
    assert_eq!(
        topo.components[0].first_triangle, 4,
        "ties by first triangle"
    );
    assert_eq!(topo.components[1].first_triangle, 16);
    assert_eq!(topo.euler, 6);
    assert!(topo.components.iter().all(|c| c.genus == Some(0)));
    assert_eq!(topo.components[2].orientation, Orientation::Inward);
    assert_eq!(topo.orientation, Orientation::Mixed, "components disagree");
    let mut fixed = m.clone();
    assert_eq!(orient_outward(&mut fixed), 1);
    let after = Topology::of(&fixed);
    assert_eq!(after.orientation, Orientation::Outward);
    assert!((after.signed_volume - 2.0 - 8.0 / 3.0).abs() < 1e-6);
}

#[test]
fn three_triangles_on_one_edge() {
    let p = vec![
        Vec3::ZERO,
        Vec3::X,
        Vec3::new(0.5, 1.0, 0.0),
        Vec3::new(0.5, -1.0, 0.0),
        Vec3::new(0.5, 0.0, 1.0),
    ];
    let m = TriMesh::new(p, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
    let topo = Topology::of(&m);
    assert_eq!(topo.edges, 7);
    assert_eq!(
        (
            topo.boundary_edges,
            topo.manifold_edges,
            topo.nonmanifold_edges
        ),
        (6, 0, 1)
    );
    assert_eq!(topo.nonmanifold_vertices, 2);
    assert!(topo.boundary_loops.is_empty());
    assert_eq!(topo.open_boundary_chains, vec![2, 2, 2]);
    assert!(!topo.is_manifold());
    let c = &topo.components[0];
    assert!(!c.manifold && c.genus.is_none());
    assert_eq!(c.nonmanifold_edges, 1);
}

#[test]
fn bowtie_vertex_is_nonmanifold_and_splits_boundary_loops() {
    let p = vec![
        Vec3::ZERO,
        Vec3::new(1.0, -0.5, 0.0),
        Vec3::new(1.0, 0.5, 0.0),
        Vec3::new(-1.0, 0.5, 0.0),
        Vec3::new(-1.0, -0.5, 0.0),
    ];
    let m = TriMesh::new(p, vec![[0, 1, 2], [0, 3, 4]]).unwrap();
    let topo = Topology::of(&m);
    assert_eq!(topo.nonmanifold_vertices, 1);
    assert_eq!(topo.nonmanifold_edges, 0);
    assert_eq!(topo.components.len(), 1, "vertex-sharing triangles connect");
    assert_eq!(topo.boundary_loops, vec![3, 3]);
    assert_eq!(topo.euler, 1);
    // Two closed cubes touching at one corner: a pinch, so no genus.
    let mut touching = translated(&cube(), Vec3::ONE);
    touching.positions.remove(0);
    let n = cube().positions.len() as u32;
    touching.triangles = touching
        .triangles
        .iter()
        .map(|t| t.map(|v| if v == 0 { 7 } else { v - 1 + n }))
        .collect();
    let mut both = cube();
    both.positions.extend(touching.positions);
    both.triangles.extend(touching.triangles);
    both.validate().unwrap();
    let topo = Topology::of(&both);
    assert_eq!(topo.components.len(), 1);
    assert_eq!(topo.nonmanifold_vertices, 1);
    assert!(topo.closed);
    assert_eq!(topo.components[0].genus, None);
    assert_eq!(topo.euler, 3);
}

/// Strip of `n` quads in the plane, every triangle counter-clockwise.
fn strip(n: u32) -> TriMesh {
    let p = (0..=n)
        .flat_map(|i| [Vec3::new(i as f32, 0.0, 0.0), Vec3::new(i as f32, 1.0, 0.0)])
        .collect();
    let t = (0..n)
        .flat_map(|i| {
            let (a, b, c, d) = (2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
            [[a, b, c], [a, c, d]]
        })
        .collect();
    TriMesh::new(p, t).unwrap()
}

#[test]
fn inconsistent_strip_is_mixed_and_orient_consistently_fixes_the_minority() {
    let good = strip(5);
    let mut m = good.clone();
    m.triangles[3].swap(1, 2);
    m.triangles[7].swap(0, 1);
    let topo = Topology::of(&m);
    assert!(!topo.consistently_oriented);
    assert_eq!(topo.orientation, Orientation::Mixed);
    assert_eq!(
        topo.boundary_loops,
        vec![12],
        "loops do not need consistent winding"
    );
    assert_eq!(
        orient_outward(&mut m.clone()),
        0,
        "mixed components are left alone"
    );
    assert_eq!(orient_consistently(&mut m).unwrap(), 2);
    let after = Topology::of(&m);
    assert!(after.consistently_oriented);
    let normal = |m: &TriMesh, t: usize| {
        let [a, b, c] = m.triangles[t].map(|v| m.positions[v as usize]);
        (b - a).cross(c - a).z
    };
    assert!(
        (0..10).all(|t| normal(&m, t) > 0.0),
        "majority winding kept"
    );
    // Majority rule: with most triangles flipped the patch is wound the other way.
    let mut mostly = flipped(&good);
    mostly.triangles[0].swap(1, 2);
    assert_eq!(orient_consistently(&mut mostly).unwrap(), 1);
    assert_eq!(mostly, flipped(&good));
}

#[test]
fn moebius_strip_is_not_orientable() {
    let m = moebius(12);
    let topo = Topology::of(&m);
    assert!(!topo.consistently_oriented);
    assert_eq!(
        topo.boundary_loops,
        vec![24],
        "one boundary curve, twice around"
    );
    assert_eq!(topo.euler, 0);
    assert!(!topo.components[0].orientable);
    let mut copy = m.clone();
    let err = orient_consistently(&mut copy).unwrap_err();
    assert!(err.to_string().contains("non-orientable"), "{err}");
    assert_eq!(copy, m, "left unchanged on error");
}

#[test]
fn degenerate_triangles_are_counted_and_collapsed_ones_ignored() {
    let mut m = cube();
    m.positions.push(Vec3::new(2.0, 0.0, 0.0));
    m.positions.push(Vec3::new(3.0, 0.0, 0.0));
    m.positions.push(Vec3::new(4.0, 0.0, 0.0));
    m.triangles.push([8, 9, 10]); // collinear: zero area
    m.triangles.push([0, 0, 1]); // collapsed
    m.triangles.push([5, 5, 5]); // collapsed
    let topo = Topology::of(&m);
    assert_eq!(topo.triangles, 15);
    assert_eq!(topo.degenerate_triangles, 3);
    assert_eq!(topo.collapsed_triangles, 2);
    assert_eq!(topo.used_vertices, 11);
    assert_eq!(topo.edges, 18 + 3);
    assert_eq!(topo.components.len(), 2);
    assert_eq!(topo.components[1].triangles, 1);
    assert_eq!(topo.components[1].orientation, Orientation::Undetermined);
    assert_eq!(topo.orientation, Orientation::Outward);
    assert_eq!(topo.euler, 2 + 1);
}

#[test]
fn empty_mesh() {
    let topo = Topology::of(&TriMesh::default());
    assert_eq!((topo.edges, topo.euler, topo.components.len()), (0, 0, 0));
    assert!(!topo.closed && topo.bounds.is_none());
    assert_eq!(topo.orientation, Orientation::Undetermined);
}

#[test]
fn json_field_names() {
    let v = serde_json::to_value(Topology::of(&cube())).unwrap();
    assert_eq!(v["orientation"], "outward");
    assert_eq!(v["boundary_loops"], serde_json::json!([]));
    assert_eq!(v["components"][0]["genus"], 0);
    assert_eq!(v["bounds"]["min"], serde_json::json!([0.0, 0.0, 0.0]));
    assert_eq!(v["used_vertices"], 8);
}
