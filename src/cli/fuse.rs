//! `chisel fuse A B -o C.ply`: the volume-preserving fusion (or, with
//! `--subtract`, the subtraction) of two closed meshes star-shaped about a
//! common centre, or of one that is not with one that is (seed 001 §2,
//! §2.6.2; SPEC §3.4).

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use serde::Serialize;

use super::report::{Report, ReportArgs, Show};
use super::{BackendChoice, Global, ViewAxes};
use crate::fusion::{FuseOptions, FusionReport, Pass, RefineOptions, fuse};
use crate::gpu::Backend;
use crate::mesh::distance::DistanceGrid;
use crate::mesh::{ScalarField, TriMesh};
use crate::render::{Panel, RenderOptions, View};
use crate::{Error, Refusal};

/// Arguments of `chisel fuse`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Mesh A (closed; any format `chisel stats` reads).
    a: PathBuf,
    /// Mesh B (closed).
    b: PathBuf,
    #[command(flatten)]
    shape: ShapeArgs,
    /// Subtract B from A (ρ³ = ρ_A³ − ρ_B³; B must lie inside A along
    /// every ray from the centre).
    #[arg(long)]
    subtract: bool,
    /// Grid cells along C's longest side when one mesh is not star-shaped
    /// about the centre (the layered fusion of seed 001 §2.6.2).
    #[arg(long, default_value_t = crate::fusion::layered::CELLS)]
    cells: usize,
    #[command(flatten)]
    backend: BackendChoice,
    /// The fused mesh (written atomically).
    #[arg(short, long)]
    output: PathBuf,
    /// Preview PNG: A and B (coloured by mesh) beside C (coloured by its
    /// distance to A or B); on a refusal, A and B with the failing rays.
    #[arg(long)]
    preview: Option<PathBuf>,
    #[command(flatten)]
    view: ViewAxes,
    #[command(flatten)]
    report: ReportArgs,
}

/// Options `fuse` and `morph` share: the centre and the refinement.
#[derive(Debug, Clone, clap::Args)]
pub struct ShapeArgs {
    /// The centre H `x,y,z`, a point of A ∩ B from which both are
    /// star-shaped, or (fuse) at least one of them (default: the deepest
    /// common point of both meshes' kernels, found by a linear programme,
    /// else the deepest point of one kernel inside the other mesh).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    center: Option<Vec<f32>>,
    /// Largest distance of a projected edge midpoint from its chord, in the
    /// inputs' units (default: 2.5·10⁻⁴ of the larger bounding-box diagonal).
    #[arg(long)]
    tolerance: Option<f64>,
    /// Icosphere level the refinement starts from.
    #[arg(long, default_value_t = crate::fusion::START_LEVEL)]
    start_level: u32,
    /// Refuse to make more triangles than this.
    #[arg(long, default_value_t = crate::fusion::MAX_TRIANGLES)]
    max_triangles: usize,
}

impl ShapeArgs {
    pub(super) fn center(&self) -> anyhow::Result<Option<Vec3>> {
        super::vec3_arg("center", self.center.as_deref())
    }

    pub(super) fn refine(&self) -> RefineOptions {
        RefineOptions {
            tolerance: self.tolerance,
            start_level: self.start_level,
            max_triangles: self.max_triangles,
        }
    }
}

/// The report of `chisel fuse`.
#[derive(Debug, Serialize)]
pub struct FuseReport<'a> {
    command: &'static str,
    a: &'a Path,
    b: &'a Path,
    #[serde(flatten)]
    fusion: &'a FusionReport,
    backend: &'static str,
    adapter: Option<String>,
    timings_s: Timings,
    outputs: Outputs<'a>,
}

impl Report for FuseReport<'_> {
    const SCHEMA: &'static str = "chisel.fuse/1";
}

#[derive(Debug, Serialize)]
struct Timings {
    read: f64,
    fuse: f64,
    total: f64,
}

#[derive(Debug, Serialize)]
struct Outputs<'a> {
    mesh: &'a Path,
    preview: Option<&'a Path>,
}

