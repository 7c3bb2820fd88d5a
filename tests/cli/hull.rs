//! `chisel phantom` and `chisel hull`: the seed's objects and figures.

use crate::support::{assert_clean_error, chisel, ok, ok_json, path_str};

/// `phantom` writes the seed's objects; `hull` reproduces the seed's
/// figures on them (Tables 4.1/4.2 for the r = 24 ball, Table 8.6 for the
/// 25/10 cylinder with its tunnel of 1,200 background voxels).
#[test]
fn phantom_and_hull_reproduce_the_seed_figures() {
    let tmp = tempfile::tempdir().unwrap();
    let ball = tmp.path().join("ball24.nrrd");
    ok(&["phantom", "ball", "--r", "24", "-o", path_str(&ball)]);
    let merged = ok_json(&["hull", path_str(&ball), "--level", "1", "--json"]);
    assert_eq!(merged["hull"]["faces"], 290);
    assert_eq!(merged["object"]["voxels"], 7208);
    assert_eq!(
        merged["zkh"].as_array().unwrap().len(),
        0,
        "a ball is digitally convex"
    );
    let tris = ok_json(&[
        "hull",
        path_str(&ball),
        "--level",
        "1",
        "--coplanar",
        "visible",
        "--json",
    ]);
    assert_eq!(tris["hull"]["faces"], 524);
    let corners = ok_json(&[
        "hull",
        path_str(&ball),
        "--level",
        "1",
        "--vertices",
        "corners",
        "--json",
    ]);
    assert_eq!(corners["candidates"]["kind"], "convex_corners");

    let cyl = tmp.path().join("cyl.mha");
    ok(&[
        "phantom",
        "cylinder-tunnel",
        "--outer",
        "25",
        "--inner",
        "10",
        "-o",
        path_str(&cyl),
    ]);
    let hull_ply = tmp.path().join("cyl_hull.ply");
    let v = ok_json(&[
        "hull",
        path_str(&cyl),
        "--level",
        "1",
        "-o",
        path_str(&hull_ply),
        "--json",
    ]);
    assert_eq!(v["object"]["voxels"], 6060);
    assert_eq!(v["object"]["boundary_facets"], 2848);
    let zkh = v["zkh"].as_array().unwrap();
    assert_eq!(zkh.len(), 1);
    assert_eq!(zkh[0]["class"], "tunnel");
    assert_eq!(zkh[0]["voxels"], 1200);
    let mesh = chisel::io::read_mesh(&hull_ply).unwrap();
    assert_eq!(
        mesh.n_vertices() as u64,
        v["hull"]["vertices"].as_u64().unwrap()
    );

    // Bad selections are clear errors.
    assert_clean_error(&["hull", path_str(&cyl), "--level", "5"], "cyl.mha");
    assert_clean_error(
        &["hull", path_str(&cyl), "--level", "1", "--component", "7"],
        "component = 7: does not exist",
    );
    let run = chisel(&[
        "phantom", "torus", "--major", "4", "--minor", "9", "-o", "t.nrrd",
    ]);
    assert_eq!(run.status.code(), Some(1));
}
