//! `chisel demo`: the main job on embedded generated data.
//!
//! Today: a head phantom's skin → vertex normals and bounds on the GPU, each
//! checked against its CPU mirror → the mesh with a GPU-derived scalar field,
//! a preview PNG and a JSON report in the output folder.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;

use super::Global;
use crate::mesh::{ScalarField, TriMesh};
use crate::parity::{Backend, compare_vec};
use crate::render::{RenderOptions, View};

/// Arguments of `chisel demo`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output folder (created if missing).
    #[arg(short, long, default_value = "chisel-demo")]
    out: PathBuf,
    /// Phantom resolution: latitude rings (longitude segments = 2×).
    #[arg(long, default_value_t = 160)]
    rings: u32,
    /// Print the report as JSON on stdout too.
    #[arg(long)]
    json: bool,
}

/// Angle (degrees) between each vertex normal and the radial direction from
/// the centre: 0 on the smooth skull, large on the nose, chin and sockets.
fn normal_deviation(mesh: &TriMesh, normals: &[[f32; 4]]) -> Vec<f32> {
    mesh.positions
        .iter()
        .zip(normals)
        .map(|(p, n)| {
            let radial = p.normalize_or_zero();
            let n = glam::Vec3::new(n[0], n[1], n[2]);
            radial.dot(n).clamp(-1.0, 1.0).acos().to_degrees()
        })
        .collect()
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out).map_err(|e| crate::Error::io(&args.out, e))?;
    let bar = global.progress(5, "demo");
    let mut stages = serde_json::Map::new();
    let mut stage = |name: &str, t: Instant| {
        stages.insert(name.into(), json!(t.elapsed().as_secs_f64()));
    };

    let t = Instant::now();
    let mut skin = crate::phantom::head_skin(args.rings, 2 * args.rings)?;
    stage("phantom", t);
    bar.inc(1);

    let t = Instant::now();
    let gpu = global.gpu()?;
    stage("gpu_open", t);
    bar.inc(1);

    let t = Instant::now();
    let gpu_normals = crate::normals::vertex_normals(&skin, Backend::Gpu(&gpu))?;
    stage("vertex_normals_gpu", t);
    let t = Instant::now();
    let cpu_normals = crate::normals::vertex_normals(&skin, Backend::Cpu)?;
    stage("vertex_normals_cpu", t);
    let normals_parity = compare_vec(
        "vertex_normals/phantom",
        &cpu_normals,
        &gpu_normals,
        crate::normals::cpu::TOL,
    );
    let max_dev = cpu_normals
        .iter()
        .zip(&gpu_normals)
        .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
        .fold(0.0f32, f32::max);
    bar.inc(1);

    let t = Instant::now();
    let gpu_bounds = crate::reduce::mesh_bounds(&skin, Backend::Gpu(&gpu))?;
    stage("bounds_reduce_gpu", t);
    let cpu_bounds = crate::reduce::mesh_bounds(&skin, Backend::Cpu)?;
    bar.inc(1);

    let t = Instant::now();
    skin.scalars.push(ScalarField {
        name: "normal_deviation_deg".into(),
        values: normal_deviation(&skin, &gpu_normals),
    });
    let mesh_path = args.out.join("phantom_skin.ply");
    crate::io::write_mesh(&mesh_path, &skin)?;
    let preview_path = args.out.join("preview.png");
    let opts = RenderOptions {
        views: vec![View::Front, View::Right, View::Top, View::Iso],
        scalars: Some("normal_deviation_deg".into()),
        title: Some("chisel demo: head phantom, GPU vertex normals".into()),
        ..Default::default()
    };
    crate::render::render_png(&gpu, &skin, &opts, &preview_path)?;
    stage("write_outputs", t);
    bar.inc(1);
    bar.finish_and_clear();

    let report = json!({
        "command": "demo",
        "adapter": gpu.describe(),
        "features": gpu.features,
        "phantom": {
            "kind": "head_skin",
            "rings": args.rings,
            "vertices": skin.n_vertices(),
            "triangles": skin.n_triangles(),
        },
        "parity": {
            "vertex_normals": {
                "tolerance_abs": crate::normals::cpu::TOL.abs,
                "max_abs_difference": max_dev,
                "status": match &normals_parity { Ok(()) => "match".to_string(), Err(m) => m.to_string() },
            },
            "bounds_reduce": {
                "gpu": gpu_bounds,
                "cpu": cpu_bounds,
                "status": if gpu_bounds == cpu_bounds { "exact match" } else { "MISMATCH" },
            },
        },
        "outputs": {
            "mesh": mesh_path,
            "preview": preview_path,
        },
        "timings_s": stages,
    });
    let report_path = args.out.join("report.json");
    super::report::write_json(&report_path, &report)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    }
    global.note(format!(
        "demo: {} vertices, normals {} (max |Δ| {max_dev:.2e}), bounds {}; wrote {}, {}, {}",
        skin.n_vertices(),
        if normals_parity.is_ok() {
            "match CPU"
        } else {
            "DIFFER from CPU"
        },
        if gpu_bounds == cpu_bounds {
            "exact"
        } else {
            "DIFFER"
        },
        mesh_path.display(),
        preview_path.display(),
        report_path.display()
    ));
    normals_parity?;
    anyhow::ensure!(
        gpu_bounds == cpu_bounds,
        "bounds_reduce: GPU {gpu_bounds:?} != CPU {cpu_bounds:?}"
    );
    Ok(())
}
