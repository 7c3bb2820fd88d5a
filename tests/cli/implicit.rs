//! `chisel implicit`: the dumbbell sampled over its time span on both
//! backends (one part before the neck breaks, two after, the same number
//! of frames and parts per frame), frames as point sets with normals, the
//! contact sheet, and clear errors for bad scenes.

use crate::common;
use crate::support::{assert_clean_error, chisel, ok_json, path_str};

fn scene(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(format!("src/implicit/scenes/{name}.toml"))
}

#[test]
fn dumbbell_particles_split_on_both_backends() {
    let tmp = tempfile::tempdir().unwrap();
    let dumbbell = scene("dumbbell");
    let mut clusters = Vec::new();
    for backend in ["cpu", "gpu"] {
        if backend == "gpu" && common::gpu().is_none() {
            continue;
        }
        let out = tmp.path().join(backend);
        let png = tmp.path().join(format!("{backend}.png"));
        let mut args = vec![
            "implicit",
            path_str(&dumbbell),
            "--frames",
            "3",
            "--edge-length",
            "0.15",
            "--backend",
            backend,
            "-o",
            path_str(&out),
            "--json",
        ];
        if backend == "gpu" {
            args.extend(["--preview", path_str(&png)]);
        }
        let v = ok_json(&args);
        assert_eq!(v["schema"], "chisel.implicit/1");
        let frames = v["frames"].as_array().unwrap();
        assert_eq!(frames.len(), 3);
        assert_eq!(frames[0]["time"], 0.0);
        assert_eq!(frames[2]["time"], 1.0);
        assert_eq!(frames[0]["converged"], true, "{}", frames[0]);
        for f in frames {
            assert!(f["residual_max"].as_f64().unwrap() < 0.1 * 0.15, "{f}");
        }
        clusters.push(
            frames
                .iter()
                .map(|f| f["clusters"].as_u64().unwrap())
                .collect::<Vec<_>>(),
        );
        for (k, f) in frames.iter().enumerate() {
            let mesh = chisel::io::read_mesh(&out.join(format!("frame_{k:04}.ply"))).unwrap();
            assert_eq!(mesh.n_vertices() as u64, f["particles"].as_u64().unwrap());
            let names: Vec<&str> = mesh.scalars.iter().map(|s| s.name.as_str()).collect();
            assert_eq!(names, ["nx", "ny", "nz", "sigma"]);
        }
        if backend == "gpu" {
            assert!(std::fs::metadata(&png).unwrap().len() > 1000);
        }
    }
    // One part at t = 0 and t = 0.5 (before the break at 0.4435 the neck
    // is still there; at 0.5 the halves are 0.06 apart, closer than the
    // 3σ̂ link), two at t = 1.
    for c in &clusters {
        assert_eq!(c[0], 1);
        assert_eq!(c[2], 2);
    }
}

#[test]
fn bad_scenes_are_clean_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let bad = tmp.path().join("bad.toml");
    std::fs::write(&bad, "iso = 0.5\n[[primitive]]\nskeleton = { point = [0, 0, 0] }\ninfluence = { blobby = { a = -1.0, b = 1.0 } }\n").unwrap();
    let out = tmp.path().join("o");
    assert_clean_error(
        &["implicit", path_str(&bad), "-o", path_str(&out)],
        "line 4",
    );
    std::fs::write(&bad, "iso = 0.5\n").unwrap();
    assert_clean_error(
        &["implicit", path_str(&bad), "-o", path_str(&out)],
        "empty scene",
    );
    let good = scene("dumbbell");
    assert_clean_error(
        &[
            "implicit",
            path_str(&good),
            "--edge-length",
            "-1",
            "-o",
            path_str(&out),
        ],
        "edge-length",
    );
    let missing = tmp.path().join("missing.toml");
    let o = chisel(&["implicit", path_str(&missing), "-o", path_str(&out)]);
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn dumbbell_network_splits_with_a_clean_manifold_every_frame() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("net");
    let v = ok_json(&[
        "implicit",
        path_str(&scene("dumbbell")),
        "--method",
        "network",
        "--frames",
        "3",
        "--edge-length",
        "0.12",
        "--backend",
        "cpu",
        "-o",
        path_str(&out),
        "--json",
    ]);
    let frames = v["frames"].as_array().unwrap();
    let comps: Vec<u64> = frames
        .iter()
        .map(|f| f["components"].as_u64().unwrap())
        .collect();
    assert_eq!(comps, [1, 2, 2]);
    for f in frames {
        assert_eq!(f["manifold"], true, "{f}");
        assert_eq!(f["self_intersections"], 0, "{f}");
        assert_eq!(f["components"], f["reference_components"], "{f}");
        assert!(f["hausdorff"].as_f64().unwrap() < 0.5 * 0.12, "{f}");
        assert!(f["quality"]["min_angle_30"].as_f64().unwrap() > 0.9, "{f}");
    }
    let mesh = chisel::io::read_mesh(&out.join("frame_0002.ply")).unwrap();
    assert_eq!(
        mesh.n_triangles() as u64,
        frames[2]["triangles"].as_u64().unwrap()
    );
}
