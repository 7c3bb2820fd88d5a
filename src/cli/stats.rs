//! `chisel stats FILE`: figures of a mesh (topology, orientation, bounds,
//! exact self-intersections) or of a volume (range, mean, labels,
//! thresholded 6-connected components).

use std::path::PathBuf;

use serde_json::{Value, json};

use super::{BackendArg, Global};
use crate::foundation::vertex_components;
use crate::mesh::{Topology, self_intersections};
use crate::parity::Backend;
use crate::volume::analysis::{VolumeStats, label_components, threshold_components};

/// Arguments of `chisel stats`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Mesh (.vtk .ply .obj .stl .byu) or volume (.nrrd .nhdr .mhd .mha .nii .nii.gz).
    file: PathBuf,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
    /// Also write the JSON report to this file.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Volumes: count voxels with value ≥ T and their 6-connected components.
    #[arg(long)]
    threshold: Option<f64>,
    /// Volumes: count voxels with value = L and their 6-connected components.
    #[arg(long)]
    label: Option<f64>,
    /// Where the bounds / value range are reduced (the GPU result is checked
    /// against the CPU mirror and the report says whether they agree).
    #[arg(long, value_enum, default_value = "cpu")]
    backend: BackendArg,
}

/// Whether `path` names a volume (by extension) rather than a mesh.
pub fn is_volume(path: &std::path::Path) -> bool {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    [".nrrd", ".nhdr", ".mhd", ".mha", ".nii", ".nii.gz"]
        .iter()
        .any(|ext| name.ends_with(ext))
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    if let Some(path) = &args.report {
        crate::foundation::fs::check_output_path(path)?;
    }
    let value = if is_volume(&args.file) {
        volume_stats(global, args)?
    } else {
        if args.threshold.is_some() || args.label.is_some() {
            anyhow::bail!(
                "--threshold and --label apply to volumes, not to the mesh {}",
                args.file.display()
            );
        }
        mesh_stats(global, args)?
    };
    super::report::emit(&value, args.json, args.report.as_deref())
}

fn mesh_stats(global: &Global, args: &Args) -> anyhow::Result<Value> {
    let mesh = crate::io::read_mesh(&args.file)?;
    let topology = Topology::of(&mesh);
    let crossings = self_intersections(&mesh);
    let (component, _) = vertex_components(mesh.n_vertices(), &mesh.triangles);
    let within = crossings
        .pairs
        .iter()
        .filter(|&&[i, j]| component[i as usize] == component[j as usize])
        .count();
    let mut value = json!({
        "file": args.file,
        "kind": "mesh",
        "scalars": mesh.scalars.iter().map(|s| s.name.clone()).collect::<Vec<_>>(),
        "topology": topology,
        "self_intersections": {
            "pairs": crossings.pairs.len(),
            "within_components": within,
            "first_pairs": &crossings.pairs[..crossings.pairs.len().min(10)],
            "zero_area_triangles": crossings.degenerate.len(),
        },
    });
    if args.backend == BackendArg::Gpu {
        let gpu = global.gpu()?;
        let gpu_bounds = crate::reduce::mesh_bounds(&mesh, Backend::Gpu(&gpu))?;
        let cpu_bounds = crate::reduce::mesh_bounds(&mesh, Backend::Cpu)?;
        value["gpu"] = json!({
            "adapter": gpu.describe(),
            "bounds": gpu_bounds,
            "matches_cpu": gpu_bounds == cpu_bounds,
        });
    }
    Ok(value)
}

fn volume_stats(global: &Global, args: &Args) -> anyhow::Result<Value> {
    let volume = crate::io::read_volume(&args.file)?;
    let stats = VolumeStats::of(&volume);
    let mut value = json!({ "file": args.file, "kind": "volume", "stats": stats });
    if let Some(t) = args.threshold {
        value["threshold"] = serde_json::to_value(threshold_components(&volume, t))?;
    }
    if let Some(l) = args.label {
        value["label"] = serde_json::to_value(label_components(&volume, l))?;
    }
    if args.backend == BackendArg::Gpu {
        let gpu = global.gpu()?;
        let gpu_range = crate::reduce::volume_range(&volume, Backend::Gpu(&gpu))?;
        let cpu_range = crate::reduce::volume_range(&volume, Backend::Cpu)?;
        value["gpu"] = json!({
            "adapter": gpu.describe(),
            "range": gpu_range,
            "matches_cpu": gpu_range == cpu_range,
        });
    }
    Ok(value)
}
