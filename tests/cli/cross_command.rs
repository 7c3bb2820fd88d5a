//! Behaviour all commands share: clean errors (exit 1, never a panic) on
//! missing or garbage input, output names and options checked before any
//! work or output, and the permissions of the files written.

use std::path::Path;

use crate::common;
use crate::support::{assert_clean_error, chisel, ok_json, path_str, plan_file};

#[test]
fn missing_and_garbage_inputs_are_clean_errors() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.ply");
    assert_clean_error(&["stats", path_str(&missing)], "missing.ply");
    let garbage = dir.path().join("garbage.vtk");
    std::fs::write(
        &garbage,
        b"# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 99999999999 float\n",
    )
    .unwrap();
    assert_clean_error(&["stats", path_str(&garbage)], "garbage.vtk");
    let vol = dir.path().join("bad.nhdr");
    std::fs::write(&vol, b"NRRD0004\ndimension: 3\nsizes: 100000 100000 100000\ntype: short\nencoding: raw\ndata file: nothing.raw\n").unwrap();
    assert_clean_error(&["stats", path_str(&vol)], "bad.nhdr");
    let out = dir.path().join("x.png");
    assert_clean_error(
        &["render", path_str(&garbage), "-o", path_str(&out)],
        "garbage.vtk",
    );
    assert!(!out.exists(), "no partial preview on failure");
}

/// Every command that draws a preview refuses a non-PNG name before it reads
/// its input (the missing input is never reached).
#[test]
fn previews_must_be_png_names_checked_first() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let (mesh, volume, jpg) = (p("missing.ply"), p("missing.nhdr"), p("look.jpg"));
    let (out, pieces, plan) = (p("o.ply"), p("pieces"), plan_file("fran_chin_advance.toml"));
    let runs: [Vec<&str>; 7] = [
        vec!["render", &mesh, "-o", &jpg],
        vec!["convert", &mesh, "-o", &out, "--preview", &jpg],
        vec!["mc", &volume, "--level", "1", "-o", &out, "--preview", &jpg],
        vec![
            "cut",
            &mesh,
            "--sphere",
            "0,0,0,1",
            "-o",
            &pieces,
            "--preview",
            &jpg,
        ],
        vec![
            "relax",
            &mesh,
            "--plan",
            &plan,
            "-o",
            &out,
            "--preview",
            &jpg,
        ],
        vec!["hull", &volume, "--level", "1", "--preview", &jpg],
        vec!["polyhedrize", &volume, "--level", "1", "--preview", &jpg],
    ];
    for args in runs {
        let run = chisel(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(
            stderr.contains("look.jpg: unsupported format: image extension `.jpg`")
                && stderr.contains("name the file .png")
                && !stderr.contains("missing"),
            "{args:?}: {stderr}"
        );
    }
    assert!(!Path::new(&jpg).exists());
}

