//! Mesh readers on the real data and writer round trips (SPEC §0.5).

mod common;

use std::path::Path;

use chisel::TriMesh;
use chisel::io::{mesh_format_carries_scalars, read_mesh, write_mesh};

use chisel::mesh::ScalarField;
use glam::Vec3;

fn assert_bounds(m: &TriMesh, lo: [f32; 3], hi: [f32; 3]) {
    let (a, b) = m.bounds().expect("non-empty");
    for i in 0..3 {
        assert!(
            (a[i] - lo[i]).abs() < 1e-5,
            "min[{i}] = {} vs {}",
            a[i],
            lo[i]
        );
        assert!(
            (b[i] - hi[i]).abs() < 1e-5,
            "max[{i}] = {} vs {}",
            b[i],
            hi[i]
        );
    }
}

fn used_vertices(m: &TriMesh) -> usize {
    let mut used = vec![false; m.n_vertices()];
    for t in &m.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    used.iter().filter(|&&u| u).count()
}

#[test]
fn fran_cut_vtk() {
    let Some(m) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    assert_eq!(m.n_vertices(), 2205);
    assert_eq!(m.n_triangles(), 4224);
    assert_eq!(used_vertices(&m), 2205);
    assert_bounds(
        &m,
        [0.0, -0.2048, -0.118986],
        [0.1056, -0.0512003, 0.00411239],
    );
    // y = -0.2048 + 0.0032·row, row = i % 49 (README §1).
    for (i, p) in m.positions.iter().enumerate() {
        let y = -0.2048 + 0.0032 * (i % 49) as f32;
        assert!((p.y - y).abs() < 1e-6, "vertex {i}: y {} vs {y}", p.y);
    }
    // The texture coordinates come as the fields `u` and `v`, in [0, 1].
    let names: Vec<&str> = m.scalars.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["u", "v"]);
    for f in &m.scalars {
        assert_eq!(f.values.len(), 2205);
        assert!(
            f.values.iter().all(|x| (0.0..=1.0).contains(x)),
            "{}",
            f.name
        );
    }
}

#[test]
fn bunny_ply_keeps_extra_properties() {
    let Some(m) = common::real_mesh("bunny.ply") else {
        return;
    };
    assert_eq!(m.n_vertices(), 35947);
    assert_eq!(m.n_triangles(), 69451);
    assert_eq!(m.n_vertices() - used_vertices(&m), 1113);
    assert_bounds(
        &m,
        [-0.0946899, 0.0329874, -0.0618736],
        [0.0610091, 0.187321, 0.0587997],
    );
    let names: Vec<&str> = m.scalars.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["confidence", "intensity"]);
    let range = |s: &ScalarField| {
        s.values
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)))
    };
    let (lo, hi) = range(m.scalar("confidence").unwrap());
    assert_eq!(lo, 0.0);
    assert!((hi - 0.999238).abs() < 1e-6, "{hi}");
    let (lo, hi) = range(m.scalar("intensity").unwrap());
    assert_eq!((lo, hi), (0.0, 0.5));
}

#[test]
fn footbones_ply_crlf() {
    let Some(m) = common::real_mesh("fsu/footbones.ply") else {
        return;
    };
    assert_eq!(m.n_vertices(), 2154);
    assert_eq!(m.n_triangles(), 4204);
    assert_eq!(used_vertices(&m), 2154);
    assert!(m.scalars.is_empty());
    assert_bounds(
        &m,
        [-5.63324, -1.86044, -2.12503],
        [5.63321, 1.86044, 2.12566],
    );
}

/// A mesh with two scalar fields and awkward coordinates (negative zero,
/// tiny and large magnitudes) that must survive every writer exactly.
fn sample_mesh() -> TriMesh {
    let mut m = common::icosphere(1);
    m.positions[0] = Vec3::new(-0.0, 1.0e-7, 12345.678);
    m.positions[1] *= 3.0e4;
    let n = m.n_vertices();
    m.scalars = vec![
        ScalarField {
            name: "displacement".into(),
            values: (0..n).map(|i| i as f32 * 0.125 - 3.0).collect(),
        },
        ScalarField {
            name: "label".into(),
            values: (0..n).map(|i| (i % 7) as f32).collect(),
        },
    ];
    m
}

