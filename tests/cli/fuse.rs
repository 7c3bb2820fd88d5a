//! `chisel fuse`: two star-shaped foot bones (cut out of footbones.ply by
//! `convert --component`, one moved by `--translate`) fused with a report
//! and a preview, on the CPU and the GPU; a subtraction; a refusal of the
//! whole foot, which is not star-shaped, with the failing rays drawn; and
//! a bone without a kernel fused with another by layers.

use std::path::Path;

use crate::common;
use crate::support::{assert_clean_error, chisel, ok, ok_json, path_str};

/// Bone 4 and bone 6 of the foot, bone 6 moved so that the two bones'
/// kernels overlap (the points from which each is star-shaped).
pub fn two_bones(dir: &Path) -> Option<(String, String)> {
    let feet = common::data("fsu/footbones.ply")?;
    let a = dir.join("bone4.ply");
    let b = dir.join("bone6.ply");
    ok(&[
        "convert",
        path_str(&feet),
        "--component",
        "4",
        "-o",
        path_str(&a),
    ]);
    ok(&[
        "convert",
        path_str(&feet),
        "--component",
        "6",
        "--translate",
        "-4.0073,1.0697,-0.4168",
        "-o",
        path_str(&b),
    ]);
    Some((path_str(&a).to_string(), path_str(&b).to_string()))
}

#[test]
fn foot_bones_fuse_with_report_and_preview() {
    let tmp = tempfile::tempdir().unwrap();
    let Some((a, b)) = two_bones(tmp.path()) else {
        return;
    };
    let out = tmp.path().join("fused.ply");
    let png = tmp.path().join("fused.png");
    let mut reports = Vec::new();
    let backends: &[&str] = if common::gpu().is_some() {
        &["cpu", "gpu"]
    } else {
        &["cpu"]
    };
    for backend in backends {
        let v = ok_json(&[
            "fuse",
            &a,
            &b,
            "--tolerance",
            "0.005",
            "--backend",
            backend,
            "-o",
            path_str(&out),
            "--preview",
            path_str(&png),
            "--json",
        ]);
        assert_eq!(v["schema"], "chisel.fuse/1");
        assert_eq!(v["backend"], *backend);
        let err = v["volumes"]["relative_error"].as_f64().unwrap();
        assert!(err < 1e-3, "{backend}: {}", v["volumes"]);
        assert_eq!(v["outside"], 0);
        assert!(v["center_search"]["clearance"].as_f64().unwrap() > 0.0);
        assert!(v["rays"].as_u64().unwrap() > 1000);
        let c = chisel::io::read_mesh(&out).unwrap();
        let topo = chisel::mesh::Topology::of(&c);
        assert!(topo.closed && topo.consistently_oriented && topo.euler == 2);
        assert_eq!(c.n_triangles() as u64, v["triangles"].as_u64().unwrap());
        assert!(std::fs::metadata(&png).unwrap().len() > 1000);
        reports.push(v);
    }
    // The CPU and GPU runs make the same surface.
    if let [cpu, gpu] = &reports[..] {
        assert_eq!(cpu["triangles"], gpu["triangles"]);
        assert_eq!(cpu["passes"], gpu["passes"]);
    }
}

#[test]
fn subtraction_and_refusals() {
    let tmp = tempfile::tempdir().unwrap();
    let Some((a, b)) = two_bones(tmp.path()) else {
        return;
    };
    let out = tmp.path().join("c.ply");
    let png = tmp.path().join("refused.png");
    // Bone 6 reaches out of bone 4: subtraction is refused, naming rays.
    let run = chisel(&[
        "fuse",
        &a,
        &b,
        "--subtract",
        "-o",
        path_str(&out),
        "--backend",
        "cpu",
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("B reaches A's surface or beyond"),
        "{stderr}"
    );
    // A bone subtracted from itself shrunk: a shell's worth of volume left.
    let small = tmp.path().join("small.ply");
    let mut bone = chisel::io::read_mesh(Path::new(&a)).unwrap();
    let h = glam::Vec3::new(-0.1368, -0.0127, -1.4538);
    for p in &mut bone.positions {
        *p = h + (*p - h) * 0.5;
    }
    chisel::io::write_mesh(&small, &bone).unwrap();
    let v = ok_json(&[
        "fuse",
        &a,
        path_str(&small),
        "--subtract",
        "--center",
        "-0.1368,-0.0127,-1.4538",
        "--tolerance",
        "0.002",
        "--backend",
        "cpu",
        "-o",
        path_str(&out),
        "--json",
    ]);
    let vol = &v["volumes"];
    let (va, vb) = (vol["a"].as_f64().unwrap(), vol["b"].as_f64().unwrap());
    assert!((vb / va - 0.125).abs() < 1e-4, "{vol}");
    assert!(vol["relative_error"].as_f64().unwrap() < 1e-3, "{vol}");
    // The whole foot is not star-shaped about any point: a subtraction is
    // refused with the rays, which the preview draws.
    let feet = common::data("fsu/footbones.ply").unwrap();
    let run = chisel(&[
        "fuse",
        path_str(&feet),
        &a,
        "--subtract",
        "--center",
        "-0.1368,-0.0127,-1.4538",
        "-o",
        path_str(&out),
        "--preview",
        path_str(&png),
        "--backend",
        "cpu",
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("mesh A is not star-shaped") && stderr.contains("hit(s)"),
        "{stderr}"
    );
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    assert_clean_error(
        &[
            "fuse",
            path_str(&feet),
            &a,
            "--subtract",
            "-o",
            path_str(&out),
        ],
        "no fusion centre found",
    );
    assert_clean_error(
        &["fuse", &a, &b, "--center", "1,2", "-o", path_str(&out)],
        "--center takes x,y,z",
    );
}

#[test]
fn bone_without_a_kernel_fuses_by_layers() {
    let Some(feet) = common::data("fsu/footbones.ply") else {
        return;
    };
    // Bone 0 has no kernel (no point from which it is star-shaped); bone 4
    // has one, moved to the middle of bone 0's box: the centre is bone 4's
    // kernel point, and the fusion goes on by layers.
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("bone0.ply"), tmp.path().join("bone4.ply"));
    ok(&[
        "convert",
        path_str(&feet),
        "--component",
        "0",
        "-o",
        path_str(&a),
    ]);
    ok(&[
        "convert",
        path_str(&feet),
        "--component",
        "4",
        "--translate",
        "-3.640803,-0.5905228,0.9142076",
        "-o",
        path_str(&b),
    ]);
    let out = tmp.path().join("c.ply");
    let png = tmp.path().join("c.png");
    let v = ok_json(&[
        "fuse",
        path_str(&a),
        path_str(&b),
        "--cells",
        "96",
        "--backend",
        "cpu",
        "-o",
        path_str(&out),
        "--preview",
        path_str(&png),
        "--json",
    ]);
    assert_eq!(v["method"], "layered");
    assert_eq!(v["star_shaped"], false);
    assert_eq!(v["layered"]["not_star_shaped"], "A");
    assert!(v["layered"]["grid_rays"].as_u64().unwrap() > 100_000);
    let err = v["volumes"]["relative_error"].as_f64().unwrap();
    assert!(err < 2e-3, "{}", v["volumes"]);
    let c = chisel::io::read_mesh(&out).unwrap();
    let topo = chisel::mesh::Topology::of(&c);
    assert!(topo.closed && topo.consistently_oriented && topo.euler == 2);
    assert_eq!(c.n_triangles() as u64, v["triangles"].as_u64().unwrap());
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
}
