//! `chisel blobby fit`: the fran_cut scan fitted with a few primitives (the
//! model file a scene the implicit room reads, the energy never rising
//! from one stage to the next, distances and the preview), and clean
//! errors for bad arguments.

use crate::common;
use crate::support::{assert_clean_error, ok_json, path_str};

#[test]
fn fran_fit_writes_a_scene_mesh_preview_and_report() {
    let Some(fran) = common::data("fran_cut.vtk") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("fran.toml");
    let mesh = tmp.path().join("fran_blobs.ply");
    let png = tmp.path().join("fran.png");
    let v = ok_json(&[
        "blobby",
        "fit",
        path_str(&fran),
        "--primitives",
        "4",
        "--backend",
        "cpu",
        "-o",
        path_str(&model),
        "--mesh",
        path_str(&mesh),
        "--preview",
        path_str(&png),
        "--json",
    ]);
    assert_eq!(v["schema"], "chisel.blobby-fit/1");
    let stages = v["stages"].as_array().unwrap();
    assert_eq!(stages.len(), 4, "{v}");
    let e: Vec<f64> = (stages.iter())
        .map(|s| s["terms"]["total"].as_f64().unwrap())
        .collect();
    assert!(e.windows(2).all(|w| w[1] <= w[0]), "E per stage {e:?}");
    let rms = v["distance"]["rms_relative"].as_f64().unwrap();
    assert!(rms > 0.0 && rms < 0.05, "{}", v["distance"]);
    let scene = chisel::implicit::Scene::from_path(&model).unwrap();
    assert_eq!(scene.primitives.len(), 4);
    let surface = chisel::io::read_mesh(&mesh).unwrap();
    assert!(surface.scalars.iter().any(|s| s.name == "distance"));
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
}

#[test]
fn bad_fit_arguments_are_clean_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("m.toml");
    let missing = tmp.path().join("missing.ply");
    assert_clean_error(
        &["blobby", "fit", path_str(&missing), "-o", path_str(&out)],
        "missing.ply",
    );
    let Some(fran) = common::data("fran_cut.vtk") else {
        return;
    };
    assert_clean_error(
        &[
            "blobby",
            "fit",
            path_str(&fran),
            "--primitives",
            "0",
            "-o",
            path_str(&out),
        ],
        "primitives",
    );
    assert_clean_error(
        &[
            "blobby",
            "fit",
            path_str(&fran),
            "--alpha",
            "-1",
            "-o",
            path_str(&out),
        ],
        "alpha",
    );
    assert!(!out.exists(), "no model written on an error");
}
