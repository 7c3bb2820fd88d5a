//! Cutting surfaces with scalpels (SPEC §5.3, seed 004 §3).
//!
//! ```text
//!  mesh + Forest ──locate (tree: expand only nodes the knife may touch)──┐
//!  mesh ───────────locate_brute_force (every triangle)───────────────────┤
//!                                                                        ▼
//!        Located: crossed triangles, cut points (identical either way)
//!                                                                        ▼
//!        assemble: exact split along the knife, regroup into connected
//!                  pieces, optional caps ──▶ CutResult { pieces, stats }
//! ```
//!
//! Files by phase:
//!
//! ```text
//!  mod.rs            API: options, stats, results; cut, cut_mesh, cut_brute_force,
//!                    cut_sequence, locate, locate_brute_force; polyhedral fallback
//!  knife.rs          knife geometry: sides, crossings, box tests
//!  locate/tree.rs    the tree walk (node classes) ─┐
//!  locate/brute_force.rs  every triangle ─────────┴─▶ locate/finish.rs: Located
//!  split.rs          assemble; split by an analytic knife (sub-triangles, caps)
//!  corefine/         triangulated knives: exact intersection (intersect.rs),
//!                    triangle splitting (face.rs), split and caps (mod.rs)
//!  cap/              caps: loops.rs, triangulate.rs (plane), sphere.rs
//!                    (refinement and repair against the cut surface), make_caps
//!  regroup.rs        pieces: connected components, numbered, in parallel chunks
//! ```
//!
//! Node classes (seed §3.1), from the root of each group down: a node whose
//! box the knife cannot touch is *clear* (class 1: one side, no expansion);
//! a node the knife may touch is expanded; after its leaves are tested it
//! is *separated* (class 2: straddled without a triangle hit) or
//! *intersected* (class 3). The seed's interval tests on cell numbers
//! become box tests in world space, which also serve knives that are not
//! aligned with the grid.
//!
//! Splitting is exact along the knife: one cut vertex per crossed mesh edge
//! (computed once per edge, from its lower-id end, so neighbours share it),
//! on the plane, on the sphere, or on the knife triangle the edge pierces.
//! A triangle with two crossed edges splits into three along the cut; one
//! with one or three crossed edges (an open knife ending inside it) splits
//! without separating, so the surface stays watertight. Pieces are the
//! connected components after the cut: triangles join across original
//! vertices and across cut vertices not separated by the cut.

mod cap;
mod corefine;
mod knife;
mod locate;
mod regroup;
mod split;

use std::time::Instant;

use glam::Vec3;

pub use corefine::{KnifeSegment, PointOrigin};
pub use knife::{Crossing, Knife, SPHERE_CHORD_ERROR, Side};

use crate::foundation::Forest;
use crate::{Error, Refusal, Result, TriMesh};
use locate::{locate_brute_force_prepared, locate_prepared};
use split::assemble;

/// Options of [`cut`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CutOptions {
    /// Close every piece with the knife surface (plane, rectangle, the
    /// sphere patch, or the part of a triangulated knife inside the solid),
    /// so closed input gives closed pieces whose volumes add up.
    pub cap: bool,
}

/// Seed §3.1 node classes counted over the visited nodes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct NodeClasses {
    /// Knife cannot touch the box: one side, not expanded.
    pub clear: usize,
    /// Expanded, no triangle crossed.
    pub separated: usize,
    /// Expanded, holds crossed triangles.
    pub intersected: usize,
}

/// What a cut did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct CutStats {
    /// Tree nodes whose box was classified (0 for a brute-force locate).
    pub nodes_visited: usize,
    /// Tree nodes in the forest.
    pub nodes_total: usize,
    /// Classes of the visited nodes.
    pub classes: NodeClasses,
    /// Triangles whose edges were tested against the knife.
    pub triangles_tested: usize,
    /// Triangles of the input.
    pub triangles_total: usize,
    /// Triangles crossed by the knife (split).
    pub triangles_split: usize,
    /// Of those, split without separating (an open knife ends inside them).
    pub triangles_partial: usize,
    /// Cut vertices created (one per crossed edge).
    pub cut_vertices: usize,
    /// Closed cut loops capped.
    pub loops_capped: usize,
    /// Cut curves left open (not capped).
    pub curves_open: usize,
    /// Rounds of sphere-cap refinement where cap triangles crossed the
    /// surface (a surface meeting the sphere at a grazing angle).
    pub cap_repair_rounds: usize,
    /// Crossings the repaired analytic sphere cap still had (cap triangles
    /// meeting surface or cap triangles beyond shared vertices, summed over
    /// the cap triangles); when nonzero the cut was redone with the
    /// polyhedral sphere (`sphere_polyhedral`).
    pub cap_crossings: u64,
    /// Whether a sphere cut ran with the polyhedral sphere
    /// ([`Knife::polyhedral_sphere`], exact intersection, caps that cannot
    /// cross the surface) because the analytic cap crossed it.
    pub sphere_polyhedral: bool,
    /// Wall time of locating crossed triangles and cut points, seconds.
    pub locate_seconds: f64,
    /// Wall time of splitting, regrouping and capping, seconds.
    pub assemble_seconds: f64,
}

