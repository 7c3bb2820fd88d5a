//! `chisel cut`: triangulated knives on the CT bone, and the warnings for
//! caps that cannot close and knives that miss.

use serde_json::Value;

use crate::common;
use crate::support::{assert_volume_conserved, ok, ok_json, path_str};

/// Triangulated knives on the CT bone at 1150, where samples equal the
/// level (marching cubes keeps every triangle's area positive, so the exact
/// predicates place them): an icosphere and a tilted sheet whose triangles
/// each hold whole cut loops. Closed at the border, every piece is closed
/// and the volumes add up; open, loops are capped and open curves counted.
#[test]
fn mesh_knives_cut_the_ct_bone() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let mut ball = common::icosphere(3);
    for p in &mut ball.positions {
        *p = *p * 30.17 + glam::Vec3::new(100.123, 60.377, 40.291);
    }
    let ball_ply = tmp.path().join("ball.ply");
    chisel::io::write_mesh(&ball_ply, &ball).unwrap();
    let n = 8;
    let mut sheet = chisel::TriMesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (
                -20.37 + 250.0 * i as f32 / n as f32,
                -20.11 + 200.0 * j as f32 / n as f32,
            );
            sheet
                .positions
                .push(glam::Vec3::new(x, 70.29 + 0.13 * x + 0.21 * z, z));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            sheet.triangles.push([a, a + 1, a + n + 2]);
            sheet.triangles.push([a, a + n + 2, a + n + 1]);
        }
    }
    let sheet_ply = tmp.path().join("sheet.ply");
    chisel::io::write_mesh(&sheet_ply, &sheet).unwrap();
    // A box whose cap crossed the bone's tube cells, which the marching-cubes
    // table once joined by a self-crossing band (two pieces were not manifold).
    let mut boxed = common::cube();
    for p in &mut boxed.positions {
        *p = *p * glam::Vec3::new(80.34, 80.46, 60.22) + glam::Vec3::new(59.96, 60.04, 30.2);
    }
    let box_ply = tmp.path().join("box.ply");
    chisel::io::write_mesh(&box_ply, &boxed).unwrap();
    let ct = dir.join("headsq/quarter.nhdr");
    for close in [true, false] {
        let bone = tmp.path().join(format!("bone_{close}.ply"));
        let mut args = vec![
            "mc",
            path_str(&ct),
            "--level",
            "1150",
            "-o",
            path_str(&bone),
            "--json",
        ];
        if close {
            args.push("--close-border");
        }
        ok_json(&args);
        for knife in [&ball_ply, &sheet_ply, &box_ply] {
            let what = format!("{} close {close}", knife.display());
            let pieces = tmp.path().join("pieces");
            let cut = ok_json(&[
                "cut",
                path_str(&bone),
                "--knife",
                path_str(knife),
                "--cap",
                "-o",
                path_str(&pieces),
                "--json",
            ]);
            let stats = &cut["stats"];
            assert!(
                stats["loops_capped"].as_u64().unwrap() > 0,
                "{what}: {stats}"
            );
            let pieces = cut["pieces"].as_array().unwrap();
            if knife != &sheet_ply {
                // A closed knife tells every piece's side, reached or not.
                assert!(pieces.iter().all(|p| p["side"] != "both"), "{what}");
            }
            if close {
                assert_eq!(stats["curves_open"], 0, "{what}");
                assert!(
                    pieces.iter().all(|p| p["closed"] == true
                        && p["manifold"] == true
                        && p["self_intersecting_pairs"] == 0),
                    "{what}"
                );
                assert_volume_conserved(&cut, &what);
            } else if knife == &sheet_ply {
                // The sheet leaves the bone where it is open at the border.
                assert!(
                    stats["curves_open"].as_u64().unwrap() > 0,
                    "{what}: {stats}"
                );
                assert!(pieces.iter().any(|p| p["closed"] == false), "{what}");
            }
        }
    }
}

/// A rectangle that ends inside the solid leaves open cut curves, which
/// `--cap` cannot close: the run says so, and the report marks the piece
/// open. A knife that misses the surface is reported too.
#[test]
fn cut_warns_when_caps_cannot_close_or_the_knife_misses() {
    let tmp = tempfile::tempdir().unwrap();
    let cube = tmp.path().join("cube.ply");
    chisel::io::write_mesh(&cube, &common::cube()).unwrap();
    let report = tmp.path().join("r.json");
    // z = 0.5, x from −0.5 to 0.5: one curve over the faces y = 0, x = 0
    // and y = 1, ending at x = 0.5 inside the cube.
    let out = ok(&[
        "cut",
        path_str(&cube),
        "--rect",
        "0,0.5,0.5,0,0,1,1,0,0,0.5,2",
        "--cap",
        "-o",
        path_str(&tmp.path().join("rect")),
        "--report",
        path_str(&report),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("warning: 1 cut curve(s) end inside the surface"),
        "{stderr}"
    );
    let v: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(v["stats"]["curves_open"], 1);
    assert!(
        (v["pieces"].as_array().unwrap().iter()).any(|p| p["closed"] == false),
        "{v}"
    );
    let out = ok(&[
        "cut",
        path_str(&cube),
        "--plane",
        "0,0,5,0,0,1",
        "-o",
        path_str(&tmp.path().join("miss")),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("warning: the knives cross no triangle"),
        "{stderr}"
    );
}