/// Negative thresholds parse, and mistakes in outputs or options are
/// reported before the work and before any output is written.
#[test]
fn volume_commands_check_their_options_first() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let ball = p("ball.nrrd");
    let v = ok_json(&["phantom", "ball", "--r", "4", "-o", &ball, "--json"]);
    assert_eq!(v["kind"], serde_json::json!({ "shape": "ball", "r": 4 }));
    // Every report names its schema and version first.
    assert_eq!(v["schema"], "chisel.phantom/1");
    let out = chisel(&["stats", &ball, "--json", "--backend", "cpu"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.starts_with("{\n  \"schema\": \"chisel.stats/1\",\n  \"file\""),
        "{text}"
    );
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(
        (&v["kind"], &v["backend"]),
        (&"volume".into(), &"cpu".into())
    );
    // Reports name the selection, and say when the ZKHs were not looked for.
    let v = ok_json(&["hull", &ball, "--level", "1", "--no-zkh", "--json"]);
    assert_eq!(v["selection"]["level"], 1.0);
    assert_eq!(v["selection"]["component"], "largest");
    assert!(v["zkh"].is_null(), "{v}");
    assert_eq!(v["zkh_skipped"], "--no-zkh");
    assert_eq!(v["candidates"]["kind"], "local26");
    let v = ok_json(&["hull", &ball, "--level", "1", "--json"]);
    assert_eq!(v["zkh"], serde_json::json!([]));
    assert!(v["zkh_skipped"].is_null());
    // A threshold below every sample selects them all (CT data in HU).
    let v = ok_json(&["stats", &ball, "--level", "-5", "--json"]);
    assert_eq!(v["level"]["voxels"], 216, "{v}");
    assert_eq!(v["level"]["selection"], "value >= -5");
    let fails = |args: &[&str], says: &str| {
        let run = chisel(args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
    };
    let (mesh, png) = (p("hull.ply"), p("hull.png"));
    fails(
        &[
            "hull",
            &ball,
            "--level",
            "1",
            "-o",
            &mesh,
            "--preview",
            &png,
            "--view-up",
            "1,0,0",
            "--view-front",
            "2,0,0",
        ],
        "must not be parallel",
    );
    assert!(!Path::new(&mesh).exists(), "no output before the check");
    fails(
        &["polyhedrize", &ball, "--level", "1", "-o", &p("cells.ply")],
        "-o takes the binary cell list",
    );
    fails(
        &[
            "polyhedrize",
            &ball,
            "--level",
            "1",
            "--cells-json",
            &p("cells.txt"),
        ],
        "name the file .json",
    );
    // A slice has no surface: --mesh is a usage error (exit 2).
    let slice = ["polyhedrize", &ball, "--level", "1", "--slice", "3"];
    let run = chisel(&[&slice[..], &["--mesh", &mesh]].concat());
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("cannot be used with"), "{stderr}");
    // A flat object (a 3 × 3 × 1 plate): no ZKH search, and no mesh to
    // write, refused before the cell list is written.
    let plate = p("plate.nrrd");
    let v = chisel::volume::Volume::new(
        [3, 3, 1],
        [1.0; 3],
        [0.0; 3],
        chisel::volume::VolumeData::U8(vec![1; 9]),
    )
    .unwrap();
    chisel::io::write_volume(Path::new(&plate), &v).unwrap();
    let v = ok_json(&["hull", &plate, "--level", "1", "--json"]);
    assert_eq!(v["zkh_skipped"], "flat hull: no inside", "{v}");
    assert!(v["zkh"].is_null(), "{v}");
    let cells = p("plate.cells");
    fails(
        &[
            "polyhedrize",
            &plate,
            "--level",
            "1",
            "-o",
            &cells,
            "--mesh",
            &mesh,
        ],
        "every shell is flat",
    );
    assert!(!Path::new(&cells).exists());
    // Thresholds and vectors may start with a minus sign.
    let v = ok_json(&["hull", &ball, "--level", "-1", "--no-zkh", "--json"]);
    assert_eq!(v["selection"]["level"], -1.0);
    fails(
        &[
            "hull",
            &ball,
            "--level",
            "1",
            "--preview",
            &png,
            "--view-up",
            "-1,0,0",
            "--view-front",
            "-2,0,0",
        ],
        "must not be parallel",
    );
    // A slice is verified by its shells; no surface, so no ray-parity check.
    let v = ok_json(&[&slice[..], &["--verify", "--json"]].concat());
    assert_eq!(v["verified"], true, "{v}");
    assert!(v["verify_ray_parity_mismatches"].is_null(), "{v}");
    for command in ["scan", "stats"] {
        fails(
            &[
                command,
                &ball,
                "--level",
                "1",
                "--report",
                &p("nodir/r.json"),
            ],
            "folder",
        );
    }
    fails(
        &["convert", &ball, "-o", &p("x.raw")],
        "volume extension `.raw`",
    );
    fails(
        &["convert", &ball, "-o", &p("x")],
        "volume file name without extension",
    );
}

