//! Knife location: the tree equals the brute-force locate, leaf tables, and a forest
//! of another mesh is refused.

use super::*;
use chisel::foundation::forest::LEAF_VERTICES;

/// Everything but the counts: crossed triangles, cut vertex numbering,
/// points (bit for bit) and sides.
fn same_located(a: &Located, b: &Located, what: &str) {
    assert_eq!(a.triangles, b.triangles, "{what}: crossed triangles");
    assert_eq!(a.edge_cuts, b.edge_cuts, "{what}: edge cuts");
    assert_eq!(a.points, b.points, "{what}: points");
    assert_eq!(a.lower_negative, b.lower_negative, "{what}: sides");
    assert_eq!(a.edges, b.edges, "{what}: edges");
}

#[test]
fn tree_locate_equals_the_scan_on_every_analytic_knife() {
    let s = mc(&shell_volume(40, 11.0, 16.0));
    let c = DVec3::splat(19.5);
    let knives = [
        plane([19.5, 19.5, 21.3], [0.1, 0.2, 1.0]),
        plane([19.5, 19.5, 19.5], [0.0, 0.0, 1.0]),
        Knife::Sphere {
            centre: c + DVec3::new(13.0, 2.0, 1.0),
            radius: 6.3,
        },
        Knife::Rect {
            centre: c,
            normal: DVec3::new(0.3, -0.2, 1.0),
            u_axis: DVec3::X,
            half_extents: [14.0, 6.0],
        },
    ];
    let plain = Forest::from_triangles(s.mesh.view()).forest;
    // The same boxes taken as unsorted: every child box is tested instead
    // of the binary-searched slab.
    assert!(s.forest.axis_sorted);
    let unsorted = Forest {
        axis_sorted: false,
        ..s.forest.clone()
    };
    for k in &knives {
        let scan = locate_brute_force(&s.mesh, k).unwrap();
        assert!(!scan.triangles.is_empty(), "{k:?} misses the shell");
        let tree = locate(&s.mesh, &s.forest, k).unwrap();
        same_located(&tree, &scan, "marching-cubes forest");
        assert!(tree.stats.triangles_tested < tree.stats.triangles_total / 4);
        same_located(
            &locate(&s.mesh, &plain, k).unwrap(),
            &scan,
            "virtual-grid forest",
        );
        let all = locate(&s.mesh, &unsorted, k).unwrap();
        same_located(&all, &scan, "unsorted forest");
        assert!(all.stats.nodes_visited > tree.stats.nodes_visited, "{k:?}");
        assert!(all.stats.triangles_tested >= tree.stats.triangles_tested);
    }
    // Negative control: a knife moved by a tenth of a voxel differs.
    let moved = plane([19.5, 19.5, 21.4], [0.1, 0.2, 1.0]);
    let a = locate(&s.mesh, &s.forest, &knives[0]).unwrap();
    let b = locate(&s.mesh, &s.forest, &moved).unwrap();
    assert_ne!(a.points, b.points);
}

/// Every leaf's tables: its distinct vertices in order of first use by its
/// triangles, their positions, and each triangle's corners as indices into
/// them. Returns the most vertices a leaf lists.
fn check_leaf_tables(mesh: &TriMesh, f: &Forest) -> usize {
    assert_eq!(f.corners.len(), f.triangles.len());
    assert_eq!(f.leaf_positions.len(), f.leaf_vertices.len());
    for (&v, &q) in f.leaf_vertices.iter().zip(&f.leaf_positions) {
        assert_eq!(q, mesh.positions[v as usize], "leaf position of vertex {v}");
    }
    let mut most = 0;
    for c in &f.cells {
        let mut first_use = Vec::new();
        let mut seen = std::collections::HashSet::new();
        for i in c.triangles.range() {
            for v in mesh.triangles[f.triangles[i] as usize] {
                if seen.insert(v) {
                    first_use.push(v);
                }
            }
        }
        assert_eq!(&f.leaf_vertices[c.vertices.range()], &first_use[..]);
        most = most.max(first_use.len());
        assert!(first_use.len() <= LEAF_VERTICES);
        for i in c.triangles.range() {
            let want = mesh.triangles[f.triangles[i] as usize];
            let got = f.corners[i].map(|v| {
                assert!(usize::from(v) < c.vertices.len());
                f.leaf_vertices[c.vertices.start as usize + usize::from(v)]
            });
            assert_eq!(got, want);
        }
    }
    most
}

