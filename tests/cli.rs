//! End-to-end tests of the `chisel` binary: every command on real data,
//! JSON reports, exit codes, and clear errors (never a panic) on bad files.

mod common;

use std::path::Path;
use std::process::Output;

use serde_json::Value;

fn chisel(args: &[&str]) -> Output {
    common::run_chisel(env!("CARGO_BIN_EXE_chisel"), args)
}

/// Runs chisel and asserts it succeeded.
fn ok(args: &[&str]) -> Output {
    let out = chisel(args);
    assert!(
        out.status.success(),
        "chisel {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn ok_json(args: &[&str]) -> Value {
    let out = ok(args);
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "chisel {args:?}: stdout is not JSON ({e}): {}",
            String::from_utf8_lossy(&out.stdout)
        )
    })
}

/// A failing run must exit with status 1 (not 101 = panic) and name the file.
fn assert_clean_error(args: &[&str], names: &str) {
    let out = chisel(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "chisel {args:?}: {stderr}");
    assert!(
        stderr.contains(names),
        "error should name {names}: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
}

/// A plan shipped in `src/tissue/plans/`.
fn plan_file(name: &str) -> String {
    format!("{}/src/tissue/plans/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn path_str(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn info_lists_adapters_as_json() {
    let Some(_gpu) = common::gpu() else { return };
    let v = ok_json(&["info", "--json"]);
    let adapters = v["adapters"].as_array().expect("adapters array");
    assert!(!adapters.is_empty());
    assert!(
        adapters[0]["max_storage_buffer_binding_size"]
            .as_u64()
            .unwrap()
            > 0
    );
    assert!(v["chosen"]["name"].is_string(), "{v}");
}

#[test]
fn unknown_adapter_is_a_clear_error() {
    let out = chisel(&["info", "--adapter", "no-such-adapter-xyz"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("no GPU adapter matches `no-such-adapter-xyz`"),
        "{stderr}"
    );
    // A driver is the advice only when there is no adapter at all;
    // otherwise the user is pointed at the ones found.
    if stderr.contains("found: []") {
        assert!(stderr.contains("mesa-vulkan-drivers"), "{stderr}");
    } else {
        assert!(
            stderr.contains("Choose one of those") && !stderr.contains("mesa-vulkan-drivers"),
            "{stderr}"
        );
    }
}

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
        vec!["convert", &mesh, &out, "--preview", &jpg],
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
        vec!["hull", &volume, "--threshold", "1", "--preview", &jpg],
        vec![
            "polyhedrize",
            &volume,
            "--threshold",
            "1",
            "--preview",
            &jpg,
        ],
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
    // Reports name the selection, and say when the ZKHs were not looked for.
    let v = ok_json(&["hull", &ball, "--threshold", "1", "--no-zkh", "--json"]);
    assert_eq!(v["selection"]["threshold"], 1.0);
    assert_eq!(v["selection"]["component"], "largest");
    assert!(v["zkh"].is_null(), "{v}");
    assert_eq!(v["zkh_skipped"], "--no-zkh");
    assert_eq!(v["candidates"]["kind"], "local26");
    let v = ok_json(&["hull", &ball, "--threshold", "1", "--json"]);
    assert_eq!(v["zkh"], serde_json::json!([]));
    assert!(v["zkh_skipped"].is_null());
    // A threshold below every sample selects them all (CT data in HU).
    let v = ok_json(&["stats", &ball, "--threshold", "-5", "--json"]);
    assert_eq!(v["threshold"]["voxels"], 216, "{v}");
    assert_eq!(v["threshold"]["selection"], "value >= -5");
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
            "--threshold",
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
        &[
            "polyhedrize",
            &ball,
            "--threshold",
            "1",
            "-o",
            &p("cells.ply"),
        ],
        "-o takes the binary cell list",
    );
    fails(
        &[
            "polyhedrize",
            &ball,
            "--threshold",
            "1",
            "--cells-json",
            &p("cells.txt"),
        ],
        "name the file .json",
    );
    // A slice has no surface: --mesh is a usage error (exit 2).
    let slice = ["polyhedrize", &ball, "--threshold", "1", "--slice", "3"];
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
    let v = ok_json(&["hull", &plate, "--threshold", "1", "--json"]);
    assert_eq!(v["zkh_skipped"], "flat hull: no inside", "{v}");
    assert!(v["zkh"].is_null(), "{v}");
    let cells = p("plate.cells");
    fails(
        &[
            "polyhedrize",
            &plate,
            "--threshold",
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
    let v = ok_json(&["hull", &ball, "--threshold", "-1", "--no-zkh", "--json"]);
    assert_eq!(v["selection"]["threshold"], -1.0);
    fails(
        &[
            "hull",
            &ball,
            "--threshold",
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
                "--threshold",
                "1",
                "--report",
                &p("nodir/r.json"),
            ],
            "folder",
        );
    }
    fails(&["convert", &ball, &p("x.raw")], "volume extension `.raw`");
    fails(
        &["convert", &ball, &p("x")],
        "volume file name without extension",
    );
}

#[test]
fn stats_meshes_match_the_data_readme() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let fran = ok_json(&["stats", path_str(&dir.join("fran_cut.vtk")), "--json"]);
    let t = &fran["topology"];
    assert_eq!(t["vertices"], 2205);
    assert_eq!(t["triangles"], 4224);
    assert_eq!(t["edges"], 6428);
    assert_eq!(t["boundary_edges"], 184);
    assert_eq!(t["components"].as_array().unwrap().len(), 1);
    assert_eq!(t["euler"], 1);
    assert_eq!(t["orientation"], "inward");

    let bunny = ok_json(&["stats", path_str(&dir.join("bunny.ply")), "--json"]);
    let t = &bunny["topology"];
    assert_eq!(t["vertices"], 35947);
    assert_eq!(t["used_vertices"], 34834);
    assert_eq!(t["triangles"], 69451);
    assert_eq!(t["boundary_edges"], 223);
    assert_eq!(t["euler"], -3);
    assert_eq!(t["orientation"], "inward");
    assert_eq!(
        bunny["scalars"],
        serde_json::json!(["confidence", "intensity"])
    );

    let feet = ok_json(&["stats", path_str(&dir.join("fsu/footbones.ply")), "--json"]);
    let t = &feet["topology"];
    let comps = t["components"].as_array().unwrap();
    assert_eq!(comps.len(), 26);
    assert!(comps.iter().all(|c| c["closed"] == true && c["genus"] == 0));
    assert_eq!(t["euler"], 52);
    assert_eq!(t["orientation"], "outward");
    // The bones overlap at the joints (checked with an independent float
    // test): 378 crossing pairs between bones, 3 within one bone.
    let x = &feet["self_intersections"];
    assert_eq!(x["pairs"], 381);
    assert_eq!(x["within_components"], 3);
    assert_eq!(x["first_pairs"][0], serde_json::json!([43, 48]));
    for clean in [&fran, &bunny] {
        assert_eq!(clean["self_intersections"]["pairs"], 0);
        assert_eq!(clean["self_intersections"]["zero_area_triangles"], 0);
    }
}

#[test]
fn stats_volumes_match_the_data_readme() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let head = ok_json(&[
        "stats",
        path_str(&dir.join("headsq/quarter.nhdr")),
        "--json",
        "--threshold",
        "1150",
    ]);
    let s = &head["stats"];
    assert_eq!(s["dims"], serde_json::json!([64, 64, 93]));
    assert_eq!(s["spacing"], serde_json::json!([3.2, 3.2, 1.5]));
    assert_eq!(s["min"], 0.0);
    assert_eq!(s["max"], 3926.0);
    assert!((s["mean"].as_f64().unwrap() - 507.69).abs() < 0.01);
    assert!(head["threshold"]["voxels"].as_u64().unwrap() > 0);
    assert!(head["threshold"]["components"].as_u64().unwrap() >= 1);

    let frog = ok_json(&[
        "stats",
        path_str(&dir.join("froggy/frogtissue.mhd")),
        "--json",
        "--label",
        "13",
    ]);
    assert_eq!(frog["stats"]["dims"], serde_json::json!([500, 470, 136]));
    assert_eq!(frog["label"]["voxels"], 440_722);
}

