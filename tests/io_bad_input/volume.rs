//! The volume readers (NRRD, MetaImage, NIfTI, raw) on hostile and broken
//! input.

use chisel::io::{RawSpec, read_raw_volume, read_volume};
use chisel::volume::ScalarType;

use crate::{Kind, expect, kind, put};

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
            &format!("{MET_444}TransformMatrix = 1 0 0 1 1 0 0 0 1\nElementDataFile = LOCAL\n"),
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
    // A rotation (qform: half a turn about y) is kept; a sheared sform is
    // refused.
    let mut f = nifti([2, 2, 2], 2, 8);
    f[252..254].copy_from_slice(&1i16.to_le_bytes());
    f[260..264].copy_from_slice(&1f32.to_le_bytes());
    f.extend([0u8; 8]);
    let dir = tempfile::tempdir().unwrap();
    let v = read_volume(&put(dir.path(), "q.nii", &f)).unwrap();
    assert_eq!(
        v.axes,
        [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]
    );
    let mut f = nifti([2, 2, 2], 2, 8);
    f[254..256].copy_from_slice(&1i16.to_le_bytes());
    for (at, x) in [(280, 1f32), (284, 1.0), (300, 1.0), (320, 1.0)] {
        f[at..at + 4].copy_from_slice(&x.to_le_bytes());
    }
    f.extend([0u8; 8]);
    expect("s.nii", &f, Kind::Unsupported, "byte 280");
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
