//! Reference files written by VTK 9.7.2 (`scripts/make_vtk_references.py`)
//! read with chisel's readers and compared with what VTK's readers report;
//! round trips through chisel's writers; negative controls.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use serde_json::Value;

use super::super::vtk::legacy_type_name;
use super::*;
use crate::volume::{Space, VolumeData};
use crate::{Error, Volume};

fn data(name: &str) -> (PathBuf, Vec<u8>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/vtk")
        .join(name);
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (path, bytes)
}

fn expected() -> Value {
    serde_json::from_slice(&data("expected.json").1).unwrap()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0)
}

fn files(kind: &str, ext: &str) -> Vec<(String, Value)> {
    let all = expected();
    let files = all["files"].as_object().unwrap();
    let out: Vec<_> = files
        .iter()
        .filter(|(n, v)| n.ends_with(ext) && v["kind"] == kind)
        .map(|(n, v)| (n.clone(), v.clone()))
        .collect();
    assert!(!out.is_empty());
    out
}

fn check_image(name: &str, v: &Volume, e: &Value) {
    let dims: Vec<u64> = e["dims"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_u64().unwrap())
        .collect();
    assert_eq!(v.dims.map(|d| d as u64).to_vec(), dims, "{name}");
    assert_eq!(v.spacing.to_vec(), floats(&e["spacing"]), "{name}");
    assert_eq!(v.origin.to_vec(), floats(&e["origin"]), "{name}");
    // VTK's Direction: row-major, columns = index axes.
    let direction: Vec<f64> = (0..9).map(|i| v.axes[i % 3][i / 3]).collect();
    assert_eq!(direction, floats(&e["direction"]), "{name}");
    assert_eq!(v.space, None);
    assert_eq!(
        legacy_type_name(&v.data),
        e["type"].as_str().unwrap(),
        "{name}"
    );
    let want = floats(&e["values"]);
    assert_eq!(v.len(), want.len(), "{name}");
    for (i, w) in want.iter().enumerate() {
        assert!(close(v.data.get_f64(i), *w), "{name} sample {i}");
    }
    let sum: f64 = (0..v.len()).map(|i| v.data.get_f64(i)).sum();
    assert!(close(sum, e["sum"].as_f64().unwrap()), "{name}");
    // The world bounds VTK reports are those of the sample positions.
    let bounds = floats(&e["bounds"]);
    for c in 0..3 {
        let corners = (0..8).map(|m| {
            v.world(std::array::from_fn(|k| {
                if m >> k & 1 == 1 {
                    (v.dims[k] - 1) as f64
                } else {
                    0.0
                }
            }))[c]
        });
        let lo = corners.clone().fold(f64::INFINITY, f64::min);
        let hi = corners.fold(f64::NEG_INFINITY, f64::max);
        assert!(
            close(lo, bounds[2 * c]) && close(hi, bounds[2 * c + 1]),
            "{name} axis {c}"
        );
    }
}

#[test]
fn reads_every_vti_reference_file() {
    for (name, e) in files("image", ".vti") {
        let (path, bytes) = data(&name);
        assert_eq!(dataset_type(&bytes), Some(XmlDataset::ImageData), "{name}");
        let (v, skipped) = read_image(&path, &bytes).unwrap_or_else(|e| panic!("{e}"));
        check_image(&name, &v, &e);
        if name == "image_f64_extra.vti" {
            assert_eq!(skipped, ["point doubled", "point gradient", "cell cellid"]);
        } else {
            assert!(skipped.is_empty(), "{name}: {skipped:?}");
        }
        // Round trip through chisel's writer: identical.
        let mut out = Vec::new();
        write_image(&mut out, &v).unwrap();
        let (back, skipped) = read_image(Path::new("mem.vti"), &out).unwrap();
        assert_eq!(back, v, "{name}");
        assert!(skipped.is_empty());
    }
}

