//! `chisel render`: a PNG of a real mesh.

use crate::common;
use crate::support::{ok, path_str};

#[test]
fn render_writes_a_png_of_a_real_mesh() {
    let Some(_gpu) = common::gpu() else { return };
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let png = tmp.path().join("bunny.png");
    ok(&[
        "render",
        path_str(&dir.join("bunny.ply")),
        "-o",
        path_str(&png),
        "--scalars",
        "intensity",
        "--views",
        "front,iso",
        "--size",
        "128",
    ]);
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
}