#[cfg(unix)]
#[test]
fn outputs_are_world_readable_files() {
    use std::os::unix::fs::PermissionsExt;
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let ply = tmp.path().join("fran.ply");
    let out = chisel(&[
        "convert",
        path_str(&dir.join("fran_cut.vtk")),
        "-o",
        path_str(&ply),
    ]);
    assert!(out.status.success());
    let mode = std::fs::metadata(&ply).unwrap().permissions().mode();
    assert_eq!(
        mode & 0o044,
        0o044,
        "mode {mode:o}: group/other cannot read the output"
    );
}

/// `--backend auto` (the default everywhere) keeps a software adapter's
/// work on the CPU paths and says so; `--backend gpu` runs on it anyway.
#[test]
fn the_backend_choice_is_the_same_everywhere_and_printed() {
    let Some(_gpu) = common::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let ball = dir.path().join("ball.nrrd");
    let ball = path_str(&ball);
    ok_json(&["phantom", "ball", "--r", "4", "-o", ball, "--json"]);
    for (backend, says, report) in [
        (None, "backend: cpu (auto: the adapter", "cpu"),
        (Some("cpu"), "backend: cpu\n", "cpu"),
        (Some("gpu"), "backend: gpu on", "gpu"),
    ] {
        let mut args = vec!["stats", ball, "--json", "--adapter", "cpu"];
        args.extend(backend.map(|b| ["--backend", b]).iter().flatten());
        // Without --quiet: the choice is a note on stderr.
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_chisel"))
            .args(&args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success() && stderr.contains(says),
            "{args:?}: {stderr}"
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(v["backend"], report, "{args:?}");
    }
}

/// A ball of radius 3 as `v.nrrd` in `dir`.
fn small_ball(dir: &Path) -> std::path::PathBuf {
    let vol = dir.join("v.nrrd");
    ok_json(&[
        "phantom",
        "ball",
        "--r",
        "3",
        "-o",
        path_str(&vol),
        "--json",
    ]);
    vol
}

/// No output of a command may name one of its inputs: the same path, a
/// symbolic link, a hard link, or the data file a header names. Each is
/// refused before any work, and the input is left byte for byte as it was.
#[test]
fn outputs_never_overwrite_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let vol = small_ball(d);
    let mesh = d.join("m.ply");
    ok_json(&[
        "mc",
        path_str(&vol),
        "--level",
        "1",
        "-o",
        path_str(&mesh),
        "--json",
    ]);
    let before = |p: &Path| std::fs::read(p).unwrap();
    let (vol_bytes, mesh_bytes) = (before(&vol), before(&mesh));
    let same = |what: &str| {
        assert_eq!(
            std::fs::read(&vol).unwrap(),
            vol_bytes,
            "{what}: volume changed"
        );
        assert_eq!(
            std::fs::read(&mesh).unwrap(),
            mesh_bytes,
            "{what}: mesh changed"
        );
    };
    let (v, m) = (path_str(&vol), path_str(&mesh));
    assert_clean_error(&["stats", v, "--report", v], "is the input");
    same("stats --report");
    assert_clean_error(
        &["mc", v, "--level", "1", "-o", m, "--report", v],
        "is the input",
    );
    assert_clean_error(&["hull", v, "--level", "1", "--report", v], "is the input");
    assert_clean_error(&["convert", m, "-o", m], "is the input");
    assert_clean_error(&["render", m, "-o", m], "is the input");
    same("mc, hull, convert, render");
    // relax: the plan and the mesh are inputs.
    let plan = d.join("plan.toml");
    std::fs::copy(plan_file("fran_chin_advance.toml"), &plan).unwrap();
    let plan_bytes = before(&plan);
    let p = path_str(&plan);
    assert_clean_error(&["relax", m, "--plan", p, "-o", m], "is the input");
    assert_clean_error(
        &[
            "relax",
            m,
            "--plan",
            p,
            "-o",
            path_str(&d.join("r.ply")),
            "--report",
            p,
        ],
        "is the input",
    );
    assert_eq!(before(&plan), plan_bytes);
    same("relax");
    // Through a symbolic link and a hard link.
    #[cfg(unix)]
    {
        let soft = d.join("soft.ply");
        std::os::unix::fs::symlink(&mesh, &soft).unwrap();
        assert_clean_error(&["convert", m, "-o", path_str(&soft)], "is the input");
        let hard = d.join("hard.ply");
        std::fs::hard_link(&mesh, &hard).unwrap();
        assert_clean_error(&["convert", m, "-o", path_str(&hard)], "is the input");
        same("links");
    }
    // A detached header's data file: writing `b.nhdr` writes `b.raw`, the
    // data of the input `a.nhdr`.
    let raw = d.join("b.raw");
    std::fs::write(&raw, [1u8; 8]).unwrap();
    let a = d.join("a.nhdr");
    std::fs::write(
        &a,
        b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: b.raw\n",
    )
    .unwrap();
    assert_clean_error(
        &["convert", path_str(&a), "-o", path_str(&d.join("b.nhdr"))],
        "is the input",
    );
    assert_eq!(std::fs::read(&raw).unwrap(), [1u8; 8]);
    assert!(!d.join("b.nhdr").exists());
}