#[test]
fn reads_every_vtp_reference_file() {
    for (name, e) in files("poly", ".vtp") {
        let (path, bytes) = data(&name);
        assert_eq!(dataset_type(&bytes), Some(XmlDataset::PolyData), "{name}");
        let (m, notes) = read_poly(&path, &bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(
            m.positions.len() as u64,
            e["points"].as_u64().unwrap(),
            "{name}"
        );
        assert_eq!(
            m.triangles.len() as u64,
            e["triangles"].as_u64().unwrap(),
            "{name}"
        );
        assert_eq!(notes.verts, e["verts"].as_u64().unwrap(), "{name}");
        assert_eq!(notes.lines, e["lines"].as_u64().unwrap(), "{name}");
        assert_eq!(notes.strips, e["strips"].as_u64().unwrap(), "{name}");
        m.validate().unwrap();
        let bounds = floats(&e["bounds"]);
        for c in 0..3 {
            let coord = m.positions.iter().map(|p| f64::from(p[c]));
            let lo = coord.clone().fold(f64::INFINITY, f64::min);
            let hi = coord.fold(f64::NEG_INFINITY, f64::max);
            assert_eq!([lo, hi], [bounds[2 * c], bounds[2 * c + 1]], "{name}");
        }
        let sum: f64 = m
            .positions
            .iter()
            .flat_map(|p| p.to_array())
            .map(f64::from)
            .sum();
        assert!(close(sum, e["coordinate_sum"].as_f64().unwrap()), "{name}");
        let scalars = e["scalars"].as_object().unwrap();
        assert_eq!(m.scalars.len(), scalars.len(), "{name}");
        for s in &m.scalars {
            let want = &scalars[&s.name];
            let range = floats(&want["range"]);
            let lo = s
                .values
                .iter()
                .map(|&v| f64::from(v))
                .fold(f64::INFINITY, f64::min);
            let hi = s
                .values
                .iter()
                .map(|&v| f64::from(v))
                .fold(f64::NEG_INFINITY, f64::max);
            assert_eq!([lo, hi], [range[0], range[1]], "{name} {}", s.name);
            let sum: f64 = s.values.iter().map(|&v| f64::from(v)).sum();
            assert!(
                close(sum, want["sum"].as_f64().unwrap()),
                "{name} {}",
                s.name
            );
        }
        if name.starts_with("poly_pieces") {
            assert_eq!(notes.skipped, ["point Normals (3 components)"]);
        } else {
            // The sphere's 48 triangles, a quad, a pentagon, a strip of 6.
            assert_eq!(notes.polygons_split, 2, "{name}");
            assert_eq!(notes.triangles_from_polygons, 5, "{name}");
            assert_eq!(notes.triangles_from_strips, 4, "{name}");
            assert_eq!(notes.skipped, ["point normal3 (3 components)"], "{name}");
        }
        // Round trip through chisel's writer: identical.
        let mut out = Vec::new();
        write_poly(&mut out, &m).unwrap();
        let (back, notes) = read_poly(Path::new("mem.vtp"), &out).unwrap();
        assert_eq!(back, m, "{name}");
        assert_eq!(notes, super::poly::PolyNotes::default());
    }
}

#[test]
fn strips_keep_the_orientation_and_polygons_fan() {
    let (path, bytes) = data("poly_ascii.vtp");
    let (m, _) = read_poly(&path, &bytes).unwrap();
    let base = 34; // the sphere's points come first
    let n = m.triangles.len();
    // chisel reads Verts, Lines, Strips, Polys in that order: the strip's
    // triangles come first, the pentagon's last.
    let strip = &m.triangles[..4];
    assert_eq!(
        strip,
        [
            [base + 9, base + 10, base + 11],
            [base + 11, base + 10, base + 12],
            [base + 11, base + 12, base + 13],
            [base + 13, base + 12, base + 14],
        ]
    );
    let pentagon = &m.triangles[n - 3..];
    assert_eq!(
        pentagon,
        [
            [base + 4, base + 5, base + 6],
            [base + 4, base + 6, base + 7],
            [base + 4, base + 7, base + 8],
        ]
    );
}

#[test]
fn writes_rotated_and_reflected_frames_and_keeps_the_type() {
    let axes = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]];
    let v = Volume::new(
        [3, 2, 2],
        [0.1, 0.25, 3.0],
        [1e-9, -2.5, 1e12],
        VolumeData::U32((0..12).map(|i| i * 300_000_000).collect()),
    )
    .unwrap()
    .with_frame(axes, Some(Space::Lps))
    .unwrap();
    let mut out = Vec::new();
    write_image(&mut out, &v).unwrap();
    let (back, _) = read_image(Path::new("mem.vti"), &out).unwrap();
    // The anatomical frame is not stored in a .vti; all else is.
    assert_eq!(back.space, None);
    assert_eq!(
        Volume {
            space: None,
            ..v.clone()
        },
        back
    );
    // An empty mesh and one without scalars round-trip too.
    let m = crate::TriMesh::default();
    let mut out = Vec::new();
    write_poly(&mut out, &m).unwrap();
    assert_eq!(read_poly(Path::new("mem.vtp"), &out).unwrap().0, m);
}

