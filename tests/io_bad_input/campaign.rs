//! Regressions of the input-robustness campaign against the release binary
//! (issue "The inputs real users have") that need more than a file: endless
//! inputs (devices behind links) read boundedly. The corrupt files it found
//! are regression files of `tests/fuzz/regressions/`; the command-line
//! findings (outputs over inputs, NaN levels) are in
//! `tests/cli/cross_command.rs`.

use std::path::Path;

use chisel::io::{read_mesh, read_volume};

use crate::{Kind, kind, put};

/// A symbolic link `name` → `target` in `dir`.
#[cfg(unix)]
fn link(dir: &Path, name: &str, target: &Path) -> std::path::PathBuf {
    let p = dir.join(name);
    std::os::unix::fs::symlink(target, &p).unwrap();
    p
}

#[cfg(unix)]
#[test]
fn endless_inputs_are_refused_from_their_first_bytes() {
    // A device reports length 0 and never ends: every mesh reader refuses
    // its first bytes (no magic, or binary where text is due) at once.
    let dir = tempfile::tempdir().unwrap();
    let zero = Path::new("/dev/zero");
    for name in ["z.ply", "z.vtk", "z.obj", "z.byu"] {
        let p = link(dir.path(), name, zero);
        let t = std::time::Instant::now();
        let e = read_mesh(&p).unwrap_err();
        assert_eq!(kind(&e), Kind::Format, "{name}: {e}");
        assert!(t.elapsed().as_secs() < 5, "{name}: read too long");
    }
    // Binary STL: 80 zero bytes and a count of 0 imply 84 bytes; the 85th
    // is data past the facets.
    let p = link(dir.path(), "z.stl", zero);
    let e = read_mesh(&p).unwrap_err();
    assert!(e.to_string().contains("more data"), "{e}");
    // A text volume whose data file is the device: ASCII samples expected.
    put(
        dir.path(),
        "z.nhdr",
        b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: ascii\ndata file: zero.txt\n",
    );
    link(dir.path(), "zero.txt", zero);
    let e = read_volume(&dir.path().join("z.nhdr")).unwrap_err();
    assert!(e.to_string().contains("zero.txt"), "{e}");
}

/// A FIFO is read once: the format comes from its name (its first bytes
/// cannot be looked at twice), and the whole stream is read boundedly; a
/// format whose reader opens the file twice (NRRD, MetaImage) refuses a
/// FIFO before opening it (the second open would wait without end).
#[cfg(unix)]
#[test]
fn fifos_are_read_once_by_their_names() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("m.ply");
    let m = chisel::TriMesh {
        positions: vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
        triangles: vec![[0, 1, 2]],
        ..Default::default()
    };
    chisel::io::write_mesh(&mesh, &m).unwrap();
    let volume = dir.path().join("v.nrrd");
    let v = chisel::Volume::new(
        [2, 2, 2],
        [1.0; 3],
        [0.0; 3],
        chisel::volume::VolumeData::U8((0..8).collect()),
    )
    .unwrap();
    chisel::io::write_volume(&volume, &v).unwrap();
    let fifo = |name: &str| {
        let p = dir.path().join(name);
        let status = std::process::Command::new("mkfifo")
            .arg(&p)
            .status()
            .unwrap();
        assert!(status.success());
        p
    };
    let f = fifo("f.ply");
    let bytes = std::fs::read(&mesh).unwrap();
    let writer_path = f.clone();
    let writer = std::thread::spawn(move || std::fs::write(writer_path, bytes).unwrap());
    assert_eq!(read_mesh(&f).unwrap(), m);
    writer.join().unwrap();
    // No writer: the refusal comes before any open.
    let e = read_volume(&fifo("f.nrrd")).unwrap_err();
    assert!(e.to_string().contains("a pipe or FIFO"), "{e}");
    assert!(chisel::io::read_volume(&volume).is_ok());
}
