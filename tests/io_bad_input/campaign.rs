//! Regressions of the input-robustness campaign against the release binary
//! (issue "The inputs real users have"): endless inputs read boundedly,
//! decompression bombs refused without an abort, trailing and missing data
//! refused in every format, header fields named. The command-line findings
//! (outputs over inputs, NaN levels) are in `tests/cli/cross_command.rs`.

use std::io::Write;
use std::path::Path;

use chisel::io::{read_mesh, read_surface, read_volume};

use crate::{Kind, expect, kind, put};

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

/// A gzip stream of `bytes`.
fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(bytes).unwrap();
    enc.finish().unwrap()
}

/// A zlib stream of `bytes`.
fn zlib(bytes: &[u8]) -> Vec<u8> {
    let mut enc = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(bytes).unwrap();
    enc.finish().unwrap()
}

#[test]
fn decompression_bombs_are_errors_not_aborts() {
    // 1 GiB announced, 1 MiB delivered: the samples' room is reserved
    // exactly (fallibly), and the short stream is an error.
    let mut f =
        b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1024 1024 1024\nencoding: gzip\n\n".to_vec();
    f.extend(gzip(&vec![0u8; 1 << 20]));
    let m = expect("bomb.nrrd", &f, Kind::Size, "after decompression");
    assert!(m.contains("decompressed stream"), "{m}");
    // A stream longer than the header says: an error, read one byte past.
    let mut f = b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: gzip\n\n".to_vec();
    f.extend(gzip(&[1u8; 65]));
    expect("long.nrrd", &f, Kind::Format, "exactly 64 bytes");
}

#[test]
fn trailing_data_is_refused_in_every_format() {
    // Bytes after a complete zlib stream (MetaImage), as NRRD refuses
    // bytes after its samples.
    let mut f = b"NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nCompressedData = True\nElementDataFile = LOCAL\n"
        .to_vec();
    f.extend(zlib(&[3u8; 64]));
    let good = f.clone();
    f.extend(b"junk");
    expect("z.mha", &f, Kind::Format, "after the zlib stream");
    let dir = tempfile::tempdir().unwrap();
    let v = read_volume(&put(dir.path(), "good.mha", &good)).unwrap();
    assert_eq!(v.data.len(), 64);
    // Binary PLY: data past the announced elements, even a whitespace byte.
    let mut ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
    for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for c in v {
            ply.extend(c.to_le_bytes());
        }
    }
    ply.push(3);
    for i in [0i32, 1, 2] {
        ply.extend(i.to_le_bytes());
    }
    read_mesh(&put(dir.path(), "good.ply", &ply)).unwrap();
    ply.push(b'\n');
    expect("t.ply", &ply, Kind::Format, "more data");
    // Binary STL: fewer facets announced than the data holds (a hole), 0
    // with facets after it, or one trailing byte.
    let facet = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.];
    let stl = |n: u32, facets: usize, extra: &[u8]| {
        let mut b = vec![b'x'; 80];
        b.extend(n.to_le_bytes());
        for _ in 0..facets {
            b.extend([0u8; 12]);
            for c in facet {
                b.extend(c.to_le_bytes());
            }
            b.extend([0u8; 2]);
        }
        b.extend(extra);
        b
    };
    read_mesh(&put(dir.path(), "good.stl", &stl(2, 2, &[]))).unwrap();
    expect("hole.stl", &stl(1, 2, &[]), Kind::Format, "byte 134");
    expect("zero.stl", &stl(0, 2, &[]), Kind::Format, "byte 84");
    expect("byte.stl", &stl(2, 2, b"\n"), Kind::Format, "more data");
}

#[test]
fn header_fields_are_named_and_checked() {
    // NRRD `space origin` with fewer components than the space.
    let f = b"NRRD0004\ntype: uchar\ndimension: 3\nspace: left-posterior-superior\nsizes: 2 2 2\nspace origin: (1,2)\nencoding: raw\n\n\0\0\0\0\0\0\0\0";
    let m = expect("o.nrrd", f, Kind::Format, "space origin");
    assert!(m.contains("3 components"), "{m}");
    // NIfTI `vox_offset` far past the file.
    let mut n = vec![0u8; 352];
    let mut set = |at: usize, bytes: &[u8]| n[at..at + bytes.len()].copy_from_slice(bytes);
    set(0, &348i32.to_le_bytes());
    for (i, d) in [3i16, 2, 2, 2, 1, 1, 1, 1].iter().enumerate() {
        set(40 + 2 * i, &d.to_le_bytes());
    }
    set(70, &2i16.to_le_bytes());
    set(72, &8i16.to_le_bytes());
    for i in 0..4 {
        set(76 + 4 * i, &1f32.to_le_bytes());
    }
    set(108, &3e38f32.to_le_bytes());
    set(344, b"n+1\0");
    n.extend([0u8; 8]);
    let m = expect("v.nii", &n, Kind::Format, "byte 108");
    assert!(m.contains("vox_offset"), "{m}");
}

#[test]
fn a_file_without_triangles_is_no_surface() {
    let dir = tempfile::tempdir().unwrap();
    let p = put(dir.path(), "points.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    // A point set is a mesh (spline data, statistics) ...
    assert_eq!(read_mesh(&p).unwrap().positions.len(), 3);
    // ... but not a surface.
    let e = read_surface(&p).unwrap_err();
    assert_eq!(kind(&e), Kind::Format);
    assert!(e.to_string().contains("a mesh with triangles"), "{e}");
}