#[test]
fn stats_gpu_backend_matches_cpu_on_real_data() {
    let Some(_gpu) = common::gpu() else { return };
    let Some(dir) = common::data_dir() else {
        return;
    };
    let v = ok_json(&[
        "stats",
        path_str(&dir.join("fran_cut.vtk")),
        "--json",
        "--backend",
        "gpu",
    ]);
    assert_eq!(v["gpu"]["matches_cpu"], true, "{v}");
    let v = ok_json(&[
        "stats",
        path_str(&dir.join("headsq/quarter.nhdr")),
        "--json",
        "--backend",
        "gpu",
    ]);
    assert_eq!(v["gpu"]["matches_cpu"], true, "{v}");
    assert_eq!(v["gpu"]["range"]["max"], 3926.0);
}

#[test]
fn convert_round_trips_a_real_mesh_and_volume() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let ply = tmp.path().join("fran.ply");
    let png = tmp.path().join("fran.png");
    let preview: &[&str] = if common::gpu().is_some() {
        &["--preview", path_str(&png)]
    } else {
        &[]
    };
    ok(&[
        &[
            "convert",
            path_str(&dir.join("fran_cut.vtk")),
            path_str(&ply),
        ],
        preview,
    ]
    .concat());
    assert_eq!(png.is_file(), !preview.is_empty());
    let a = chisel::io::read_mesh(&dir.join("fran_cut.vtk")).unwrap();
    let b = chisel::io::read_mesh(&ply).unwrap();
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.triangles, b.triangles);

    let nrrd = tmp.path().join("head.nrrd");
    ok(&[
        "convert",
        path_str(&dir.join("headsq/quarter.nhdr")),
        path_str(&nrrd),
    ]);
    let a = chisel::io::read_volume(&dir.join("headsq/quarter.nhdr")).unwrap();
    let b = chisel::io::read_volume(&nrrd).unwrap();
    assert_eq!(a, b);

    let out = chisel(&[
        "convert",
        path_str(&dir.join("fran_cut.vtk")),
        path_str(&nrrd),
    ]);
    assert_eq!(out.status.code(), Some(1), "mesh → volume must be refused");
}

#[test]
fn render_writes_a_png_of_a_real_mesh() {
    let Some(_gpu) = common::gpu() else { return };
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let png = tmp.path().join("bunny.png");
    ok(&[
        "render",
        path_str(&dir.join("bunny.ply")),
        "-o",
        path_str(&png),
        "--scalars",
        "intensity",
        "--views",
        "front,iso",
        "--size",
        "128",
    ]);
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
}

#[test]
fn demo_runs_and_writes_its_outputs() {
    let Some(_gpu) = common::gpu() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let out_dir = tmp.path().join("demo");
    ok(&["demo", "--out", path_str(&out_dir)]);
    let report: Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["relax_gpu"]["status"], "converged");
    assert_eq!(report["parity"]["same_status_and_iterations"], true);
    assert!(report["parity"]["max_epidermis_distance"].as_f64().unwrap() < 1e-3);
    assert_eq!(report["marching_cubes_gpu_equals_cpu"], true);
    assert_eq!(report["ct"]["skin_groups"], 1);
    assert!(report["cut"]["fragments"]["jaw"].as_u64().unwrap() > 100);
    for f in ["before_after.png", "bone_before_after.png", "head_ct.nrrd"] {
        assert!(out_dir.join(f).is_file(), "{f}");
    }
    let bone = chisel::io::read_mesh(&out_dir.join("bone_moved.ply")).unwrap();
    let moved = bone
        .scalar("displacement")
        .unwrap()
        .values
        .iter()
        .filter(|&&d| (d - 6.0).abs() < 1e-3)
        .count();
    assert_eq!(
        moved as u64,
        report["cut"]["fragments"]["jaw"].as_u64().unwrap()
    );
    let ct = chisel::io::read_volume(&out_dir.join("head_ct.nrrd")).unwrap();
    assert_eq!(
        ct.dims.to_vec(),
        report["phantom"]["dims"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.as_u64().unwrap() as usize)
            .collect::<Vec<_>>()
    );
    let mesh = chisel::io::read_mesh(&out_dir.join("relaxed_skin.ply")).unwrap();
    let d = mesh.scalar("displacement").expect("displacement field");
    let max = d.values.iter().copied().fold(0.0f32, f32::max);
    assert!(
        max > 3.0 && max < 12.0,
        "a 6 mm jaw advance moved the skin by {max} mm"
    );
    // The marching-cubes skin, its short edges collapsed, is embedded, and
    // with bend springs it stays so; the report counts as the library does.
    let crossings = &report["skin_self_intersecting_pairs"];
    assert_eq!(crossings["before"], 0);
    assert_eq!(crossings["after"], 0);
    assert_eq!(chisel::mesh::self_intersections(&mesh).pairs.len(), 0);
    // The skin follows the jaw, it does not outrun it.
    let ratio = report["skin_overshoot"]["ratio"].as_f64().unwrap();
    assert!(ratio > 0.5 && ratio < 1.1, "skin/bone displacement {ratio}");
    assert!(
        report["ct"]["skin_collapse"]["collapsed_edges"]
            .as_u64()
            .unwrap()
            > 1000
    );
    assert!(report["network"]["springs_per_class"][5].as_u64().unwrap() > 10_000);
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

