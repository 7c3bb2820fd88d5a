//! `chisel relax MESH [--bone-mesh BONE] --plan PLAN` / `chisel relax --ct
//! VOLUME --skin-level L --bone-level L --plan PLAN`: takes the epidermis and bone from meshes or from a
//! CT (marching cubes), cuts the bone by the plan's knives, builds the
//! layered spring network over it (seed 000 ch. 4), runs the surgery plan
//! and writes the relaxed skin with per-vertex displacement, the moved
//! bone, before/after previews and a report.

mod skin;

pub use skin::{
    Crossings, Overshoot, SkinSpline, skin_crossings, skin_overshoot, skin_spline, spline_path,
};

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::report::{Report, ReportArgs, Show};
use super::{BackendChoice, Global, ViewAxes, vec3_arg};
use crate::tissue::ct::CtFigures;
use glam::Vec3;

use crate::gpu::Backend;
use crate::mesh::{ScalarField, TriMesh};
use crate::render::{Facing, Panel, RenderOptions, View};
use crate::tissue::ct::{CT_BENDING, CT_SUBCUTIS_DEPTH};
use crate::tissue::network::{Material, Stiffness};
use crate::tissue::{
    BoneCutFigures, CtParams, Dynamics, Fragments, Job, NetworkParams, Plan, RelaxOptions,
    RelaxReport, Solver, SpringNetwork, Status, layers_from_ct,
};

/// Arguments of `chisel relax`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Epidermis mesh (any format `chisel stats` reads); omit with `--ct`.
    #[arg(required_unless_present = "ct", conflicts_with = "ct")]
    mesh: Option<PathBuf>,
    /// CT volume: the epidermis is its surface at `--skin-level`, the bone
    /// its surface at `--bone-level` (marching cubes).
    #[arg(long, requires_all = ["skin_level", "bone_level"])]
    ct: Option<PathBuf>,
    /// Skin iso-level of the `--ct` volume (headsq: 500).
    #[arg(long, requires = "ct", allow_hyphen_values = true, value_parser = super::level_f32)]
    skin_level: Option<f32>,
    /// Bone iso-level of the `--ct` volume (headsq: 1150).
    #[arg(long, requires = "ct", allow_hyphen_values = true, value_parser = super::level_f32)]
    bone_level: Option<f32>,
    /// Bone mesh under an epidermis MESH; without it the bone layer is the
    /// skin scaled by 0.7 about the origin.
    #[arg(long, conflicts_with = "ct")]
    bone_mesh: Option<PathBuf>,
    /// Surgery plan, TOML or JSON (see `src/tissue/plans/` for examples);
    /// its `[[cut]]` knives cut the bone before the network is built.
    #[arg(long)]
    plan: PathBuf,
    /// Origin O of the layer construction `x,y,z` (default: SPEC §1.1 rule).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    origin: Option<Vec<f32>>,
    /// Subcutis at this fraction of the way from each skin vertex to the
    /// nearest bone vertex (needs a bone; default 0.5 with `--ct`, else
    /// the seed's 0.8 scaling about O).
    #[arg(long)]
    subcutis_depth: Option<f32>,
    /// With `--ct`: collapse epidermis edges shorter than this (mm; 0 keeps
    /// the marching-cubes skin; default 0.6 × the largest voxel spacing).
    #[arg(long, requires = "ct")]
    skin_min_edge: Option<f32>,
    /// Stiffness of bend springs across the epidermis's edges (beyond the
    /// seed; 0 = none). Default 1.0 with `--ct`, else 0.
    #[arg(long)]
    bending: Option<f32>,
    /// Solver: `explicit` (the seed's damped dynamics) or `chebyshev` (accelerated equilibrium).
    #[arg(long, default_value = "explicit")]
    solver: Solver,
    #[command(flatten)]
    backend: BackendChoice,
    /// Node mass m (overrides the plan's `[dynamics]`; default 1).
    #[arg(long)]
    mass: Option<f32>,
    /// Damping γ (overrides the plan's `[dynamics]`; default 0.5).
    #[arg(long)]
    damping: Option<f32>,
    /// Time step Δt (overrides the plan's `[dynamics]`; default 0.9 × the
    /// stability limit).
    #[arg(long)]
    dt: Option<f32>,
    /// Accept a Δt at or above the stability limit.
    #[arg(long)]
    force_dt: bool,
    /// ε: converged when max |v| < ε (overrides the plan's `[dynamics]`;
    /// default 1e-5 × the bounding-box diagonal).
    #[arg(long)]
    epsilon: Option<f32>,
    /// δ: stalled when the nodes moved less than δ over the window
    /// (overrides the plan's `[dynamics]`; default 10·ε·Δt).
    #[arg(long)]
    delta: Option<f32>,
    /// Stall window in iterations (overrides the plan's `[dynamics]`; default 100).
    #[arg(long)]
    window: Option<u32>,
    /// Iterations between convergence checks (overrides the plan's
    /// `[dynamics]`; default 25).
    #[arg(long)]
    check_every: Option<u32>,
    /// Iteration cap per `converge` increment (overrides the plan's
    /// `[dynamics]`; default 100 000).
    #[arg(long)]
    max_iterations: Option<u32>,
    /// Relaxed skin (PLY/VTK keep the `displacement` field), written atomically.
    #[arg(short, long)]
    output: PathBuf,
    /// The bone after the plan (cut and moved), with its `displacement`.
    #[arg(long)]
    bone_output: Option<PathBuf>,
    /// Before/after preview PNG of the skin with a displacement colour map.
    #[arg(long)]
    preview: Option<PathBuf>,
    /// Before/after preview PNG of the bone (moved fragments coloured).
    #[arg(long)]
    bone_preview: Option<PathBuf>,
    /// Also write the relaxed skin as its smooth DMS spline surface at this
    /// accuracy (points per edge) to OUTPUT with `_spline` before the
    /// extension, and add it to the preview. A closed skin is splined as
    /// its patch facing `--view-front` (default +z).
    #[arg(long)]
    spline: Option<u32>,
    #[command(flatten)]
    view: ViewAxes,
    #[command(flatten)]
    report: ReportArgs,
}

