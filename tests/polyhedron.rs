//! Background components inside the hull (ZKH) and their classes.

mod common;

use chisel::hull::{ConvexHull, HullOptions};
use chisel::phantom::voxel::{cube, cylinder_tunnel, ellipsoid_dent, torus};
use chisel::polyhedron::{ZkhClass, background_components};
use chisel::volume::{Volume, VolumeData};
use chisel::voxel::{CandidateKind, Component, DigitalObject, Selection};

fn object(v: &Volume) -> DigitalObject {
    DigitalObject::from_volume(v, Selection::Threshold(1.0), Component::All).unwrap()
}

fn hull(o: &DigitalObject) -> ConvexHull {
    ConvexHull::of_object(o, CandidateKind::Local26, HullOptions::default()).unwrap()
}

#[test]
fn cylinder_tunnels_match_table_8_6() {
    for (d_o, d_i, voxels) in [(25, 10, 1_200), (50, 35, 14_595), (75, 60, 42_420)] {
        let o = object(&cylinder_tunnel(d_o, d_i, 15).unwrap());
        let h = hull(&o);
        let z = background_components(&o, &h).unwrap();
        assert_eq!(z.len(), 1, "{d_o}/{d_i}");
        assert_eq!(z[0].voxels, voxels);
        assert_eq!(z[0].class, ZkhClass::Tunnel);
        // The two sets are the top and the bottom face.
        assert!(
            z[0].face_sets.iter().all(|s| s.len() == 1),
            "{:?}",
            z[0].face_sets
        );
        // The component as an object of its own: the central cylinder.
        let s2 = &z[0].object;
        assert_eq!(s2.n_voxels(), voxels);
        assert_eq!(s2.voxel_bbox(), z[0].bbox);
        assert!(s2.voxels().all(|v| !o.contains(v)
            && h.containment(chisel::voxel::voxel_centre(v))
                != chisel::hull::Containment::Outside));
        let h2 = hull(s2);
        assert!(
            h2.vertices()
                .iter()
                .all(|&c| s2.contains(c.map(|x| (x - 1) / 2)))
        );
    }
}

#[test]
fn cavity_concavity_tunnel_branched() {
    // Cube with a 3×3×3 cavity.
    let o = common::carved(9, |x, y, z| {
        (4..=6).contains(&x) && (4..=6).contains(&y) && (4..=6).contains(&z)
    });
    let z = background_components(&o, &hull(&o)).unwrap();
    assert_eq!(
        (z.len(), z[0].class, z[0].voxels),
        (1, ZkhClass::Cavity, 27)
    );
    assert!(z[0].face_sets.is_empty());
    // Cube with a pit in the top face: a concavity.
    let o = common::carved(9, |x, y, z| {
        (4..=6).contains(&x) && (4..=6).contains(&y) && z >= 7
    });
    let z = background_components(&o, &hull(&o)).unwrap();
    assert_eq!(
        (z.len(), z[0].class, z[0].voxels),
        (1, ZkhClass::Concavity, 27)
    );
    // Straight tunnel along x.
    let o = common::carved(9, |_, y, z| y == 5 && z == 5);
    let z = background_components(&o, &hull(&o)).unwrap();
    assert_eq!((z.len(), z[0].class, z[0].voxels), (1, ZkhClass::Tunnel, 9));
    // Crossing tunnels in a cube: the four exits lie on four side faces,
    // which are edge-connected through each other — one set, so by Def. CO
    // a concavity (the seed's Fig. 4.16 shows exactly this case).
    let o = common::carved(9, |x, y, z| z == 5 && (y == 5 || x == 5));
    let z = background_components(&o, &hull(&o)).unwrap();
    assert_eq!(
        (z.len(), z[0].class, z[0].face_sets.len()),
        (1, ZkhClass::Concavity, 1)
    );
    // The same cross in a ball: four exits on separate facet patches.
    let ball = chisel::phantom::voxel::digital_ball(30).unwrap();
    let n = ball.dims[0];
    let VolumeData::U8(mut data) = ball.data.clone() else {
        unreachable!()
    };
    for z in 15..=16 {
        for y in 0..n {
            for x in 0..n {
                if (15..=16).contains(&y) || (15..=16).contains(&x) {
                    data[x + n * (y + n * z)] = 0;
                }
            }
        }
    }
    let o = object(&Volume::new(ball.dims, [1.0; 3], [0.0; 3], VolumeData::U8(data)).unwrap());
    let z = background_components(&o, &hull(&o)).unwrap();
    let big = z.iter().max_by_key(|c| c.voxels).unwrap();
    assert_eq!(
        (big.class, big.face_sets.len()),
        (ZkhClass::BranchedTunnel, 4),
        "{z:?}"
    );
    // Two separate tunnels: two ZKHs.
    let o = common::carved(9, |_, y, z| z == 5 && (y == 3 || y == 7));
    let z = background_components(&o, &hull(&o)).unwrap();
    assert_eq!(
        z.iter().map(|c| c.class).collect::<Vec<_>>(),
        vec![ZkhClass::Tunnel; 2]
    );
    // A convex object has none.
    let o = object(&cube(5).unwrap());
    assert!(background_components(&o, &hull(&o)).unwrap().is_empty());
}

