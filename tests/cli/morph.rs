//! `chisel morph`: foot bone 4 into bone 6 as frames with one connectivity,
//! volumes linear in t, a contact-sheet preview; a moving centre.

use crate::fuse::two_bones;
use crate::support::{ok_json, path_str};

#[test]
fn foot_bone_morph_writes_frames_with_one_connectivity() {
    let tmp = tempfile::tempdir().unwrap();
    let Some((a, b)) = two_bones(tmp.path()) else {
        return;
    };
    let dir = tmp.path().join("frames");
    let png = tmp.path().join("morph.png");
    let v = ok_json(&[
        "morph",
        &a,
        &b,
        "--frames",
        "5",
        "--tolerance",
        "0.002",
        "--backend",
        "cpu",
        "-o",
        path_str(&dir),
        "--preview",
        path_str(&png),
        "--json",
    ]);
    assert_eq!(v["schema"], "chisel.morph/1");
    let frames = v["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 5);
    for f in frames {
        assert!(
            f["volumes"]["relative_error"].as_f64().unwrap() < 1e-3,
            "{f}"
        );
    }
    let meshes: Vec<_> = (0..5)
        .map(|k| chisel::io::read_mesh(&dir.join(format!("frame{k:03}.ply"))).unwrap())
        .collect();
    assert!(meshes.iter().all(|m| m.triangles == meshes[0].triangles));
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    // H moving from bone 4's kernel to a point still inside both kernels.
    let v = ok_json(&[
        "morph",
        &a,
        &b,
        "--frames",
        "3",
        "--center",
        "-0.1368,-0.0127,-1.4538",
        "--center-end",
        "-0.1168,-0.0127,-1.4538",
        "--tolerance",
        "0.005",
        "--backend",
        "cpu",
        "-o",
        path_str(&dir),
        "--json",
    ]);
    let x: Vec<f64> = (v["frames"].as_array().unwrap().iter())
        .map(|f| f["center"][0].as_f64().unwrap())
        .collect();
    assert!((x[1] - (-0.1268)).abs() < 1e-6, "{x:?}");
    assert!(
        !dir.join("frame003.ply").exists(),
        "frames of the earlier run left"
    );
}
