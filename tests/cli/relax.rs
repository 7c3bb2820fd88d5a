//! `chisel relax`: the chin advance on fran_cut (both backends) and on the
//! CT head, and clear errors for bad plans and arguments.

use serde_json::Value;

use crate::common;
use crate::support::{assert_clean_error, chisel, ok_json, path_str, plan_file};

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
            // The defaults, given: the flags parse and the report prints them.
            "--mass",
            "1",
            "--check-every",
            "25",
        ];
        let preview = tmp.path().join("fran.png");
        if backend == "gpu" {
            args.extend(["--preview", path_str(&preview), "--spline", "3"]);
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
        if backend == "gpu" {
            // `--spline 3`: the relaxed skin as its DMS spline, written next
            // to the output; its displacement is the relaxation's.
            let s = &v["spline"];
            assert_eq!(s["domain"], "whole skin");
            assert_eq!(
                (s["points"].as_u64(), s["triangles"].as_u64()),
                (Some(8633), Some(16896))
            );
            let spline_path = tmp.path().join(format!("fran_{backend}_spline.ply"));
            assert_eq!(v["outputs"]["spline"], path_str(&spline_path));
            let sm = chisel::io::read_mesh(&spline_path).unwrap();
            assert_eq!(sm.n_triangles(), 16_896);
            let smax = s["max_displacement"].as_f64().unwrap();
            assert!(
                (smax - max as f64).abs() < 0.3 * max as f64,
                "{smax} vs {max}"
            );
        }
        assert_eq!(
            v["skin_self_intersecting_pairs"],
            serde_json::json!({ "before": 0, "after": 0 }),
            "{backend}"
        );
        assert_eq!(v["relax"]["status"], "converged", "{backend}");
        let r = &v["relax"];
        assert_eq!(
            (r["mass"].as_f64(), r["damping"].as_f64()),
            (Some(1.0), Some(0.5))
        );
        assert_eq!(
            (r["check_every"].as_u64(), r["window"].as_u64()),
            (Some(25), Some(100))
        );
        assert_eq!(r["max_iterations"], 100_000);
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
        "--skin-level",
        "500",
        "--bone-level",
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
                "typo.toml: plan step 1 `advance`: unknown fragment `chn`; known: [chin]"
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
        "--skin-level",
        "500",
        "--bone-level",
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
        vec![
            "--ct",
            path_str(&ct),
            "--skin-level",
            skin,
            "--bone-level",
            bone,
        ]
    };
    // The bone level is a number, the bone mesh another flag.
    fails(&ct_args("500", "skull.ply"), 2, "--bone-level");
    let mut ct_and_mesh = ct_args("500", "1150");
    ct_and_mesh.extend(["--bone-mesh", "skull.ply"]);
    fails(&ct_and_mesh, 2, "cannot be used with");
    fails(&ct_args("1150", "500"), 1, "skin < bone");
    let mut negative = ct_args("500", "1150");
    negative.extend(["--skin-min-edge", "-1"]);
    fails(&negative, 1, "skin_min_edge = -1");
    fails(&[path_str(&fran), "--skin-min-edge", "1"], 2, "--ct");
    // A plan that cuts the bone needs one.
    fails(&[path_str(&fran)], 1, "needs a bone mesh");
    // Usage errors: --skin-level without --ct, a mesh and --ct together.
    fails(&[path_str(&fran), "--skin-level", "500"], 2, "--ct");
    let mut both = ct_args("500", "1150");
    both.insert(0, path_str(&fran));
    fails(&both, 2, "cannot be used with");
    assert!(!out.exists());
}
