//! `chisel spline`: fran_cut's smooth face on both backends (the counts
//! the formula predicts, the same surface), the control nets, the UVs that
//! come with the mesh, and clear errors.

use crate::common;
use crate::support::{assert_clean_error, chisel, ok_json, path_str};

#[test]
fn fran_cut_spline_on_both_backends() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let fran = dir.join("fran_cut.vtk");
    let mut meshes = Vec::new();
    for backend in ["cpu", "gpu"] {
        if backend == "gpu" && common::gpu().is_none() {
            continue;
        }
        let out = tmp.path().join(format!("smooth_{backend}.ply"));
        let net = tmp.path().join(format!("net_{backend}.ply"));
        let png = tmp.path().join(format!("smooth_{backend}.png"));
        let mut args = vec![
            "spline",
            path_str(&fran),
            "--n",
            "5",
            "--backend",
            backend,
            "-o",
            path_str(&out),
            "--control-net",
            path_str(&net),
            "--json",
        ];
        if backend == "gpu" {
            args.extend(["--preview", path_str(&png)]);
        }
        let v = ok_json(&args);
        assert_eq!(v["schema"], "chisel.spline/1");
        assert_eq!(v["output"], v["predicted"], "{backend}");
        assert_eq!(v["output"]["points"], 34_161);
        assert_eq!(v["output"]["triangles"], 67_584);
        assert_eq!(v["fit"]["method"], "quasi");
        assert_eq!(v["param"]["mirrored"], true);
        assert!(v["knots"]["min_quality"].as_f64().unwrap() > 0.03);
        // The smooth skin stays within 1/3 of a mean edge (4.6 mm) of the
        // mesh; the largest gap is at the nostril.
        let d = v["distance"]["max"].as_f64().unwrap();
        assert!(d > 1e-4 && d < 6e-3, "{d}");
        let mesh = chisel::io::read_mesh(&out).unwrap();
        for f in ["nx", "ny", "nz", "distance", "curvature"] {
            assert!(mesh.scalar(f).is_some(), "{f}");
        }
        let net = chisel::io::read_mesh(&net).unwrap();
        assert_eq!(
            (net.n_vertices(), net.n_triangles()),
            (2205 + 6428, 4 * 4224)
        );
        if backend == "gpu" {
            assert!(png.exists());
        }
        meshes.push(mesh);
    }
    if let [cpu, gpu] = &meshes[..] {
        let worst = cpu
            .positions
            .iter()
            .zip(&gpu.positions)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-6, "cpu vs gpu surface: {worst}");
        assert_eq!(cpu.triangles, gpu.triangles);
    }
}

#[test]
fn control_nets_and_given_uvs() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let fran = dir.join("fran_cut.vtk");
    let out = tmp.path().join("o.ply");
    let run = |extra: &[&str]| {
        let mut a = vec![
            "spline",
            path_str(&fran),
            "--n",
            "3",
            "--backend",
            "cpu",
            "-o",
            path_str(&out),
            "--json",
        ];
        a.extend(extra);
        ok_json(&a)
    };
    let id = run(&["--fit", "identify"]);
    let lsq = run(&["--fit", "lsq"]);
    let faired = run(&["--fit", "lsq", "--fairing", "0.1"]);
    let rms = |v: &serde_json::Value| v["fit"]["rms"].as_f64().unwrap();
    assert!(rms(&lsq) < 0.1 * rms(&id), "{} vs {}", rms(&lsq), rms(&id));
    assert!(rms(&faired) > rms(&lsq));
    assert!(lsq["fit"]["iterations"].as_u64().unwrap() > 0);
    // The mesh's own vertices as dense data, projected by the same map.
    let data = run(&[
        "--fit",
        "lsq",
        "--data",
        path_str(&fran),
        "--fairing",
        "0.01",
    ]);
    assert_eq!(data["fit"]["data_points"], 2205);
    assert_eq!(data["fit"]["outside"], 0);
    // The scan's texture coordinates as the parametrisation.
    let uv = run(&["--param", "uv"]);
    assert_eq!(uv["param"]["projection"], "uv");
    assert_eq!(uv["output"]["points"], 8633);
}

#[test]
fn bad_spline_arguments_are_refused_clearly() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let fran = dir.join("fran_cut.vtk");
    let out = tmp.path().join("o.ply");
    let o = path_str(&out);
    let f = path_str(&fran);
    // The planar projection folds fran_cut's sides: refused with the ids.
    assert_clean_error(
        &["spline", f, "--n", "3", "--param", "planar", "-o", o],
        "folds 53 triangle",
    );
    assert_clean_error(&["spline", f, "--n", "1", "-o", o], "points per edge");
    assert_clean_error(
        &["spline", f, "--n", "3", "--data", f, "-o", o],
        "--fit lsq",
    );
    assert_clean_error(
        &["spline", f, "--n", "3", "--fairing", "0.5", "-o", o],
        "--fit lsq",
    );
    assert_clean_error(
        &[
            "spline",
            f,
            "--n",
            "3",
            "--fit",
            "lsq",
            "--fairing",
            "-1",
            "-o",
            o,
        ],
        "fairing",
    );
    // A mesh without texture coordinates cannot use --param uv.
    let bunny = dir.join("bunny.ply");
    assert_clean_error(
        &[
            "spline",
            path_str(&bunny),
            "--n",
            "3",
            "--param",
            "uv",
            "-o",
            o,
        ],
        "texture coordinates",
    );
    assert!(!out.exists(), "nothing written");
    let _ = chisel;
}
