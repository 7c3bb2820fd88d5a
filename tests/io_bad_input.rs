//! Hostile and broken inputs for every reader (SPEC §0.5): each must give
//! an `Error` naming the file and a position — never a panic, a hang, a
//! giant allocation or a silent partial result — plus a seeded mutation
//! loop over valid files of every format and the atomic-write guarantees.

mod common;

use std::path::{Path, PathBuf};

use chisel::foundation::fs::write_atomic_with;
use chisel::io::{RawSpec, read_mesh, read_raw_volume, read_volume, write_mesh, write_volume};
use chisel::volume::{ScalarType, VolumeData};
use chisel::{Error, TriMesh, Volume};
use glam::Vec3;

fn put(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Format,
    Size,
    Unsupported,
    Io,
}

fn kind(e: &Error) -> Kind {
    match e {
        Error::Format { .. } => Kind::Format,
        Error::Size { .. } => Kind::Size,
        Error::Unsupported { .. } => Kind::Unsupported,
        Error::Io { .. } => Kind::Io,
        other => panic!("unexpected error variant: {other}"),
    }
}

/// Reads `bytes` saved as `name` (mesh or volume by extension) and checks the
/// error variant and that the message names the file and contains `at`.
fn expect(name: &str, bytes: &[u8], want: Kind, at: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = put(dir.path(), name, bytes);
    expect_at(&path, want, at)
}

fn expect_at(path: &Path, want: Kind, at: &str) -> String {
    let r = if is_volume(path) {
        read_volume(path).map(|_| ())
    } else {
        read_mesh(path).map(|_| ())
    };
    let e = r.expect_err("hostile input must be rejected");
    let msg = e.to_string();
    assert_eq!(kind(&e), want, "{msg}");
    let file = path.file_name().unwrap().to_string_lossy();
    assert!(msg.contains(&*file), "message lacks the file name: {msg}");
    assert!(msg.contains(at), "message lacks `{at}`: {msg}");
    msg
}

fn is_volume(path: &Path) -> bool {
    let n = path.to_string_lossy().to_ascii_lowercase();
    [".nrrd", ".nhdr", ".mha", ".mhd", ".nii", ".nii.gz"]
        .iter()
        .any(|e| n.ends_with(e))
}

// ---------------------------------------------------------------- VTK

const VTK_HEAD: &str = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\n";

fn vtk(body: &str) -> Vec<u8> {
    format!("{VTK_HEAD}{body}").into_bytes()
}

#[test]
fn vtk_bad_inputs() {
    let pts = "POINTS 3 float\n0 0 0 1 0 0 0 1 0\n";
    // Truncated in the middle of the cells.
    expect(
        "t.vtk",
        &vtk(&format!("{pts}POLYGONS 1 4\n3 0 1")),
        Kind::Format,
        "line 8",
    );
    // Oversized: the header claims far more points than the file holds.
    let m = expect(
        "o.vtk",
        &vtk("POINTS 1000000 float\n0 0 0\n"),
        Kind::Size,
        "line 5",
    );
    assert!(m.contains("3000000 point coordinates"), "{m}");
    // Malformed token.
    let m = expect(
        "m.vtk",
        &vtk("POINTS 3 float\n0 0 0 1 zero 0 0 1 0\n"),
        Kind::Format,
        "line 6",
    );
    assert!(m.contains("`zero`"), "{m}");
    // Hostile: NaN coordinate, index out of range, 2-point polygon,
    // negative and overflowing counts, unknown section, wrong dataset.
    expect(
        "n.vtk",
        &vtk("POINTS 3 float\n0 0 0 nan 0 0 0 1 0\n"),
        Kind::Format,
        "line 6",
    );
    expect(
        "i.vtk",
        &vtk(&format!("{pts}POLYGONS 1 4\n3 0 1 7\n")),
        Kind::Format,
        "line 8",
    );
    expect(
        "p.vtk",
        &vtk(&format!("{pts}POLYGONS 1 3\n2 0 1\n")),
        Kind::Format,
        "line 8",
    );
    expect(
        "c.vtk",
        &vtk(&format!("{pts}POLYGONS 1 9\n3 0 1 2\n")),
        Kind::Size,
        "line 7",
    );
    expect("g.vtk", &vtk("POINTS -3 float\n"), Kind::Format, "line 5");
    expect(
        "h.vtk",
        &vtk("POINTS 18446744073709551615 float\n0\n"),
        Kind::Size,
        "line 5",
    );
    expect("u.vtk", &vtk("GRID 3\n"), Kind::Format, "line 5");
    expect(
        "d.vtk",
        b"# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\n",
        Kind::Format,
        "line 4",
    );
    expect(
        "s.vtk",
        &vtk(&format!("{pts}POINT_DATA 4\n")),
        Kind::Format,
        "line 7",
    );
    // Binary payload shorter than announced: refused at the header line
    // before reading; a short cell list is reported at its byte offset.
    let mut b =
        b"# vtk DataFile Version 3.0\nt\nBINARY\nDATASET POLYDATA\nPOINTS 2 float\n".to_vec();
    b.extend([0u8; 20]);
    expect("b.vtk", &b, Kind::Size, "line 5");
    b.extend([0u8; 4]);
    b.extend(b"\nPOLYGONS 1 4\n");
    let cells_at = b.len();
    for v in [3i32, 0, 1, 5] {
        b.extend(v.to_be_bytes());
    }
    let m = expect("c.vtk", &b, Kind::Format, "byte");
    assert!(m.contains(&format!("byte {}", cells_at + 12)), "{m}");
}

