//! `chisel cut MESH --plane ... | --rect ... | --sphere ... | --knife ...`:
//! scalpel cuts through the bounding-box B+ tree (seed 004 §3), optionally
//! capped so every piece is closed.

use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};
use serde::Serialize;

use super::report::{Report, ReportArgs, Show};
use super::{Global, ViewAxes};
use crate::cut::{CutOptions, CutStats, Knife, cut_sequence};
use crate::mesh::{ScalarField, TriMesh};
use crate::render::RenderOptions;

/// The report of `chisel cut`.
#[derive(Debug, Serialize)]
pub struct CutReport<'a> {
    command: &'static str,
    mesh: &'a Path,
    input_triangles: usize,
    input_signed_volume: f64,
    knives: usize,
    cap: bool,
    pieces: Vec<Piece>,
    stats: &'a CutStats,
}

impl Report for CutReport<'_> {
    const SCHEMA: &'static str = "chisel.cut/1";
}

/// One piece written by `chisel cut`.
#[derive(Debug, Serialize)]
struct Piece {
    file: PathBuf,
    /// `positive` or `negative`: the side of the (last) knife.
    side: String,
    vertices: usize,
    triangles: usize,
    closed: bool,
    manifold: bool,
    signed_volume: f64,
    /// Crossing triangle pairs of a capped piece (`null` uncapped).
    self_intersecting_pairs: Option<usize>,
}

/// Arguments of `chisel cut`. Knives apply in the order planes, rectangles,
/// spheres, meshes; each may be given several times.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Mesh to cut.
    mesh: PathBuf,
    /// Infinite plane `px,py,pz,nx,ny,nz` (a point and the normal).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, action = clap::ArgAction::Append)]
    plane: Vec<f64>,
    /// Bounded rectangle `cx,cy,cz,nx,ny,nz,ux,uy,uz,hu,hv` (centre, normal,
    /// in-plane u axis, half extents along u and v = n × u).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, action = clap::ArgAction::Append)]
    rect: Vec<f64>,
    /// Sphere `cx,cy,cz,r`.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, action = clap::ArgAction::Append)]
    sphere: Vec<f64>,
    /// A triangulated knife surface (any mesh format).
    #[arg(long)]
    knife: Vec<PathBuf>,
    /// Close each piece with the knife surface (planes, rectangles, the
    /// sphere patch, the part of a triangulated knife inside the solid).
    #[arg(long)]
    cap: bool,
    /// Output folder for `piece_NNN.ply` (created if missing).
    #[arg(short, long)]
    output: PathBuf,
    /// Preview PNG with the pieces coloured by index.
    #[arg(long)]
    preview: Option<PathBuf>,
    /// In the preview, each piece moves away from the mesh's centre by
    /// this fraction of its own centre's offset, so pieces inside others
    /// show (0: in place, at most 10). Bounding-box centres; the written
    /// pieces never move.
    #[arg(long, default_value_t = 0.3)]
    explode: f32,
    #[command(flatten)]
    view: ViewAxes,
    #[command(flatten)]
    report: ReportArgs,
}

fn v3(a: &[f64]) -> DVec3 {
    DVec3::new(a[0], a[1], a[2])
}

fn knives(args: &Args) -> anyhow::Result<Vec<Knife>> {
    for (name, values, n) in [
        ("plane", &args.plane, 6),
        ("rect", &args.rect, 11),
        ("sphere", &args.sphere, 4),
    ] {
        anyhow::ensure!(
            values.len() % n == 0,
            "--{name} takes {n} comma-separated numbers per knife, got {} in all",
            values.len()
        );
    }
    let mut out: Vec<Knife> = args
        .plane
        .chunks_exact(6)
        .map(|p| Knife::Plane {
            point: v3(p),
            normal: v3(&p[3..]),
        })
        .collect();
    out.extend(args.rect.chunks_exact(11).map(|r| Knife::Rect {
        centre: v3(r),
        normal: v3(&r[3..]),
        u_axis: v3(&r[6..]),
        half_extents: [r[9], r[10]],
    }));
    out.extend(args.sphere.chunks_exact(4).map(|s| Knife::Sphere {
        centre: v3(s),
        radius: s[3],
    }));
    for path in &args.knife {
        out.push(Knife::Mesh(crate::io::read_surface(path)?));
    }
    anyhow::ensure!(
        !out.is_empty(),
        "give at least one knife: --plane, --rect, --sphere or --knife"
    );
    Ok(out)
}