fn err_image(bytes: &[u8]) -> Error {
    read_image(Path::new("bad.vti"), bytes).unwrap_err()
}

fn err_poly(bytes: &[u8]) -> Error {
    read_poly(Path::new("bad.vtp"), bytes).unwrap_err()
}

fn appended_start(bytes: &[u8]) -> usize {
    let tag = bytes
        .windows(13)
        .position(|w| w == b"<AppendedData")
        .unwrap();
    tag + bytes[tag..].iter().position(|&b| b == b'_').unwrap() + 1
}

fn replace(bytes: &[u8], from: &str, to: &str) -> Vec<u8> {
    let at = bytes
        .windows(from.len())
        .position(|w| w == from.as_bytes())
        .unwrap_or_else(|| panic!("`{from}` not found"));
    [&bytes[..at], to.as_bytes(), &bytes[at + from.len()..]].concat()
}

#[test]
fn a_corrupted_byte_count_is_named() {
    let (_, mut bytes) = data("image_appended_raw.vti");
    let s = appended_start(&bytes);
    bytes[s] = 200; // the UInt64 byte count: 120 → 200
    let e = err_image(&bytes).to_string();
    assert!(
        e.contains(&format!("byte {s}"))
            && e.contains("a byte count of 120")
            && e.contains("found 200"),
        "{e}"
    );
}

#[test]
fn a_truncated_appended_section_is_named() {
    let (_, bytes) = data("image_appended_raw.vti");
    let s = appended_start(&bytes);
    let cut = [&bytes[..s + 50], b"\n  </AppendedData>\n</VTKFile>\n"].concat();
    let e = err_image(&cut).to_string();
    assert!(
        e.contains(&format!("byte {}", s + 8))
            && e.contains("120 bytes of the data of DataArray `density`")
            && e.contains("ends after 45 bytes"), // 42 and the whitespace before the closing tag
        "{e}"
    );
    // Without the closing tags.
    let e = err_image(&bytes[..s + 50]).to_string();
    assert!(e.contains("to end with `</AppendedData>`"), "{e}");
}

/// A .vti of 120 bytes of `Int16` (5×4×3) whose one zlib block holds `inflated`.
fn zlib_image(inflated: usize, announced_last: u64) -> Vec<u8> {
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    z.write_all(&vec![7u8; inflated]).unwrap();
    let comp = z.finish().unwrap();
    let mut out = br#"<?xml version="1.0"?>
<VTKFile type="ImageData" version="1.0" byte_order="LittleEndian" header_type="UInt32" compressor="vtkZLibDataCompressor">
<ImageData WholeExtent="0 4 0 3 0 2" Origin="0 0 0" Spacing="1 1 1">
<Piece Extent="0 4 0 3 0 2"><PointData Scalars="s">
<DataArray type="Int16" Name="s" format="appended" offset="0"/>
</PointData></Piece></ImageData>
<AppendedData encoding="raw">
_"#
    .to_vec();
    for w in [1u32, 120, announced_last as u32, comp.len() as u32] {
        out.extend_from_slice(&w.to_le_bytes());
    }
    out.extend_from_slice(&comp);
    out.extend_from_slice(b"\n</AppendedData>\n</VTKFile>\n");
    out
}