// ---------------------------------------------------------------- PLY

fn ply_header(format: &str, nv: u64, nf: u64) -> String {
    format!(
        "ply\nformat {format} 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\n\
         property float z\nelement face {nf}\nproperty list uchar int vertex_indices\nend_header\n"
    )
}

#[test]
fn ply_bad_inputs() {
    let ascii = |body: &str| format!("{}{body}", ply_header("ascii", 3, 1)).into_bytes();
    expect(
        "t.ply",
        &ascii("0 0 0\n1 0 0\n0 1 0\n3 0 1"),
        Kind::Size,
        "line 13",
    );
    expect(
        "u.ply",
        &ascii("0 0 0\n1 0 0\n0 1 0\n3 0 1     "),
        Kind::Format,
        "line 13",
    );
    expect(
        "m.ply",
        &ascii("0 0 0\n1 0 0\n0 1 x\n3 0 1 2\n"),
        Kind::Format,
        "line 12",
    );
    expect(
        "n.ply",
        &ascii("0 0 0\n1 0 0\n0 inf 0\n3 0 1 2\n"),
        Kind::Format,
        "line 12",
    );
    expect(
        "i.ply",
        &ascii("0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
        Kind::Format,
        "line 13",
    );
    expect(
        "k.ply",
        &ascii("0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
        Kind::Format,
        "line 13",
    );
    expect(
        "v.ply",
        &ascii("0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n"),
        Kind::Format,
        "line 13",
    );
    let big = format!("{}0 0 0\n", ply_header("ascii", 4_000_000_000, 1)).into_bytes();
    expect("o.ply", &big, Kind::Size, "line 3");
    expect(
        "f.ply",
        b"ply\nformat ascii 2.0 x\nend_header\n",
        Kind::Format,
        "line 2",
    );
    expect(
        "y.ply",
        b"ply\nformat ascii 1.0\nproperty float x\n",
        Kind::Format,
        "line 3",
    );
    expect(
        "z.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n",
        Kind::Format,
        "line 3",
    );
    expect(
        "e.ply",
        b"ply\nformat ascii 1.0\nelement vertex 0\n",
        Kind::Format,
        "line 4",
    );
    // Binary: truncated payload and a face count that does not fit.
    let mut b = ply_header("binary_little_endian", 3, 1).into_bytes();
    b.extend([0u8; 30]);
    expect("b.ply", &b, Kind::Size, "line 3");
    let mut b = ply_header("binary_little_endian", 3, 1).into_bytes();
    b.extend([0u8; 36]);
    let faces_at = b.len();
    b.push(3);
    for v in [0i32, 1, 3] {
        b.extend(v.to_le_bytes());
    }
    let m = expect("c.ply", &b, Kind::Format, "byte");
    assert!(m.contains(&format!("byte {}", faces_at + 9)), "{m}");
    let mut b = ply_header("binary_big_endian", 0, 1).into_bytes();
    b.extend([255u8]);
    expect("l.ply", &b, Kind::Size, "byte");
}

// ---------------------------------------------------------------- OBJ

#[test]
fn obj_bad_inputs() {
    let v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    expect(
        "m.obj",
        format!("{v}v 1 two 3\n").as_bytes(),
        Kind::Format,
        "line 4",
    );
    expect("t.obj", b"v 0 0\n", Kind::Format, "line 1");
    expect("n.obj", b"v 0 NaN 0\n", Kind::Format, "line 1");
    expect(
        "z.obj",
        format!("{v}f 0 1 2\n").as_bytes(),
        Kind::Format,
        "line 4",
    );
    expect(
        "r.obj",
        format!("{v}f 1 2 4\n").as_bytes(),
        Kind::Format,
        "line 4",
    );
    expect(
        "g.obj",
        format!("{v}f -1 -2 -4\n").as_bytes(),
        Kind::Format,
        "line 4",
    );
    expect(
        "k.obj",
        format!("{v}\nf 1 2\n").as_bytes(),
        Kind::Format,
        "line 5",
    );
    expect(
        "x.obj",
        format!("{v}f 1 2 a/1\n").as_bytes(),
        Kind::Format,
        "line 4",
    );
    expect(
        "h.obj",
        format!("{v}f 1 2 99999999999999999999\n").as_bytes(),
        Kind::Format,
        "line 4",
    );
}

// ---------------------------------------------------------------- STL

fn stl_binary(n_claimed: u32, facets: &[[f32; 9]]) -> Vec<u8> {
    let mut b = vec![b' '; 80];
    b.extend(n_claimed.to_le_bytes());
    for f in facets {
        b.extend([0u8; 12]);
        for c in f {
            b.extend(c.to_le_bytes());
        }
        b.extend([0u8; 2]);
    }
    b
}

#[test]
fn stl_bad_inputs() {
    let tri = [0., 0., 0., 1., 0., 0., 0., 1., 0.];
    let m = expect(
        "o.stl",
        &stl_binary(1000, &[tri, tri]),
        Kind::Size,
        "byte 80",
    );
    assert!(m.contains("1000 facets"), "{m}");
    expect(
        "h.stl",
        &stl_binary(u32::MAX, &[tri]),
        Kind::Size,
        "byte 80",
    );
    let mut nan = tri;
    nan[4] = f32::NAN;
    expect("n.stl", &stl_binary(1, &[nan]), Kind::Format, "byte 112");
    expect("s.stl", b"x", Kind::Format, "line 1");
    let facet = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n";
    expect(
        "t.stl",
        format!("solid a\n{facet}vertex 0 1").as_bytes(),
        Kind::Format,
        "line 6",
    );
    expect(
        "m.stl",
        format!("solid a\n{facet}vertex 0 one 0\nendloop\nendfacet\nendsolid\n").as_bytes(),
        Kind::Format,
        "line 6",
    );
    expect(
        "k.stl",
        format!("solid a\n{facet}endloop\nendfacet\nendsolid\n").as_bytes(),
        Kind::Format,
        "line 2",
    );
    expect(
        "q.stl",
        format!("solid a\n{facet}vertex 0 1 0\nendloop\nendfacet\nfacet\n").as_bytes(),
        Kind::Format,
        "line 10",
    );
}

// ---------------------------------------------------------------- BYU

#[test]
fn byu_bad_inputs() {
    let coords = "0 0 0 1 0 0 0 1 0\n";
    expect(
        "t.byu",
        format!("1 3 1 3\n1 1\n{coords}1 2").as_bytes(),
        Kind::Size,
        "line 1",
    );
    expect(
        "u.byu",
        format!("1 3 2 3\n1 2\n{coords}1 2 -3 1 2 3").as_bytes(),
        Kind::Format,
        "line 4",
    );
    expect(
        "o.byu",
        b"1 3000000 1 3\n1 1\n0 0 0\n",
        Kind::Size,
        "line 1",
    );
    expect(
        "m.byu",
        b"1 3 1 3\n1 1\n0 0 0 1 0 0 0 x 0\n",
        Kind::Format,
        "line 3",
    );
    expect(
        "n.byu",
        b"1 3 1 3\n1 1\n0 0 0 1 0 0 0 nan 0\n",
        Kind::Format,
        "line 3",
    );
    expect(
        "i.byu",
        format!("1 3 1 3\n1 1\n{coords}1 2 -4\n").as_bytes(),
        Kind::Format,
        "line 4",
    );
    expect(
        "z.byu",
        format!("1 3 1 3\n1 1\n{coords}1 0 -3\n").as_bytes(),
        Kind::Format,
        "line 4",
    );
    expect(
        "k.byu",
        format!("1 3 1 2\n1 1\n{coords}1 -2\n").as_bytes(),
        Kind::Format,
        "line 4",
    );
    expect(
        "r.byu",
        format!("1 3 1 3\n1 5\n{coords}1 2 -3\n").as_bytes(),
        Kind::Format,
        "line 2",
    );
    expect("g.byu", b"1 -3 1 3\n", Kind::Format, "line 1");
}

// ---------------------------------------------------------------- NRRD

fn nrrd(fields: &str, data: &[u8]) -> Vec<u8> {
    let mut f = format!("NRRD0004\n{fields}\n").into_bytes();
    f.extend(data);
    f
}

const U8_444: &str = "type: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n";

#[test]
fn nrrd_bad_inputs() {
    let m = expect("t.nrrd", &nrrd(U8_444, &[1; 63]), Kind::Size, "byte 62");
    assert!(m.contains("64 samples"), "{m}");
    // Oversized: data past what the header describes, at its first byte.
    let m = expect("l.nrrd", &nrrd(U8_444, &[1; 65]), Kind::Format, "byte 126");
    assert!(m.contains("1 more bytes"), "{m}");
    // ... unless a byte skip picks the samples out of a larger file.
    let dir = tempfile::tempdir().unwrap();
    put(dir.path(), "big.raw", &[7u8; 100]);
    let p = put(
        dir.path(),
        "k.nhdr",
        &nrrd(&format!("{U8_444}byte skip: 8\ndata file: big.raw\n"), &[]),
    );
    assert_eq!(read_volume(&p).unwrap().len(), 64);
    let huge =
        "type: float\ndimension: 3\nsizes: 100000 100000 100000\nendian: little\nencoding: raw\n";
    expect("h.nrrd", &nrrd(huge, &[0; 8]), Kind::Size, "line 4");
    let over =
        "type: uchar\ndimension: 3\nsizes: 4294967296 4294967296 4294967296\nencoding: raw\n";
    expect("v.nrrd", &nrrd(over, &[0; 8]), Kind::Size, "line 4");
    expect(
        "g.nrrd",
        &nrrd(
            "type: uchar\ndimension: 3\nsizes: 4 -4 4\nencoding: raw\n",
            &[0; 64],
        ),
        Kind::Format,
        "line 4",
    );
    expect(
        "y.nrrd",
        &nrrd(
            "type: quaternion\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n",
            &[0; 64],
        ),
        Kind::Format,
        "line 2",
    );
    expect("x.nrrd", b"NRRX0004\n", Kind::Format, "line 1");
    expect(
        "f.nrrd",
        &nrrd("type: uchar\ndimension 3\n", &[]),
        Kind::Format,
        "line 3",
    );
    expect(
        "e.nrrd",
        &nrrd("type: uchar\ndimension: 3\nencoding: raw\n", &[0; 64]),
        Kind::Format,
        "field `sizes`",
    );
    expect(
        "s.nrrd",
        &nrrd(&format!("{U8_444}spacings: 1 nan -2\n"), &[0; 64]),
        Kind::Format,
        "line 6",
    );
    expect(
        "o.nrrd",
        &nrrd(&format!("{U8_444}space origin: (0,nan,0)\n"), &[0; 64]),
        Kind::Format,
        "line 6",
    );
    expect(
        "n.nrrd",
        &nrrd(
            "type: short\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n",
            &[0; 128],
        ),
        Kind::Format,
        "field `endian`",
    );
    let gz = "type: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: gzip\n";
    expect(
        "z.nrrd",
        &nrrd(gz, b"not gzip at all"),
        Kind::Format,
        "byte 63",
    );
    let short = {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        e.write_all(&[5u8; 10]).unwrap();
        e.finish().unwrap()
    };
    expect("w.nrrd", &nrrd(gz, &short), Kind::Size, "byte 63");
    let dir = tempfile::tempdir().unwrap();
    let p = put(
        dir.path(),
        "d.nhdr",
        &nrrd(&format!("{U8_444}data file: missing.raw\n"), &[]),
    );
    let e = read_volume(&p).unwrap_err();
    assert_eq!(kind(&e), Kind::Io, "{e}");
    assert!(e.to_string().contains("missing.raw"), "{e}");
    expect(
        "p.nhdr",
        &nrrd(&format!("{U8_444}data file: s%d 1 4 0\n"), &[]),
        Kind::Format,
        "line 6",
    );
    expect(
        "q.nhdr",
        &nrrd(&format!("{U8_444}data file: s%d 1 4000000000000 1\n"), &[]),
        Kind::Format,
        "line 6",
    );
    expect(
        "r.nhdr",
        &nrrd(&format!("{U8_444}data file: s%s 1 4 1\n"), &[]),
        Kind::Format,
        "line 6",
    );
}

// ---------------------------------------------------------------- MetaImage

fn mha(fields: &str, data: &[u8]) -> Vec<u8> {
    let mut f = format!("NDims = 3\n{fields}").into_bytes();
    f.extend(data);
    f
}

const MET_444: &str = "DimSize = 4 4 4\nElementType = MET_UCHAR\n";

#[test]
fn metaimage_bad_inputs() {
    let local = format!("{MET_444}ElementDataFile = LOCAL\n");
    let m = expect("t.mha", &mha(&local, &[0; 10]), Kind::Size, "byte");
    assert!(m.contains("64 samples"), "{m}");
    expect(
        "h.mha",
        &mha(
            "DimSize = 65536 65536 65536\nElementType = MET_DOUBLE\nElementDataFile = LOCAL\n",
            &[],
        ),
        Kind::Size,
        "line 2",
    );
    expect(
        "m.mha",
        &mha(
            "DimSize = 4 four 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
            &[0; 64],
        ),
        Kind::Format,
        "line 2",
    );
    expect(
        "g.mha",
        &mha(
            "DimSize = 4 -4 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
            &[0; 64],
        ),
        Kind::Format,
        "line 2",
    );
    expect(
        "y.mha",
        &mha(
            "DimSize = 4 4 4\nElementType = MET_COMPLEX\nElementDataFile = LOCAL\n",
            &[0; 64],
        ),
        Kind::Format,
        "line 3",
    );
    expect(
        "s.mha",
        &mha(
            &format!(
                "{MET_444}ElementSpacing = 1 nan 1\n{}",
                "ElementDataFile = LOCAL\n"
            ),
            &[0; 64],
        ),
        Kind::Format,
        "line 4",
    );
    expect(
        "r.mha",
        &mha(
            &format!("{MET_444}TransformMatrix = 0 1 0 1 0 0 0 0 1\nElementDataFile = LOCAL\n"),
            &[0; 64],
        ),
        Kind::Unsupported,
        "line 4",
    );
    expect("e.mha", &mha(MET_444, &[]), Kind::Format, "line");
    expect("k.mha", b"NDims: 3\n", Kind::Format, "line 1");
    let z = format!("{MET_444}CompressedData = True\nElementDataFile = LOCAL\n");
    expect(
        "z.mha",
        &mha(&z, b"garbage, not zlib"),
        Kind::Format,
        "byte",
    );
    let long = {
        use std::io::Write;
        let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
        e.write_all(&[1u8; 65]).unwrap();
        e.finish().unwrap()
    };
    let m = expect("l.mha", &mha(&z, &long), Kind::Format, "byte");
    assert!(m.contains("more data"), "{m}");
}

// ---------------------------------------------------------------- NIfTI

fn nifti(dims: [i16; 3], datatype: i16, bitpix: i16) -> Vec<u8> {
    let mut b = vec![0u8; 352];
    let mut set = |at: usize, bytes: &[u8]| b[at..at + bytes.len()].copy_from_slice(bytes);
    set(0, &348i32.to_le_bytes());
    for (i, d) in [3, dims[0], dims[1], dims[2], 1, 1, 1, 1]
        .iter()
        .enumerate()
    {
        set(40 + 2 * i, &d.to_le_bytes());
    }
    set(70, &datatype.to_le_bytes());
    set(72, &bitpix.to_le_bytes());
    for i in 0..4 {
        set(76 + 4 * i, &1f32.to_le_bytes());
    }
    set(108, &352f32.to_le_bytes());
    set(344, b"n+1\0");
    b
}

#[test]
fn nifti_bad_inputs() {
    expect(
        "t.nii",
        &nifti([2, 2, 2], 2, 8)[..200],
        Kind::Size,
        "byte 0",
    );
    let mut f = nifti([2, 2, 2], 2, 8);
    f.extend([0u8; 7]);
    expect("d.nii", &f, Kind::Size, "byte 352");
    let mut f = nifti([2, 2, 2], 2, 8);
    f[0..4].copy_from_slice(&349i32.to_le_bytes());
    expect("h.nii", &f, Kind::Format, "byte 0");
    let mut f = nifti([2, -2, 2], 2, 8);
    f.extend([0u8; 8]);
    expect("g.nii", &f, Kind::Format, "byte 44");
    let mut f = nifti([32767, 32767, 32767], 64, 64);
    f.extend([0u8; 8]);
    expect("v.nii", &f, Kind::Size, "byte 40");
    expect(
        "y.nii",
        &nifti([2, 2, 2], 1, 1),
        Kind::Unsupported,
        "byte 70",
    );
    expect("b.nii", &nifti([2, 2, 2], 4, 8), Kind::Format, "byte 72");
    let mut f = nifti([2, 2, 2], 2, 8);
    f[84..88].copy_from_slice(&f32::NAN.to_le_bytes());
    expect("p.nii", &f, Kind::Format, "byte 84");
    let mut f = nifti([2, 2, 2], 2, 8);
    f[108..112].copy_from_slice(&(-5f32).to_le_bytes());
    expect("o.nii", &f, Kind::Format, "byte 108");
    let mut f = nifti([2, 2, 2], 2, 8);
    f[344..348].copy_from_slice(b"ni1\0");
    expect("m.nii", &f, Kind::Unsupported, "byte 344");
    let mut f = nifti([2, 2, 2], 2, 8);
    f[252..254].copy_from_slice(&1i16.to_le_bytes());
    f[260..264].copy_from_slice(&1f32.to_le_bytes());
    f.extend([0u8; 8]);
    expect("q.nii", &f, Kind::Unsupported, "byte 256");
    expect(
        "z.nii.gz",
        b"\x1f\x8b\x08\x00garbage",
        Kind::Format,
        "byte 0",
    );
    let gz_short = {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        e.write_all(&nifti([2, 2, 2], 2, 8)).unwrap();
        e.write_all(&[1u8; 3]).unwrap();
        e.finish().unwrap()
    };
    expect("s.nii.gz", &gz_short, Kind::Size, "byte 0");
}

#[test]
fn raw_bad_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let path = put(dir.path(), "r.bin", &[0u8; 100]);
    let spec = RawSpec {
        dims: [5, 5, 5],
        scalar_type: ScalarType::U8,
        big_endian: false,
        spacing: [1.0; 3],
        origin: [0.0; 3],
        header_bytes: 0,
    };
    let e = read_raw_volume(&path, &spec).unwrap_err();
    assert_eq!(kind(&e), Kind::Size, "{e}");
    assert!(
        e.to_string().contains("r.bin") && e.to_string().contains("byte 0"),
        "{e}"
    );
    // 100 bytes hold 4 × 5 × 5 samples exactly, not 4 × 4 × 5 ones.
    let exact = RawSpec {
        dims: [4, 5, 5],
        ..spec.clone()
    };
    assert_eq!(read_raw_volume(&path, &exact).unwrap().len(), 100);
    let e = read_raw_volume(
        &path,
        &RawSpec {
            dims: [4, 4, 5],
            ..spec.clone()
        },
    )
    .unwrap_err();
    assert_eq!(kind(&e), Kind::Format, "{e}");
    assert!(
        e.to_string().contains("byte 80") && e.to_string().contains("20 more bytes"),
        "{e}"
    );
    // A header skip picks a region of a larger file: bytes after it are fine.
    let region = RawSpec {
        dims: [4, 4, 5],
        header_bytes: 4,
        ..spec.clone()
    };
    assert_eq!(read_raw_volume(&path, &region).unwrap().len(), 80);
    let huge = RawSpec {
        dims: [usize::MAX, 2, 2],
        ..spec.clone()
    };
    assert_eq!(
        kind(&read_raw_volume(&path, &huge).unwrap_err()),
        Kind::Size
    );
    let past = RawSpec {
        dims: [1, 1, 1],
        header_bytes: u64::MAX,
        ..spec
    };
    assert_eq!(
        kind(&read_raw_volume(&path, &past).unwrap_err()),
        Kind::Size
    );
}

#[test]
fn unknown_extensions_are_unsupported() {
    let dir = tempfile::tempdir().unwrap();
    let p = put(dir.path(), "x.xyz", b"");
    assert_eq!(kind(&read_mesh(&p).unwrap_err()), Kind::Unsupported);
    assert_eq!(kind(&read_volume(&p).unwrap_err()), Kind::Unsupported);
}

/// The memory budget: a child run of this binary with a 1000-byte budget
/// must refuse the 780 kB headsq volume before reading it.
#[test]
fn memory_budget_is_enforced() {
    if std::env::var_os("CHISEL_BUDGET_CHILD").is_some() {
        let Some(p) = common::data("headsq/quarter.nhdr") else {
            return;
        };
        let e = read_volume(&p).unwrap_err();
        assert_eq!(kind(&e), Kind::Size, "{e}");
        assert!(e.to_string().contains("CHISEL_MAX_INPUT_BYTES"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let m = put(dir.path(), "big.obj", &[b'#'; 2000]);
        assert_eq!(kind(&read_mesh(&m).unwrap_err()), Kind::Size);
        return;
    }
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["memory_budget_is_enforced", "--exact", "--test-threads=1"])
        .env("CHISEL_BUDGET_CHILD", "1")
        .env("CHISEL_MAX_INPUT_BYTES", "1000")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "child failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("1 passed"));
}

// ---------------------------------------------------------------- mutation loop

/// Valid small files of every format, written by chisel and by hand.
fn valid_files(dir: &Path) -> Vec<PathBuf> {
    let mut m = common::icosphere(0);
    m.scalars.push(chisel::mesh::ScalarField {
        name: "s".into(),
        values: (0..m.n_vertices()).map(|i| i as f32).collect(),
    });
    let mut files = Vec::new();
    for name in ["m.ply", "m.vtk", "m.obj", "m.stl", "m.byu"] {
        let p = dir.join(name);
        write_mesh(&p, &m).unwrap();
        files.push(p);
    }
    files.push(put(
        dir,
        "a.ply",
        format!(
            "{}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
            ply_header("ascii", 3, 1)
        )
        .as_bytes(),
    ));
    files.push(put(
        dir,
        "a.stl",
        b"solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid a\n",
    ));
    let mut b =
        b"# vtk DataFile Version 3.0\nt\nBINARY\nDATASET POLYDATA\nPOINTS 3 float\n".to_vec();
    for c in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        b.extend(c.to_be_bytes());
    }
    b.extend(b"\nTRIANGLE_STRIPS 1 4\n");
    for i in [3i32, 0, 1, 2] {
        b.extend(i.to_be_bytes());
    }
    files.push(put(dir, "b.vtk", &b));
    let v = Volume::new(
        [3, 4, 2],
        [1.0, 2.0, 0.5],
        [0.0, -1.0, 2.0],
        VolumeData::I16((0..24).map(|i| i * 300 - 3000).collect()),
    )
    .unwrap();
    for name in ["v.nrrd", "v.mha", "v.nii", "v.nii.gz", "v.mhd"] {
        let p = dir.join(name);
        write_volume(&p, &v).unwrap();
        files.push(p);
    }
    let mut gz =
        b"NRRD0004\ntype: short\ndimension: 3\nsizes: 3 4 2\nendian: big\nencoding: gzip\n\n"
            .to_vec();
    {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        for i in 0..24i16 {
            e.write_all(&(i * 300).to_be_bytes()).unwrap();
        }
        gz.extend(e.finish().unwrap());
    }
    files.push(put(dir, "g.nrrd", &gz));
    files
}

/// Seeded mutations (truncation, byte flips, digit insertions, repeats) of
/// valid files: every read must return `Ok` or `Err`, never panic.
#[test]
fn mutated_files_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let files = valid_files(dir.path());
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move |n: usize| {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s % n.max(1) as u64) as usize
    };
    let (mut ok, mut err) = (0, 0);
    for path in &files {
        let original = std::fs::read(path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let target = dir.path().join(format!("mut_{name}"));
        // The `.mhd` header keeps pointing at the intact `v.raw`.
        for round in 0..120 {
            let mut b = original.clone();
            match round % 4 {
                0 => b.truncate(next(b.len())),
                1 => {
                    for _ in 0..1 + next(4) {
                        let i = next(b.len());
                        b[i] ^= 1 << next(8);
                    }
                }
                2 => {
                    let i = next(b.len());
                    let digits = [b"9".as_slice(), b"-", b"99999999999", b" ", b"\n", b"nan"];
                    b.splice(i..i, digits[next(digits.len())].iter().copied());
                }
                _ => {
                    let i = next(b.len());
                    let j = (i + next(64)).min(b.len());
                    let chunk = b[i..j].to_vec();
                    b.splice(j..j, chunk);
                }
            }
            std::fs::write(&target, &b).unwrap();
            let r = if is_volume(&target) {
                read_volume(&target).map(|_| ())
            } else {
                read_mesh(&target).map(|_| ())
            };
            match r {
                Ok(()) => ok += 1,
                Err(_) => err += 1,
            }
        }
    }
    // Both outcomes occur: the loop really exercises the error paths.
    assert!(ok > 0 && err > 0, "ok {ok}, err {err}");
}

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
    assert!(r.is_err());
    assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));
    // An existing output survives a failed overwrite untouched.
    std::fs::write(&out, b"old").unwrap();
    let r = write_atomic_with(&out, |w| {
        w.write_all(b"new partial")?;
        Err(std::io::Error::other("interrupted"))
    });
    assert!(r.is_err());
    assert_eq!(std::fs::read(&out).unwrap(), b"old");
    assert_eq!(listing(dir.path()), ["out.ply"]);
    // An invalid mesh is refused before anything is written.
    let bad = TriMesh {
        positions: vec![Vec3::ZERO; 3],
        triangles: vec![[0, 1, 3]],
        scalars: Vec::new(),
    };
    assert!(write_mesh(&dir.path().join("bad.stl"), &bad).is_err());
    assert_eq!(listing(dir.path()), ["out.ply"]);
    // A volume NIfTI cannot hold is refused without leaving anything.
    let wide = Volume::new(
        [40_000, 1, 1],
        [1.0; 3],
        [0.0; 3],
        VolumeData::U8(vec![0; 40_000]),
    )
    .unwrap();
    assert!(write_volume(&dir.path().join("wide.nii"), &wide).is_err());
    assert_eq!(listing(dir.path()), ["out.ply"]);
    // A successful write leaves exactly the output.
    write_mesh(&out, &common::tetra()).unwrap();
    assert_eq!(listing(dir.path()), ["out.ply"]);
    assert_eq!(read_mesh(&out).unwrap(), common::tetra());
}
