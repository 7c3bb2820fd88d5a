//! DICOM series and files against series with known content written by
//! pydicom (`scripts/make_dicom_references.py`, a writer independent of
//! the dicom-rs crates chisel reads with; `tests/data/dicom/expected.json`
//! holds what each one holds).

use std::path::{Path, PathBuf};

use chisel::Error;
use chisel::io::{ReadOptions, dicom_series, read_volume, read_volume_with, write_volume};
use chisel::volume::{ScalarType, Space, Volume};

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dicom")
}

fn expected(name: &str) -> serde_json::Value {
    let text = std::fs::read_to_string(dir().join("expected.json")).unwrap();
    let all: serde_json::Value = serde_json::from_str(&text).unwrap();
    all[name].clone()
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .flat_map(|x| match x.as_array() {
            Some(row) => row.iter().map(|y| y.as_f64().unwrap()).collect(),
            None => vec![x.as_f64().unwrap()],
        })
        .collect()
}

fn close(found: &[f64], want: &[f64], tol: f64, what: &str) {
    assert_eq!(found.len(), want.len(), "{what}");
    for (f, w) in found.iter().zip(want) {
        assert!((f - w).abs() <= tol, "{what}: {found:?} vs {want:?}");
    }
}

/// The volume agrees with expected.json: integer figures exactly, the
/// geometry to the decimal strings' precision.
fn check(name: &str, v: &Volume) {
    let e = expected(name);
    let dims: Vec<usize> = floats(&e["dims"]).iter().map(|&d| d as usize).collect();
    assert_eq!(v.dims.to_vec(), dims, "{name}: dims");
    close(
        &v.spacing,
        &floats(&e["spacing"]),
        1e-9,
        &format!("{name}: spacing"),
    );
    close(
        &v.origin,
        &floats(&e["origin"]),
        1e-9,
        &format!("{name}: origin"),
    );
    // Image Orientation (Patient) travels as decimal strings of 16 characters.
    let axes: Vec<f64> = v.axes.iter().flatten().copied().collect();
    close(&axes, &floats(&e["axes"]), 1e-12, &format!("{name}: axes"));
    assert_eq!(v.space, Some(Space::Lps));
    assert_eq!(
        v.data.scalar_type().name(),
        e["scalar_type"].as_str().unwrap(),
        "{name}: scalar type"
    );
    let values: Vec<f64> = (0..v.len()).map(|i| v.data.get_f64(i)).collect();
    let min = values.iter().copied().fold(f64::INFINITY, f64::min);
    let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(min, e["min"].as_f64().unwrap(), "{name}: min");
    assert_eq!(max, e["max"].as_f64().unwrap(), "{name}: max");
    assert_eq!(
        values.iter().sum::<f64>(),
        e["sum"].as_f64().unwrap(),
        "{name}: sum"
    );
    assert_eq!(*values.last().unwrap(), e["last"].as_f64().unwrap());
    // Sample (i, j, k) holds 3i + 20j + 200k + 7 stored: slice order along
    // the normal, not the files' order.
    for k in 0..v.dims[2] {
        for j in 0..v.dims[1] {
            for i in 0..v.dims[0] {
                let at = i + v.dims[0] * (j + v.dims[1] * k);
                let stored = (3 * i + 20 * j + 200 * k + 7) as f64;
                let slope_intercept = if name == "ct_fractional_rescale" {
                    (0.5, -10.25)
                } else {
                    (1.0, -1024.0)
                };
                assert_eq!(
                    values[at],
                    stored * slope_intercept.0 + slope_intercept.1,
                    "{name}: sample ({i}, {j}, {k})"
                );
            }
        }
    }
}