/// All pieces in one mesh with a `piece` scalar (for the preview), each
/// moved by `explode` × (its box centre − the centre of all boxes).
fn merged(pieces: &[TriMesh], explode: f32) -> TriMesh {
    let centre = |b: Option<(Vec3, Vec3)>| b.map_or(Vec3::ZERO, |(lo, hi)| (lo + hi) * 0.5);
    let all = pieces
        .iter()
        .filter_map(TriMesh::bounds)
        .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)));
    let mut m = TriMesh::default();
    let mut ids = Vec::new();
    for (k, p) in pieces.iter().enumerate() {
        let base = m.positions.len() as u32;
        let shift = explode * (centre(p.bounds()) - centre(all));
        m.positions.extend(p.positions.iter().map(|&q| q + shift));
        m.triangles
            .extend(p.triangles.iter().map(|t| t.map(|v| v + base)));
        ids.extend(std::iter::repeat_n(k as f32, p.n_vertices()));
    }
    m.scalars.push(ScalarField {
        name: "piece".into(),
        values: ids,
    });
    m
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    // The preview axes are checked before the work, as the output paths are.
    let facing = args.view.facing()?;
    if !(0.0..=10.0).contains(&args.explode) {
        anyhow::bail!("--explode must be between 0 and 10, got {}", args.explode);
    }
    super::check_output_dir(&args.output)?;
    if let Some(path) = &args.preview {
        crate::foundation::fs::check_png_output(path)?;
    }
    args.report.check()?;
    let mesh = crate::io::read_surface(&args.mesh)?;
    let knives = knives(args)?;
    let result = cut_sequence(&mesh, &knives, &CutOptions { cap: args.cap })?;
    super::clear_numbered_outputs(global, &args.output, "piece_")?;
    let mut pieces = Vec::new();
    for (k, (piece, side)) in result.pieces.iter().zip(&result.sides).enumerate() {
        let path = args.output.join(format!("piece_{k:03}.ply"));
        crate::io::write_mesh(&path, piece)?;
        let topo = crate::mesh::Topology::of(piece);
        // Caps are new geometry: check them (uncapped pieces are parts of
        // the input and keep its crossings, if any).
        let crossings = args
            .cap
            .then(|| crate::mesh::self_intersections(piece).pairs.len());
        pieces.push(Piece {
            file: path,
            side: format!("{side:?}").to_lowercase(),
            vertices: piece.n_vertices(),
            triangles: piece.n_triangles(),
            closed: topo.closed,
            manifold: topo.nonmanifold_edges == 0 && topo.nonmanifold_vertices == 0,
            signed_volume: topo.signed_volume,
            self_intersecting_pairs: crossings,
        });
    }
    if let Some(path) = &args.preview {
        let gpu = global.gpu()?;
        let opts = RenderOptions {
            scalars: Some("piece".into()),
            ..super::preview_options(
                if args.explode == 0.0 {
                    format!("chisel cut: {} pieces", result.pieces.len())
                } else {
                    format!(
                        "chisel cut: {} pieces, exploded {}",
                        result.pieces.len(),
                        args.explode
                    )
                },
                facing,
            )
        };
        crate::render::render_png(&gpu, &merged(&result.pieces, args.explode), &opts, path)?;
    }
    let crossings: usize = pieces
        .iter()
        .filter_map(|p| p.self_intersecting_pairs)
        .sum();
    let report = CutReport {
        command: "cut",
        mesh: &args.mesh,
        input_triangles: mesh.n_triangles(),
        input_signed_volume: crate::mesh::Topology::of(&mesh).signed_volume,
        knives: knives.len(),
        cap: args.cap,
        pieces,
        stats: &result.stats,
    };
    if result.stats.sphere_polyhedral {
        global.note(format!(
            "the sphere cap crossed the surface ({} crossings left after {} repair rounds): \
             cut along the polyhedral sphere instead (within {} r of the sphere)",
            result.stats.cap_crossings,
            result.stats.cap_repair_rounds,
            crate::cut::SPHERE_CHORD_ERROR
        ));
    }
    let s = &result.stats;
    if s.triangles_split == 0 {
        eprintln!(
            "warning: the knives cross no triangle of {}: the pieces are its connected components",
            args.mesh.display()
        );
    }
    if args.cap && s.curves_open > 0 {
        eprintln!(
            "warning: {} cut curve(s) end inside the surface (a rectangle or knife mesh that \
             does not cut through, or a surface border): they are not capped, and the pieces \
             they bound stay open (`closed: false` in the report), the two sides of each such \
             slit touching along it ({crossings} touching or crossing triangle pairs in all)",
            s.curves_open
        );
    } else if crossings > 0 {
        eprintln!(
            "warning: capped pieces cross themselves in {crossings} triangle pairs; a crossing \
             input keeps its crossings (`chisel stats` counts them)"
        );
    }
    global.note(format!(
        "{} pieces; tree visited {} of {} nodes, tested {} of {} triangles; wrote {}",
        result.pieces.len(),
        result.stats.nodes_visited,
        result.stats.nodes_total,
        result.stats.triangles_tested,
        result.stats.triangles_total,
        args.output.display()
    ));
    args.report.emit(&report, Show::WithJson)
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        std::iter::once(self.mesh.as_path())
            .chain(self.knife.iter().map(|k| k.as_path()))
            .collect()
    }
}