#[test]
fn relax_fran_chin_advance_agrees_between_backends() {
    let Some(_gpu) = common::gpu() else { return };
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let plan = plan_file("fran_chin_advance.toml");
    let plan = plan.as_str();
    let fran = dir.join("fran_cut.vtk");
    let mut reports = Vec::new();
    for backend in ["gpu", "cpu"] {
        let out = tmp.path().join(format!("fran_{backend}.ply"));
        let report = tmp.path().join(format!("fran_{backend}.json"));
        let mut args = vec![
            "relax",
            path_str(&fran),
            "--plan",
            plan,
            "--backend",
            backend,
            "-o",
            path_str(&out),
            "--report",
            path_str(&report),
        ];
        let preview = tmp.path().join("fran.png");
        if backend == "gpu" {
            args.extend(["--preview", path_str(&preview)]);
        }
        let run = chisel(&args);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let mesh = chisel::io::read_mesh(&out).unwrap();
        let d = mesh.scalar("displacement").expect("displacement field");
        let max = d.values.iter().copied().fold(0.0f32, f32::max);
        // The plan moves the chin by 4 mm; the skin follows by millimetres.
        assert!(max > 0.002 && max < 0.008, "max displacement {max} m");
        let v: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
        assert_eq!(
            v["skin_self_intersecting_pairs"],
            serde_json::json!({ "before": 0, "after": 0 }),
            "{backend}"
        );
        assert_eq!(v["relax"]["status"], "converged", "{backend}");
        // Without bend springs the chin skin outruns the 4 mm bone move by
        // about 24 % (README known limits), and the run says so.
        let overshoot = &v["skin_overshoot"];
        let bone = overshoot["bone_max"].as_f64().unwrap();
        let ratio = overshoot["ratio"].as_f64().unwrap();
        // The plan's translate = [0.00335, 0, -0.00218].
        assert!(
            (bone - 0.00335f64.hypot(0.00218)).abs() < 1e-6,
            "bone moves {bone} m"
        );
        assert!(
            (ratio - max as f64 / bone).abs() < 1e-4 && ratio > 1.1,
            "{overshoot}"
        );
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(
            stderr.contains("more than the bone's largest move"),
            "{stderr}"
        );
        reports.push((mesh, v));
    }
    assert!(tmp.path().join("fran.png").is_file());
    let (gpu_mesh, gpu_v) = &reports[0];
    let (cpu_mesh, cpu_v) = &reports[1];
    assert_eq!(gpu_v["relax"]["iterations"], cpu_v["relax"]["iterations"]);
    let max_diff = gpu_mesh
        .positions
        .iter()
        .zip(&cpu_mesh.positions)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0f32, f32::max);
    assert!(max_diff < 1e-6, "GPU and CPU skins differ by {max_diff} m");
}

