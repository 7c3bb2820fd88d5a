//! Atomic writes: a failed write leaves neither a partial output nor a
//! temporary file.

use std::path::Path;

use chisel::foundation::fs::write_atomic_with;
use chisel::io::{read_mesh, write_mesh, write_volume};
use chisel::volume::VolumeData;
use chisel::{TriMesh, Volume};
use glam::Vec3;

use crate::common;

// ---------------------------------------------------------------- atomic writes

fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn failed_writes_leave_no_partial_output_or_temp_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.ply");
    // A writer that fails half-way.
    let r = write_atomic_with(&out, |w| {
        w.write_all(&[7u8; 100_000])?;
        Err(std::io::Error::other("disk on fire"))
    });
    assert!(matches!(r, Err(chisel::Error::Io { .. })));
    assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));
    // An existing output survives a failed overwrite untouched.
    std::fs::write(&out, b"old").unwrap();
    let r = write_atomic_with(&out, |w| {
        w.write_all(b"new partial")?;
        Err(std::io::Error::other("interrupted"))
    });
    assert!(matches!(r, Err(chisel::Error::Io { .. })));
    assert_eq!(std::fs::read(&out).unwrap(), b"old");
    assert_eq!(listing(dir.path()), ["out.ply"]);
    // An invalid mesh is refused before anything is written.
    let bad = TriMesh {
        positions: vec![Vec3::ZERO; 3],
        triangles: vec![[0, 1, 3]],
        scalars: Vec::new(),
    };
    assert!(matches!(
        write_mesh(&dir.path().join("bad.stl"), &bad),
        Err(chisel::Error::InvalidData { .. })
    ));
    assert_eq!(listing(dir.path()), ["out.ply"]);
    // A volume NIfTI cannot hold is refused without leaving anything.
    let wide = Volume::new(
        [40_000, 1, 1],
        [1.0; 3],
        [0.0; 3],
        VolumeData::U8(vec![0; 40_000]),
    )
    .unwrap();
    assert!(matches!(
        write_volume(&dir.path().join("wide.nii"), &wide),
        Err(chisel::Error::Limit {
            asked: 40_000,
            allowed: 32767,
            ..
        })
    ));
    assert_eq!(listing(dir.path()), ["out.ply"]);
    // A successful write leaves exactly the output.
    write_mesh(&out, &common::tetra()).unwrap();
    assert_eq!(listing(dir.path()), ["out.ply"]);
    assert_eq!(read_mesh(&out).unwrap(), common::tetra());
}