/// Result of a cut.
#[derive(Debug, Clone)]
pub struct CutResult {
    /// The pieces (connected components after the cut), each its own
    /// indexed mesh; numbered by their first triangle in input order, each
    /// with its input vertices in input order, then its cut and cap points.
    pub pieces: Vec<TriMesh>,
    /// Side of each piece.
    pub sides: Vec<Side>,
    /// Counts and timings.
    pub stats: CutStats,
}

/// Crossed triangles and cut points of one knife on one mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Located {
    /// Crossed triangles, ascending ids.
    pub triangles: Vec<u32>,
    /// Per crossed triangle, the cut vertex of each edge `(v_k, v_k+1)`
    /// (index into `points`) or `u32::MAX`.
    pub edge_cuts: Vec<[u32; 3]>,
    /// Cut vertex positions (f32, as stored in the pieces).
    pub points: Vec<Vec3>,
    /// Per cut vertex, whether its edge's lower-id end is on the negative side.
    pub lower_negative: Vec<bool>,
    /// Per cut vertex, its edge `(lower id, higher id)` (for a triangulated
    /// knife: of the surface or of the knife, see `origins`); `(v, v)` for a
    /// cut at mesh vertex `v` (analytic knives: a vertex on the knife), at
    /// v's position, with `lower_negative` v's side. A cut vertex joined
    /// from crossings of one triangle that round to one point keeps the
    /// edge of the one that survives (a vertex cut if any).
    pub edges: Vec<(u32, u32)>,
    /// Triangulated knife only: per cut vertex, which edge crosses which
    /// triangle (`edge_cuts` is then empty: an edge may be crossed more
    /// than once).
    pub origins: Vec<PointOrigin>,
    /// Triangulated knife only: the cut curve, one segment per intersecting
    /// (surface triangle, knife triangle) pair, sorted by both.
    pub segments: Vec<KnifeSegment>,
    /// Query counts.
    pub stats: CutStats,
}

/// Cuts a surface organised in `forest` (from marching cubes or
/// [`Forest::from_triangles`]) with `knife`, through the tree.
pub fn cut(mesh: &TriMesh, forest: &Forest, knife: &Knife, opts: &CutOptions) -> Result<CutResult> {
    let t0 = Instant::now();
    let prepared = knife.prepare(forest_scale(forest))?;
    let mut located = locate_prepared(mesh, forest, &prepared)?;
    located.stats.locate_seconds = t0.elapsed().as_secs_f64();
    let analytic = assemble(mesh, located, &prepared, opts, Some(forest))?;
    polyhedral_if_crossed(knife, opts, analytic, |k| cut(mesh, forest, k, opts))
}

/// Orientations of the polyhedral sphere tried before giving up.
const POLYHEDRAL_ATTEMPTS: u32 = 4;

/// A capped sphere cut whose repaired cap still crosses the surface
/// (`cap_crossings > 0`: the sphere passes within f32 rounding of mesh
/// vertices, or a loop edge's chord lets a cap point land outside a surface
/// that leaves the sphere at a grazing angle) is redone with
/// [`Knife::polyhedral_sphere`] by `run`: the surface is then cut along the
/// polyhedron (within the caps' chord bound of the sphere) by the exact
/// intersection, and the caps are the polyhedron's part inside the solid,
/// which cannot cross it. An orientation the exact test refuses (a
/// degenerate touch) is replaced by the next; when every one is refused the
/// analytic result is kept, its `cap_crossings` saying what is wrong.
fn polyhedral_if_crossed(
    knife: &Knife,
    opts: &CutOptions,
    analytic: CutResult,
    run: impl Fn(&Knife) -> Result<CutResult>,
) -> Result<CutResult> {
    let Knife::Sphere { centre, radius } = knife else {
        return Ok(analytic);
    };
    if !opts.cap || analytic.stats.cap_crossings == 0 {
        return Ok(analytic);
    }
    for attempt in 0..POLYHEDRAL_ATTEMPTS {
        let poly = Knife::Mesh(Knife::polyhedral_sphere(*centre, *radius, attempt));
        match run(&poly) {
            Ok(mut r) => {
                let (a, s) = (&analytic.stats, &mut r.stats);
                s.cap_repair_rounds = a.cap_repair_rounds;
                s.cap_crossings = a.cap_crossings;
                s.sphere_polyhedral = true;
                s.locate_seconds += a.locate_seconds;
                s.assemble_seconds += a.assemble_seconds;
                return Ok(r);
            }
            // A degenerate touch of this orientation: try the next one.
            Err(Error::Refused(Refusal::KnifeContact { .. } | Refusal::CutCurve { .. })) => {}
            Err(e) => return Err(e),
        }
    }
    Ok(analytic)
}

