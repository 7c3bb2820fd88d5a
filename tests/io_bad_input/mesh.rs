//! The mesh readers (VTK, PLY, OBJ, STL, BYU) on hostile and broken input.

use crate::{Kind, expect};

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
        "found a VTK legacy STRUCTURED_POINTS volume",
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

pub(crate) fn ply_header(format: &str, nv: u64, nf: u64) -> String {
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