#[test]
fn relax_rejects_a_bad_plan_clearly() {
    let tmp = tempfile::tempdir().unwrap();
    // The plan is checked before the inputs are read: the missing CT is
    // never reached, the step's unknown fragment is reported.
    let typo = tmp.path().join("typo.toml");
    std::fs::write(
        &typo,
        "[[cut]]\nname = \"chin\"\nknife = { plane = { point = [0.0, 0.0, 112.0], normal = [0.0, 0.0, 1.0] } }\n\
         side = \"positive\"\n[[step]]\nname = \"advance\"\nselect = { fragment = \"chn\" }\n",
    )
    .unwrap();
    let run = chisel(&[
        "relax",
        "--ct",
        "no_such_ct.nhdr",
        "--skin",
        "500",
        "--bone",
        "1150",
        "--plan",
        path_str(&typo),
        "-o",
        path_str(&tmp.path().join("o.ply")),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        !run.status.success()
            && stderr.contains(
                "typo.toml: plan step 1 `advance`: unknown fragment `chn` (known: [chin])"
            )
            && !stderr.contains("no_such_ct"),
        "{stderr}"
    );
    let Some(dir) = common::data_dir() else {
        return;
    };
    let plan = tmp.path().join("bad_plan.toml");
    std::fs::write(&plan, "[[step]]\nname = \"x\"\nselect = { sphere = { center = [0, 0, 0], radius = 1.0 } }\ntranslate = [0, 0, 1]\nincrements = 0\niterations = 1\nfoo = 3\n").unwrap();
    let out = tmp.path().join("o.ply");
    assert_clean_error(
        &[
            "relax",
            path_str(&dir.join("fran_cut.vtk")),
            "--plan",
            path_str(&plan),
            "--backend",
            "cpu",
            "-o",
            path_str(&out),
        ],
        "bad_plan.toml",
    );
    assert!(!out.exists());
}

/// The CT → tissue pipeline on the real CT head: skin and bone by marching
/// cubes, the lower mandible cut free by the plan's knife and advanced
/// 5 mm, the tissue relaxed (CPU mirror; the kernels' parity is proven in
/// `tests/parity`), previews in the CT's anatomical axes.
#[test]
fn relax_ct_headsq_chin_advance_end_to_end() {
    let Some(_gpu) = common::gpu() else { return };
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let plan = plan_file("headsq_chin_advance.toml");
    let plan = plan.as_str();
    let ct = dir.join("headsq/quarter.nhdr");
    let out = |name: &str| tmp.path().join(name);
    let (skin, bone, preview, bone_preview) = (
        out("skin.ply"),
        out("bone.ply"),
        out("skin.png"),
        out("bone.png"),
    );
    let v = ok_json(&[
        "relax",
        "--ct",
        path_str(&ct),
        "--skin",
        "500",
        "--bone",
        "1150",
        "--plan",
        plan,
        "--solver",
        "chebyshev",
        "--backend",
        "cpu",
        "-o",
        path_str(&skin),
        "--bone-output",
        path_str(&bone),
        "--preview",
        path_str(&preview),
        "--bone-preview",
        path_str(&bone_preview),
        "--view-up",
        "0,0,-1",
        "--view-front",
        "0,-1,0",
        "--json",
    ]);
    assert_eq!(v["relax"]["status"], "converged");
    assert_eq!(v["ct"]["figures"]["skin_groups"], 26);
    assert_eq!(v["ct"]["figures"]["bone_groups"], 76);
    assert_eq!(v["network"]["subcutis_depth"], 0.5);
    // The CT defaults: skin edges below 0.6 × 3.2 mm collapsed, bend
    // springs; the chin advance then leaves the skin embedded (without
    // either, 162 triangle pairs cross; README).
    let collapse = &v["ct"]["figures"]["skin_collapse"];
    assert!((collapse["min_edge"].as_f64().unwrap() - 1.92).abs() < 1e-6);
    assert_eq!(collapse["crossing_pairs"], 0);
    assert!(v["network"]["springs_per_class"][5].as_u64().unwrap() > 30_000);
    assert_eq!(v["skin_self_intersecting_pairs"]["before"], 0);
    assert_eq!(v["skin_self_intersecting_pairs"]["after"], 0);
    let ratio = v["skin_overshoot"]["ratio"].as_f64().unwrap();
    assert!(ratio > 0.5 && ratio < 1.1, "skin/bone displacement {ratio}");
    let chin = v["cut"]["fragments"]["chin"].as_u64().unwrap();
    assert!(chin > 1000, "{chin} chin vertices");
    assert_eq!(v["cut"]["knives"][0]["curves_open"], 0);
    // The fragment moved by 5 mm, nothing else of the bone.
    let bone_mesh = chisel::io::read_mesh(&bone).unwrap();
    let d = &bone_mesh.scalar("displacement").unwrap().values;
    let moved = d.iter().filter(|&&x| (x - 5.0).abs() < 1e-3).count();
    let still = d.iter().filter(|&&x| x < 1e-4).count();
    assert_eq!(moved as u64, chin);
    assert_eq!(moved + still, d.len());
    // The skin over the chin follows; the skin far from it stays.
    let skin_mesh = chisel::io::read_mesh(&skin).unwrap();
    let s = &skin_mesh.scalar("displacement").unwrap().values;
    let max = s.iter().copied().fold(0.0f32, f32::max);
    assert!(max > 3.0 && max < 10.0, "max skin displacement {max} mm");
    let forehead = skin_mesh
        .positions
        .iter()
        .zip(s)
        .filter(|(p, _)| p.z < 40.0)
        .map(|(_, &d)| d)
        .fold(0.0f32, f32::max);
    assert!(forehead < 0.1, "the upper head moved {forehead} mm");
    for png in [&preview, &bone_preview] {
        assert_eq!(&std::fs::read(png).unwrap()[1..4], b"PNG");
    }
}

#[test]
fn relax_ct_arguments_are_checked() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("o.ply");
    let ct = dir.join("headsq/quarter.nhdr");
    let fran = dir.join("fran_cut.vtk");
    let plan = plan_file("ct_phantom_jaw_advance.toml");
    // Runs `relax INPUT.. --plan P --backend cpu -o OUT` and checks the exit code and message.
    let fails = |input: &[&str], code: i32, says: &str| {
        let mut args = vec!["relax"];
        args.extend_from_slice(input);
        args.extend(["--plan", &plan, "--backend", "cpu", "-o", path_str(&out)]);
        let run = chisel(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(code), "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
    };
    let ct_args = |skin: &'static str, bone: &'static str| {
        vec!["--ct", path_str(&ct), "--skin", skin, "--bone", bone]
    };
    fails(
        &ct_args("500", "skull.ply"),
        1,
        "--bone is the bone iso-level",
    );
    fails(&ct_args("1150", "500"), 1, "skin < bone");
    let mut negative = ct_args("500", "1150");
    negative.extend(["--skin-min-edge", "-1"]);
    fails(&negative, 1, "shortest skin edge");
    fails(&[path_str(&fran), "--skin-min-edge", "1"], 2, "--ct");
    // A plan that cuts the bone needs one.
    fails(&[path_str(&fran)], 1, "needs a bone mesh");
    // Usage errors: --skin without --ct, a mesh and --ct together.
    fails(&[path_str(&fran), "--skin", "500"], 2, "--ct");
    let mut both = ct_args("500", "1150");
    both.insert(0, path_str(&fran));
    fails(&both, 2, "cannot be used with");
    assert!(!out.exists());
}

#[test]
fn mc_and_capped_cut_of_the_ct_bone() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let bone = tmp.path().join("bone.ply");
    let groups = tmp.path().join("groups");
    let mc = ok_json(&[
        "mc",
        path_str(&dir.join("headsq/quarter.nhdr")),
        "--level",
        "1150",
        "-o",
        path_str(&bone),
        "--groups-dir",
        path_str(&groups),
        "--json",
    ]);
    assert_eq!(mc["triangles"], 78_792);
    let n_groups = mc["group_count"].as_u64().unwrap() as usize;
    assert_eq!(mc["groups"].as_array().unwrap().len(), n_groups);
    assert_eq!(std::fs::read_dir(&groups).unwrap().count(), n_groups);

    let closed = tmp.path().join("closed.ply");
    ok_json(&[
        "mc",
        path_str(&dir.join("headsq/quarter.nhdr")),
        "--level",
        "1150",
        "--close-border",
        "-o",
        path_str(&closed),
        "--json",
    ]);
    let pieces = tmp.path().join("pieces");
    let cut = ok_json(&[
        "cut",
        path_str(&closed),
        "--plane",
        "100,100,60,0,0.3,1",
        "--cap",
        "-o",
        path_str(&pieces),
        "--json",
    ]);
    assert_volume_conserved(&cut, "plane cut");
    let original = cut["input_signed_volume"].as_f64().unwrap();
    assert!(
        cut["pieces"]
            .as_array()
            .unwrap()
            .iter()
            .all(|p| p["closed"] == true)
    );
    let tested = cut["stats"]["triangles_tested"].as_u64().unwrap();
    let all = cut["stats"]["triangles_total"].as_u64().unwrap();
    assert!(tested * 4 < all, "tree tested {tested} of {all} triangles");

    let out = chisel(&[
        "cut",
        path_str(&closed),
        "--plane",
        "1,2,3",
        "-o",
        path_str(&pieces),
    ]);
    assert_eq!(out.status.code(), Some(1), "a plane needs 6 numbers");
    assert_clean_error(
        &[
            "cut",
            path_str(&closed),
            "--plane",
            "100,100,60,0,0.3,1",
            "--explode",
            "-1",
            "-o",
            path_str(&pieces),
        ],
        "--explode must be between 0 and 10",
    );
    assert_clean_error(
        &[
            "cut",
            path_str(&closed),
            "--plane",
            "100,100,60,0,0.3,1",
            "-o",
            path_str(&closed.join("sub")),
        ],
        "is a file, not a folder",
    );

    // A sphere whose summed loop area points at a pole inside a cap: the
    // caps must still be the sphere's part inside the bone (no piece with a
    // whole, inside-out sphere), and the earlier run's pieces are replaced.
    let sphere = ok_json(&[
        "cut",
        path_str(&closed),
        "--sphere",
        "100,100,70,40",
        "--cap",
        "-o",
        path_str(&pieces),
        "--json",
    ]);
    let volumes: Vec<f64> = sphere["pieces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["signed_volume"].as_f64().unwrap())
        .collect();
    let ball = 4.0 / 3.0 * std::f64::consts::PI * 40f64.powi(3);
    assert!(
        volumes.iter().all(|&v| v > -0.01 * ball && v < original),
        "{volumes:?}"
    );
    assert!(((volumes.iter().sum::<f64>() - original) / original).abs() < 1e-6);
    assert_eq!(
        std::fs::read_dir(&pieces).unwrap().count(),
        volumes.len(),
        "stale pieces of the plane cut removed"
    );

    // Outputs are checked before the work; an empty surface writes nothing.
    let surface = tmp.path().join("never.ply");
    assert_clean_error(
        &[
            "mc",
            path_str(&dir.join("headsq/quarter.nhdr")),
            "--level",
            "1150",
            "-o",
            path_str(&surface),
            "--report",
            path_str(&tmp.path().join("no/such/r.json")),
        ],
        "does not exist",
    );
    assert_clean_error(
        &[
            "mc",
            path_str(&dir.join("headsq/quarter.nhdr")),
            "--level",
            "-500",
            "-o",
            path_str(&surface),
        ],
        "level -500 lies outside the data range 0 to 3926",
    );
    assert!(!surface.exists());
}

/// Triangulated knives on the CT bone at 1150, where samples equal the
/// level (marching cubes keeps every triangle's area positive, so the exact
/// predicates place them): an icosphere and a tilted sheet whose triangles
/// each hold whole cut loops. Closed at the border, every piece is closed
/// and the volumes add up; open, loops are capped and open curves counted.
/// The pieces' signed volumes of a `cut --json` report add up to the
/// input's within 1e-6 relative.
fn assert_volume_conserved(cut: &Value, what: &str) {
    let total: f64 = cut["pieces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["signed_volume"].as_f64().unwrap())
        .sum();
    let original = cut["input_signed_volume"].as_f64().unwrap();
    assert!(
        ((total - original) / original).abs() < 1e-6,
        "{what}: {total} vs {original}"
    );
}

#[test]
fn mesh_knives_cut_the_ct_bone() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let mut ball = common::icosphere(3);
    for p in &mut ball.positions {
        *p = *p * 30.17 + glam::Vec3::new(100.123, 60.377, 40.291);
    }
    let ball_ply = tmp.path().join("ball.ply");
    chisel::io::write_mesh(&ball_ply, &ball).unwrap();
    let n = 8;
    let mut sheet = chisel::TriMesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (
                -20.37 + 250.0 * i as f32 / n as f32,
                -20.11 + 200.0 * j as f32 / n as f32,
            );
            sheet
                .positions
                .push(glam::Vec3::new(x, 70.29 + 0.13 * x + 0.21 * z, z));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            sheet.triangles.push([a, a + 1, a + n + 2]);
            sheet.triangles.push([a, a + n + 2, a + n + 1]);
        }
    }
    let sheet_ply = tmp.path().join("sheet.ply");
    chisel::io::write_mesh(&sheet_ply, &sheet).unwrap();
    // A box whose cap crossed the bone's tube cells, which the marching-cubes
    // table once joined by a self-crossing band (two pieces were not manifold).
    let mut boxed = common::cube();
    for p in &mut boxed.positions {
        *p = *p * glam::Vec3::new(80.34, 80.46, 60.22) + glam::Vec3::new(59.96, 60.04, 30.2);
    }
    let box_ply = tmp.path().join("box.ply");
    chisel::io::write_mesh(&box_ply, &boxed).unwrap();
    let ct = dir.join("headsq/quarter.nhdr");
    for close in [true, false] {
        let bone = tmp.path().join(format!("bone_{close}.ply"));
        let mut args = vec![
            "mc",
            path_str(&ct),
            "--level",
            "1150",
            "-o",
            path_str(&bone),
            "--json",
        ];
        if close {
            args.push("--close-border");
        }
        ok_json(&args);
        for knife in [&ball_ply, &sheet_ply, &box_ply] {
            let what = format!("{} close {close}", knife.display());
            let pieces = tmp.path().join("pieces");
            let cut = ok_json(&[
                "cut",
                path_str(&bone),
                "--knife",
                path_str(knife),
                "--cap",
                "-o",
                path_str(&pieces),
                "--json",
            ]);
            let stats = &cut["stats"];
            assert!(
                stats["loops_capped"].as_u64().unwrap() > 0,
                "{what}: {stats}"
            );
            let pieces = cut["pieces"].as_array().unwrap();
            if knife != &sheet_ply {
                // A closed knife tells every piece's side, reached or not.
                assert!(pieces.iter().all(|p| p["side"] != "both"), "{what}");
            }
            if close {
                assert_eq!(stats["curves_open"], 0, "{what}");
                assert!(
                    pieces.iter().all(|p| p["closed"] == true
                        && p["manifold"] == true
                        && p["self_intersecting_pairs"] == 0),
                    "{what}"
                );
                assert_volume_conserved(&cut, &what);
            } else if knife == &sheet_ply {
                // The sheet leaves the bone where it is open at the border.
                assert!(
                    stats["curves_open"].as_u64().unwrap() > 0,
                    "{what}: {stats}"
                );
                assert!(pieces.iter().any(|p| p["closed"] == false), "{what}");
            }
        }
    }
}