/// Cuts any mesh: builds its forest first (virtual grid, see [`Forest::from_triangles`]).
pub fn cut_mesh(mesh: &TriMesh, knife: &Knife, opts: &CutOptions) -> Result<CutResult> {
    mesh.validate()?;
    let forest = Forest::from_triangles(mesh.view()).forest;
    cut(mesh, &forest, knife, opts)
}

/// The same cut by a plain scan of every triangle (the comparison the
/// tree is measured against); gives identical pieces.
pub fn cut_brute_force(mesh: &TriMesh, knife: &Knife, opts: &CutOptions) -> Result<CutResult> {
    let t0 = Instant::now();
    let prepared = knife.prepare(scene_scale(mesh))?;
    let mut located = locate_brute_force_prepared(mesh, &prepared)?;
    located.stats.locate_seconds = t0.elapsed().as_secs_f64();
    let analytic = assemble(mesh, located, &prepared, opts, None)?;
    polyhedral_if_crossed(knife, opts, analytic, |k| cut_brute_force(mesh, k, opts))
}

/// Several knives in sequence: each cuts every piece of the previous one.
pub fn cut_sequence(mesh: &TriMesh, knives: &[Knife], opts: &CutOptions) -> Result<CutResult> {
    let mut pieces = vec![mesh.clone()];
    let mut sides = vec![Side::Both];
    let mut stats = CutStats::default();
    for k in knives {
        let mut next = Vec::new();
        let mut next_sides = Vec::new();
        for p in &pieces {
            let r = cut_mesh(p, k, opts)?;
            stats.accumulate(&r.stats);
            next.extend(r.pieces);
            next_sides.extend(r.sides);
        }
        pieces = next;
        sides = next_sides;
    }
    Ok(CutResult {
        pieces,
        sides,
        stats,
    })
}

impl CutStats {
    /// Adds `b`'s counts and timings (several cuts reported as one).
    pub fn accumulate(&mut self, b: &CutStats) {
        let a = self;
        a.nodes_visited += b.nodes_visited;
        a.nodes_total += b.nodes_total;
        a.classes.clear += b.classes.clear;
        a.classes.separated += b.classes.separated;
        a.classes.intersected += b.classes.intersected;
        a.triangles_tested += b.triangles_tested;
        a.triangles_total += b.triangles_total;
        a.triangles_split += b.triangles_split;
        a.triangles_partial += b.triangles_partial;
        a.cut_vertices += b.cut_vertices;
        a.loops_capped += b.loops_capped;
        a.curves_open += b.curves_open;
        a.cap_repair_rounds += b.cap_repair_rounds;
        a.cap_crossings += b.cap_crossings;
        a.sphere_polyhedral |= b.sphere_polyhedral;
        a.locate_seconds += b.locate_seconds;
        a.assemble_seconds += b.assemble_seconds;
    }
}

/// Scene size from the group boxes (no pass over the vertices).
fn forest_scale(forest: &Forest) -> f64 {
    forest
        .groups
        .iter()
        .map(|g| {
            f64::from(
                g.bbox
                    .min
                    .abs()
                    .max(g.bbox.max.abs())
                    .max_element()
                    .max((g.bbox.max - g.bbox.min).max_element()),
            )
        })
        .fold(1e-30, f64::max)
}

fn scene_scale(mesh: &TriMesh) -> f64 {
    mesh.bounds().map_or(1.0, |(lo, hi)| {
        f64::from(
            lo.abs()
                .max(hi.abs())
                .max_element()
                .max((hi - lo).max_element()),
        )
    })
}

/// Locates the cut through the tree (public for benchmarks and tests).
pub fn locate(mesh: &TriMesh, forest: &Forest, knife: &Knife) -> Result<Located> {
    let prepared = knife.prepare(forest_scale(forest))?;
    locate_prepared(mesh, forest, &prepared)
}

/// Locates the cut by scanning every triangle (public for benchmarks and tests).
pub fn locate_brute_force(mesh: &TriMesh, knife: &Knife) -> Result<Located> {
    let prepared = knife.prepare(scene_scale(mesh))?;
    locate_brute_force_prepared(mesh, &prepared)
}
