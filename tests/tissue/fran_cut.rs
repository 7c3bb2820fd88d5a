//! The real fran_cut data: its network, the seed plans and the refined
//! networks' sizes against the benchmark's.

use super::*;

#[test]
fn fran_cut_network_and_seed_plans() {
    let Some(face) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let net = SpringNetwork::build(&face, None, &NetworkParams::default()).unwrap();
    // SPEC default origin: back face (x = 0) of the bounding box, mid y/z.
    assert!(net.origin.x.abs() < 1e-6, "{}", net.origin);
    assert!((net.origin.y + 0.128).abs() < 1e-4 && (net.origin.z + 0.0574).abs() < 1e-4);
    // 6,615 nodes; 42,978 springs with a free end (43k as in the issue).
    assert_eq!(net.n_nodes(), 6615);
    let c = net.class_counts();
    assert_eq!(c[0] + c[1] + c[2] + c[3], 6428 + 15061 + 6428 + 15061);
    let plan = Plan::from_toml_str(phantom::FRAN_TABLE2_TOML, "table2").unwrap();
    let r = plan.resolve(&net, &Fragments::new()).unwrap();
    let counts: Vec<usize> = r.steps.iter().map(|s| s.bone_vertices.len()).collect();
    for (got, want) in counts.iter().zip([60, 60, 150, 70]) {
        assert!(got.abs_diff(want) * 10 <= want, "{counts:?}");
    }
    let report = relax(&net, &r, &RelaxOptions::default(), Backend::Cpu).unwrap();
    assert_eq!(report.iterations, 10 + 10 + 8 + 5);
    assert_ne!(report.status, Status::Diverged);
    let skin = report.skin_mesh(&net);
    assert_eq!(skin.n_vertices(), 2205);
    assert!(
        skin.scalar("displacement")
            .unwrap()
            .values
            .iter()
            .any(|&d| d > 1e-4)
    );
}

#[test]
fn refined_fran_cut_sizes_match_the_benchmark_networks() {
    let Some(face) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let (cols, rows) = FRAN_GRID;
    let fine = phantom::refine_grid(&face, cols, rows, 4).unwrap();
    assert_eq!(fine.n_vertices(), 177 * 193);
    // Same orientation as the input (inward), same bounds.
    let (lo, hi) = fine.bounds().unwrap();
    let (lo0, hi0) = face.bounds().unwrap();
    assert!((lo - lo0).abs().max_element() < 1e-3 && (hi - hi0).abs().max_element() < 1e-3);
}