#[test]
fn zlib_blocks_must_inflate_to_their_announced_size() {
    assert!(read_image(Path::new("ok.vti"), &zlib_image(120, 120)).is_ok());
    let e = err_image(&zlib_image(121, 120)).to_string();
    assert!(
        e.contains("compressed block 0 of DataArray `s` inflating to 120 bytes")
            && e.contains("a longer stream"),
        "{e}"
    );
    let e = err_image(&zlib_image(100, 120)).to_string();
    assert!(e.contains("a stream that ends at byte 100 of 120"), "{e}");
    let e = err_image(&zlib_image(120, 100)).to_string();
    assert!(
        e.contains("announcing 120 bytes") && e.contains("100 bytes"),
        "{e}"
    );
    // A garbled stream.
    let mut b = zlib_image(120, 120);
    let s = appended_start(&b) + 16;
    b[s] ^= 0xff;
    let e = err_image(&b).to_string();
    assert!(
        e.contains(&format!("byte {s}")) && e.contains("a zlib stream"),
        "{e}"
    );
}

#[test]
fn counts_and_indices_are_checked() {
    let (_, bytes) = data("poly_ascii.vtp");
    let e = err_poly(&replace(
        &bytes,
        "NumberOfPoints=\"49\"",
        "NumberOfPoints=\"48\"",
    ))
    .to_string();
    assert!(
        e.contains("144 values in DataArray `Points`") && e.contains("more values"),
        "{e}"
    );
    let e = err_poly(&replace(
        &bytes,
        "NumberOfPoints=\"49\"",
        "NumberOfPoints=\"99999999\"",
    ))
    .to_string();
    assert!(
        e.contains("299999997 ASCII values of DataArray `Points` needs"),
        "{e}"
    );
    let tiny = br#"<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian">
<PolyData><Piece NumberOfPoints="3" NumberOfPolys="1">
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0</DataArray></Points>
<Polys><DataArray type="Int64" Name="connectivity" format="ascii">0 1 5</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">3</DataArray></Polys>
</Piece></PolyData></VTKFile>
"#;
    let e = err_poly(tiny).to_string();
    assert!(
        e.contains("point indices in 0..3") && e.contains("5 at entry 2"),
        "{e}"
    );
    let ok = replace(tiny, "0 1 5", "0 1 2");
    let (m, _) = read_poly(Path::new("ok.vtp"), &ok).unwrap();
    assert_eq!(m.triangles, [[0, 1, 2]]);
    let e = err_poly(&replace(&ok, ">3<", ">4<")).to_string();
    assert!(
        e.contains("4 values in DataArray `connectivity`") && e.contains("found 3 values"),
        "{e}"
    );
}

#[test]
fn trailing_data_is_an_error() {
    let (_, bytes) = data("image_appended_raw.vti");
    let e = err_image(&[&bytes[..], b"junk"].concat()).to_string();
    assert!(
        e.contains("to end with `</AppendedData>` and `</VTKFile>`"),
        "{e}"
    );
    let (_, bytes) = data("image_ascii.vti");
    let e = err_image(&[&bytes[..], b"junk"].concat()).to_string();
    assert!(e.contains("the end of the file after </VTKFile>"), "{e}");
    // Bytes in the appended section that no array refers to.
    let (_, bytes) = data("image_appended_raw.vti");
    let end = bytes
        .windows(15)
        .rposition(|w| w == b"</AppendedData>")
        .unwrap();
    let extra = [&bytes[..end], b"XYZ", &bytes[end..]].concat();
    let e = err_image(&extra).to_string();
    assert!(e.contains("data no array refers to"), "{e}");
    // Base64 text after an inline array's data.
    let (_, bytes) = data("image_binary.vti");
    let e = err_image(&replace(&bytes, "uAA=", "uAA=AAAA")).to_string();
    assert!(
        e.contains("`</DataArray>` after the data of DataArray `density`"),
        "{e}"
    );
}

