//! `chisel convert`: a real mesh and volume round-trip unchanged.

use crate::common;
use crate::support::{chisel, ok, path_str};

#[test]
fn convert_round_trips_a_real_mesh_and_volume() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let ply = tmp.path().join("fran.ply");
    let png = tmp.path().join("fran.png");
    let preview: &[&str] = if common::gpu().is_some() {
        &["--preview", path_str(&png)]
    } else {
        &[]
    };
    ok(&[
        &[
            "convert",
            path_str(&dir.join("fran_cut.vtk")),
            "-o",
            path_str(&ply),
        ],
        preview,
    ]
    .concat());
    assert_eq!(png.is_file(), !preview.is_empty());
    let a = chisel::io::read_mesh(&dir.join("fran_cut.vtk")).unwrap();
    let b = chisel::io::read_mesh(&ply).unwrap();
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.triangles, b.triangles);

    let nrrd = tmp.path().join("head.nrrd");
    ok(&[
        "convert",
        path_str(&dir.join("headsq/quarter.nhdr")),
        "-o",
        path_str(&nrrd),
    ]);
    let a = chisel::io::read_volume(&dir.join("headsq/quarter.nhdr")).unwrap();
    let b = chisel::io::read_volume(&nrrd).unwrap();
    assert_eq!(a, b);

    let out = chisel(&[
        "convert",
        path_str(&dir.join("fran_cut.vtk")),
        "-o",
        path_str(&nrrd),
    ]);
    assert_eq!(out.status.code(), Some(1), "mesh → volume must be refused");
}
