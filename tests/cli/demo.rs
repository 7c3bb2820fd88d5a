//! `chisel demo`: the end-to-end run and the outputs it writes.

use serde_json::Value;

use crate::common;
use crate::support::{ok, path_str};

#[test]
fn demo_runs_and_writes_its_outputs() {
    let Some(_gpu) = common::gpu() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let out_dir = tmp.path().join("demo");
    ok(&["demo", "--output", path_str(&out_dir)]);
    let report: Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["relax_gpu"]["status"], "converged");
    assert_eq!(report["parity"]["same_status_and_iterations"], true);
    assert!(report["parity"]["max_epidermis_distance"].as_f64().unwrap() < 1e-3);
    assert_eq!(report["marching_cubes_gpu_equals_cpu"], true);
    assert_eq!(report["ct"]["skin_groups"], 1);
    assert!(report["cut"]["fragments"]["jaw"].as_u64().unwrap() > 100);
    for f in ["before_after.png", "bone_before_after.png", "head_ct.nrrd"] {
        assert!(out_dir.join(f).is_file(), "{f}");
    }
    let bone = chisel::io::read_mesh(&out_dir.join("bone_moved.ply")).unwrap();
    let moved = bone
        .scalar("displacement")
        .unwrap()
        .values
        .iter()
        .filter(|&&d| (d - 6.0).abs() < 1e-3)
        .count();
    assert_eq!(
        moved as u64,
        report["cut"]["fragments"]["jaw"].as_u64().unwrap()
    );
    let ct = chisel::io::read_volume(&out_dir.join("head_ct.nrrd")).unwrap();
    assert_eq!(
        ct.dims.to_vec(),
        report["phantom"]["dims"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.as_u64().unwrap() as usize)
            .collect::<Vec<_>>()
    );
    let mesh = chisel::io::read_mesh(&out_dir.join("relaxed_skin.ply")).unwrap();
    let d = mesh.scalar("displacement").expect("displacement field");
    let max = d.values.iter().copied().fold(0.0f32, f32::max);
    assert!(
        max > 3.0 && max < 12.0,
        "a 6 mm jaw advance moved the skin by {max} mm"
    );
    // The marching-cubes skin, its short edges collapsed, is embedded, and
    // with bend springs it stays so; the report counts as the library does.
    let crossings = &report["skin_self_intersecting_pairs"];
    assert_eq!(crossings["before"], 0);
    assert_eq!(crossings["after"], 0);
    assert_eq!(chisel::mesh::self_intersections(&mesh).pairs.len(), 0);
    // The skin follows the jaw, it does not outrun it.
    let ratio = report["skin_overshoot"]["ratio"].as_f64().unwrap();
    assert!(ratio > 0.5 && ratio < 1.1, "skin/bone displacement {ratio}");
    assert!(
        report["ct"]["skin_collapse"]["collapsed_edges"]
            .as_u64()
            .unwrap()
            > 1000
    );
    assert!(report["network"]["springs_per_class"][5].as_u64().unwrap() > 10_000);
    // The relaxed face as its DMS spline: the patch facing +z at n = 5,
    // (n − 1)² = 16 triangles per patch triangle, moved with the jaw.
    let s = &report["skin_spline"];
    assert_eq!(s["domain"], "patch facing [0, 0, 1]");
    let spline = chisel::io::read_mesh(&out_dir.join("relaxed_skin_spline.ply")).unwrap();
    assert_eq!(spline.n_vertices() as u64, s["points"].as_u64().unwrap());
    assert_eq!(
        spline.n_triangles() as u64,
        s["triangles"].as_u64().unwrap()
    );
    assert_eq!(spline.n_triangles() % 16, 0);
    assert!(spline.n_vertices() > 5_000, "{}", spline.n_vertices());
    let smax = s["max_displacement"].as_f64().unwrap();
    assert!(
        (smax - max as f64).abs() < 1.5,
        "spline {smax} vs mesh {max} mm"
    );
    for f in ["nx", "ny", "nz", "displacement"] {
        assert!(spline.scalar(f).is_some(), "{f}");
    }
}