#[test]
fn series_in_every_written_form_agree_with_their_content() {
    for name in [
        "ct_explicit",
        "ct_implicit",
        "ct_rle",
        "ct_no_meta",
        "ct_fractional_rescale",
    ] {
        let v = read_volume(&dir().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        check(name, &v);
    }
}

#[test]
fn fractional_rescale_is_kept_as_f32() {
    let v = read_volume(&dir().join("ct_fractional_rescale")).unwrap();
    assert_eq!(v.data.scalar_type(), ScalarType::F32);
}

#[test]
fn enhanced_multiframe_frames_are_ordered_along_the_normal() {
    let v = read_volume(&dir().join("multiframe.dcm")).unwrap();
    check("multiframe.dcm", &v);
}

/// Negative control: the files' names are not the slice order, so a
/// reader that sorted by name (or took the first file's position as the
/// origin) would fail `check`.
#[test]
fn file_names_are_not_the_slice_order() {
    let series = dir().join("ct_explicit");
    let first_by_name = read_volume(&series.join("IM0000")).unwrap();
    let whole = read_volume(&series).unwrap();
    assert_eq!(first_by_name.dims, [6, 5, 1]);
    assert_ne!(first_by_name.origin, whole.origin);
    // One slice keeps its own position, orientation and Slice Thickness.
    assert_eq!(first_by_name.axes, whole.axes);
    assert_eq!(first_by_name.spacing, whole.spacing);
}

#[test]
fn content_not_the_extension_says_dicom() {
    let tmp = tempfile::tempdir().unwrap();
    let fake = tmp.path().join("slice.nrrd");
    std::fs::copy(dir().join("ct_explicit/IM0001"), &fake).unwrap();
    let v = read_volume(&fake).unwrap();
    assert_eq!(v.dims, [6, 5, 1]);
    assert!(chisel::io::is_volume(&dir().join("ct_explicit/IM0001")).unwrap());
}

#[test]
fn gantry_tilt_and_gaps_are_refused_with_the_reason() {
    let tilt = read_volume(&dir().join("ct_tilt")).unwrap_err();
    assert!(matches!(tilt, Error::Unsupported { .. }), "{tilt}");
    assert!(tilt.to_string().contains("gantry tilt"), "{tilt}");
    let gap = read_volume(&dir().join("ct_gap")).unwrap_err();
    assert!(
        gap.to_string().contains("non-uniform DICOM slice spacing"),
        "{gap}"
    );
    assert!(gap.to_string().contains("5.0000 mm"), "{gap}");
}

#[test]
fn several_series_are_listed_and_one_is_chosen_by_uid() {
    let d = dir().join("two_series");
    let uids: Vec<String> = expected("two_series")["uids"]
        .as_array()
        .unwrap()
        .iter()
        .map(|u| u.as_str().unwrap().to_string())
        .collect();
    let listed = dicom_series(&d).unwrap();
    assert_eq!(
        listed.iter().map(|s| s.uid.clone()).collect::<Vec<_>>(),
        uids
    );
    assert!(
        listed
            .iter()
            .all(|s| s.files == 2 && s.rows == 5 && s.columns == 6)
    );
    assert_eq!(listed[1].description.as_deref(), Some("series b"));
    let err = read_volume(&d).unwrap_err().to_string();
    assert!(err.contains(&uids[0]) && err.contains(&uids[1]), "{err}");
    assert!(err.contains("--series"), "{err}");
    let options = ReadOptions {
        series: Some(uids[1].clone()),
    };
    let (v, _) = read_volume_with(&d, &options).unwrap();
    assert_eq!(v.dims, [6, 5, 2]);
    let missing = ReadOptions {
        series: Some("1.2.3".into()),
    };
    let err = read_volume_with(&d, &missing).unwrap_err().to_string();
    assert!(err.contains("1.2.3") && err.contains(&uids[0]), "{err}");
}

#[test]
fn other_files_in_the_directory_are_passed_over() {
    let tmp = tempfile::tempdir().unwrap();
    for entry in std::fs::read_dir(dir().join("ct_explicit")).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), tmp.path().join(entry.file_name())).unwrap();
    }
    std::fs::write(tmp.path().join("README.txt"), "exported by a viewer\n").unwrap();
    std::fs::write(tmp.path().join("short"), b"DI").unwrap();
    check("ct_explicit", &read_volume(tmp.path()).unwrap());
}

#[test]
fn a_damaged_file_is_an_error_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    for entry in std::fs::read_dir(dir().join("ct_explicit")).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), tmp.path().join(entry.file_name())).unwrap();
    }
    let victim = tmp.path().join("IM0002");
    let bytes = std::fs::read(&victim).unwrap();
    // Cut inside the pixel data.
    std::fs::write(&victim, &bytes[..bytes.len() - 20]).unwrap();
    let err = read_volume(tmp.path()).unwrap_err().to_string();
    assert!(err.contains("IM0002"), "{err}");
    // An empty directory.
    let empty = tempfile::tempdir().unwrap();
    let err = read_volume(empty.path()).unwrap_err().to_string();
    assert!(err.contains("DICOM image files"), "{err}");
}

/// DICOM (LPS) → NIfTI (RAS) → NRRD: every voxel at the same world
/// position, the samples unchanged.
#[test]
fn orientation_survives_other_formats() {
    let v = read_volume(&dir().join("ct_explicit")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let nii = tmp.path().join("ct.nii.gz");
    write_volume(&nii, &v).unwrap();
    let nrrd = tmp.path().join("ct.nrrd");
    write_volume(&nrrd, &read_volume(&nii).unwrap()).unwrap();
    let back = read_volume(&nrrd).unwrap();
    assert_eq!(back.data, v.data);
    for index in [[0.0, 0.0, 0.0], [5.0, 4.0, 3.0], [2.0, 1.0, 3.0]] {
        let (a, b) = (v.world(index), back.world(index));
        let b = match back.space {
            Some(s) => {
                let signs = s.signs_to(Space::Lps);
                [b[0] * signs[0], b[1] * signs[1], b[2] * signs[2]]
            }
            None => b,
        };
        close(&a, &b, 1e-5, "world position");
    }
}

/// Transfer syntaxes this build does not decode are refused by name.
#[test]
fn undecodable_transfer_syntaxes_are_named() {
    let j2k = read_volume(&dir().join("jpeg2000.dcm")).unwrap_err();
    assert!(matches!(j2k, Error::Unsupported { .. }), "{j2k}");
    assert!(j2k.to_string().contains("1.2.840.10008.1.2.4.90"), "{j2k}");
    let deflated = read_volume(&dir().join("deflated.dcm")).unwrap_err();
    assert!(matches!(deflated, Error::Unsupported { .. }), "{deflated}");
    assert!(
        deflated.to_string().contains("1.2.840.10008.1.2.1.99"),
        "{deflated}"
    );
    assert!(deflated.to_string().contains("deflated"), "{deflated}");
}