/// A and B read, with their names for captions.
pub(super) fn read_pair(a: &Path, b: &Path) -> anyhow::Result<(TriMesh, TriMesh)> {
    Ok((crate::io::read_surface(a)?, crate::io::read_surface(b)?))
}

/// A progress bar over a refinement: the position follows the largest
/// deviation on a log scale from the first pass's down to the tolerance.
pub(super) struct RefineProgress {
    pub bar: indicatif::ProgressBar,
    first: Option<f64>,
    tolerance: f64,
}

impl RefineProgress {
    pub(super) fn new(global: &Global, what: &str, tolerance: f64) -> Self {
        RefineProgress {
            bar: global.progress(100, what),
            first: None,
            tolerance,
        }
    }

    pub(super) fn pass(&mut self, pass: &Pass) {
        let first = *self.first.get_or_insert(pass.max_deviation);
        let span = (first / self.tolerance).ln().max(1e-9);
        let done = (first / pass.max_deviation.max(self.tolerance)).ln() / span;
        self.bar.set_position((100.0 * done.clamp(0.0, 1.0)) as u64);
    }
}

/// The meshes as one, with a `mesh` scalar: its index in `parts`.
fn together(parts: &[&TriMesh]) -> TriMesh {
    let mut m = TriMesh::default();
    let mut values = Vec::new();
    for (k, part) in parts.iter().enumerate() {
        let n = m.positions.len() as u32;
        m.positions.extend(&part.positions);
        m.triangles
            .extend(part.triangles.iter().map(|t| t.map(|v| v + n)));
        values.resize(m.positions.len(), k as f32);
    }
    m.scalars.push(ScalarField {
        name: "mesh".into(),
        values,
    });
    m
}

/// Thin triangular prisms from `center` along `dirs`, `length` long.
fn needles(center: Vec3, dirs: &[[f32; 3]], length: f32) -> TriMesh {
    let mut m = TriMesh::default();
    let width = 0.004 * length;
    for d in dirs {
        let d = Vec3::from(*d).normalize_or_zero();
        let side = d.any_orthonormal_vector() * width;
        let up = d.cross(side);
        let base = m.positions.len() as u32;
        for end in [center, center + d * length] {
            m.positions
                .extend([end + side, end - side * 0.5 + up, end - side * 0.5 - up]);
        }
        for k in 0..3u32 {
            let (i, j) = (base + k, base + (k + 1) % 3);
            m.triangles.push([i, j, j + 3]);
            m.triangles.push([i, j + 3, i + 3]);
        }
    }
    m
}

