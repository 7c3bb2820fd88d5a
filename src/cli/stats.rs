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
    Series(SeriesList),
}

/// `stats` of a DICOM directory holding several series: the list.
#[derive(Debug, Serialize)]
pub struct SeriesList {
    file: PathBuf,
    /// `dicom_directory`.
    kind: &'static str,
    series: Vec<crate::io::SeriesInfo>,
    hint: &'static str,
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
    /// What the reader changed or skipped (polygons triangulated, arrays
    /// passed over).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    notes: Vec<String>,
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
    /// What the reader skipped (VTK arrays besides the volume's).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    notes: Vec<String>,
    /// A DICOM directory: its series (the one read among them).
    #[serde(skip_serializing_if = "Option::is_none")]
    dicom_series: Option<Vec<crate::io::SeriesInfo>>,
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
    /// Mesh (.vtk .vtp .ply .obj .stl .byu), volume (.nrrd .nhdr .mhd .mha .nii
    /// .nii.gz .vtk .vti, DICOM) or a DICOM directory (several series are listed).
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

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    args.report.check()?;
    let report = if args.file.is_dir() && global.series.is_none() {
        // A DICOM directory: its series; the volume when there is one.
        let series = crate::io::dicom_series(&args.file)?;
        if series.len() == 1 {
            StatsReport::Volume(volume_stats(global, args, Some(series))?)
        } else {
            no_volume_options(args)?;
            StatsReport::Series(SeriesList {
                file: args.file.clone(),
                kind: "dicom_directory",
                series,
                hint: "choose one with --series UID",
            })
        }
    } else if crate::io::is_volume(&args.file)? {
        let series = match args.file.is_dir() {
            true => Some(crate::io::dicom_series(&args.file)?),
            false => None,
        };
        StatsReport::Volume(volume_stats(global, args, series)?)
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
    let (mesh, notes) = crate::io::read_mesh_noted(&args.file)?;
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
        notes,
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

/// `--level` and `--label` need a volume.
fn no_volume_options(args: &Args) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.level.is_none() && args.label.is_none(),
        "--level and --label need one volume; {} holds several DICOM series (--series UID \
         chooses one)",
        args.file.display()
    );
    Ok(())
}

fn volume_stats(
    global: &Global,
    args: &Args,
    series: Option<Vec<crate::io::SeriesInfo>>,
) -> anyhow::Result<VolumeStatsReport> {
    let options = crate::io::ReadOptions {
        series: global.series.clone(),
    };
    let (volume, notes) = crate::io::read_volume_with(&args.file, &options)?;
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
        notes,
        dicom_series: series,
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
