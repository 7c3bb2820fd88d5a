//! Network construction: class counts on open, closed and multi-component
//! meshes, the default origin, eq. 4.1 links, refused networks, stiffness
//! regions and bend springs.

use super::*;

fn two_spheres() -> TriMesh {
    let a = common::icosphere(1);
    let mut m = a.clone();
    let off = a.n_vertices() as u32;
    m.positions
        .extend(a.positions.iter().map(|p| *p + Vec3::new(3.0, 0.0, 0.0)));
    m.triangles
        .extend(a.triangles.iter().map(|t| t.map(|i| i + off)));
    m
}

/// With the default bone (a scaled copy), eq. 4.1 links q_i to b_i, so the
/// class counts have closed forms in #V and #E.
fn check_counts(mesh: &TriMesh) -> SpringNetwork {
    let net = SpringNetwork::build(mesh, None, &NetworkParams::default()).unwrap();
    let n = mesh.n_vertices();
    let e = unique_edges(&mesh.triangles).len();
    assert_eq!(net.n_nodes(), 3 * n);
    assert_eq!(net.n_free, 2 * n);
    assert_eq!(net.class_counts(), [e, n + 2 * e, e, n + 2 * e, e, 0]);
    // Rest length = initial length; springs unique and ordered.
    for w in net.springs.windows(2) {
        assert!((w[0].a, w[0].b) < (w[1].a, w[1].b));
    }
    for s in &net.springs {
        let (a, b) = (net.rest[s.a as usize], net.rest[s.b as usize]);
        let d = Vec3::new(a[0] - b[0], a[1] - b[1], a[2] - b[2]).length();
        assert!((d - s.rest).abs() <= 1e-6 * d.max(1.0));
    }
    // The gather CSR is the symmetric closure over free nodes, rows sorted.
    let mut expect = 0;
    for s in &net.springs {
        expect +=
            usize::from((s.a as usize) < net.n_free) + usize::from((s.b as usize) < net.n_free);
    }
    assert_eq!(net.csr.entries.len(), expect);
    for i in 0..net.n_free {
        let row = &net.csr.entries[net.csr.offsets[i] as usize..net.csr.offsets[i + 1] as usize];
        let ids: Vec<u32> = row.iter().map(|e| e & 0x0fff_ffff).collect();
        assert!(ids.windows(2).all(|w| w[0] < w[1]), "row {i} not sorted");
    }
    net
}

#[test]
fn network_counts_open_closed_and_multi_component() {
    check_counts(&grid(6, 5));
    let closed = check_counts(&common::icosphere(2));
    // Closed surface: origin at the bounding-box centre, layers nest.
    assert!(closed.origin.length() < 1e-6);
    check_counts(&two_spheres());
}

#[test]
fn default_origin_is_behind_an_open_patch_whatever_the_winding() {
    let mut m = grid(5, 5);
    // Bulge the patch toward +z so its outer side is +z.
    for p in &mut m.positions {
        p.z = 3.0 - 0.1 * ((p.x - 2.0).powi(2) + (p.y - 2.0).powi(2));
    }
    let o = chisel::tissue::default_origin(&m).unwrap();
    let lo = m.bounds().unwrap().0;
    assert_eq!(o.z, lo.z, "origin must be on the back (−z) face");
    m.flip_winding();
    assert_eq!(chisel::tissue::default_origin(&m).unwrap(), o);
}

#[test]
fn nearest_bone_links_follow_eq_4_1_with_a_real_bone_mesh() {
    let skin = common::icosphere(2);
    let mut bone = common::icosphere(1);
    for p in &mut bone.positions {
        *p = *p * 0.6 + Vec3::new(0.05, -0.02, 0.0);
    }
    let params = NetworkParams {
        origin: Some([0.0; 3]),
        ..NetworkParams::default()
    };
    let net = SpringNetwork::build(&skin, Some(&bone), &params).unwrap();
    let n = skin.n_vertices();
    let s = 0.7f64 / 0.8;
    for i in 0..n {
        let q = net.rest[n + i];
        let target = DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64) * s;
        let brute = (0..bone.n_vertices())
            .min_by(|&a, &b| {
                let da = bone.positions[a].as_dvec3().distance_squared(target);
                let db = bone.positions[b].as_dvec3().distance_squared(target);
                da.total_cmp(&db).then(a.cmp(&b))
            })
            .unwrap();
        let b = (2 * n + brute) as u32;
        assert!(
            net.springs
                .iter()
                .any(|sp| sp.a == (n + i) as u32 && sp.b == b && sp.class == SpringClass::Muscle),
            "q_{i} not linked to its nearest bone vertex {brute}"
        );
    }
    // Bone nodes are fixed: no CSR rows.
    assert_eq!(net.csr.offsets.len(), 2 * n + 1);
}