/// Runs `job` on `backend`, with a spinner, returning the report.
pub fn run_job(
    global: &Global,
    job: &Job,
    opts: &RelaxOptions,
    backend: Backend<'_>,
) -> anyhow::Result<RelaxReport> {
    let spinner = if global.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new_spinner()
    };
    spinner.set_message(format!(
        "relaxing {} nodes on {}",
        job.network.n_nodes(),
        backend.name()
    ));
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    let report = job.run(opts, backend);
    spinner.finish_and_clear();
    Ok(report?)
}

/// `mesh` with a `displacement` field: zero, or |p − before| per vertex.
fn with_displacement(mesh: &TriMesh, before: Option<&[Vec3]>) -> TriMesh {
    let values = match before {
        None => vec![0.0; mesh.n_vertices()],
        Some(b) => mesh
            .positions
            .iter()
            .zip(b)
            .map(|(p, q)| p.distance(*q))
            .collect(),
    };
    TriMesh {
        positions: mesh.positions.clone(),
        triangles: mesh.triangles.clone(),
        scalars: vec![ScalarField {
            name: "displacement".into(),
            values,
        }],
    }
}

/// The input skin with a zero `displacement` field (the "before" panel).
pub fn before_mesh(skin: &TriMesh) -> TriMesh {
    with_displacement(skin, None)
}

/// The bone mesh before and after the plan, each with its `displacement`
/// (bone nodes are the network's nodes `n_free..`, in bone-mesh order).
pub fn bone_before_after(job: &Job, report: &RelaxReport) -> Option<(TriMesh, TriMesh)> {
    let bone = job.bone.as_ref()?;
    let first = job.network.n_free;
    let moved = TriMesh {
        positions: report.positions[first..first + bone.n_vertices()]
            .iter()
            .map(|p| Vec3::new(p[0], p[1], p[2]))
            .collect(),
        triangles: bone.triangles.clone(),
        scalars: Vec::new(),
    };
    Some((
        with_displacement(bone, None),
        with_displacement(&moved, Some(&bone.positions)),
    ))
}