/// `phantom` writes the seed's objects; `hull` reproduces the seed's
/// figures on them (Tables 4.1/4.2 for the r = 24 ball, Table 8.6 for the
/// 25/10 cylinder with its tunnel of 1,200 background voxels).
#[test]
fn phantom_and_hull_reproduce_the_seed_figures() {
    let tmp = tempfile::tempdir().unwrap();
    let ball = tmp.path().join("ball24.nrrd");
    ok(&["phantom", "ball", "--r", "24", "-o", path_str(&ball)]);
    let merged = ok_json(&["hull", path_str(&ball), "--threshold", "1", "--json"]);
    assert_eq!(merged["hull"]["faces"], 290);
    assert_eq!(merged["object"]["voxels"], 7208);
    assert_eq!(
        merged["zkh"].as_array().unwrap().len(),
        0,
        "a ball is digitally convex"
    );
    let tris = ok_json(&[
        "hull",
        path_str(&ball),
        "--threshold",
        "1",
        "--coplanar",
        "visible",
        "--json",
    ]);
    assert_eq!(tris["hull"]["faces"], 524);
    let corners = ok_json(&[
        "hull",
        path_str(&ball),
        "--threshold",
        "1",
        "--vertices",
        "corners",
        "--json",
    ]);
    assert_eq!(corners["candidates"]["kind"], "convex_corners");

    let cyl = tmp.path().join("cyl.mha");
    ok(&[
        "phantom",
        "cylinder-tunnel",
        "--outer",
        "25",
        "--inner",
        "10",
        "-o",
        path_str(&cyl),
    ]);
    let hull_ply = tmp.path().join("cyl_hull.ply");
    let v = ok_json(&[
        "hull",
        path_str(&cyl),
        "--threshold",
        "1",
        "-o",
        path_str(&hull_ply),
        "--json",
    ]);
    assert_eq!(v["object"]["voxels"], 6060);
    assert_eq!(v["object"]["boundary_facets"], 2848);
    let zkh = v["zkh"].as_array().unwrap();
    assert_eq!(zkh.len(), 1);
    assert_eq!(zkh[0]["class"], "tunnel");
    assert_eq!(zkh[0]["voxels"], 1200);
    let mesh = chisel::io::read_mesh(&hull_ply).unwrap();
    assert_eq!(
        mesh.n_vertices() as u64,
        v["hull"]["vertices"].as_u64().unwrap()
    );

    // Bad selections are clear errors.
    assert_clean_error(&["hull", path_str(&cyl), "--threshold", "5"], "cyl.mha");
    assert_clean_error(
        &[
            "hull",
            path_str(&cyl),
            "--threshold",
            "1",
            "--component",
            "7",
        ],
        "component 7",
    );
    let run = chisel(&[
        "phantom", "torus", "--major", "4", "--minor", "9", "-o", "t.nrrd",
    ]);
    assert_eq!(run.status.code(), Some(1));
}

