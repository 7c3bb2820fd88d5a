//! Digital objects, their boundary complex and the seed's test objects.

mod common;

use chisel::phantom::voxel::{cube, cylinder_tunnel, digital_ball, ellipsoid_dent, torus};
use chisel::volume::{Volume, VolumeData};
use chisel::voxel::{
    CandidateKind, Component, DigitalObject, Frame, Selection, marching_cubes_integers,
};

fn object(v: &Volume) -> DigitalObject {
    DigitalObject::from_volume(v, Selection::Threshold(1.0), Component::All).unwrap()
}

fn from_voxels(dims: [usize; 3], voxels: &[[usize; 3]]) -> DigitalObject {
    let mut mask = vec![false; dims.iter().product()];
    for v in voxels {
        mask[v[0] + dims[0] * (v[1] + dims[1] * v[2])] = true;
    }
    DigitalObject::from_mask(dims, &mask, Frame::default()).unwrap()
}

#[test]
fn seed_ball_r100_has_523984_voxels() {
    // §3.3: "Eine digitale Kugel mit dem Radius 100 und einer 0-Zelle als
    // Mittelpunkt besteht aus 523984 Voxeln".
    assert_eq!(object(&digital_ball(100).unwrap()).n_voxels(), 523_984);
}

#[test]
fn seed_cylinders_table_8_6() {
    // (d_o, d_i, voxels, facets, marching-cubes triangles, MC integers)
    let rows = [
        (25, 10, 6_060, 2_848, 5_696, 25_632),
        (50, 35, 14_520, 6_976, 13_952, 62_784),
        (75, 60, 23_640, 11_192, 22_384, 100_728),
        (100, 85, 32_160, 15_328, 30_656, 137_952),
    ];
    for (d_o, d_i, voxels, facets, tris, ints) in rows {
        let o = object(&cylinder_tunnel(d_o, d_i, 15).unwrap());
        assert_eq!(o.n_voxels(), voxels, "{d_o}/{d_i}");
        assert_eq!(o.n_boundary_facets(), facets, "{d_o}/{d_i}");
        assert_eq!(2 * o.n_boundary_facets(), tris);
        assert_eq!(marching_cubes_integers(tris), ints);
        let t = o.topology().unwrap();
        assert_eq!(t.n2, facets);
        assert_eq!(
            (t.genus, t.tunnels, t.cavities, t.shells),
            (1, 1, 0, 1),
            "{d_o}/{d_i}"
        );
    }
}

#[test]
fn single_voxel_boundary_is_a_sphere() {
    let o = from_voxels([3, 3, 3], &[[1, 1, 1]]);
    let t = o.topology().unwrap();
    assert_eq!((t.n0, t.n1, t.n2, t.euler, t.genus), (8, 12, 6, 2, 0));
    assert_eq!(
        (t.convex_vertices, t.convex_edges, t.concave_edges),
        (8, 12, 0)
    );
    assert_eq!(o.n_boundary_facets(), 6);
}

#[test]
fn genus_and_lhuilier_counts() {
    let t = object(&cube(6).unwrap()).topology().unwrap();
    assert_eq!(
        (t.genus, t.tunnels, t.cavities, t.shells, t.components),
        (0, 0, 0, 1, 1)
    );
    assert_eq!(
        (t.convex_vertices, t.concave_vertices, t.saddle_vertices),
        (8, 0, 0)
    );

    let t = object(&torus(24, 8).unwrap()).topology().unwrap();
    assert_eq!((t.genus, t.tunnels, t.cavities), (1, 1, 0));
    assert_eq!(t.non_manifold_edges + t.non_manifold_vertices, 0);

    // Cube with a one-voxel cavity: two shells, eq. 4.3 gives g = −1 and
    // Lhuilier's eq. 4.4 b = 1, t = 0 (the seed's Fig. 4.18 example).
    let mut voxels = Vec::new();
    for z in 1..6 {
        for y in 1..6 {
            for x in 1..6 {
                if [x, y, z] != [3, 3, 3] {
                    voxels.push([x, y, z]);
                }
            }
        }
    }
    let t = from_voxels([7, 7, 7], &voxels).topology().unwrap();
    assert_eq!(
        (t.euler, t.genus, t.shells, t.cavities, t.tunnels),
        (4, -1, 2, 1, 0)
    );
}

#[test]
fn non_manifold_edge_and_vertex_are_counted_and_opened() {
    // Two voxels sharing only an edge: two 6-components, two spheres.
    let t = from_voxels([4, 4, 3], &[[1, 1, 1], [2, 2, 1]])
        .topology()
        .unwrap();
    assert_eq!((t.non_manifold_edges, t.non_manifold_vertices), (1, 2));
    assert_eq!((t.n0, t.n1, t.n2, t.euler), (16, 24, 12, 4));
    assert_eq!(
        (t.components, t.shells, t.cavities, t.tunnels),
        (2, 2, 0, 0)
    );
    // Sharing only a vertex.
    let t = from_voxels([4, 4, 4], &[[1, 1, 1], [2, 2, 2]])
        .topology()
        .unwrap();
    assert_eq!((t.non_manifold_edges, t.non_manifold_vertices), (0, 1));
    assert_eq!((t.n0, t.n1, t.n2, t.euler, t.shells), (16, 24, 12, 4, 2));
    // A ring of four voxels closed through edge contacts only: genus 0 per
    // component, no tunnel (the object is four 6-components).
    let t = from_voxels([5, 5, 3], &[[1, 2, 1], [2, 1, 1], [3, 2, 1], [2, 3, 1]])
        .topology()
        .unwrap();
    assert_eq!(
        (t.components, t.shells, t.tunnels, t.non_manifold_edges),
        (4, 4, 0, 4)
    );
}

