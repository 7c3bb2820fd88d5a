//! `chisel polyhedrize`: verified cells, the merged surface, press-in.

use serde_json::Value;

use crate::support::{assert_clean_error, ok, ok_json, path_str};

#[test]
fn polyhedrize_writes_verified_cells() {
    let tmp = tempfile::tempdir().unwrap();
    let cyl = tmp.path().join("cyl.nrrd");
    ok(&[
        "phantom",
        "cylinder-tunnel",
        "--outer",
        "50",
        "--inner",
        "35",
        "-o",
        path_str(&cyl),
    ]);
    let cells = tmp.path().join("cyl.cells");
    let cells_json = tmp.path().join("cyl.json");
    let mesh = tmp.path().join("cyl.ply");
    let png = tmp.path().join("cyl.png");
    let v = ok_json(&[
        "polyhedrize",
        path_str(&cyl),
        "--level",
        "1",
        "-o",
        path_str(&cells),
        "--cells-json",
        path_str(&cells_json),
        "--mesh",
        path_str(&mesh),
        "--preview",
        path_str(&png),
        "--verify",
        "--json",
    ]);
    // Seed Table 8.7, holed faces split: 60 faces against 13,952 triangles.
    assert_eq!(v["polyhedron"]["faces"], 60);
    assert_eq!(v["polyhedron"]["shells"], 2);
    assert_eq!(v["marching_cubes"]["triangles"], 13952);
    assert_eq!(v["verified"], true);
    assert_eq!(v["zkh"][0]["class"], "tunnel");
    // The merged surface: 58 faces, the two caps holed (60 split).
    assert_eq!(v["mesh"], "merged");
    assert_eq!(
        (v["merged_faces"].as_u64(), v["merged_faces_split"].as_u64()),
        (Some(58), Some(60))
    );
    let back = chisel::polyhedron::Polyhedron::from_bytes(
        &std::fs::read(&cells).unwrap(),
        "cyl.cells",
        chisel::voxel::Frame::default(),
    )
    .unwrap();
    assert_eq!(back.shells.len(), 2);
    let j: Value = serde_json::from_slice(&std::fs::read(&cells_json).unwrap()).unwrap();
    assert_eq!(j["shells"][1]["role"], "background");
    let m = chisel::io::read_mesh(&mesh).unwrap();
    assert!(m.scalar("depth").is_some());
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    // Cutting-out (Def. AU): both caps marked, same merged surface.
    let v = ok_json(&[
        "polyhedrize",
        path_str(&cyl),
        "--level",
        "1",
        "--press-in",
        "--verify",
        "--json",
    ]);
    assert_eq!(v["verified"], true);
    assert_eq!(v["options"]["press_in"], true);
    assert_eq!(v["zkh"][0]["pressed_faces"], 2);
    assert_eq!(v["merged_faces"], 58);
    // Corner vertices are for hulls only: a clear error.
    assert_clean_error(
        &[
            "polyhedrize",
            path_str(&cyl),
            "--level",
            "1",
            "--vertices",
            "corners",
        ],
        "voxel centres",
    );
}