#[test]
fn polyhedrize_writes_verified_cells() {
    let tmp = tempfile::tempdir().unwrap();
    let cyl = tmp.path().join("cyl.nrrd");
    ok(&[
        "phantom",
        "cylinder-tunnel",
        "--outer",
        "50",
        "--inner",
        "35",
        "-o",
        path_str(&cyl),
    ]);
    let cells = tmp.path().join("cyl.cells");
    let cells_json = tmp.path().join("cyl.json");
    let mesh = tmp.path().join("cyl.ply");
    let png = tmp.path().join("cyl.png");
    let v = ok_json(&[
        "polyhedrize",
        path_str(&cyl),
        "--threshold",
        "1",
        "-o",
        path_str(&cells),
        "--cells-json",
        path_str(&cells_json),
        "--mesh",
        path_str(&mesh),
        "--preview",
        path_str(&png),
        "--verify",
        "--json",
    ]);
    // Seed Table 8.7, holed faces split: 60 faces against 13,952 triangles.
    assert_eq!(v["polyhedron"]["faces"], 60);
    assert_eq!(v["polyhedron"]["shells"], 2);
    assert_eq!(v["marching_cubes"]["triangles"], 13952);
    assert_eq!(v["verified"], true);
    assert_eq!(v["zkh"][0]["class"], "tunnel");
    // The merged surface: 58 faces, the two caps holed (60 split).
    assert_eq!(v["mesh"], "merged");
    assert_eq!(
        (v["merged_faces"].as_u64(), v["merged_faces_split"].as_u64()),
        (Some(58), Some(60))
    );
    let back = chisel::polyhedron::Polyhedron::from_bytes(
        &std::fs::read(&cells).unwrap(),
        "cyl.cells",
        chisel::voxel::Frame::default(),
    )
    .unwrap();
    assert_eq!(back.shells.len(), 2);
    let j: Value = serde_json::from_slice(&std::fs::read(&cells_json).unwrap()).unwrap();
    assert_eq!(j["shells"][1]["role"], "background");
    let m = chisel::io::read_mesh(&mesh).unwrap();
    assert!(m.scalar("depth").is_some());
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    // Cutting-out (Def. AU): both caps marked, same merged surface.
    let v = ok_json(&[
        "polyhedrize",
        path_str(&cyl),
        "--threshold",
        "1",
        "--press-in",
        "--verify",
        "--json",
    ]);
    assert_eq!(v["verified"], true);
    assert_eq!(v["options"]["press_in"], true);
    assert_eq!(v["zkh"][0]["pressed_faces"], 2);
    assert_eq!(v["merged_faces"], 58);
    // Corner vertices are for hulls only: a clear error.
    assert_clean_error(
        &[
            "polyhedrize",
            path_str(&cyl),
            "--threshold",
            "1",
            "--vertices",
            "corners",
        ],
        "voxel centres",
    );
}