#[test]
fn leaf_tables_name_each_triangles_corners_and_positions() {
    let s = mc(&shell_volume(24, 6.0, 9.0));
    check_leaf_tables(&s.mesh, &s.forest);
    // A dense patch far smaller than the bounding box puts thousands of
    // vertices into one leaf of the virtual grid (more than the build's
    // first vertex table holds).
    let dense = dense_patch(60);
    let f = Forest::from_triangles(dense.view()).forest;
    let most = check_leaf_tables(&dense, &f);
    assert!(most > 2048, "the dense leaf lists {most} vertices");
}

/// A square patch of `n`×`n` vertices 1e-5 apart and one triangle 100
/// away: the patch falls into one cell of the virtual grid.
fn dense_patch(n: u32) -> TriMesh {
    let mut positions: Vec<glam::Vec3> = (0..n * n)
        .map(|i| glam::Vec3::new((i % n) as f32 * 1e-5, (i / n) as f32 * 1e-5, 0.0))
        .collect();
    let mut triangles = Vec::new();
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let a = x + n * y;
            triangles.push([a, a + 1, a + n + 1]);
            triangles.push([a, a + n + 1, a + n]);
        }
    }
    let far = positions.len() as u32;
    positions.extend([
        glam::Vec3::splat(100.0),
        glam::Vec3::new(101.0, 100.0, 100.0),
        glam::Vec3::new(100.0, 101.0, 100.0),
    ]);
    triangles.push([far, far + 1, far + 2]);
    TriMesh::new(positions, triangles).unwrap()
}

#[test]
fn a_cell_listing_more_vertices_than_a_leaf_holds_gets_several_leaves() {
    // 300² = 90,000 vertices in one cell: two leaves, each within
    // `LEAF_VERTICES`, and the tree still finds what the scan finds.
    let dense = dense_patch(300);
    let f = Forest::from_triangles(dense.view()).forest;
    let most = check_leaf_tables(&dense, &f);
    assert!(
        most > LEAF_VERTICES / 2,
        "the fullest leaf lists {most} vertices"
    );
    let split = f.rows.iter().any(|r| {
        let cells = &f.cells[r.cells.range()];
        cells.windows(2).any(|w| w[0].x == w[1].x)
    });
    assert!(split, "the dense cell is split into leaves with one key");
    for k in [
        plane([1.5e-3, 1.5e-3, 0.0], [1.0, 0.3, 0.1]),
        plane([0.7e-3, 2.9e-3, 0.0], [0.2, 1.0, 0.0]),
    ] {
        let tree = locate(&dense, &f, &k).unwrap();
        let scan = locate_brute_force(&dense, &k).unwrap();
        assert!(!tree.triangles.is_empty());
        same_located(&tree, &scan, "dense patch");
    }
}

#[test]
fn a_forest_of_another_mesh_is_an_error() {
    let s = mc(&ball_volume(16, 5.0));
    let other = mc(&ball_volume(16, 6.0));
    let k = plane([7.5, 7.5, 7.5], [0.0, 0.0, 1.0]);
    let err = locate(&s.mesh, &other.forest, &k).unwrap_err();
    assert!(
        matches!(&err, chisel::Error::Mismatch { what, .. } if what.contains("the forest's")),
        "{err}"
    );
    assert!(matches!(
        cut(&s.mesh, &other.forest, &k, &CAP),
        Err(chisel::Error::Mismatch { .. })
    ));
}