#[test]
fn candidates_of_a_cube_are_its_corners() {
    let o = object(&cube(5).unwrap());
    for kind in [
        CandidateKind::Local6,
        CandidateKind::Local18,
        CandidateKind::Local26,
        CandidateKind::ConvexVoxels,
    ] {
        let c = o.candidates(kind);
        assert_eq!(c.len(), 8, "{kind:?}");
        assert!(
            c.iter().all(|p| p.iter().all(|&x| x == 3 || x == 11)),
            "{kind:?}: {c:?}"
        );
    }
    let c = o.candidates(CandidateKind::ConvexCorners);
    assert_eq!(c.len(), 8);
    assert!(
        c.iter().all(|p| p.iter().all(|&x| x == 2 || x == 12)),
        "{c:?}"
    );
}

#[test]
fn larger_neighbourhoods_prune_more() {
    let o = object(&digital_ball(24).unwrap());
    let n6 = o.candidates(CandidateKind::Local6).len();
    let n18 = o.candidates(CandidateKind::Local18).len();
    let n26 = o.candidates(CandidateKind::Local26).len();
    assert!(n26 <= n18 && n18 <= n6 && n26 > 0, "{n6} {n18} {n26}");
}

#[test]
fn selection_by_label_and_component() {
    // Two blobs of label 7 (sizes 2 and 1) and one voxel of label 3.
    let dims = [6, 3, 3];
    let mut data = vec![0u8; 54];
    let at = |x: usize| x + 6 * (1 + 3);
    data[at(1)] = 7;
    data[at(2)] = 7;
    data[at(4)] = 7;
    data[at(3)] = 3;
    let v = Volume::new(dims, [1.0; 3], [0.0; 3], VolumeData::U8(data)).unwrap();
    let largest =
        DigitalObject::from_volume(&v, chisel::voxel::Selection::Label(7.0), Component::Largest)
            .unwrap();
    assert_eq!(largest.n_voxels(), 2);
    assert_eq!(largest.voxel_bbox(), ([1, 1, 1], [2, 1, 1]));
    assert!(
        largest.contains([1, 1, 1])
            && !largest.contains([4, 1, 1])
            && !largest.contains([-5, 0, 0])
    );
    let all = DigitalObject::from_volume(&v, Selection::Label(7.0), Component::All).unwrap();
    assert_eq!(all.n_voxels(), 3);
    let second =
        DigitalObject::from_volume(&v, Selection::Label(7.0), Component::Index(2)).unwrap();
    assert_eq!(second.voxels().collect::<Vec<_>>(), vec![[4, 1, 1]]);
    assert!(matches!(
        DigitalObject::from_volume(&v, Selection::Label(7.0), Component::Index(3)),
        Err(chisel::Error::InvalidParameter { ref name, .. }) if name == "component"
    ));
    assert!(matches!(
        DigitalObject::from_volume(&v, Selection::Label(9.0), Component::All),
        Err(chisel::Error::Refused(
            chisel::Refusal::EmptySelection { .. }
        ))
    ));
    let thr =
        DigitalObject::from_volume(&v, Selection::Threshold(3.0), Component::Largest).unwrap();
    assert_eq!(thr.n_voxels(), 4);
}

#[test]
fn phantoms_reject_bad_sizes() {
    let refused = |r: chisel::Result<chisel::Volume>, param: &str| {
        assert!(
            matches!(&r, Err(chisel::Error::InvalidParameter { name, .. }) if name == param),
            "{param}: {:?}",
            r.err()
        );
    };
    refused(digital_ball(0), "ball radius");
    refused(cylinder_tunnel(10, 10, 5), "inner diameter");
    refused(torus(5, 5), "torus tube radius");
    refused(ellipsoid_dent(5, 5, 3, 3), "dent radius");
    let o = object(&ellipsoid_dent(10, 10, 7, 4).unwrap());
    let t = o.topology().unwrap();
    assert_eq!((t.genus, t.shells), (0, 1));
}

#[test]
fn real_ct_bone_topology() {
    let Some(o) = common::ct_bone() else {
        return;
    };
    let t = o.topology().unwrap();
    eprintln!("headsq ≥ 1150 largest: {} voxels, {t:?}", o.n_voxels());
    assert_eq!(t.euler, t.n0 as i64 - t.n1 as i64 + t.n2 as i64);
    assert_eq!(t.n2, o.n_boundary_facets());
    assert_eq!(t.components, 1);
    // Closed orientable surfaces have an even Euler characteristic.
    assert_eq!(t.euler % 2, 0);
    assert!(t.genus > 0, "the skull has tunnels");
}
