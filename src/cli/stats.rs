//! `chisel stats FILE`: figures of a mesh (topology, orientation, bounds,
//! exact self-intersections) or of a volume (range, mean, labels,
//! thresholded 6-connected components).

use std::path::PathBuf;

use serde::Serialize;

use super::report::{Report, ReportArgs, Show};
use super::{BackendChoice, Global};
use crate::foundation::Aabb;
use crate::foundation::vertex_components;
use crate::gpu::Backend;
use crate::mesh::{Topology, self_intersections};
use crate::reduce::SampleRange;
use crate::volume::analysis::{
    ComponentCount, VolumeStats, label_components, threshold_components,
};

/// The report of `chisel stats`: a mesh's or a volume's.
#[derive(Debug, Serialize)]
#[serde(untagged)]
pub enum StatsReport {
    Mesh(MeshStats),
    Volume(VolumeStatsReport),
}

impl Report for StatsReport {
    const SCHEMA: &'static str = "chisel.stats/1";
}

/// `stats` of a mesh.
#[derive(Debug, Serialize)]
pub struct MeshStats {
    file: PathBuf,
    /// `mesh`.
    kind: &'static str,
    backend: &'static str,
    /// Names of the per-vertex scalar fields.
    scalars: Vec<String>,
    topology: Topology,
    self_intersections: CrossingFigures,
    /// With the GPU: its bounds and whether they equal the CPU mirror's.
    #[serde(skip_serializing_if = "Option::is_none")]
    gpu: Option<GpuBounds>,
}

/// Exactly crossing triangle pairs of a mesh.
#[derive(Debug, Serialize)]
struct CrossingFigures {
    pairs: usize,
    /// Pairs within one connected component.
    within_components: usize,
    /// The first ten pairs.
    first_pairs: Vec<[u32; 2]>,
    zero_area_triangles: usize,
}

#[derive(Debug, Serialize)]
struct GpuBounds {
    adapter: String,
    bounds: Option<Aabb>,
    matches_cpu: bool,
}

/// `stats` of a volume.
#[derive(Debug, Serialize)]
pub struct VolumeStatsReport {
    file: PathBuf,
    /// `volume`.
    kind: &'static str,
    backend: &'static str,
    stats: VolumeStats,
    /// Samples ≥ `--level` and their 6-connected components.
    #[serde(skip_serializing_if = "Option::is_none")]
    level: Option<ComponentCount>,
    /// Samples equal to `--label` and their 6-connected components.
    #[serde(skip_serializing_if = "Option::is_none")]
    label: Option<ComponentCount>,
    /// With the GPU: its value range and whether it equals the CPU mirror's.
    #[serde(skip_serializing_if = "Option::is_none")]
    gpu: Option<GpuRange>,
}

#[derive(Debug, Serialize)]
struct GpuRange {
    adapter: String,
    range: Option<SampleRange>,
    matches_cpu: bool,
}

/// Arguments of `chisel stats`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Mesh (.vtk .ply .obj .stl .byu) or volume (.nrrd .nhdr .mhd .mha .nii .nii.gz).
    file: PathBuf,
    #[command(flatten)]
    report: ReportArgs,
    /// Volumes: count voxels with value ≥ this level and their 6-connected components.
    #[arg(long, allow_hyphen_values = true, value_parser = super::level_f64)]
    level: Option<f64>,
    /// Volumes: count voxels with value = this label and their 6-connected components.
    #[arg(long, allow_hyphen_values = true, value_parser = super::level_f64)]
    label: Option<f64>,
    /// With the GPU, the bounds / value range are also reduced there and
    /// checked against the CPU mirror (the report says whether they agree).
    #[command(flatten)]
    backend: BackendChoice,
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
    args.report.check()?;
    let report = if is_volume(&args.file) {
        StatsReport::Volume(volume_stats(global, args)?)
    } else {
        if args.level.is_some() || args.label.is_some() {
            anyhow::bail!(
                "--level and --label apply to volumes, not to the mesh {}",
                args.file.display()
            );
        }
        StatsReport::Mesh(mesh_stats(global, args)?)
    };
    args.report.emit(&report, Show::Always)
}

fn mesh_stats(global: &Global, args: &Args) -> anyhow::Result<MeshStats> {
    let mesh = crate::io::read_mesh(&args.file)?;
    let topology = Topology::of(&mesh);
    let crossings = self_intersections(&mesh);
    let (component, _) = vertex_components(mesh.n_vertices(), &mesh.triangles);
    let within = crossings
        .pairs
        .iter()
        .filter(|&&[i, j]| component[i as usize] == component[j as usize])
        .count();
    let gpu = match global.backend(&args.backend)? {
        Some(gpu) => {
            let bounds = crate::reduce::mesh_bounds(&mesh, Backend::Gpu(&gpu))?;
            Some(GpuBounds {
                adapter: gpu.describe(),
                matches_cpu: bounds == crate::reduce::mesh_bounds(&mesh, Backend::Cpu)?,
                bounds,
            })
        }
        None => None,
    };
    Ok(MeshStats {
        file: args.file.clone(),
        kind: "mesh",
        backend: if gpu.is_some() { "gpu" } else { "cpu" },
        scalars: mesh.scalars.iter().map(|s| s.name.clone()).collect(),
        topology,
        self_intersections: CrossingFigures {
            pairs: crossings.pairs.len(),
            within_components: within,
            first_pairs: crossings.pairs[..crossings.pairs.len().min(10)].to_vec(),
            zero_area_triangles: crossings.degenerate.len(),
        },
        gpu,
    })
}

fn volume_stats(global: &Global, args: &Args) -> anyhow::Result<VolumeStatsReport> {
    let volume = crate::io::read_volume(&args.file)?;
    let gpu = match global.backend(&args.backend)? {
        Some(gpu) => {
            let range = crate::reduce::volume_range(&volume, Backend::Gpu(&gpu))?;
            Some(GpuRange {
                adapter: gpu.describe(),
                matches_cpu: range == crate::reduce::volume_range(&volume, Backend::Cpu)?,
                range,
            })
        }
        None => None,
    };
    Ok(VolumeStatsReport {
        file: args.file.clone(),
        kind: "volume",
        backend: if gpu.is_some() { "gpu" } else { "cpu" },
        stats: VolumeStats::of(&volume),
        level: args.level.map(|t| threshold_components(&volume, t)),
        label: args.label.map(|l| label_components(&volume, l)),
        gpu,
    })
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        vec![self.file.as_path()]
    }
}
