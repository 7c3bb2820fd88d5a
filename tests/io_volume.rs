//! Volume readers on the real data and writer round trips (SPEC §0.5).

mod common;

use std::path::Path;

use chisel::io::{RawSpec, read_raw_volume, read_volume, write_volume};
use chisel::volume::{ScalarType, Space, VolumeData};
use chisel::{Error, Volume};

fn histogram_u8(v: &Volume) -> [usize; 256] {
    let VolumeData::U8(d) = &v.data else {
        panic!("expected u8 samples, got {:?}", v.data.scalar_type())
    };
    let mut h = [0usize; 256];
    for &x in d {
        h[x as usize] += 1;
    }
    h
}

fn mean(v: &Volume) -> f64 {
    (0..v.len()).map(|i| v.data.get_f64(i)).sum::<f64>() / v.len() as f64
}

#[test]
fn headsq_multi_file_nrrd() {
    let Some(v) = common::real_volume("headsq/quarter.nhdr") else {
        return;
    };
    assert_eq!(v.dims, [64, 64, 93]);
    assert_eq!(v.spacing, [3.2, 3.2, 1.5]);
    assert_eq!(v.origin, [0.0; 3]);
    let VolumeData::I16(d) = &v.data else {
        panic!("expected i16, got {:?}", v.data.scalar_type())
    };
    assert_eq!(*d.iter().min().unwrap(), 0);
    assert_eq!(*d.iter().max().unwrap(), 3926);
    assert_eq!(d.iter().filter(|&&x| x == 0).count(), 58_590);
    assert!((mean(&v) - 507.69).abs() < 0.01, "{}", mean(&v));
}

#[test]
fn frogtissue_inflates_past_wrong_compressed_size() {
    let Some(v) = common::real_volume("froggy/frogtissue.mhd") else {
        return;
    };
    assert_eq!(v.dims, [500, 470, 136]);
    assert_eq!(v.spacing, [1.0, 1.0, 1.5]);
    let h = histogram_u8(&v);
    let expected = common::FROG_LABELS.map(|(l, c)| (l as usize, c as usize));
    for (label, count) in expected {
        assert_eq!(h[label], count, "label {label}");
    }
    assert_eq!(h.iter().filter(|&&c| c > 0).count(), 26);
}

#[test]
fn foot_mha_2d_with_separate_data() {
    let Some(v) = common::real_volume("foot/foot.mha") else {
        return;
    };
    assert_eq!(v.dims, [256, 256, 1]);
    assert_eq!(v.spacing, [1.0, 1.0, 1.0]);
    let h = histogram_u8(&v);
    assert_eq!(v.len() - h[0], 65_153);
    assert_eq!(h.iter().filter(|&&c| c > 0).count(), 165);
}

#[test]
fn head_mr_volume_three_digit_exponents() {
    let Some(v) = common::real_volume("HeadMRVolume.mhd") else {
        return;
    };
    assert_eq!(v.dims, [48, 62, 42]);
    assert_eq!(v.spacing, [4.0; 3]);
    assert!((mean(&v) - 24.468).abs() < 0.001, "{}", mean(&v));
    let h = histogram_u8(&v);
    assert_eq!(v.len() - h[0], 123_631);
    assert_eq!(h[254], 0);
}

const WRITE_NAMES: [&str; 6] = ["v.nrrd", "v.nhdr", "v.mha", "v.mhd", "v.nii", "v.nii.gz"];

/// A 5×4×3 volume of every element type with values that need all bytes
/// (so a byte-order mistake shows), f32-exact spacing and origin.
fn sample_volumes() -> Vec<Volume> {
    let dims = [5, 4, 3];
    let n: usize = 60;
    let data = [
        VolumeData::U8((0..n).map(|i| (i * 37 % 256) as u8).collect()),
        VolumeData::I8((0..n).map(|i| (i as i8).wrapping_mul(-7)).collect()),
        VolumeData::U16((0..n).map(|i| (i as u16).wrapping_mul(4099)).collect()),
        VolumeData::I16((0..n).map(|i| (i as i16 - 30).wrapping_mul(1031)).collect()),
        VolumeData::U32(
            (0..n)
                .map(|i| (i as u32).wrapping_mul(0x0101_0307))
                .collect(),
        ),
        VolumeData::I32(
            (0..n)
                .map(|i| (i as i32 - 30).wrapping_mul(0x0102_0305))
                .collect(),
        ),
        VolumeData::F32((0..n).map(|i| i as f32 * -0.3 + 1e-20).collect()),
        VolumeData::F64((0..n).map(|i| (i as f64).sqrt() * 1e200).collect()),
    ];
    data.into_iter()
        .map(|d| Volume::new(dims, [0.5, 1.25, 3.0], [-10.5, 3.25, 0.0], d).unwrap())
        .collect()
}