#[test]
fn refusals_say_why() {
    let (_, bytes) = data("image_binary_zlib.vti");
    let e = err_image(&replace(
        &bytes,
        "vtkZLibDataCompressor",
        "vtkLZ4DataCompressor",
    ));
    assert!(
        matches!(e, Error::Unsupported { .. }) && e.to_string().contains("vtkLZ4DataCompressor"),
        "{e}"
    );
    let (_, bytes) = data("image_ascii.vti");
    let e = err_image(&replace(
        &bytes,
        "Direction=\"0 -1 0 1 0 0 0 0 1\"",
        "Direction=\"1 1 0 1 0 0 0 0 1\"",
    ));
    assert!(e.to_string().contains("an orthonormal Direction"), "{e}");
    let e = err_image(&replace(&bytes, "type=\"Int16\"", "type=\"Int64\""));
    assert!(
        matches!(e, Error::Unsupported { .. }) && e.to_string().contains("64-bit"),
        "{e}"
    );
    let e = err_image(&replace(
        &bytes,
        "WholeExtent=\"0 4 0 3 0 2\"",
        "WholeExtent=\"0 4 0 3 0 1\"",
    ));
    assert!(e.to_string().contains("within the WholeExtent"), "{e}");
    let e = err_image(&replace(
        &bytes,
        "WholeExtent=\"0 4 0 3 0 2\"",
        "WholeExtent=\"0 4 0 3 0 3\"",
    ));
    assert!(
        matches!(e, Error::Unsupported { .. }) && e.to_string().contains("leave 20 of 80 points"),
        "{e}"
    );
    let e = err_image(&replace(
        &bytes,
        "ImageData\" version",
        "PolyData\" version",
    ));
    assert!(
        e.to_string().contains("<VTKFile type=\"ImageData\">"),
        "{e}"
    );
    let (_, bytes) = data("image_binary.vti");
    let e = err_image(&replace(&bytes, "eAAAAAAAAADO", "eAAAAAAAAA*O")).to_string();
    assert!(e.contains("base64 data") && e.contains("`*`"), "{e}");
    // A whole extent far past the budget: refused before allocating.
    let (_, bytes) = data("image_appended_raw.vti");
    let big = replace(
        &bytes,
        "WholeExtent=\"0 4 0 3 0 2\"",
        "WholeExtent=\"0 99999 0 99999 0 99999\"",
    );
    let big = replace(
        &big,
        "Extent=\"0 4 0 3 0 2\"",
        "Extent=\"0 99999 0 99999 0 99999\"",
    );
    let e = err_image(&big);
    assert!(matches!(e, Error::Size { .. }), "{e}");
}

#[test]
fn sniffs_the_dataset_type() {
    assert_eq!(
        dataset_type(b"<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\""),
        None
    );
    assert_eq!(
        dataset_type(
            b"<?xml version=\"1.0\"?>\n<!-- c -->\n<VTKFile type=\"PolyData\" version=\"1.0\">"
        ),
        Some(XmlDataset::PolyData)
    );
    assert_eq!(
        dataset_type(b"<VTKFile type=\"UnstructuredGrid\">"),
        Some(XmlDataset::Other)
    );
    assert_eq!(dataset_type(b"# vtk DataFile Version 3.0\n"), None);
    assert_eq!(dataset_type(b"<svg>"), None);
}

/// Writes chisel's .vti, .vtp and STRUCTURED_POINTS versions of reference
/// files into `$CHISEL_VTK_OUT`, for `scripts/make_vtk_references.py
/// --check-chisel DIR` to read with VTK's own readers (run by hand).
#[test]
#[ignore = "writes files for VTK to read; set CHISEL_VTK_OUT"]
fn write_files_for_vtk() {
    let Ok(dir) = std::env::var("CHISEL_VTK_OUT") else {
        return;
    };
    let dir = Path::new(&dir);
    for name in [
        "image_appended_raw.vti",
        "image_reflect.vti",
        "image_f64_extra.vti",
    ] {
        let (path, bytes) = data(name);
        let (v, _) = read_image(&path, &bytes).unwrap();
        let mut out = Vec::new();
        write_image(&mut out, &v).unwrap();
        std::fs::write(dir.join(format!("chisel_{name}")), out).unwrap();
        let flat = Volume {
            axes: crate::volume::IDENTITY_AXES,
            ..v
        };
        let mut out = Vec::new();
        super::super::vtk::write_structured_points(&mut out, &flat).unwrap();
        std::fs::write(dir.join(format!("chisel_{name}.vtk")), out).unwrap();
    }
    let (path, bytes) = data("poly_binary_zlib.vtp");
    let (m, _) = read_poly(&path, &bytes).unwrap();
    let mut out = Vec::new();
    write_poly(&mut out, &m).unwrap();
    std::fs::write(dir.join("chisel_poly.vtp"), out).unwrap();
}