#[test]
fn unused_vertices_keep_dermis_and_muscle_links() {
    let mut m = grid(4, 4);
    m.positions.push(Vec3::new(1.5, 1.5, 2.0));
    let net = SpringNetwork::build(&m, None, &NetworkParams::default()).unwrap();
    let v = (m.n_vertices() - 1) as u32;
    let n = m.n_vertices() as u32;
    let has = |a, b, c| {
        net.springs
            .iter()
            .any(|s| s.a == a && s.b == b && s.class == c)
    };
    assert!(has(v, n + v, SpringClass::Dermis));
    assert!(has(n + v, 2 * n + v, SpringClass::Muscle));
}

#[test]
fn bad_networks_are_refused() {
    let empty = TriMesh::default();
    assert!(matches!(
        SpringNetwork::build(&empty, None, &NetworkParams::default()),
        Err(chisel::Error::Empty { .. })
    ));
    let m = grid(3, 3);
    let bad_scale = NetworkParams {
        subcutis_scale: f32::NAN,
        ..NetworkParams::default()
    };
    assert!(matches!(
        SpringNetwork::build(&m, None, &bad_scale),
        Err(chisel::Error::InvalidParameter { ref name, .. }) if name == "subcutis_scale"
    ));
    let bad_origin = NetworkParams {
        origin: Some([0.0, f32::INFINITY, 0.0]),
        ..NetworkParams::default()
    };
    let e = SpringNetwork::build(&m, None, &bad_origin).unwrap_err();
    assert!(e.to_string().contains("origin"), "{e}");
}

#[test]
fn stiffness_regions_override_springs_in_the_region() {
    let m = grid(6, 6);
    let params = NetworkParams {
        regions: vec![chisel::tissue::StiffnessRegion {
            region: Selector::Box {
                min: [-1.0, -1.0, -10.0],
                max: [2.0, 2.0, 10.0],
            },
            class: Some(SpringClass::Epidermis),
            scale: 4.0,
        }],
        ..NetworkParams::default()
    };
    let net = SpringNetwork::build(&m, None, &params).unwrap();
    assert_eq!(net.materials.len(), 7);
    assert_eq!(net.materials[6].c1, 4.0);
    let overridden = net.springs.iter().filter(|s| s.material == 6).count();
    assert!(overridden > 0);
    assert!(
        net.springs
            .iter()
            .filter(|s| s.material == 6)
            .all(|s| s.class == SpringClass::Epidermis)
    );
}

fn with_bending(c: f32) -> NetworkParams {
    NetworkParams {
        stiffness: Stiffness {
            bending: Material::linear(c),
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Bend springs join the two apexes of every interior epidermis edge
/// (rest = their distance); where the apexes already share an edge (a
/// tetrahedron) the epidermis spring is kept.
#[test]
fn bend_springs_span_each_interior_edge() {
    let sphere = common::icosphere(2);
    let net = SpringNetwork::build(&sphere, None, &with_bending(0.5)).unwrap();
    let (n, e) = (sphere.n_vertices(), unique_edges(&sphere.triangles).len());
    assert_eq!(net.class_counts(), [e, n + 2 * e, e, n + 2 * e, e, e]);
    assert_eq!(net.materials[SpringClass::Bending as usize].c1, 0.5);
    let mut apexes = std::collections::HashMap::<(u32, u32), Vec<u32>>::new();
    for t in &sphere.triangles {
        for k in 0..3 {
            let (a, b) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
            apexes.entry((a, b)).or_default().push(t[(k + 2) % 3]);
        }
    }
    let mut want: Vec<(u32, u32)> = apexes
        .values()
        .map(|c| (c[0].min(c[1]), c[0].max(c[1])))
        .collect();
    want.sort_unstable();
    let got: Vec<(u32, u32)> = net
        .springs
        .iter()
        .filter(|s| s.class == SpringClass::Bending)
        .map(|s| (s.a, s.b))
        .collect();
    assert_eq!(got, want);
    // Open grid: one per interior edge; the border edges have one apex.
    let g = grid(6, 5);
    let net = SpringNetwork::build(&g, None, &with_bending(1.0)).unwrap();
    let interior = unique_edges(&g.triangles).len() - 2 * (5 + 4);
    assert_eq!(net.class_counts()[5], interior);
    let tetra = SpringNetwork::build(&common::tetra(), None, &with_bending(1.0)).unwrap();
    assert_eq!(tetra.class_counts()[5], 0);
    assert_eq!(tetra.class_counts()[0], 6);
    // Off by default; negative stiffness refused.
    let plain = SpringNetwork::build(&sphere, None, &NetworkParams::default()).unwrap();
    assert_eq!(plain.class_counts()[5], 0);
    for bad in [-1.0, f32::NAN] {
        let e = SpringNetwork::build(&sphere, None, &with_bending(bad)).unwrap_err();
        assert!(e.to_string().contains("Bending"), "{e}");
    }
}
