//! `chisel scan`, the large-volume hull scan (SPEC §4.3, seed 003 §4.2):
//! one row per structure of a volume holding several of the seed's objects
//! (figures of Tables 4.2 and 8.6), CPU and GPU reports identical but for
//! timings and adapter, the CT head bone and the frog tissue labels against
//! the data README, and clear errors on bad input.

use std::path::Path;

use chisel::Volume;
use chisel::phantom::voxel;
use chisel::volume::VolumeData;
use serde_json::Value;

use crate::common;
use crate::support::{chisel, path_str};

fn scan_json(args: &[&str]) -> Value {
    let mut all = vec!["scan"];
    all.extend_from_slice(args);
    all.push("--json");
    let out = chisel(&all);
    assert!(
        out.status.success(),
        "chisel {all:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("chisel {all:?}: {e}"))
}

/// Copies the object voxels (non-zero) of `src` into `dst` (dims `dims`)
/// at `offset`, with value `value`.
fn place(dst: &mut [u8], dims: [usize; 3], src: &Volume, offset: [usize; 3], value: u8) {
    let [sx, sy, sz] = src.dims;
    for z in 0..sz {
        for y in 0..sy {
            for x in 0..sx {
                if src.data.get_f64(x + sx * (y + sy * z)) != 0.0 {
                    let (gx, gy, gz) = (x + offset[0], y + offset[1], z + offset[2]);
                    dst[gx + dims[0] * (gy + dims[1] * gz)] = value;
                }
            }
        }
    }
}

/// Five structures side by side along x, apart: label 1 the r = 24 ball
/// (7,208 voxels, 290 hull faces, digitally convex), label 2 the 25/10
/// cylinder of height 15 (6,060 voxels, 2,848 facets, one tunnel of 1,200
/// voxels), label 3 a 6³ cube, label 4 one voxel, label 5 two 4³ cubes two
/// voxels apart (two components; their gap of 32 voxels is the label's
/// one ZKH).
fn seed_objects(dir: &Path) -> std::path::PathBuf {
    let dims = [96, 28, 28];
    let mut data = vec![0u8; dims.iter().product()];
    place(
        &mut data,
        dims,
        &voxel::digital_ball(24).unwrap(),
        [0; 3],
        1,
    );
    place(
        &mut data,
        dims,
        &voxel::cylinder_tunnel(25, 10, 15).unwrap(),
        [28, 0, 0],
        2,
    );
    place(&mut data, dims, &voxel::cube(6).unwrap(), [56, 0, 0], 3);
    data[66 + dims[0] * (3 + dims[1] * 3)] = 4;
    let small = voxel::cube(4).unwrap();
    place(&mut data, dims, &small, [70, 0, 0], 5);
    place(&mut data, dims, &small, [76, 0, 0], 5);
    let v = Volume::new(dims, [1.0; 3], [0.0; 3], VolumeData::U8(data)).unwrap();
    let path = dir.join("seed_objects.nrrd");
    chisel::io::write_volume(&path, &v).unwrap();
    path
}

fn rows(v: &Value) -> &Vec<Value> {
    v["rows"].as_array().expect("rows")
}

/// The row of the structure with `voxels` voxels (exactly one).
fn row_of(v: &Value, voxels: u64) -> &Value {
    let found: Vec<&Value> = rows(v)
        .iter()
        .filter(|r| r["object"]["voxels"] == voxels)
        .collect();
    assert_eq!(found.len(), 1, "rows of {voxels} voxels");
    found[0]
}

/// Every scanned, non-degenerate row: the closed hull holds the object
/// and its ZKHs and nothing else; the scan covers the hull's box.
fn check_row_invariants(v: &Value) {
    for r in rows(v) {
        if r["degenerate"] == "collinear" {
            assert!(r["hull"].is_null() && r["scan"].is_null(), "{r}");
            continue;
        }
        let s = &r["scan"];
        let n_box: u64 = s["box"]["dims"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.as_u64().unwrap())
            .product();
        let (inside, on, outside) = (
            s["inside"].as_u64().unwrap(),
            s["on"].as_u64().unwrap(),
            s["outside"].as_u64().unwrap(),
        );
        assert_eq!(inside + on + outside, n_box, "{r}");
        assert_eq!(r["convexity"]["hull_voxels"], inside + on, "{r}");
        if !r["hull"]["planar"].as_bool().unwrap() {
            let zkh = r["zkh"]["voxels"].as_u64().unwrap();
            let voxels = r["object"]["voxels"].as_u64().unwrap();
            assert_eq!(voxels + zkh, inside + on, "{r}");
        }
    }
}

/// The report without what may differ between backends and runs.
fn comparable(mut v: Value) -> Value {
    let m = v.as_object_mut().unwrap();
    for k in ["timings_s", "backend", "adapter", "arithmetic"] {
        assert!(m.remove(k).is_some(), "report lacks {k}");
    }
    v
}

#[test]
fn seed_objects_get_one_row_each() {
    let tmp = tempfile::tempdir().unwrap();
    let vol = seed_objects(tmp.path());
    let v = scan_json(&[path_str(&vol), "--level", "1"]);
    assert_eq!(v["structures"], 6);
    assert_eq!(v["scanned"], 6);
    assert_eq!(v["degenerate"], 1);
    check_row_invariants(&v);

    let ball = row_of(&v, 7208);
    assert_eq!(ball["hull"]["faces"], 290);
    assert_eq!(ball["zkh"]["count"], 0, "a ball is digitally convex");
    assert_eq!(ball["convexity"]["digital"], 1.0);

    let cyl = row_of(&v, 6060);
    assert_eq!(cyl["object"]["boundary_facets"], 2848);
    let z = &cyl["zkh"];
    assert_eq!(z["count"], 1);
    assert_eq!(z["tunnels"]["count"], 1);
    assert_eq!(z["tunnels"]["voxels"], 1200);
    assert_eq!(z["largest"], 1200);
    assert_eq!(cyl["convexity"]["hull_voxels"], 6060 + 1200);

    // A 6³ cube: 6 square faces on its outer voxel centres, 4³ voxels
    // strictly inside, the rest of its box on the hull.
    let cube = row_of(&v, 216);
    assert_eq!(cube["hull"]["faces"], 6);
    assert_eq!(cube["hull"]["vertices"], 8);
    assert_eq!(cube["hull"]["integers_eq_8_2"], 3 * 8 + 5 * 6);
    assert_eq!(cube["hull"]["volume_voxels"], 125.0);
    assert_eq!(cube["scan"]["inside"], 64);
    assert_eq!(cube["scan"]["on"], 216 - 64);
    assert_eq!(cube["scan"]["outside"], 0);
    assert_eq!(cube["zkh"]["count"], 0);

    let single = row_of(&v, 1);
    assert_eq!(single["degenerate"], "collinear");
    // The two small cubes are separate components here.
    let small: Vec<&Value> = rows(&v)
        .iter()
        .filter(|r| r["object"]["voxels"] == 64)
        .collect();
    assert_eq!(small.len(), 2);
    assert!(small.iter().all(|r| r["zkh"]["count"] == 0));
    // Totals over the rows.
    assert_eq!(v["zkh"]["count"], 1);
    assert_eq!(v["zkh"]["tunnels"]["voxels"], 1200);

    // --min-voxels skips and counts.
    let v = scan_json(&[path_str(&vol), "--level", "1", "--min-voxels", "100"]);
    assert_eq!(v["structures"], 6);
    assert_eq!(v["scanned"], 3);
    assert_eq!(v["skipped"]["count"], 3);
    assert_eq!(v["skipped"]["voxels"], 1 + 64 + 64);
}

#[test]
fn labels_give_one_row_per_value() {
    let tmp = tempfile::tempdir().unwrap();
    let vol = seed_objects(tmp.path());
    let report = tmp.path().join("scan.json");
    let v = scan_json(&[path_str(&vol), "--labels", "--report", path_str(&report)]);
    let written: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(comparable(written), comparable(v.clone()));
    check_row_invariants(&v);
    let labels: Vec<f64> = rows(&v)
        .iter()
        .map(|r| r["label"].as_f64().unwrap())
        .collect();
    assert_eq!(labels, [1.0, 2.0, 3.0, 4.0, 5.0]);
    let by_label = |l: usize| &rows(&v)[l - 1];
    assert_eq!(by_label(1)["hull"]["faces"], 290);
    assert_eq!(by_label(2)["zkh"]["tunnels"]["voxels"], 1200);
    assert_eq!(by_label(4)["degenerate"], "collinear");
    // Label 5 is both cubes: two components, one hull (the 10 × 4 × 4 box
    // of their centres), and the gap between them is its ZKH.
    let pair = by_label(5);
    assert_eq!(pair["object"]["voxels"], 128);
    assert_eq!(pair["components"], 2);
    assert_eq!(pair["hull"]["faces"], 6);
    assert_eq!(pair["zkh"]["count"], 1);
    assert_eq!(pair["zkh"]["voxels"], 2 * 4 * 4);
    assert!(rows(&v)[..4].iter().all(|r| r["components"] == 1));

    // Without --json nothing on stdout (the summary goes to stderr).
    let out = chisel(&["scan", path_str(&vol), "--labels"]);
    assert!(out.status.success());
    assert!(
        out.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
}

#[test]
fn cpu_and_gpu_reports_agree() {
    let Some(_gpu) = common::gpu() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let vol = seed_objects(tmp.path());
    for selection in [&["--level", "1"][..], &["--labels"][..]] {
        let mut args = vec![path_str(&vol)];
        args.extend_from_slice(selection);
        let cpu = scan_json(&args);
        args.extend_from_slice(&["--backend", "gpu"]);
        let gpu = scan_json(&args);
        assert_eq!(gpu["backend"], "gpu");
        assert!(gpu["adapter"].is_string() && gpu["arithmetic"].is_string());
        assert_eq!(comparable(cpu), comparable(gpu), "{selection:?}");
    }
    // The CT head bone, small enough for lavapipe.
    let Some(head) = common::data("headsq/quarter.nhdr") else {
        return;
    };
    let args = [path_str(&head), "--level", "1150"];
    let cpu = scan_json(&args);
    let gpu = scan_json(&[&args[..], &["--backend", "gpu"]].concat());
    assert_eq!(comparable(cpu), comparable(gpu));
}

/// headsq ≥ 1150: 34,295 voxels in 64 components (README); the largest
/// (33,898 voxels) has the hull and ZKHs `chisel hull` reports: 252 faces,
/// 114 ZKHs = 36 cavities + 78 concavities.
#[test]
fn ct_head_bone_components() {
    let Some(head) = common::data("headsq/quarter.nhdr") else {
        return;
    };
    let v = scan_json(&[path_str(&head), "--level", "1150"]);
    assert_eq!(v["structures"], 64);
    assert_eq!(v["scanned"], 64);
    check_row_invariants(&v);
    let total: u64 = rows(&v)
        .iter()
        .map(|r| r["object"]["voxels"].as_u64().unwrap())
        .sum();
    assert_eq!(total, 34_295);
    let bone = row_of(&v, 33_898);
    assert_eq!(bone["id"], 1);
    assert_eq!(bone["hull"]["faces"], 252);
    assert_eq!(bone["hull"]["vertices"], 186);
    let z = &bone["zkh"];
    assert_eq!(z["count"], 114);
    assert_eq!(z["cavities"]["count"], 36);
    assert_eq!(z["concavities"]["count"], 78);
    assert_eq!(z["tunnels"]["count"], 0);
    assert_eq!(z["branched_tunnels"]["count"], 0);

    let big = scan_json(&[path_str(&head), "--level", "1150", "--min-voxels", "24"]);
    assert_eq!(
        big["scanned"].as_u64().unwrap() + big["skipped"]["count"].as_u64().unwrap(),
        64
    );
    assert_eq!(
        big["skipped"]["voxels"].as_u64().unwrap()
            + rows(&big)
                .iter()
                .map(|r| r["object"]["voxels"].as_u64().unwrap())
                .sum::<u64>(),
        34_295
    );
}

/// frogtissue: one row per non-zero label with the README's voxel counts;
/// label 13 is 440,722 voxels in 289 components.
#[test]
fn frog_tissue_labels() {
    let Some(frog) = common::data("froggy/frogtissue.mhd") else {
        return;
    };
    let v = scan_json(&[path_str(&frog), "--labels"]);
    check_row_invariants(&v);
    let got: Vec<(i64, u64)> = rows(&v)
        .iter()
        .map(|r| {
            (
                r["label"].as_f64().unwrap() as i64,
                r["object"]["voxels"].as_u64().unwrap(),
            )
        })
        .collect();
    assert_eq!(got, &common::FROG_LABELS[1..]);
    let tissue = &rows(&v)[12];
    assert_eq!(tissue["label"], 13.0);
    assert_eq!(tissue["components"], 289);
    assert!(tissue["zkh"]["count"].as_u64().unwrap() > 0);
    // Label 21 is 4 voxels on one line.
    assert_eq!(rows(&v)[18]["label"], 21.0);
    assert_eq!(rows(&v)[18]["degenerate"], "collinear");
}

#[test]
fn bad_input_is_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let vol = seed_objects(tmp.path());
    // No selection, or both: usage errors (exit 2).
    let out = chisel(&["scan", path_str(&vol)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--level"));
    let out = chisel(&["scan", path_str(&vol), "--level", "1", "--labels"]);
    assert_eq!(out.status.code(), Some(2));
    // Missing, unreadable, empty selection: exit 1 naming the file.
    for (args, names) in [
        (
            vec![path_str(&tmp.path().join("missing.nrrd")), "--labels"],
            "missing.nrrd",
        ),
        (vec![path_str(&vol), "--level", "9"], "seed_objects.nrrd"),
    ] {
        let out = chisel(&[&["scan"][..], &args].concat());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(names), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    let garbage = tmp.path().join("garbage.nhdr");
    std::fs::write(&garbage, b"NRRD0004\ndimension: 3\nsizes: 4 4\n").unwrap();
    let out = chisel(&["scan", path_str(&garbage), "--labels"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("garbage.nhdr"), "{stderr}");
    // Fractional values are intensities, not labels.
    let smooth = tmp.path().join("smooth.nrrd");
    let ramp = (0..64).map(|i| i as f32 * 0.25).collect();
    let v = Volume::new([4, 4, 4], [1.0; 3], [0.0; 3], VolumeData::F32(ramp)).unwrap();
    chisel::io::write_volume(&smooth, &v).unwrap();
    let out = chisel(&["scan", path_str(&smooth), "--labels"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("smooth.nrrd") && stderr.contains("found the value 0.25"),
        "{stderr}"
    );
}