/// Levels and labels: NaN is refused as a usage error, `-inf` and negative
/// numbers are values.
#[test]
fn nan_levels_are_refused_and_negative_ones_parse() {
    let dir = tempfile::tempdir().unwrap();
    let vol = small_ball(dir.path());
    let v = path_str(&vol);
    for args in [
        vec!["stats", v, "--level", "nan"],
        vec!["stats", v, "--label", "NaN"],
        vec!["mc", v, "--level", "nan", "-o", "x.ply"],
        vec!["hull", v, "--level", "nan"],
        vec!["scan", v, "--level", "nan"],
    ] {
        let run = chisel(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains("NaN compares false"), "{args:?}: {stderr}");
    }
    for level in ["-inf", "-1", "-1e3"] {
        let r = ok_json(&["stats", v, "--level", level, "--json"]);
        let n = r["stats"]["voxels"].as_u64().unwrap();
        assert_eq!(r["level"]["voxels"].as_u64(), Some(n), "{level}: {r}");
    }
    let r = ok_json(&["stats", v, "--level=-1", "--json"]);
    assert!(r["level"]["voxels"].as_u64().unwrap() > 0);
}

/// Buffers derived from an input (marching cubes arrays, per-voxel labels)
/// are allocated against the memory budget too: a volume that fits the
/// budget but whose surface does not is an error naming the buffer, not an
/// abort.
#[test]
fn derived_buffers_stay_within_the_memory_budget() {
    let dir = tempfile::tempdir().unwrap();
    let ball = dir.path().join("ball.nrrd");
    ok_json(&[
        "phantom",
        "ball",
        "--r",
        "20",
        "-o",
        path_str(&ball),
        "--json",
    ]);
    let out = dir.path().join("s.ply");
    let run = |budget: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_chisel"))
            .args([
                "mc",
                path_str(&ball),
                "--level",
                "0.5",
                "-o",
                path_str(&out),
                "-q",
            ])
            .env("CHISEL_MAX_INPUT_BYTES", budget)
            .env("CHISEL_ADAPTER", "cpu")
            .output()
            .unwrap()
    };
    let input_bytes = std::fs::metadata(&ball).unwrap().len();
    // Enough for the file, not for the surface's vertex positions.
    let tight = run(&(input_bytes + 4096).to_string());
    let stderr = String::from_utf8_lossy(&tight.stderr);
    assert_eq!(tight.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("marching cubes"), "{stderr}");
    assert!(stderr.contains("memory budget"), "{stderr}");
    // Negative control: the default budget makes the surface.
    assert!(run("17179869184").status.success());
}