/// Writes a before/after preview (shared framing and colour range): one
/// column per `(mesh, caption)`, coloured by `displacement`.
pub fn write_preview(
    gpu: &crate::Gpu,
    meshes: &[(&TriMesh, &str)],
    views: Vec<View>,
    facing: Facing,
    title: String,
    path: &Path,
) -> anyhow::Result<()> {
    let panels: Vec<Panel<'_>> = meshes
        .iter()
        .map(|(mesh, caption)| Panel {
            mesh,
            caption: (*caption).into(),
            scalars: None,
        })
        .collect();
    let opts = RenderOptions {
        width: 384,
        height: 384,
        views,
        scalars: Some("displacement".into()),
        title: Some(title),
        facing,
        ..Default::default()
    };
    crate::render::render_panels(gpu, &panels, &opts)?.save_png(path)?;
    Ok(())
}

/// The report's `network` figures: node, free-node and spring counts, the
/// springs per class and the subcutis depth used (`relax` adds the origin
/// and the build time).
#[derive(Debug, Serialize)]
pub struct NetworkFigures {
    nodes: usize,
    free_nodes: usize,
    springs: usize,
    springs_per_class: [usize; 6],
    subcutis_depth: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    origin: Option<Vec3>,
    #[serde(skip_serializing_if = "Option::is_none")]
    build_seconds: Option<f64>,
}

impl NetworkFigures {
    pub fn of(net: &SpringNetwork, subcutis_depth: Option<f32>) -> Self {
        NetworkFigures {
            nodes: net.n_nodes(),
            free_nodes: net.n_free,
            springs: net.springs.len(),
            springs_per_class: net.class_counts(),
            subcutis_depth,
            origin: None,
            build_seconds: None,
        }
    }
}

/// The report of `chisel relax`.
#[derive(Debug, Serialize)]
pub struct RelaxRunReport<'a> {
    command: &'static str,
    mesh: Option<&'a Path>,
    ct: Option<CtInput<'a>>,
    bone_mesh: Option<&'a Path>,
    plan: &'a Path,
    cut: Option<&'a BoneCutFigures>,
    network: NetworkFigures,
    relax: &'a RelaxReport,
    /// `null` when the relaxation diverged (nothing was written).
    outputs: Option<RelaxOutputs<'a>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    skin_self_intersecting_pairs: Option<Crossings>,
    #[serde(skip_serializing_if = "Option::is_none")]
    skin_overshoot: Option<Overshoot>,
    #[serde(skip_serializing_if = "Option::is_none")]
    spline: Option<SkinSpline>,
}

impl Report for RelaxRunReport<'_> {
    const SCHEMA: &'static str = "chisel.relax/1";
}

/// The CT the layers came from, with what marching cubes found.
#[derive(Debug, Serialize)]
struct CtInput<'a> {
    volume: &'a Path,
    figures: &'a CtFigures,
}

#[derive(Debug, Serialize)]
struct RelaxOutputs<'a> {
    mesh: &'a Path,
    spline: Option<PathBuf>,
    bone: Option<&'a Path>,
    preview: Option<&'a Path>,
    bone_preview: Option<&'a Path>,
}