#[test]
fn seed_objects_classes() {
    let o = object(&torus(40, 12).unwrap());
    let z = background_components(&o, &hull(&o)).unwrap();
    assert!(z.iter().any(|c| c.class == ZkhClass::Tunnel), "{z:?}");
    let o = object(&ellipsoid_dent(13, 13, 8, 5).unwrap());
    let z = background_components(&o, &hull(&o)).unwrap();
    let big = z.iter().max_by_key(|c| c.voxels).unwrap();
    assert_eq!(big.class, ZkhClass::Concavity);
}

#[test]
fn flat_hull_has_no_inside() {
    let v = Volume::new(
        [4, 4, 3],
        [1.0; 3],
        [0.0; 3],
        VolumeData::U8({
            let mut d = vec![0u8; 48];
            for i in [5, 6, 9, 10] {
                d[16 + i] = 1;
            }
            d
        }),
    )
    .unwrap();
    let o = object(&v);
    let h = hull(&o);
    assert!(h.is_planar());
    assert!(matches!(
        background_components(&o, &h),
        Err(chisel::Error::Refused(chisel::Refusal::Flat { .. }))
    ));
}

#[test]
fn real_ct_bone_components() {
    let Some(o) = common::ct_bone() else {
        return;
    };
    let h = hull(&o);
    let z = background_components(&o, &h).unwrap();
    let count = |k| z.iter().filter(|c| c.class == k).count();
    eprintln!(
        "headsq bone: {} ZKH: {} cavities, {} concavities, {} tunnels, {} branched; largest {} voxels",
        z.len(),
        count(ZkhClass::Cavity),
        count(ZkhClass::Concavity),
        count(ZkhClass::Tunnel),
        count(ZkhClass::BranchedTunnel),
        z.iter().map(|c| c.voxels).max().unwrap_or(0)
    );
    assert!(count(ZkhClass::Cavity) > 0 && count(ZkhClass::Concavity) > 0);
    // Every background voxel inside the hull belongs to exactly one ZKH.
    let total: u64 = z.iter().map(|c| c.voxels).sum();
    let (lo, hi) = h.voxel_bbox();
    let hs = h.half_spaces();
    let mut brute = 0u64;
    for zz in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                let c = chisel::voxel::voxel_centre([x, y, zz]);
                brute += u64::from(!o.contains([x, y, zz]) && hs.iter().all(|s| s.side(c) <= 0));
            }
        }
    }
    assert_eq!(total, brute);
}

#[test]
fn pressing_in_selects_the_faces_the_component_crosses() {
    use chisel::polyhedron::faces_to_press;
    // Tunnel through a cylinder: the top and bottom faces.
    let o = object(&cylinder_tunnel(25, 10, 15).unwrap());
    let h = hull(&o);
    let z = background_components(&o, &h).unwrap();
    let marked = faces_to_press(&h, &z[0]);
    let mut expect: Vec<u32> = z[0].face_sets.iter().flatten().copied().collect();
    expect.sort_unstable();
    assert_eq!(marked, expect);
    for &f in &marked {
        assert_eq!(h.faces()[f as usize].plane.normal.map(i64::abs), [0, 0, 1]);
    }
    // A pit in the top face of a cube: only the top face.
    let o = common::carved(9, |x, y, z| {
        (4..=6).contains(&x) && (4..=6).contains(&y) && z >= 7
    });
    let h = hull(&o);
    let z = background_components(&o, &h).unwrap();
    let marked = faces_to_press(&h, &z[0]);
    assert_eq!(marked.len(), 1);
    assert_eq!(h.faces()[marked[0] as usize].plane.normal, [0, 0, 1]);
    // A cavity: nothing to press.
    let o = common::carved(9, |x, y, z| {
        (4..=6).contains(&x) && (4..=6).contains(&y) && (4..=6).contains(&z)
    });
    let h = hull(&o);
    let z = background_components(&o, &h).unwrap();
    assert!(faces_to_press(&h, &z[0]).is_empty());
    // A groove along the top edge region of a cube touches the top face
    // only along its interior: the x = max face is crossed too when the
    // groove runs out through it.
    let o = common::carved(9, |x, y, z| x >= 5 && y == 5 && z == 9);
    let h = hull(&o);
    let z = background_components(&o, &h).unwrap();
    let marked = faces_to_press(&h, &z[0]);
    let normals: Vec<[i64; 3]> = marked
        .iter()
        .map(|&f| h.faces()[f as usize].plane.normal)
        .collect();
    assert!(
        normals.contains(&[0, 0, 1]) && normals.contains(&[1, 0, 0]),
        "{normals:?}"
    );
}
