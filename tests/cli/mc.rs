//! `chisel mc`: the CT bone, its groups and closed border (cut with caps),
//! and why a surface is empty.

use std::path::Path;

use crate::common;
use crate::support::{assert_clean_error, assert_volume_conserved, chisel, ok_json, path_str};

#[test]
fn mc_and_capped_cut_of_the_ct_bone() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let bone = tmp.path().join("bone.ply");
    let groups = tmp.path().join("groups");
    let mc = ok_json(&[
        "mc",
        path_str(&dir.join("headsq/quarter.nhdr")),
        "--level",
        "1150",
        "-o",
        path_str(&bone),
        "--groups-dir",
        path_str(&groups),
        "--json",
    ]);
    assert_eq!(mc["triangles"], 78_792);
    let n_groups = mc["group_count"].as_u64().unwrap() as usize;
    assert_eq!(mc["groups"].as_array().unwrap().len(), n_groups);
    assert_eq!(std::fs::read_dir(&groups).unwrap().count(), n_groups);
    // Only the mesh: the same triangles, no groups.
    let mesh_only = tmp.path().join("mesh_only.ply");
    let bare = ok_json(&[
        "mc",
        path_str(&dir.join("headsq/quarter.nhdr")),
        "--level",
        "1150",
        "--no-groups",
        "-o",
        path_str(&mesh_only),
        "--json",
    ]);
    assert_eq!(bare["triangles"], 78_792);
    assert!(bare["group_count"].is_null());
    assert_eq!(bare["groups"].as_array().unwrap().len(), 0);
    assert_eq!(
        std::fs::read(&mesh_only).unwrap(),
        std::fs::read(&bone).unwrap()
    );

    let closed = tmp.path().join("closed.ply");
    ok_json(&[
        "mc",
        path_str(&dir.join("headsq/quarter.nhdr")),
        "--level",
        "1150",
        "--close-border",
        "-o",
        path_str(&closed),
        "--json",
    ]);
    let pieces = tmp.path().join("pieces");
    let cut = ok_json(&[
        "cut",
        path_str(&closed),
        "--plane",
        "100,100,60,0,0.3,1",
        "--cap",
        "-o",
        path_str(&pieces),
        "--json",
    ]);
    assert_volume_conserved(&cut, "plane cut");
    let original = cut["input_signed_volume"].as_f64().unwrap();
    assert!(
        cut["pieces"]
            .as_array()
            .unwrap()
            .iter()
            .all(|p| p["closed"] == true)
    );
    let tested = cut["stats"]["triangles_tested"].as_u64().unwrap();
    let all = cut["stats"]["triangles_total"].as_u64().unwrap();
    assert!(tested * 4 < all, "tree tested {tested} of {all} triangles");

    let out = chisel(&[
        "cut",
        path_str(&closed),
        "--plane",
        "1,2,3",
        "-o",
        path_str(&pieces),
    ]);
    assert_eq!(out.status.code(), Some(1), "a plane needs 6 numbers");
    assert_clean_error(
        &[
            "cut",
            path_str(&closed),
            "--plane",
            "100,100,60,0,0.3,1",
            "--explode",
            "-1",
            "-o",
            path_str(&pieces),
        ],
        "--explode must be between 0 and 10",
    );
    assert_clean_error(
        &[
            "cut",
            path_str(&closed),
            "--plane",
            "100,100,60,0,0.3,1",
            "-o",
            path_str(&closed.join("sub")),
        ],
        "is a file, not a folder",
    );

    // A sphere whose summed loop area points at a pole inside a cap: the
    // caps must still be the sphere's part inside the bone (no piece with a
    // whole, inside-out sphere), and the earlier run's pieces are replaced.
    let sphere = ok_json(&[
        "cut",
        path_str(&closed),
        "--sphere",
        "100,100,70,40",
        "--cap",
        "-o",
        path_str(&pieces),
        "--json",
    ]);
    let volumes: Vec<f64> = sphere["pieces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["signed_volume"].as_f64().unwrap())
        .collect();
    let ball = 4.0 / 3.0 * std::f64::consts::PI * 40f64.powi(3);
    assert!(
        volumes.iter().all(|&v| v > -0.01 * ball && v < original),
        "{volumes:?}"
    );
    assert!(((volumes.iter().sum::<f64>() - original) / original).abs() < 1e-6);
    assert_eq!(
        std::fs::read_dir(&pieces).unwrap().count(),
        volumes.len(),
        "stale pieces of the plane cut removed"
    );

    // Outputs are checked before the work; an empty surface writes nothing.
    let surface = tmp.path().join("never.ply");
    assert_clean_error(
        &[
            "mc",
            path_str(&dir.join("headsq/quarter.nhdr")),
            "--level",
            "1150",
            "-o",
            path_str(&surface),
            "--report",
            path_str(&tmp.path().join("no/such/r.json")),
        ],
        "does not exist",
    );
    assert_clean_error(
        &[
            "mc",
            path_str(&dir.join("headsq/quarter.nhdr")),
            "--level",
            "-500",
            "-o",
            path_str(&surface),
        ],
        "level -500 lies outside the data range 0 to 3926",
    );
    assert!(!surface.exists());
}

/// An empty marching-cubes surface says why: a level outside the data, a
/// label no voxel has; a 2-D image and a fractional label are refused.
#[test]
fn mc_says_why_a_surface_is_empty() {
    let tmp = tempfile::tempdir().unwrap();
    let vol = tmp.path().join("v.nhdr");
    let data: Vec<u8> = (0..27).map(|i| if i == 13 { 7 } else { 1 }).collect();
    let v = chisel::Volume::new(
        [3; 3],
        [1.0; 3],
        [0.0; 3],
        chisel::volume::VolumeData::U8(data),
    )
    .unwrap();
    chisel::io::write_volume(&vol, &v).unwrap();
    let flat = tmp.path().join("flat.nhdr");
    let data = vec![1u8; 9];
    let f = chisel::Volume::new(
        [3, 3, 1],
        [1.0; 3],
        [0.0; 3],
        chisel::volume::VolumeData::U8(data),
    )
    .unwrap();
    chisel::io::write_volume(&flat, &f).unwrap();
    let out = tmp.path().join("s.ply");
    let mc = |input: &Path, what: &[&str], names: &str| {
        let mut args = vec![
            "mc",
            path_str(input),
            "--backend",
            "cpu",
            "-o",
            path_str(&out),
        ];
        args.extend(what);
        assert_clean_error(&args, names);
        assert!(!out.exists());
    };
    mc(
        &vol,
        &["--level", "9"],
        "level 9 lies outside the data range 1 to 7",
    );
    mc(
        &vol,
        &["--label", "3"],
        "label 3 occurs in no voxel (values 1 to 7)",
    );
    mc(&vol, &["--label", "2.5"], "--label takes a whole number");
    mc(
        &flat,
        &["--level", "0.5"],
        "marching cubes needs at least 2 samples along each axis",
    );
    // In range, every sample on one side (≥ 1): closing the border helps.
    mc(
        &vol,
        &["--level", "1"],
        "no cell has samples on both sides of level 1 (try --close-border",
    );
}