/// Where the epidermis and bone come from.
enum Input<'a> {
    /// A CT volume with the skin and bone iso-levels.
    Ct(&'a Path, f32, f32),
    /// An epidermis mesh (the bone mesh is `--bone-mesh`, if any).
    Mesh(&'a Path),
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    let t = Instant::now();
    // The preview axes are checked before the work, as the output paths are.
    let facing = args.view.facing()?;
    // Every output is checked before the work starts.
    crate::io::check_mesh_output(&args.output)?;
    if args.spline.is_some() {
        crate::io::check_mesh_output(&spline_path(&args.output))?;
    }
    if let Some(path) = &args.bone_output {
        crate::io::check_mesh_output(path)?;
    }
    for path in [&args.preview, &args.bone_preview].into_iter().flatten() {
        crate::foundation::fs::check_png_output(path)?;
    }
    args.report.check()?;
    if args.bone_mesh.is_none() && args.ct.is_none() {
        if args.bone_output.is_some() {
            anyhow::bail!("--bone-output needs a bone (--bone-mesh or --ct)");
        }
        if args.bone_preview.is_some() {
            anyhow::bail!("--bone-preview needs a bone (--bone-mesh or --ct)");
        }
    }
    let input = match (&args.ct, &args.mesh) {
        (Some(ct), _) => {
            let (Some(skin_level), Some(bone_level)) = (args.skin_level, args.bone_level) else {
                anyhow::bail!("--ct needs --skin-level LEVEL and --bone-level LEVEL");
            };
            Input::Ct(ct, skin_level, bone_level)
        }
        (None, Some(mesh)) => Input::Mesh(mesh),
        (None, None) => anyhow::bail!("give an epidermis MESH or --ct VOLUME"),
    };
    // The plan is checked before the inputs are read (a CT takes seconds);
    // its steps may select only fragments its own cuts free.
    let plan = Plan::from_path(&args.plan)?;
    plan.check_fragments(&Fragments::new())?;
    let dynamics = plan.dynamics.overridden_by(&Dynamics {
        mass: args.mass,
        damping: args.damping,
        dt: args.dt,
        epsilon: args.epsilon,
        delta: args.delta,
        window: args.window,
        check_every: args.check_every,
        max_iterations: args.max_iterations,
    });
    let gpu = global.backend(&args.backend)?;
    let backend = gpu.as_ref().map_or(Backend::Cpu, Backend::Gpu);
    let (skin, bone, ct) = match input {
        Input::Ct(ct, skin_level, bone_level) => {
            let volume = global.read_volume(ct)?;
            let mut ct_params = CtParams::for_volume(&volume, skin_level, bone_level);
            if let Some(e) = args.skin_min_edge {
                ct_params.skin_min_edge = e;
            }
            let layers = layers_from_ct(&volume, &ct_params, backend)?;
            let f = &layers.figures;
            global.note(format!(
                "CT: skin {} vertices (largest of {} groups; {} short edges collapsed, \
                 {} left below {} mm), bone {} vertices in {} groups",
                f.skin_vertices,
                f.skin_groups,
                f.skin_collapse.collapsed_edges,
                f.skin_collapse.short_edges_left,
                f.skin_collapse.min_edge,
                f.bone_vertices,
                f.bone_groups
            ));
            (layers.skin, Some(layers.bone), Some(layers.figures))
        }
        Input::Mesh(mesh) => {
            let skin = crate::io::read_surface(mesh)?;
            let bone = args
                .bone_mesh
                .as_deref()
                .map(crate::io::read_surface)
                .transpose()?;
            (skin, bone, None)
        }
    };
    let mut params = NetworkParams {
        origin: vec3_arg("origin", args.origin.as_deref())?.map(|o| o.to_array()),
        subcutis_depth: args
            .subcutis_depth
            .or(ct.as_ref().map(|_| CT_SUBCUTIS_DEPTH)),
        stiffness: Stiffness {
            bending: Material::linear(args.bending.unwrap_or(if ct.is_some() {
                CT_BENDING
            } else {
                0.0
            })),
            ..Default::default()
        },
        ..Default::default()
    };
    dynamics.apply_to_network(&mut params);
    let job = Job::build(skin, bone, plan, Fragments::new(), &params)?;
    let build_s = t.elapsed().as_secs_f64();
    global.note(format!(
        "network: {} nodes ({} free), {} springs; plan `{}` with {} cuts, {} steps",
        job.network.n_nodes(),
        job.network.n_free,
        job.network.springs.len(),
        args.plan.display(),
        job.plan.cuts.len(),
        job.plan.steps.len()
    ));
    let mut opts = RelaxOptions {
        solver: args.solver,
        force_dt: args.force_dt,
        ..Default::default()
    };
    dynamics.apply_to_options(&mut opts);
    let report = run_job(global, &job, &opts, backend)?;
    let diverged =
        report.status == Status::Diverged || report.epidermis.iter().any(|p| !p.is_finite());
    let mut network = NetworkFigures::of(&job.network, params.subcutis_depth);
    network.origin = Some(job.network.origin);
    network.build_seconds = Some(build_s);
    let mut run_report = RelaxRunReport {
        command: "relax",
        mesh: args.mesh.as_deref(),
        ct: match (&args.ct, &ct) {
            (Some(volume), Some(figures)) => Some(CtInput { volume, figures }),
            _ => None,
        },
        bone_mesh: args.bone_mesh.as_deref(),
        plan: &args.plan,
        cut: job.cut.as_ref(),
        network,
        relax: &report,
        outputs: None,
        skin_self_intersecting_pairs: None,
        skin_overshoot: None,
        spline: None,
    };
    if diverged {
        // The report says where and how; the garbage state is not written.
        if let Some(path) = &args.report.file {
            super::report::write(path, &run_report)?;
        }
        let at = report
            .steps
            .iter()
            .find_map(|s| {
                s.increments
                    .iter()
                    .find(|i| i.status == Status::Diverged)
                    .map(|i| format!(" in step `{}`, increment {}", s.name, i.increment))
            })
            .unwrap_or_default();
        anyhow::bail!(
            "the relaxation diverged{at} after {} iterations; {} \
             (use more increments, or a smaller --dt)",
            report.iterations,
            if args.report.file.is_some() {
                "only the report was written"
            } else {
                "nothing was written"
            }
        );
    }
    for s in &report.steps {
        for i in s
            .increments
            .iter()
            .filter(|i| i.status != Status::Converged)
        {
            eprintln!(
                "warning: step `{}`, increment {}: {} after {} iterations (max |v| {:.3e})",
                s.name, i.increment, i.status, i.iterations, i.max_speed
            );
        }
    }
    let relaxed = report.skin_mesh(&job.network);
    crate::io::write_mesh(&args.output, &relaxed)?;
    let crossings = skin_crossings(&job.skin, &relaxed);
    let overshoot = skin_overshoot(&job.network, &job.plan, &report)?;
    let bones = bone_before_after(&job, &report);
    if let (Some(path), Some((_, after))) = (&args.bone_output, &bones) {
        crate::io::write_mesh(path, after)?;
    }
    let spline = match args.spline {
        Some(n) => {
            let axes = match facing {
                Facing::Anatomical { up, front } => (front, up),
                _ => (Vec3::Z, Vec3::Y),
            };
            let s = skin_spline(&job.skin, &relaxed.positions, n, axes, backend)?;
            crate::io::write_mesh(&spline_path(&args.output), &s.after)?;
            Some(s)
        }
        None => None,
    };
    let title = job.plan.name.clone().unwrap_or_default();
    if args.preview.is_some() || args.bone_preview.is_some() {
        let mut opened = None;
        let preview_gpu = global.preview_gpu(&gpu, &mut opened)?;
        if let Some(path) = &args.preview {
            let before = before_mesh(&job.skin);
            let mut meshes = vec![(&before, "before"), (&relaxed, "after")];
            if let Some(s) = &spline {
                meshes.push((&s.after, "after, spline"));
            }
            write_preview(
                preview_gpu,
                &meshes,
                vec![View::Front, View::Right],
                facing,
                format!("relax: {title} - skin displacement (mesh units)"),
                path,
            )?;
        }
        if let (Some(path), Some((before, after))) = (&args.bone_preview, &bones) {
            write_preview(
                preview_gpu,
                &[(before, "before"), (after, "after")],
                vec![View::Front, View::Right],
                facing,
                format!("relax: {title} - bone displacement (mesh units)"),
                path,
            )?;
        }
    }
    global.note(format!(
        "{} after {} iterations ({:.2} s, {:.0} it/s); max displacement {:.4}; wrote {}",
        report.status,
        report.iterations,
        report.seconds,
        report.iterations_per_second,
        report.max_displacement,
        args.output.display()
    ));
    run_report.outputs = Some(RelaxOutputs {
        mesh: &args.output,
        spline: spline.as_ref().map(|_| spline_path(&args.output)),
        bone: args.bone_output.as_deref(),
        preview: args.preview.as_deref(),
        bone_preview: args.bone_preview.as_deref(),
    });
    run_report.skin_self_intersecting_pairs = Some(crossings);
    run_report.skin_overshoot = Some(overshoot);
    run_report.spline = spline;
    args.report.emit(&run_report, Show::WithJson)
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        [
            self.mesh.as_deref(),
            self.ct.as_deref(),
            self.bone_mesh.as_deref(),
            Some(self.plan.as_path()),
        ]
        .into_iter()
        .flatten()
        .collect()
    }
}
