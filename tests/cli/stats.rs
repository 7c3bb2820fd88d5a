//! `chisel stats`: the real meshes' and volumes' figures of the data README,
//! and the GPU backend against the CPU.

use crate::common;
use crate::support::{ok_json, path_str};

#[test]
fn stats_meshes_match_the_data_readme() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let fran = ok_json(&["stats", path_str(&dir.join("fran_cut.vtk")), "--json"]);
    let t = &fran["topology"];
    assert_eq!(t["vertices"], 2205);
    assert_eq!(t["triangles"], 4224);
    assert_eq!(t["edges"], 6428);
    assert_eq!(t["boundary_edges"], 184);
    assert_eq!(t["components"].as_array().unwrap().len(), 1);
    assert_eq!(t["euler"], 1);
    assert_eq!(t["orientation"], "inward");

    let bunny = ok_json(&["stats", path_str(&dir.join("bunny.ply")), "--json"]);
    let t = &bunny["topology"];
    assert_eq!(t["vertices"], 35947);
    assert_eq!(t["used_vertices"], 34834);
    assert_eq!(t["triangles"], 69451);
    assert_eq!(t["boundary_edges"], 223);
    assert_eq!(t["euler"], -3);
    assert_eq!(t["orientation"], "inward");
    assert_eq!(
        bunny["scalars"],
        serde_json::json!(["confidence", "intensity"])
    );

    let feet = ok_json(&["stats", path_str(&dir.join("fsu/footbones.ply")), "--json"]);
    let t = &feet["topology"];
    let comps = t["components"].as_array().unwrap();
    assert_eq!(comps.len(), 26);
    assert!(comps.iter().all(|c| c["closed"] == true && c["genus"] == 0));
    assert_eq!(t["euler"], 52);
    assert_eq!(t["orientation"], "outward");
    // The bones overlap at the joints (checked with an independent float
    // test): 378 crossing pairs between bones, 3 within one bone.
    let x = &feet["self_intersections"];
    assert_eq!(x["pairs"], 381);
    assert_eq!(x["within_components"], 3);
    assert_eq!(x["first_pairs"][0], serde_json::json!([43, 48]));
    for clean in [&fran, &bunny] {
        assert_eq!(clean["self_intersections"]["pairs"], 0);
        assert_eq!(clean["self_intersections"]["zero_area_triangles"], 0);
    }
}

#[test]
fn stats_volumes_match_the_data_readme() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let head = ok_json(&[
        "stats",
        path_str(&dir.join("headsq/quarter.nhdr")),
        "--json",
        "--level",
        "1150",
    ]);
    let s = &head["stats"];
    assert_eq!(s["dims"], serde_json::json!([64, 64, 93]));
    assert_eq!(s["spacing"], serde_json::json!([3.2, 3.2, 1.5]));
    assert_eq!(s["min"], 0.0);
    assert_eq!(s["max"], 3926.0);
    assert!((s["mean"].as_f64().unwrap() - 507.69).abs() < 0.01);
    assert!(head["level"]["voxels"].as_u64().unwrap() > 0);
    assert!(head["level"]["components"].as_u64().unwrap() >= 1);

    let frog = ok_json(&[
        "stats",
        path_str(&dir.join("froggy/frogtissue.mhd")),
        "--json",
        "--label",
        "13",
    ]);
    assert_eq!(frog["stats"]["dims"], serde_json::json!([500, 470, 136]));
    assert_eq!(frog["label"]["voxels"], 440_722);
}

#[test]
fn stats_gpu_backend_matches_cpu_on_real_data() {
    let Some(_gpu) = common::gpu() else { return };
    let Some(dir) = common::data_dir() else {
        return;
    };
    let v = ok_json(&[
        "stats",
        path_str(&dir.join("fran_cut.vtk")),
        "--json",
        "--backend",
        "gpu",
    ]);
    assert_eq!(v["gpu"]["matches_cpu"], true, "{v}");
    let v = ok_json(&[
        "stats",
        path_str(&dir.join("headsq/quarter.nhdr")),
        "--json",
        "--backend",
        "gpu",
    ]);
    assert_eq!(v["gpu"]["matches_cpu"], true, "{v}");
    assert_eq!(v["gpu"]["range"]["max"], 3926.0);
}

/// A DICOM directory: one series is read (and listed); several are listed
/// until `--series` chooses one; `mc` reads a series the same way.
#[test]
fn stats_lists_dicom_series_and_reads_the_chosen_one() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dicom");
    let one = ok_json(&["stats", path_str(&root.join("ct_explicit")), "--json"]);
    assert_eq!(one["kind"], "volume");
    assert_eq!(one["dicom_series"].as_array().unwrap().len(), 1);
    assert_eq!(one["stats"]["dims"], serde_json::json!([6, 5, 4]));
    assert_eq!(one["stats"]["space"], "LPS");
    assert_eq!(one["stats"]["min"], -1017.0);
    assert_eq!(one["stats"]["max"], -322.0);

    let two = root.join("two_series");
    let listed = ok_json(&["stats", path_str(&two), "--json"]);
    assert_eq!(listed["kind"], "dicom_directory");
    let series = listed["series"].as_array().unwrap();
    assert_eq!(series.len(), 2);
    let uid = series[1]["uid"].as_str().unwrap();
    assert_eq!(series[1]["description"], "series b");
    let chosen = ok_json(&["stats", path_str(&two), "--series", uid, "--json"]);
    assert_eq!(chosen["stats"]["dims"], serde_json::json!([6, 5, 2]));
    // Other commands refuse the unchosen directory, naming both series.
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("s.ply");
    crate::support::assert_clean_error(
        &[
            "mc",
            path_str(&two),
            "--level",
            "-500",
            "-o",
            path_str(&out),
        ],
        uid,
    );
    crate::support::ok(&[
        "mc",
        path_str(&root.join("ct_explicit")),
        "--level",
        "-500",
        "-o",
        path_str(&out),
    ]);
    assert!(out.exists());
}
