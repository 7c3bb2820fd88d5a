//! The real meshes' figures from `../shared/data/README.md`.

use chisel::mesh::{Orientation, Topology, orient_outward};

use crate::common::real_mesh;
use crate::flipped;

#[test]
fn fran_cut_is_an_inward_disk() {
    let Some(m) = real_mesh("fran_cut.vtk") else {
        return;
    };
    let topo = Topology::of(&m);
    assert_eq!(
        (topo.vertices, topo.used_vertices, topo.triangles),
        (2205, 2205, 4224)
    );
    assert_eq!(topo.degenerate_triangles, 0);
    assert_eq!(
        (topo.edges, topo.boundary_edges, topo.manifold_edges),
        (6428, 184, 6244)
    );
    assert_eq!((topo.nonmanifold_edges, topo.nonmanifold_vertices), (0, 0));
    assert_eq!(topo.components.len(), 1);
    assert_eq!(topo.boundary_loops, vec![184]);
    assert_eq!(topo.euler, 1);
    assert!(topo.consistently_oriented && !topo.closed);
    assert_eq!(topo.orientation, Orientation::Inward);
    assert!((topo.area - 0.033760).abs() < 1e-5, "{}", topo.area);
    let mut out = m.clone();
    assert_eq!(orient_outward(&mut out), 1);
    assert_eq!(Topology::of(&out).orientation, Orientation::Outward);
}

#[test]
fn bunny_is_inward_genus_zero_with_five_holes() {
    let Some(m) = real_mesh("bunny.ply") else {
        return;
    };
    let topo = Topology::of(&m);
    assert_eq!(
        (topo.vertices, topo.used_vertices, topo.triangles),
        (35947, 34834, 69451)
    );
    assert_eq!(topo.degenerate_triangles, 0);
    assert_eq!(
        (topo.edges, topo.boundary_edges, topo.manifold_edges),
        (104288, 223, 104065)
    );
    assert_eq!((topo.nonmanifold_edges, topo.nonmanifold_vertices), (0, 0));
    assert_eq!(topo.boundary_loops, vec![80, 42, 40, 39, 22]);
    assert_eq!(topo.euler, -3);
    assert_eq!(topo.components.len(), 1);
    assert!(topo.consistently_oriented);
    assert_eq!(topo.orientation, Orientation::Inward);
    assert!((topo.area - 0.057129).abs() < 1e-5, "{}", topo.area);
    assert!(topo.signed_volume < -5e-4, "{}", topo.signed_volume);
}

#[test]
fn footbones_are_26_outward_genus_zero_shells() {
    let Some(m) = real_mesh("fsu/footbones.ply") else {
        return;
    };
    let topo = Topology::of(&m);
    assert_eq!(
        (topo.vertices, topo.used_vertices, topo.triangles),
        (2154, 2154, 4204)
    );
    assert_eq!(
        (topo.edges, topo.boundary_edges, topo.manifold_edges),
        (6306, 0, 6306)
    );
    assert_eq!(topo.nonmanifold_vertices, 0);
    assert_eq!(topo.euler, 52);
    assert!(topo.closed && topo.consistently_oriented);
    let tris: Vec<usize> = topo.components.iter().map(|c| c.triangles).collect();
    assert_eq!(
        tris,
        vec![
            598, 586, 392, 360, 228, 212, 154, 146, 146, 146, 134, 134, 134, 126, 124, 74, 66, 60,
            60, 60, 48, 46, 46, 46, 46, 32
        ]
    );
    assert!(
        topo.components
            .iter()
            .all(|c| c.closed && c.genus == Some(0))
    );
    assert!(
        topo.components
            .iter()
            .all(|c| c.orientation == Orientation::Outward)
    );
    assert_eq!(topo.orientation, Orientation::Outward);
    assert!(
        (topo.signed_volume - 18.5289).abs() < 1e-3,
        "{}",
        topo.signed_volume
    );
    let mut f = flipped(&m);
    assert_eq!(Topology::of(&f).orientation, Orientation::Inward);
    assert_eq!(orient_outward(&mut f), 26);
    assert_eq!(Topology::of(&f).orientation, Orientation::Outward);
    assert_eq!(f, m);
}
