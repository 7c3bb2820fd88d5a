//! Mesh readers on the real data and writer round trips (SPEC §0.5).

mod common;

use chisel::TriMesh;

use chisel::mesh::ScalarField;

fn assert_bounds(m: &TriMesh, lo: [f32; 3], hi: [f32; 3]) {
    let (a, b) = m.bounds().expect("non-empty");
    for i in 0..3 {
        assert!(
            (a[i] - lo[i]).abs() < 1e-5,
            "min[{i}] = {} vs {}",
            a[i],
            lo[i]
        );
        assert!(
            (b[i] - hi[i]).abs() < 1e-5,
            "max[{i}] = {} vs {}",
            b[i],
            hi[i]
        );
    }
}

fn used_vertices(m: &TriMesh) -> usize {
    let mut used = vec![false; m.n_vertices()];
    for t in &m.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    used.iter().filter(|&&u| u).count()
}

#[test]
fn fran_cut_vtk() {
    let Some(m) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    assert_eq!(m.n_vertices(), 2205);
    assert_eq!(m.n_triangles(), 4224);
    assert_eq!(used_vertices(&m), 2205);
    assert_bounds(
        &m,
        [0.0, -0.2048, -0.118986],
        [0.1056, -0.0512003, 0.00411239],
    );
    // y = -0.2048 + 0.0032·row, row = i % 49 (README §1).
    for (i, p) in m.positions.iter().enumerate() {
        let y = -0.2048 + 0.0032 * (i % 49) as f32;
        assert!((p.y - y).abs() < 1e-6, "vertex {i}: y {} vs {y}", p.y);
    }
}

#[test]
fn bunny_ply_keeps_extra_properties() {
    let Some(m) = common::real_mesh("bunny.ply") else {
        return;
    };
    assert_eq!(m.n_vertices(), 35947);
    assert_eq!(m.n_triangles(), 69451);
    assert_eq!(m.n_vertices() - used_vertices(&m), 1113);
    assert_bounds(
        &m,
        [-0.0946899, 0.0329874, -0.0618736],
        [0.0610091, 0.187321, 0.0587997],
    );
    let names: Vec<&str> = m.scalars.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["confidence", "intensity"]);
    let range = |s: &ScalarField| {
        s.values
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)))
    };
    let (lo, hi) = range(m.scalar("confidence").unwrap());
    assert_eq!(lo, 0.0);
    assert!((hi - 0.999238).abs() < 1e-6, "{hi}");
    let (lo, hi) = range(m.scalar("intensity").unwrap());
    assert_eq!((lo, hi), (0.0, 0.5));
}

#[test]
fn footbones_ply_crlf() {
    let Some(m) = common::real_mesh("fsu/footbones.ply") else {
        return;
    };
    assert_eq!(m.n_vertices(), 2154);
    assert_eq!(m.n_triangles(), 4204);
    assert_eq!(used_vertices(&m), 2154);
    assert!(m.scalars.is_empty());
    assert_bounds(
        &m,
        [-5.63324, -1.86044, -2.12503],
        [5.63321, 1.86044, 2.12566],
    );
}