/// `chisel bench relax` on fran_cut: rates of both step kernels on both
/// backends in one run, the traffic figures they imply, and the time to
/// equilibrium after the chin plan's first increment (the explicit kernel
/// is bit-exact on lavapipe, so its GPU run lands on the CPU state).
#[test]
fn bench_relax_reports_rates_and_equilibrium() {
    let Some(gpu) = common::gpu() else { return };
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let report = tmp.path().join("bench.json");
    let fran = dir.join("fran_cut.vtk");
    let plan = plan_file("fran_chin_advance.toml");
    let v = ok_json(&[
        "bench",
        "relax",
        path_str(&fran),
        "--plan",
        &plan,
        "--seconds",
        "0.05",
        "--approach",
        "--json",
        "--report",
        path_str(&report),
    ]);
    let written: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(written, v);
    assert!(v["machine"]["threads"].as_u64().unwrap() >= 1);
    let net = &v["networks"][0];
    assert_eq!(net["nodes"], 6615);
    assert_eq!(net["free_nodes"], 4410);
    let bytes = net["bytes_per_iteration"].as_u64().unwrap();
    // 84 bytes per free node, 32 per bone node, 4 per CSR entry.
    let entries = net["csr_entries"].as_u64().unwrap();
    assert_eq!(bytes, 4410 * 84 + 2205 * 32 + entries * 4);
    let rates = net["rates"].as_array().unwrap();
    let runs: Vec<(&str, &str)> = rates
        .iter()
        .map(|r| {
            (
                r["solver"].as_str().unwrap(),
                r["backend"].as_str().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        runs,
        [
            ("explicit", "cpu"),
            ("explicit", "gpu"),
            ("chebyshev", "cpu"),
            ("chebyshev", "gpu")
        ]
    );
    for r in rates {
        let (n, s) = (
            r["iterations"].as_f64().unwrap(),
            r["seconds"].as_f64().unwrap(),
        );
        assert!(n >= 8.0 && s > 0.0, "{r}");
        let rate = r["iterations_per_second"].as_f64().unwrap();
        assert!((rate - n / s).abs() <= 1e-9 * rate, "{r}");
        let gbs = r["effective_gb_per_second"].as_f64().unwrap();
        assert!((gbs - rate * bytes as f64 / 1e9).abs() <= 1e-9 * gbs, "{r}");
    }
    let settled = net["time_to_equilibrium"].as_array().unwrap();
    assert_eq!(settled.len(), 4);
    for s in settled {
        assert_eq!(s["status"], "converged", "{s}");
        // Both solvers reach the same state within their stop tests.
        assert!(s["gap_percent"].as_f64().unwrap() < 3.0, "{s}");
    }
    // The explicit kernel is bit-exact with its mirror on a software adapter;
    // a GPU whose compiler fuses multiply-adds settles to the same state
    // within rounding (NVIDIA H200: 0.0015 % apart).
    if gpu.is_software() {
        assert_eq!(settled[1]["gap_percent"], 0.0, "explicit GPU vs CPU");
        assert_eq!(settled[0]["iterations"], settled[1]["iterations"]);
    } else {
        let gap = settled[1]["gap_percent"].as_f64().unwrap();
        assert!(gap < 0.1, "explicit GPU vs CPU: {gap} %");
    }
    let approach = &net["approach"];
    assert_eq!(approach["reference_status"], "converged");
    for a in approach["runs"].as_array().unwrap() {
        assert_eq!(a["reached"], true, "{a}");
        assert!(a["gap_percent"].as_f64().unwrap() <= 1.0, "{a}");
    }
}

/// `--grid` and `--refine` build the refined networks of the benchmarks:
/// fran_cut refined 2× has 89 × 97 vertices per layer.
#[test]
fn bench_relax_refines_the_scan_grid() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let fran = dir.join("fran_cut.vtk");
    let v = ok_json(&[
        "bench",
        "relax",
        path_str(&fran),
        "--grid",
        "45,49",
        "--refine",
        "1,2",
        "--backend",
        "cpu",
        "--solver",
        "explicit",
        "--seconds",
        "0.02",
        "--json",
    ]);
    let nodes: Vec<u64> = (v["networks"].as_array().unwrap().iter())
        .map(|n| n["nodes"].as_u64().unwrap())
        .collect();
    assert_eq!(nodes, [6615, 3 * 89 * 97]);
    for n in v["networks"].as_array().unwrap() {
        assert_eq!(n["rates"].as_array().unwrap().len(), 1);
        assert!(n["time_to_equilibrium"].is_null());
        assert!(n["spectrum"].is_null());
    }
}

/// `--export` writes the network the rates run on: the arrays equal the
/// network built here, the bone carries the plan's first increment, and
/// the header's counts match the files.
#[test]
fn bench_relax_exports_the_network() {
    use chisel::tissue::{NetworkParams, SpringNetwork};
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let fran = dir.join("fran_cut.vtk");
    let plan = plan_file("fran_chin_advance.toml");
    let out = tmp.path().join("nets");
    let v = ok_json(&[
        "bench",
        "relax",
        path_str(&fran),
        "--backend",
        "cpu",
        "--solver",
        "explicit",
        "--seconds",
        "0.02",
        "--plan",
        &plan,
        "--export",
        path_str(&out),
        "--json",
    ]);
    let lanes = v["machine"]["cpu_lanes"].as_str().unwrap();
    assert!(["four", "eight", "sixteen"].contains(&lanes), "{lanes}");
    let x1 = out.join("x1");
    let words = |name: &str| -> Vec<u32> {
        let b = std::fs::read(x1.join(name)).unwrap();
        assert_eq!(b.len() % 4, 0, "{name}");
        b.chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    let mesh = chisel::io::read_mesh(&fran).unwrap();
    let net = SpringNetwork::build(&mesh, None, &NetworkParams::default()).unwrap();
    let bits =
        |rows: &[[f32; 4]]| -> Vec<u32> { rows.iter().flatten().map(|x| x.to_bits()).collect() };
    assert_eq!(words("rest.f32"), bits(&net.rest));
    assert_eq!(words("offsets.u32"), net.csr.offsets);
    assert_eq!(words("entries.u32"), net.csr.entries);
    let mut table = vec![[0.0f32; 4]; 16];
    for (row, m) in table.iter_mut().zip(&net.materials) {
        *row = m.table_row();
    }
    assert_eq!(words("materials.f32"), bits(&table));
    let u: Vec<f32> = words("displacement.f32")
        .into_iter()
        .map(f32::from_bits)
        .collect();
    assert_eq!(u.len(), 4 * net.n_nodes());
    let (free, bone) = u.split_at(4 * net.n_free);
    assert!(
        free.chunks(4)
            .all(|p| p == [0.0, 0.0, 0.0, 1.0 / net.params.mass])
    );
    let moved = bone.chunks(4).filter(|p| p[..3] != [0.0; 3]).count();
    assert!(
        moved > 10 && bone.chunks(4).all(|p| p[3] == 0.0),
        "{moved} bone nodes moved"
    );
    let header: Value =
        serde_json::from_slice(&std::fs::read(x1.join("network.json")).unwrap()).unwrap();
    assert_eq!(header["nodes"], 6615);
    assert_eq!(header["free"], 4410);
    assert_eq!(header["entries"], net.csr.entries.len());
    assert!(header["dt"].as_f64().unwrap() > 0.0);
}

#[test]
fn bench_relax_arguments_are_checked() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let fran = dir.join("fran_cut.vtk");
    let fran = path_str(&fran);
    let run = |extra: &[&str], names: &str| {
        let mut args = vec!["bench", "relax", fran, "--backend", "cpu"];
        args.extend(extra);
        assert_clean_error(&args, names);
    };
    run(&["--refine", "8"], "--grid COLS,ROWS");
    run(
        &["--grid", "10,10"],
        "fran_cut.vtk: --grid 10,10 needs 100 vertices",
    );
    run(&["--grid", "45"], "--grid takes COLS,ROWS");
    run(&["--refine", "0"], "--refine factors are 1..=64");
    run(&["--seconds", "0"], "--seconds takes a positive number");
    let cut_plan = plan_file("ct_phantom_jaw_advance.toml");
    run(
        &["--plan", &cut_plan],
        "ct_phantom_jaw_advance.toml: the plan cuts the bone",
    );
    assert_clean_error(
        &[
            "bench",
            "relax",
            "/nonexistent/skin.ply",
            "--backend",
            "cpu",
        ],
        "/nonexistent/skin.ply",
    );
}

/// A rectangle that ends inside the solid leaves open cut curves, which
/// `--cap` cannot close: the run says so, and the report marks the piece
/// open. A knife that misses the surface is reported too.
#[test]
fn cut_warns_when_caps_cannot_close_or_the_knife_misses() {
    let tmp = tempfile::tempdir().unwrap();
    let cube = tmp.path().join("cube.ply");
    chisel::io::write_mesh(&cube, &common::cube()).unwrap();
    let report = tmp.path().join("r.json");
    // z = 0.5, x from −0.5 to 0.5: one curve over the faces y = 0, x = 0
    // and y = 1, ending at x = 0.5 inside the cube.
    let out = ok(&[
        "cut",
        path_str(&cube),
        "--rect",
        "0,0.5,0.5,0,0,1,1,0,0,0.5,2",
        "--cap",
        "-o",
        path_str(&tmp.path().join("rect")),
        "--report",
        path_str(&report),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("warning: 1 cut curve(s) end inside the surface"),
        "{stderr}"
    );
    let v: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(v["stats"]["curves_open"], 1);
    assert!(
        (v["pieces"].as_array().unwrap().iter()).any(|p| p["closed"] == false),
        "{v}"
    );
    let out = ok(&[
        "cut",
        path_str(&cube),
        "--plane",
        "0,0,5,0,0,1",
        "-o",
        path_str(&tmp.path().join("miss")),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("warning: the knives cross no triangle"),
        "{stderr}"
    );
}

/// An empty marching-cubes surface says why: a level outside the data, a
/// label no voxel has; a 2-D image and a fractional label are refused.
#[test]
fn mc_says_why_a_surface_is_empty() {
    let tmp = tempfile::tempdir().unwrap();
    let vol = tmp.path().join("v.nhdr");
    let data: Vec<u8> = (0..27).map(|i| if i == 13 { 7 } else { 1 }).collect();
    let v = chisel::Volume::new(
        [3; 3],
        [1.0; 3],
        [0.0; 3],
        chisel::volume::VolumeData::U8(data),
    )
    .unwrap();
    chisel::io::write_volume(&vol, &v).unwrap();
    let flat = tmp.path().join("flat.nhdr");
    let data = vec![1u8; 9];
    let f = chisel::Volume::new(
        [3, 3, 1],
        [1.0; 3],
        [0.0; 3],
        chisel::volume::VolumeData::U8(data),
    )
    .unwrap();
    chisel::io::write_volume(&flat, &f).unwrap();
    let out = tmp.path().join("s.ply");
    let mc = |input: &Path, what: &[&str], names: &str| {
        let mut args = vec![
            "mc",
            path_str(input),
            "--backend",
            "cpu",
            "-o",
            path_str(&out),
        ];
        args.extend(what);
        assert_clean_error(&args, names);
        assert!(!out.exists());
    };
    mc(
        &vol,
        &["--level", "9"],
        "level 9 lies outside the data range 1 to 7",
    );
    mc(
        &vol,
        &["--label", "3"],
        "label 3 occurs in no voxel (values 1 to 7)",
    );
    mc(&vol, &["--label", "2.5"], "--label takes a whole number");
    mc(
        &flat,
        &["--level", "0.5"],
        "marching cubes needs at least 2 samples along each axis",
    );
    // In range, every sample on one side (≥ 1): closing the border helps.
    mc(
        &vol,
        &["--level", "1"],
        "no cell has samples on both sides of level 1 (try --close-border",
    );
}