fn round_trip(name: &str, m: &TriMesh) -> TriMesh {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    write_mesh(&path, m).unwrap_or_else(|e| panic!("{e}"));
    read_mesh(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Triangles as corner positions (bit patterns), for formats that renumber.
fn corner_soup(m: &TriMesh) -> Vec<[[u32; 3]; 3]> {
    m.triangles
        .iter()
        .map(|t| {
            t.map(|v| {
                m.positions[v as usize]
                    .to_array()
                    .map(|c| (c + 0.0).to_bits())
            })
        })
        .collect()
}

#[test]
fn ply_and_vtk_round_trip_with_scalars() {
    let m = sample_mesh();
    for name in ["m.ply", "m.vtk"] {
        assert!(mesh_format_carries_scalars(Path::new(name)));
        let back = round_trip(name, &m);
        assert_eq!(back, m, "{name}");
    }
}

#[test]
fn obj_and_byu_round_trip_without_scalars() {
    let m = sample_mesh();
    for name in ["m.obj", "m.byu", "m.g"] {
        assert!(!mesh_format_carries_scalars(Path::new(name)));
        let back = round_trip(name, &m);
        assert_eq!(back.positions, m.positions, "{name}");
        assert_eq!(back.triangles, m.triangles, "{name}");
        assert!(back.scalars.is_empty(), "{name}");
    }
}

#[test]
fn stl_round_trip_welds_to_the_same_surface() {
    let m = sample_mesh();
    assert!(!mesh_format_carries_scalars(Path::new("m.stl")));
    let back = round_trip("m.stl", &m);
    // Every icosphere vertex is used and distinct, so welding restores the count.
    assert_eq!(back.n_vertices(), m.n_vertices());
    assert_eq!(corner_soup(&back), corner_soup(&m));
    assert!(back.scalars.is_empty());
}

#[test]
fn real_meshes_round_trip_through_ply_and_vtk() {
    for rel in ["bunny.ply", "fran_cut.vtk", "fsu/footbones.ply"] {
        let Some(m) = common::real_mesh(rel) else {
            return;
        };
        for name in ["m.ply", "m.vtk"] {
            assert_eq!(round_trip(name, &m), m, "{rel} via {name}");
        }
    }
}

fn read_text(name: &str, text: &[u8]) -> TriMesh {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    read_mesh(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn unit_quad_points() -> Vec<Vec3> {
    vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(2.0, 0.5, 0.0),
    ]
}

/// VTK BINARY (big-endian): a quad polygon, a 4-point strip, point scalars
/// with a lookup table, normals and an empty CELL_DATA section.
#[test]
fn vtk_binary_big_endian_polygons_and_strips() {
    let pts = unit_quad_points();
    let mut f =
        b"# vtk DataFile Version 3.0\nbinary test\nBINARY\nDATASET POLYDATA\nPOINTS 5 float\n"
            .to_vec();
    for p in &pts {
        for c in p.to_array() {
            f.extend(c.to_be_bytes());
        }
    }
    f.extend(b"\nPOLYGONS 1 5\n");
    for v in [4i32, 0, 1, 2, 3] {
        f.extend(v.to_be_bytes());
    }
    f.extend(b"\nTRIANGLE_STRIPS 1 5\n");
    for v in [4i32, 1, 4, 2, 0] {
        f.extend(v.to_be_bytes());
    }
    f.extend(b"\nCELL_DATA 2\nPOINT_DATA 5\nSCALARS temp double 1\nLOOKUP_TABLE default\n");
    for v in [0.5f64, -1.0, 2.0, 3.0, 1e-3] {
        f.extend(v.to_be_bytes());
    }
    f.extend(b"\nNORMALS n float\n");
    for _ in 0..15 {
        f.extend(1f32.to_be_bytes());
    }
    f.extend(b"\n");
    let m = read_text("b.vtk", &f);
    assert_eq!(m.positions, pts);
    assert_eq!(
        m.triangles,
        [[0, 1, 2], [0, 2, 3], [1, 4, 2], [2, 4, 0]],
        "fan, then strip with alternating winding"
    );
    assert_eq!(m.scalars.len(), 1);
    assert_eq!(m.scalars[0].name, "temp");
    assert_eq!(m.scalars[0].values, [0.5, -1.0, 2.0, 3.0, 1e-3]);
}

/// VTK 5.1 ASCII cells (OFFSETS/CONNECTIVITY) and a FIELD array.
#[test]
fn vtk_51_offsets_connectivity() {
    let f = b"# vtk DataFile Version 5.1\nnew layout\nASCII\nDATASET POLYDATA\n\
POINTS 5 float\n0 0 0 1 0 0 1 1 0 0 1 0 2 0.5 0\n\
POLYGONS 3 7\nOFFSETS vtktypeint64\n0 4 7\nCONNECTIVITY vtktypeint64\n0 1 2 3 1 4 2\n\
POINT_DATA 5\nFIELD FieldData 2\nw 1 5 float\n1 2 3 4 5\nuv 2 5 float\n0 0 0 0 0 0 0 0 0 0\n";
    let m = read_text("n.vtk", f);
    assert_eq!(m.positions, unit_quad_points());
    assert_eq!(m.triangles, [[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
    assert_eq!(m.scalars.len(), 1);
    assert_eq!(m.scalars[0].values, [1.0, 2.0, 3.0, 4.0, 5.0]);
}

/// PLY binary big-endian with classic type names, an extra property, a quad
/// and an extra element after the faces.
#[test]
fn ply_binary_big_endian() {
    let pts = unit_quad_points();
    let mut f = b"ply\r\nformat binary_big_endian 1.0\r\ncomment x\r\nelement vertex 5\r\n\
property float x\r\nproperty float y\r\nproperty float z\r\nproperty uchar quality\r\n\
element face 2\r\nproperty uchar flags\r\nproperty list uchar int vertex_indices\r\n\
element edge 1\r\nproperty int vertex1\r\nproperty int vertex2\r\nend_header\r\n"
        .to_vec();
    for (i, p) in pts.iter().enumerate() {
        for c in p.to_array() {
            f.extend(c.to_be_bytes());
        }
        f.push(10 * i as u8);
    }
    f.extend([0u8, 4]);
    for v in [0i32, 1, 2, 3] {
        f.extend(v.to_be_bytes());
    }
    f.extend([0u8, 3]);
    for v in [1i32, 4, 2] {
        f.extend(v.to_be_bytes());
    }
    for v in [0i32, 1] {
        f.extend(v.to_be_bytes());
    }
    let m = read_text("b.ply", &f);
    assert_eq!(m.positions, pts);
    assert_eq!(m.triangles, [[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
    assert_eq!(m.scalars.len(), 1);
    assert_eq!(m.scalars[0].name, "quality");
    assert_eq!(m.scalars[0].values, [0.0, 10.0, 20.0, 30.0, 40.0]);
}

#[test]
fn ply_binary_little_endian_matches_ascii() {
    let ascii = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n\
property double z\nelement face 1\nproperty list uint8 uint32 vertex_index\nend_header\n\
0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float64 x\n\
property float64 y\nproperty float64 z\nelement face 1\nproperty list uint8 uint32 vertex_index\nend_header\n"
        .to_vec();
    for v in [0f64, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend(v.to_le_bytes());
    }
    bin.push(3);
    for v in [0u32, 1, 2] {
        bin.extend(v.to_le_bytes());
    }
    let a = read_text("a.ply", ascii);
    assert_eq!(a.n_triangles(), 1);
    assert_eq!(a, read_text("b.ply", &bin));
}

/// A binary payload may start with a byte that is whitespace in text
/// (0x09–0x0d, 0x20): it is data, not padding after the header. (A 1 in 43
/// little-endian PLY files has one, e.g. a first x of 59.96, 0x426fd70a.)
#[test]
fn binary_payloads_starting_with_whitespace_bytes() {
    for byte in [0x09u32, 0x0a, 0x0b, 0x0c, 0x0d, 0x20] {
        // First payload byte = `byte`: the low byte in little-endian files,
        // the high byte in big-endian ones.
        let le = f32::from_bits(0x426f_d700 | byte);
        let be = f32::from_bits(byte << 24 | 0x6f_d70a);
        for (first, name) in [(le, "le.ply"), (be, "be.ply"), (be, "be.vtk")] {
            let mut pts = unit_quad_points();
            pts[0].x = first;
            let mesh = TriMesh::new(pts.clone(), vec![[0, 1, 2], [0, 2, 3]]).unwrap();
            let mut f = Vec::new();
            if name.ends_with(".vtk") {
                f.extend(
                    b"# vtk DataFile Version 3.0\nws\nBINARY\nDATASET POLYDATA\nPOINTS 5 float\n",
                );
                f.extend(
                    pts.iter()
                        .flat_map(|p| p.to_array())
                        .flat_map(f32::to_be_bytes),
                );
                f.extend(b"\nPOLYGONS 2 8\n");
                f.extend(
                    [3i32, 0, 1, 2, 3, 0, 2, 3]
                        .iter()
                        .flat_map(|v| v.to_be_bytes()),
                );
                f.extend(b"\n");
            } else {
                let endian = if name == "le.ply" { "little" } else { "big" };
                f.extend(format!(
                    "ply\nformat binary_{endian}_endian 1.0\nelement vertex 5\nproperty float x\n\
property float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
                ).bytes());
                let le = name == "le.ply";
                let word = |v: [u8; 4]| if le { v } else { [v[3], v[2], v[1], v[0]] };
                f.extend(
                    pts.iter()
                        .flat_map(|p| p.to_array())
                        .flat_map(|c| word(c.to_le_bytes())),
                );
                for t in &mesh.triangles {
                    f.push(3);
                    f.extend(t.iter().flat_map(|&v| word(v.to_le_bytes())));
                }
            }
            let m = read_text(name, &f);
            assert_eq!(m.positions, pts, "{name} first byte {byte:#04x}");
            assert_eq!(m.triangles, mesh.triangles, "{name} first byte {byte:#04x}");
        }
    }
    // chisel's own writer and reader round-trip such a mesh.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("w.ply");
    let mut pts = unit_quad_points();
    pts[0].x = 59.96;
    let mesh = TriMesh::new(pts, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2]]).unwrap();
    chisel::io::write_mesh(&path, &mesh).unwrap();
    assert_eq!(read_mesh(&path).unwrap(), mesh);
}

#[test]
fn obj_corner_forms_negative_indices_and_polygons() {
    let f = b"# test\nmtllib x.mtl\no quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n\
f 1/1/1 2/1/1 3//1 4\nv 2 0.5 0 1.0\ns off\nf -4 -1 -3\n";
    let m = read_text("q.obj", f);
    assert_eq!(m.positions, unit_quad_points());
    assert_eq!(m.triangles, [[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
}

#[test]
fn stl_ascii_and_binary_weld_shared_corners() {
    let ascii = b"solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n\
   vertex 1 1 0\n  endloop\n endfacet\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n\
   vertex 1 1 0\n   vertex -0 1 0\n  endloop\n endfacet\nendsolid t\n";
    let a = read_text("a.stl", ascii);
    assert_eq!(a.n_vertices(), 4);
    assert_eq!(a.triangles, [[0, 1, 2], [0, 2, 3]]);
    // Binary whose 80-byte header starts with "solid": the length decides.
    let mut bin = b"solid but binary".to_vec();
    bin.resize(80, b' ');
    bin.extend(2u32.to_le_bytes());
    for tri in [
        [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.]],
        [[0., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
    ] {
        bin.extend([0u8; 12]);
        for c in tri.iter().flatten() {
            bin.extend(c.to_le_bytes());
        }
        bin.extend([0u8; 2]);
    }
    assert_eq!(read_text("b.stl", &bin), a);
}

/// MovieBYU with two parts and a quad (seed 000's format).
#[test]
fn byu_two_parts_and_a_quad() {
    let f = b"2 5 2 7\n1 1 2 2\n0 0 0 1 0 0 1 1 0 0 1 0 2 0.5 0\n1 2 3 -4\n2 5 -3\n";
    let m = read_text("t.byu", f);
    assert_eq!(m.positions, unit_quad_points());
    assert_eq!(m.triangles, [[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
}