/// The failing rays of a refusal, if it is one with rays.
fn failing_rays(e: &Error) -> Option<(Vec3, Vec<[f32; 3]>)> {
    match e {
        Error::Refused(
            Refusal::NotStarShaped {
                center, examples, ..
            }
            | Refusal::OpenAlongRays {
                center, examples, ..
            },
        ) => Some((
            glam::DVec3::from(*center).as_vec3(),
            examples.iter().map(|(d, _)| *d).collect(),
        )),
        _ => None,
    }
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    let facing = args.view.facing()?;
    let t0 = Instant::now();
    crate::io::check_mesh_output(&args.output)?;
    if let Some(p) = &args.preview {
        crate::foundation::fs::check_png_output(p)?;
    }
    args.report.check()?;
    let center = args.shape.center()?;
    let (a, b) = read_pair(&args.a, &args.b)?;
    let read_s = t0.elapsed().as_secs_f64();
    let gpu = global.backend(&args.backend)?;
    let backend = gpu.as_ref().map_or(Backend::Cpu, Backend::Gpu);
    let options = FuseOptions {
        center,
        subtract: args.subtract,
        refine: args.shape.refine(),
        cells: args.cells,
    };
    let mut progress = RefineProgress::new(
        global,
        "fuse: refine",
        args.shape.refine().tolerance_for(&a, &b)?,
    );
    let t1 = Instant::now();
    let result = fuse(&a, &b, &options, backend, |p| progress.pass(p));
    progress.bar.finish_and_clear();
    let fused = match result {
        Ok(f) => f,
        Err(e) => {
            if let (Some(path), Some((h, dirs))) = (&args.preview, failing_rays(&e)) {
                let diagonal = together(&[&a, &b])
                    .bounds()
                    .map_or(1.0, |(lo, hi)| (hi - lo).length());
                let rays = needles(h, &dirs, 0.75 * diagonal);
                let mut opened = None;
                let g = global.preview_gpu(&gpu, &mut opened)?;
                let image = crate::render::render_panels(
                    g,
                    &[Panel {
                        mesh: &together(&[&a, &b, &rays]),
                        caption: format!("A 0, B 1, {} rays 2", dirs.len()),
                        scalars: Some("mesh".into()),
                    }],
                    &RenderOptions {
                        width: 512,
                        height: 512,
                        views: vec![View::Front, View::Iso],
                        title: Some(format!("chisel fuse refused: {e}")),
                        facing,
                        ..Default::default()
                    },
                )?;
                image.save_png(path)?;
                global.note(format!("wrote the failing rays to {}", path.display()));
            }
            return Err(e.into());
        }
    };
    let fuse_s = t1.elapsed().as_secs_f64();
    crate::io::write_mesh(&args.output, &fused.mesh)?;
    let r = &fused.report;
    if let Some(path) = &args.preview {
        let inputs = together(&[&a, &b]);
        // C coloured by its distance to A ∪ B over the largest: where the
        // overlap's excess went (the colour bar is shared with `mesh`).
        let mut c = fused.mesh.clone();
        let to_inputs = DistanceGrid::new(&inputs);
        let d: Vec<f64> = c.positions.iter().map(|p| to_inputs.distance(*p)).collect();
        let largest = d.iter().copied().fold(0.0, f64::max);
        c.scalars.push(ScalarField {
            name: "moved".into(),
            values: d
                .iter()
                .map(|x| (x / largest.max(f64::MIN_POSITIVE)) as f32)
                .collect(),
        });
        let mut opened = None;
        let g = global.preview_gpu(&gpu, &mut opened)?;
        let image = crate::render::render_panels(
            g,
            &[
                Panel {
                    mesh: &inputs,
                    caption: "A, B".into(),
                    scalars: Some("mesh".into()),
                },
                Panel {
                    mesh: &c,
                    caption: format!("C ({} triangles)", r.triangles),
                    scalars: Some("moved".into()),
                },
            ],
            &RenderOptions {
                width: 384,
                height: 384,
                views: vec![View::Front, View::Right, View::Iso],
                title: Some(format!(
                    "chisel {}: {} (0) and {} (1); C coloured by distance to A or B over its largest, {:.3e}; volume error {:.1e}",
                    r.operation,
                    super::file_name(&args.a),
                    super::file_name(&args.b),
                    largest,
                    r.volumes.relative_error
                )),
                facing,
                ..Default::default()
            },
        )?;
        image.save_png(path)?;
    }
    global.note(format!(
        "{}: H ({:.4}, {:.4}, {:.4}), {} triangles, vol A {:.6e} + B {:.6e} → C {:.6e} (relative error {:.2e}), {} rays; wrote {}",
        r.operation,
        r.center[0],
        r.center[1],
        r.center[2],
        r.triangles,
        r.volumes.a,
        r.volumes.b,
        r.volumes.c,
        r.volumes.relative_error,
        r.rays,
        args.output.display()
    ));
    let report = FuseReport {
        command: if args.subtract {
            "fuse --subtract"
        } else {
            "fuse"
        },
        a: &args.a,
        b: &args.b,
        fusion: r,
        backend: backend.name(),
        adapter: gpu.as_ref().map(|g| g.describe()),
        timings_s: Timings {
            read: read_s,
            fuse: fuse_s,
            total: t0.elapsed().as_secs_f64(),
        },
        outputs: Outputs {
            mesh: &args.output,
            preview: args.preview.as_deref(),
        },
    };
    args.report.emit(&report, Show::WithJson)
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        vec![self.a.as_path(), self.b.as_path()]
    }
}
