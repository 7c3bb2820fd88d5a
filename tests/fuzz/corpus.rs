//! The seeds: small valid files of every reader, written by chisel's writers
//! and by hand (the variants the writers do not make: ASCII and big-endian
//! encodings, strips, gzip and zlib streams, detached data), and the
//! shipped plan and scene.

use std::io::Write;
use std::path::Path;

use chisel::Volume;
use chisel::io::{write_mesh, write_volume};
use chisel::volume::VolumeData;

/// One seed: its file name (the extension picks the reader), its bytes,
/// and whether any truncation and any appended byte must be refused (the
/// binary formats, whose headers fix their length).
#[derive(Debug, Clone)]
pub struct Seed {
    /// The reader it exercises (campaign sizes are per reader).
    pub reader: &'static str,
    pub name: String,
    pub bytes: Vec<u8>,
    pub strict: bool,
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

fn zlib(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

const PLY_HEAD: &str = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                        element face 1\nproperty list uchar int vertex_indices\nend_header\n";

/// Every seed. Detached volumes (`.nhdr`, `.mhd`) name a data file the
/// caller writes once next to the cases ([`data_files`]).
pub fn seeds(scratch: &Path) -> Vec<Seed> {
    let mut out = Vec::new();
    let mut add = |name: &str, bytes: Vec<u8>, strict: bool| {
        out.push(Seed {
            reader: reader_of(name),
            name: name.into(),
            bytes,
            strict,
        })
    };
    // Meshes through the writers (binary PLY and STL are strict).
    let mut m = crate::common::icosphere(0);
    m.scalars.push(chisel::mesh::ScalarField {
        name: "s".into(),
        values: (0..m.n_vertices()).map(|i| i as f32).collect(),
    });
    for (name, strict) in [
        ("m.ply", true),
        ("m.vtk", false),
        ("m.obj", false),
        ("m.stl", true),
        ("m.byu", false),
    ] {
        let p = scratch.join(name);
        write_mesh(&p, &m).unwrap();
        add(name, std::fs::read(&p).unwrap(), strict);
    }
    // Hand-written mesh variants.
    add(
        "a.ply",
        format!("ply\nformat ascii 1.0\n{PLY_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").into_bytes(),
        false,
    );
    let mut be = format!("ply\nformat binary_big_endian 1.0\n{PLY_HEAD}").into_bytes();
    for c in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        be.extend(c.to_be_bytes());
    }
    be.push(3);
    for i in [0i32, 1, 2] {
        be.extend(i.to_be_bytes());
    }
    add("be.ply", be, true);
    add(
        "a.stl",
        b"solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n\
          endloop\nendfacet\nendsolid a\n"
            .to_vec(),
        false,
    );
    let mut vtk =
        b"# vtk DataFile Version 3.0\nt\nBINARY\nDATASET POLYDATA\nPOINTS 3 float\n".to_vec();
    for c in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        vtk.extend(c.to_be_bytes());
    }
    vtk.extend(b"\nTRIANGLE_STRIPS 1 4\n");
    for i in [3i32, 0, 1, 2] {
        vtk.extend(i.to_be_bytes());
    }
    add("b.vtk", vtk, false);
    add(
        "q.obj",
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1 4/1\nf -4 -3 -2\n".to_vec(),
        false,
    );
    // Volumes through the writers (attached ones are strict).
    let v = Volume::new(
        [3, 4, 2],
        [1.0, 2.0, 0.5],
        [0.0, -1.0, 2.0],
        VolumeData::I16((0..24).map(|i| i * 300 - 3000).collect()),
    )
    .unwrap();
    for name in ["v.nrrd", "v.mha", "v.nii", "v.nii.gz"] {
        let p = scratch.join(name);
        write_volume(&p, &v).unwrap();
        add(name, std::fs::read(&p).unwrap(), true);
    }
    // Hand-written volume variants: gzip big-endian NRRD, ASCII NRRD, zlib
    // MetaImage, detached headers. (The decompression bomb is a regression
    // file: seeds are valid.)
    let mut g =
        b"NRRD0004\ntype: short\ndimension: 3\nsizes: 3 4 2\nendian: big\nencoding: gzip\n\n"
            .to_vec();
    g.extend(gzip(
        &(0..24i16)
            .flat_map(|i| (i * 300).to_be_bytes())
            .collect::<Vec<u8>>(),
    ));
    add("g.nrrd", g, true);
    add(
        "t.nrrd",
        b"NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nspacings: 1 1 2\nencoding: ascii\n\n\
          0 1 2 3\n4 5 6 7e-1\n"
            .to_vec(),
        false,
    );
    let mut z = b"NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nCompressedData = True\n\
                  ElementDataFile = LOCAL\n"
        .to_vec();
    z.extend(zlib(&(0..64u8).collect::<Vec<u8>>()));
    add("z.mha", z, true);
    add(
        "d.nhdr",
        b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: raw\ndata file: d.raw\n"
            .to_vec(),
        false,
    );
    add(
        "d.mhd",
        b"NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nElementDataFile = d.raw\n".to_vec(),
        false,
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // DICOM files written by pydicom (tests/data/dicom): explicit and
    // implicit VR, RLE, no file meta, enhanced multi-frame.
    let dicom = root.join("tests/data/dicom");
    for (name, file) in [
        ("explicit.dcm", "ct_explicit/IM0001"),
        ("implicit.dcm", "ct_implicit/IM0001"),
        ("rle.dcm", "ct_rle/IM0001"),
        ("nometa.dcm", "ct_no_meta/IM0001"),
        ("multiframe.dcm", "multiframe.dcm"),
    ] {
        add(name, std::fs::read(dicom.join(file)).unwrap(), false);
    }
    // VTK files written by VTK 9.7.2 (tests/data/vtk): XML ImageData and
    // PolyData in ASCII, inline base64, appended raw and base64, zlib,
    // both byte orders and header widths; legacy STRUCTURED_POINTS.
    let vtk = root.join("tests/data/vtk");
    for file in [
        "image_ascii.vti",
        "image_binary_zlib.vti",
        "image_appended_raw.vti",
        "image_appended_b64_zlib.vti",
        "poly_ascii.vtp",
        "poly_appended_raw.vtp",
        "poly_binary_zlib_be_u32.vtp",
        "sp_ascii.vtk",
        "sp_f64_extra_binary.vtk",
    ] {
        add(file, std::fs::read(vtk.join(file)).unwrap(), false);
    }
    // Configuration: the shipped plan (TOML and as JSON) and a scene.
    add(
        "plan.toml",
        std::fs::read(root.join("src/tissue/plans/fran_chin_advance.toml")).unwrap(),
        false,
    );
    add(
        "plan.json",
        br#"{"name": "j", "step": [{"name": "s", "select": {"sphere": {"center": [0, 0, 0], "radius": 1}}, "translate": [0.001, 0, 0], "increments": 2}]}"#
            .to_vec(),
        false,
    );
    add(
        "scene.toml",
        std::fs::read(root.join("src/implicit/scenes/dumbbell.toml")).unwrap(),
        false,
    );
    out
}

/// The reader a seed's name picks.
fn reader_of(name: &str) -> &'static str {
    match name.rsplit_once('.').map_or("", |(_, e)| e) {
        _ if name.starts_with("plan") => "plan",
        _ if name.starts_with("scene") => "scene",
        "nrrd" | "nhdr" => "nrrd",
        "mha" | "mhd" => "metaimage",
        "nii" | "gz" => "nifti",
        "dcm" => "dicom",
        "vti" => "vti",
        "vtp" => "vtp",
        "vtk" if name.starts_with("sp_") => "structured_points",
        "vtk" => "vtk",
        "ply" => "ply",
        "obj" => "obj",
        "stl" => "stl",
        "byu" => "byu",
        other => panic!("no reader for .{other}"),
    }
}

/// The data files the detached seeds name, written once into `dir`.
pub fn data_files(dir: &Path) {
    std::fs::write(dir.join("d.raw"), (0..64u8).collect::<Vec<u8>>()).unwrap();
}