#[test]
fn every_volume_writer_round_trips_every_type() {
    let dir = tempfile::tempdir().unwrap();
    for v in sample_volumes() {
        for name in WRITE_NAMES {
            let path = dir.path().join(name);
            write_volume(&path, &v).unwrap_or_else(|e| panic!("{name}: {e}"));
            let back = read_volume(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
            // A volume without an anatomical frame comes back from NIfTI in
            // RAS (the format has no other world), at the same coordinates.
            let back = Volume {
                space: v.space,
                ..back
            };
            assert_eq!(back, v, "{name} {:?}", v.data.scalar_type());
        }
    }
}

#[test]
fn real_volumes_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    for rel in ["headsq/quarter.nhdr", "HeadMRVolume.mhd", "foot/foot.mha"] {
        let Some(v) = common::real_volume(rel) else {
            return;
        };
        for name in WRITE_NAMES {
            let path = dir.path().join(name);
            write_volume(&path, &v).unwrap_or_else(|e| panic!("{rel} → {name}: {e}"));
            let back = read_volume(&path).unwrap();
            assert_eq!(back.dims, v.dims, "{rel} → {name}");
            assert!(back.data == v.data, "{rel} → {name}: samples differ");
            // The same place: in one anatomical frame (NIfTI writes RAS), or,
            // for a volume that names none, the same coordinates.
            let place = |x: &Volume| match v.space {
                Some(_) => x.frame_in(Space::Lps),
                None => (x.origin, x.axes),
            };
            assert_eq!(place(&back), place(&v), "{rel} → {name}");
            // NIfTI stores pixdim as f32 (3.2 → 3.2000000477): documented.
            let tol = if name.starts_with("v.nii") { 1e-6 } else { 0.0 };
            for (a, b) in back.spacing.iter().zip(v.spacing) {
                assert!(
                    (a - b).abs() <= tol * b,
                    "{rel} → {name}: spacing {a} vs {b}"
                );
            }
        }
    }
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn i16_ramp() -> Vec<i16> {
    (0..24).map(|i| (i - 12) * 1001).collect()
}

fn i16_be(v: &[i16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_be_bytes()).collect()
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

#[test]
fn nrrd_big_endian_gzip_attached_with_directions() {
    let dir = tempfile::tempdir().unwrap();
    let mut f = b"NRRD0005\n# c\ntype: short\ndimension: 3\nspace: left-posterior-superior\n\
sizes: 4 3 2\nspace directions: (0.5,0,0) (0,0.75,0) (0,0,2)\nspace origin: (1,-2,3.5)\n\
endian: big\nencoding: gzip\nkey:=value\n\n"
        .to_vec();
    f.extend(gzip(&i16_be(&i16_ramp())));
    let v = read_volume(&write(dir.path(), "be.nrrd", &f)).unwrap();
    assert_eq!(v.dims, [4, 3, 2]);
    assert_eq!(v.spacing, [0.5, 0.75, 2.0]);
    assert_eq!(v.origin, [1.0, -2.0, 3.5]);
    assert_eq!(v.data, VolumeData::I16(i16_ramp()));
}

#[test]
fn nrrd_detached_pattern_with_subdim_list_and_skips() {
    let dir = tempfile::tempdir().unwrap();
    let ramp = i16_ramp();
    // Two files of 12 samples each (subdim 2 of sizes 4 3 2), zero-padded names.
    for (k, chunk) in ramp.chunks(12).enumerate() {
        let mut bytes = b"junk line\n".to_vec();
        bytes.extend([0xAA; 3]);
        bytes.extend(i16_be(chunk));
        write(dir.path(), &format!("s{:03}.raw", 2 * k + 2), &bytes);
    }
    let hdr = b"NRRD0004\ntype: int16\ndimension: 3\nsizes: 4 3 2\nspacings: 1 2 nan\n\
endian: big\nencoding: raw\nline skip: 1\nbyte skip: 3\ndata file: s%03d.raw 2 4 2 2\n";
    let v = read_volume(&write(dir.path(), "p.nhdr", hdr)).unwrap();
    assert_eq!(v.spacing, [1.0, 2.0, 1.0]);
    assert_eq!(v.data, VolumeData::I16(ramp.clone()));
    // The same through LIST, and with byte skip -1 (data at the end).
    let hdr = b"NRRD0004\ntype: int16\ndimension: 3\nsizes: 4 3 2\nendian: big\n\
encoding: raw\nbyte skip: -1\ndata file: LIST\ns002.raw\ns004.raw\n";
    let v = read_volume(&write(dir.path(), "l.nhdr", hdr)).unwrap();
    assert_eq!(v.data, VolumeData::I16(ramp));
}

#[test]
fn nrrd_flipped_and_permuted_directions_are_kept_sheared_ones_refused() {
    let dir = tempfile::tempdir().unwrap();
    let read = |dirs: &str| {
        let hdr = format!(
            "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 1 1\nspace directions: {dirs}\nencoding: raw\n\nx"
        );
        read_volume(&write(dir.path(), "o.nrrd", hdr.as_bytes()))
    };
    let v = read("(-2,0,0) (0,1,0) (0,0,1)").unwrap();
    assert_eq!((v.spacing, v.axes[0]), ([2.0, 1.0, 1.0], [-1.0, 0.0, 0.0]));
    assert!(v.reflects());
    let v = read("(0,1,0) (1,0,0) (0,0,1)").unwrap();
    assert_eq!(v.axes[0], [0.0, 1.0, 0.0]);
    assert!(v.reflects());
    let e = read("(0.7,0.7,0) (0,1,0) (0,0,1)").unwrap_err();
    assert!(matches!(e, Error::Unsupported { .. }), "{e}");
    assert!(
        e.to_string().contains("o.nrrd") && e.to_string().contains("line 5"),
        "{e}"
    );
}

#[test]
fn metaimage_msb_local_and_zlib() {
    use std::io::Write;
    let dir = tempfile::tempdir().unwrap();
    let ramp = i16_ramp();
    let mut f = b"ObjectType = Image\nNDims = 3\nDimSize = 4 3 2\nElementType = MET_SHORT\n\
ElementSpacing = 2 2 2 9\nOrigin = 1 2 3\nBinaryDataByteOrderMSB = True\nElementDataFile = LOCAL\n"
        .to_vec();
    f.extend(i16_be(&ramp));
    let v = read_volume(&write(dir.path(), "msb.mha", &f)).unwrap();
    assert_eq!(
        (v.dims, v.spacing, v.origin),
        ([4, 3, 2], [2.0; 3], [1.0, 2.0, 3.0])
    );
    assert_eq!(v.data, VolumeData::I16(ramp.clone()));
    // zlib with a deliberately wrong CompressedDataSize hint.
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    z.write_all(&i16_be(&ramp)).unwrap();
    let z = z.finish().unwrap();
    write(dir.path(), "z.zraw", &z);
    let hdr = format!(
        "NDims = 3\nDimSize = 4 3 2\nElementType = MET_SHORT\nElementByteOrderMSB = True\n\
CompressedData = True\nCompressedDataSize = {}\nElementDataFile = z.zraw\n",
        z.len() / 2
    );
    let v = read_volume(&write(dir.path(), "z.mhd", hdr.as_bytes())).unwrap();
    assert_eq!(v.data, VolumeData::I16(ramp));
}

/// A big-endian NIfTI-1 header built by hand (not by chisel's writer).
fn nifti_be(
    dims: [i16; 3],
    datatype: i16,
    bitpix: i16,
    pixdim: [f32; 3],
    slope: f32,
    inter: f32,
) -> Vec<u8> {
    let mut b = vec![0u8; 352];
    let mut put = |at: usize, bytes: &[u8]| b[at..at + bytes.len()].copy_from_slice(bytes);
    put(0, &348i32.to_be_bytes());
    for (i, d) in [3, dims[0], dims[1], dims[2], 1, 1, 1, 1]
        .iter()
        .enumerate()
    {
        put(40 + 2 * i, &d.to_be_bytes());
    }
    put(70, &datatype.to_be_bytes());
    put(72, &bitpix.to_be_bytes());
    for (i, p) in [1.0, pixdim[0], pixdim[1], pixdim[2]].iter().enumerate() {
        put(76 + 4 * i, &p.to_be_bytes());
    }
    put(108, &352f32.to_be_bytes());
    put(112, &slope.to_be_bytes());
    put(116, &inter.to_be_bytes());
    put(254, &1i16.to_be_bytes());
    for (r, row) in [[0.5f32, 0., 0., 7.], [0., 0.5, 0., -8.], [0., 0., 2., 9.]]
        .iter()
        .enumerate()
    {
        for (c, x) in row.iter().enumerate() {
            put(280 + 16 * r + 4 * c, &x.to_be_bytes());
        }
    }
    put(344, b"n+1\0");
    b
}

#[test]
fn nifti_big_endian_with_sform_origin_and_scaling() {
    let dir = tempfile::tempdir().unwrap();
    let ramp = i16_ramp();
    let mut f = nifti_be([4, 3, 2], 4, 16, [0.5, 0.5, 2.0], 0.0, 0.0);
    f.extend(i16_be(&ramp));
    let v = read_volume(&write(dir.path(), "be.nii", &f)).unwrap();
    assert_eq!(
        (v.dims, v.spacing, v.origin),
        ([4, 3, 2], [0.5, 0.5, 2.0], [7.0, -8.0, 9.0])
    );
    assert_eq!(v.data, VolumeData::I16(ramp.clone()));
    let v = read_volume(&write(dir.path(), "be.nii.gz", &gzip(&f))).unwrap();
    assert_eq!(v.data, VolumeData::I16(ramp.clone()));
    // scl_slope 0.5, scl_inter 10 → f32 samples.
    let mut f = nifti_be([4, 3, 2], 4, 16, [0.5, 0.5, 2.0], 0.5, 10.0);
    f.extend(i16_be(&ramp));
    let v = read_volume(&write(dir.path(), "s.nii", &f)).unwrap();
    let expected: Vec<f32> = ramp.iter().map(|&x| f32::from(x) * 0.5 + 10.0).collect();
    assert_eq!(v.data, VolumeData::F32(expected));
}

#[test]
fn raw_volume_with_header_bytes_big_endian() {
    let dir = tempfile::tempdir().unwrap();
    let ramp = i16_ramp();
    let mut f = vec![7u8; 10];
    f.extend(i16_be(&ramp));
    let path = write(dir.path(), "r.bin", &f);
    let spec = RawSpec {
        dims: [4, 3, 2],
        scalar_type: ScalarType::I16,
        big_endian: true,
        spacing: [1.0, 2.0, 3.0],
        origin: [0.0, 0.0, -5.0],
        header_bytes: 10,
    };
    let v = read_raw_volume(&path, &spec).unwrap();
    assert_eq!((v.spacing, v.origin), (spec.spacing, spec.origin));
    assert_eq!(v.data, VolumeData::I16(ramp));
    let long = RawSpec {
        header_bytes: 12,
        ..spec
    };
    let e = read_raw_volume(&path, &long).unwrap_err();
    assert!(matches!(e, Error::Size { .. }), "{e}");
}

/// An oblique frame: a rotation about (1, 2, 3) by 0.7 rad, its third axis
/// negated when `reflect`.
fn oblique_axes(reflect: bool) -> [[f64; 3]; 3] {
    let n = glam::DVec3::new(1.0, 2.0, 3.0).normalize();
    let q = glam::DQuat::from_axis_angle(n, 0.7);
    let mut axes = [glam::DVec3::X, glam::DVec3::Y, glam::DVec3::Z].map(|e| (q * e).to_array());
    if reflect {
        axes[2] = axes[2].map(|c| -c);
    }
    axes
}

/// World positions of every sample of `v` in anatomical frame `to`.
fn worlds(v: &Volume, to: Space) -> Vec<[f64; 3]> {
    let (origin, axes) = v.frame_in(to);
    let moved = Volume {
        origin,
        axes,
        space: Some(to),
        ..v.clone()
    };
    let [nx, ny, nz] = v.dims;
    (0..nx * ny * nz)
        .map(|i| {
            moved.world([
                (i % nx) as f64,
                ((i / nx) % ny) as f64,
                (i / (nx * ny)) as f64,
            ])
        })
        .collect()
}

#[test]
fn orientation_round_trips_through_every_writer() {
    let dir = tempfile::tempdir().unwrap();
    for reflect in [false, true] {
        let v = Volume::new(
            [3, 4, 2],
            [0.5, 1.25, 3.0],
            [-10.5, 3.25, 7.0],
            VolumeData::I16(i16_ramp()),
        )
        .unwrap()
        .with_frame(oblique_axes(reflect), Some(Space::Lps))
        .unwrap();
        let want = worlds(&v, Space::Lps);
        for name in WRITE_NAMES {
            let path = dir.path().join(name);
            write_volume(&path, &v).unwrap();
            let back = read_volume(&path).unwrap();
            assert_eq!(back.data, v.data);
            // NRRD and MetaImage write decimal text that reads back exactly;
            // NIfTI stores f32 (and says RAS).
            let nifti = name.starts_with("v.nii");
            assert_eq!(
                back.space,
                Some(if nifti { Space::Ras } else { Space::Lps })
            );
            let got = worlds(&back, Space::Lps);
            let worst = want
                .iter()
                .zip(&got)
                .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
                .fold(0.0f64, f64::max);
            let tol = if nifti { 2e-5 } else { 0.0 };
            assert!(
                worst <= tol,
                "{name} reflect {reflect}: worlds differ by {worst}"
            );
            assert_eq!(back.reflects(), reflect, "{name}");
        }
    }
}

#[test]
fn lps_nrrd_through_ras_nifti_keeps_every_voxel_in_place() {
    let dir = tempfile::tempdir().unwrap();
    let nrrd = write(
        dir.path(),
        "a.nrrd",
        &[
            b"NRRD0004\ntype: short\ndimension: 3\nspace: left-posterior-superior\nsizes: 3 4 2\n\
              space directions: (0,-0.5,0) (1.25,0,0) (0,0,3)\nspace origin: (10,-20,5)\n\
              endian: big\nencoding: raw\n\n"
                .as_slice(),
            &i16_be(&i16_ramp()),
        ]
        .concat(),
    );
    let v = read_volume(&nrrd).unwrap();
    assert_eq!(v.space, Some(Space::Lps));
    assert_eq!(v.spacing, [0.5, 1.25, 3.0]);
    assert_eq!(v.axes, [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
    // Sample (1, 0, 0) lies 0.5 towards anterior (−y in LPS) of the origin.
    assert_eq!(v.world([1.0, 0.0, 0.0]), [10.0, -20.5, 5.0]);
    let nii = dir.path().join("b.nii");
    write_volume(&nii, &v).unwrap();
    let r = read_volume(&nii).unwrap();
    // In RAS the same point has x and y negated.
    assert_eq!(r.space, Some(Space::Ras));
    assert_eq!(r.world([1.0, 0.0, 0.0]), [-10.0, 20.5, 5.0]);
    let again = dir.path().join("c.nrrd");
    write_volume(&again, &r).unwrap();
    let back = read_volume(&again).unwrap();
    assert_eq!(worlds(&back, Space::Lps), worlds(&v, Space::Lps));
    assert_eq!(back.data, v.data);
    // LAS is read as RAS with x negated: the same world points.
    let las = write(
        dir.path(),
        "l.nrrd",
        b"NRRD0004\ntype: uchar\ndimension: 3\nspace: LAS\nsizes: 1 1 2\n\
          space directions: (1,0,0) (0,1,0) (0,0,2)\nspace origin: (3,4,5)\nencoding: raw\n\n\x01\x02",
    );
    let l = read_volume(&las).unwrap();
    assert_eq!(l.space, Some(Space::Ras));
    assert_eq!(l.world([0.0, 0.0, 1.0]), [-3.0, 4.0, 7.0]);
    // Sheared directions are refused, naming the field.
    let sheared = write(
        dir.path(),
        "s.nrrd",
        b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 1 1\n\
          space directions: (1,0,0) (1,1,0) (0,0,1)\nencoding: raw\n\n\x01",
    );
    let e = read_volume(&sheared).unwrap_err().to_string();
    assert!(
        e.contains("space directions") && e.contains("right angles"),
        "{e}"
    );
}
