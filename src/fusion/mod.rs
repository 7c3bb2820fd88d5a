//! Volume-preserving fusion, subtraction and morphing of closed meshes by
//! radial projection (Decaudin & Gagalowicz; seed 001 §2, SPEC §3.4).
//!
//! A and B are star-shaped about a common point H ∈ A ∩ B: every ray from H
//! crosses each surface once, at distances ρ_A(d) and ρ_B(d). The fused
//! object C has the radial function ρ = ∛(ρ_A³ + ρ_B³) (eq. 5): the cone
//! of directions dΩ holds ρ³/3·dΩ of volume, so C holds exactly the volume
//! of A and B together, the overlap's excess moved outward along the rays.
//! Subtraction uses ρ_A³ − ρ_B³ (B inside A along every ray), the morph
//! ρ_t³ = (1 − t)·ρ_A³ + t·ρ_B³ (eq. 8), whose volume is linear in t.
//!
//! C is built on a sphere of directions about H ([`sphere`]): an icosphere
//! refined by newest-vertex bisection, each vertex M projected to
//! M′ = H + ρ(d)·d (eq. 6), until every edge's projected midpoint lies
//! within the tolerance of its chord and no edge longer than
//! [`CREASE_CHORD_OF_TOLERANCE`] tolerances straddles a crease (its end
//! rays cross faces of A, or of B, more than [`CREASE_DEGREES`] apart). The rays are the GPU workload (kernel
//! `ray_cast`, room [`crate::ray_cast`]); every ray is checked to cross its
//! mesh once, so a mesh that is not star-shaped about H is refused with the
//! failing directions instead of being fused wrongly. A fusion then checks
//! exactly that every vertex of A and B lies in C ([`contain`]) and refines
//! the triangles of C that a vertex pokes through until none does.
//!
//! C is closed and wound outward (the refined icosphere is, and the radial
//! projection from an interior point keeps both); its flat triangles lie
//! in the disjoint cones of their spherical triangles, so they meet only
//! at shared edges and vertices.

pub mod center;
pub mod contain;
pub mod layered;
pub mod radial;
pub mod sphere;

use std::collections::HashSet;

use glam::Vec3;
use rayon::prelude::*;

use crate::gpu::Backend;
use crate::mesh::TriMesh;
use crate::ray_cast::{Bvh, RayCaster};
use crate::{Error, Refusal, Result};
pub use center::{Found, find_center, find_center_in};
pub use layered::LayeredReport;
pub use radial::{Frame, Law, Radial};
pub use sphere::{Edge, Pass, Project, Projected, Sphere};

/// Default start icosphere level (320 triangles).
pub const START_LEVEL: u32 = 2;
/// Default tolerance as a fraction of the larger input's bounding-box diagonal.
pub const TOLERANCE_OF_DIAGONAL: f64 = 2.5e-4;
/// Default cap on C's triangles.
pub const MAX_TRIANGLES: usize = 1 << 23;
/// A triangle straddles a crease where the faces its corners' rays cross
/// (of A, or of B) differ by more than this angle (degrees).
pub const CREASE_DEGREES: f32 = 30.0;
/// Crease splits stop at chords this many tolerances long.
pub const CREASE_CHORD_OF_TOLERANCE: f64 = 8.0;
/// Most containment rounds (each refines around the vertices outside).
pub const CONTAINMENT_ROUNDS: usize = 8;

/// Options shared by fusion and morphing.
#[derive(Debug, Clone, PartialEq)]
pub struct RefineOptions {
    /// Largest allowed distance of a projected edge midpoint from its chord
    /// (input units); `None`: [`TOLERANCE_OF_DIAGONAL`] × the larger input's
    /// bounding-box diagonal.
    pub tolerance: Option<f64>,
    /// Icosphere level to start from.
    pub start_level: u32,
    /// Refuse to make more triangles than this.
    pub max_triangles: usize,
}

impl Default for RefineOptions {
    fn default() -> Self {
        RefineOptions {
            tolerance: None,
            start_level: START_LEVEL,
            max_triangles: MAX_TRIANGLES,
        }
    }
}

impl RefineOptions {
    /// The tolerance these options ask for with inputs `a` and `b`.
    ///
    /// Errors: a tolerance that is not a positive length.
    pub fn tolerance_for(&self, a: &TriMesh, b: &TriMesh) -> Result<f64> {
        let diagonal = |m: &TriMesh| {
            m.bounds()
                .map_or(0.0, |(lo, hi)| f64::from((hi - lo).length()))
        };
        let tol = self
            .tolerance
            .unwrap_or(TOLERANCE_OF_DIAGONAL * diagonal(a).max(diagonal(b)));
        if !(tol.is_finite() && tol > 0.0) {
            return Err(Error::param("tolerance", tol, "a positive length"));
        }
        Ok(tol)
    }
}

/// Options of [`fuse`].
#[derive(Debug, Clone, PartialEq)]
pub struct FuseOptions {
    /// H; `None`: searched ([`find_center`], or [`find_center_in`] when
    /// one mesh has no kernel point in A ∩ B).
    pub center: Option<Vec3>,
    /// ρ_A³ − ρ_B³ instead of ρ_A³ + ρ_B³.
    pub subtract: bool,
    pub refine: RefineOptions,
    /// Grid cells along C's longest box side when a mesh is not
    /// star-shaped about H ([`layered`]).
    pub cells: usize,
}

impl Default for FuseOptions {
    fn default() -> Self {
        FuseOptions {
            center: None,
            subtract: false,
            refine: RefineOptions::default(),
            cells: layered::CELLS,
        }
    }
}

/// Volumes and the relative error of C's against the target.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Volumes {
    pub a: f64,
    pub b: f64,
    pub c: f64,
    /// vol(A) ± vol(B), or (1 − t)·vol(A) + t·vol(B).
    pub target: f64,
    /// |vol(C) − target| / target.
    pub relative_error: f64,
}

/// What a fusion did.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FusionReport {
    /// "fuse" or "subtract".
    pub operation: &'static str,
    /// "radial" (both meshes star-shaped about H: the refined sphere) or
    /// "layered" (one is not: the grid of [`layered`]).
    pub method: &'static str,
    pub center: [f64; 3],
    /// The search's result when H was not given.
    pub center_search: Option<Found>,
    pub tolerance: f64,
    pub volumes: Volumes,
    /// Rays cast against A and B.
    pub rays: usize,
    /// Refinement passes, in order (containment rounds' passes included).
    pub passes: Vec<Pass>,
    /// Containment rounds that found vertices of A or B outside C.
    pub containment_rounds: usize,
    /// Vertices of A and B outside C at the end (0 unless the rounds ran
    /// out; a fusion does not refuse on it, the report says it).
    pub outside: usize,
    /// Every ray crossed A and B exactly once (else the layered method ran,
    /// or a refusal).
    pub star_shaped: bool,
    /// The layered method's figures.
    pub layered: Option<LayeredReport>,
    pub vertices: usize,
    pub triangles: usize,
}

/// A fused (or subtracted) mesh and its report.
#[derive(Debug, Clone)]
pub struct Fused {
    pub mesh: TriMesh,
    pub report: FusionReport,
}

/// Refines `sphere` until every edge's deviation is within `tol`; `extra`
/// edges (of the current triangles) are split in the first pass regardless.
fn refine(
    sphere: &mut Sphere,
    project: &mut impl Project,
    tol: f64,
    max_triangles: usize,
    mut extra: HashSet<Edge>,
    passes: &mut Vec<Pass>,
    on_pass: &mut dyn FnMut(&Pass),
) -> Result<()> {
    loop {
        let directions = sphere.evaluate_midpoints(project)?;
        let edges = sphere.edges();
        let deviations: Vec<f64> = edges.par_iter().map(|&e| sphere.deviation(e)).collect();
        let max_deviation = deviations.iter().copied().fold(0.0, f64::max);
        let cos_max = CREASE_DEGREES.to_radians().cos();
        let floor = CREASE_CHORD_OF_TOLERANCE * tol;
        let mut marked: HashSet<Edge> = edges
            .iter()
            .zip(&deviations)
            .filter(|&(&e, &d)| {
                d > tol || (sphere.straddles_crease(e, cos_max) && sphere.chord(e) > floor)
            })
            .map(|(e, _)| *e)
            .collect();
        let n_marked = marked.len();
        marked.extend(extra.drain());
        if marked.is_empty() {
            return Ok(());
        }
        // Each split edge adds two triangles (closure adds more: checked after).
        if sphere.tris.len() + 2 * marked.len() > max_triangles {
            return Err(Error::limit(
                "fusion: triangles of C (raise the tolerance)",
                sphere.tris.len() + 2 * marked.len(),
                max_triangles,
            ));
        }
        sphere.refine(marked)?;
        let pass = Pass {
            triangles: sphere.tris.len(),
            directions,
            marked: n_marked,
            max_deviation,
        };
        on_pass(&pass);
        passes.push(pass);
    }
}

/// Both meshes' hierarchies, built side by side.
fn bvhs(a: &TriMesh, b: &TriMesh) -> Result<(Bvh, Bvh)> {
    let (bvh_a, bvh_b) = rayon::join(|| Bvh::build(a), || Bvh::build(b));
    Ok((bvh_a?, bvh_b?))
}

/// The given centre, or the searched one with the search's result.
fn center_of(a: &TriMesh, b: &TriMesh, given: Option<Vec3>) -> Result<(Vec3, Option<Found>)> {
    Ok(match given {
        Some(c) => (c, None),
        None => {
            let found = find_center(a, b)?;
            (glam::DVec3::from(found.center).as_vec3(), Some(found))
        }
    })
}

/// The vertices that some triangle of `m` uses.
fn used_positions(m: &TriMesh) -> Vec<Vec3> {
    let mut used = vec![false; m.positions.len()];
    for t in &m.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    m.positions
        .iter()
        .zip(used)
        .filter_map(|(p, u)| u.then_some(*p))
        .collect()
}

fn volumes(a: f64, b: f64, c: f64, target: f64) -> Volumes {
    Volumes {
        a,
        b,
        c,
        target,
        relative_error: (c - target).abs() / target.abs(),
    }
}

/// Fuses (or subtracts) closed meshes `a` and `b` (see the module docs);
/// `on_pass` sees each refinement pass (for progress). Where one mesh is
/// not star-shaped about H (and H is searched for, or the rays from the
/// given H show it), a fusion goes on by the layered method ([`layered`]);
/// the report says which method ran.
///
/// Errors: a refusal when H is not given and none is found, when a ray from
/// H does not cross A or B exactly once and the layered method cannot
/// serve (a subtraction, or neither mesh star-shaped; with the failing
/// directions), when A ∩ B is not connected for the layered method, or,
/// for a subtraction, when B reaches out of A; a limit when the tolerance
/// needs more than `max_triangles`.
pub fn fuse(
    a: &TriMesh,
    b: &TriMesh,
    options: &FuseOptions,
    backend: Backend<'_>,
    mut on_pass: impl FnMut(&Pass),
) -> Result<Fused> {
    let tol = options.refine.tolerance_for(a, b)?;
    let (bvh_a, bvh_b) = bvhs(a, b)?;
    let (ca, cb) = (
        RayCaster::new(&bvh_a, backend)?,
        RayCaster::new(&bvh_b, backend)?,
    );
    let (center, center_search, mut not_star) = match options.center {
        Some(c) => (c, None, None),
        None => match find_center(a, b) {
            Ok(found) => (glam::DVec3::from(found.center).as_vec3(), Some(found), None),
            Err(Error::Refused(Refusal::NoStarCenter(why))) if !options.subtract => {
                // One mesh may have no kernel point in A ∩ B: §2.6.2 from
                // the other's.
                let found = find_center_in(b, a, ["B", "A"])
                    .map(|f| (f, "A"))
                    .or_else(|e| {
                        find_center_in(a, b, ["A", "B"])
                            .map(|f| (f, "B"))
                            .map_err(|_| e)
                    });
                match found {
                    Ok((f, which)) => (glam::DVec3::from(f.center).as_vec3(), Some(f), Some(which)),
                    Err(Error::Refused(Refusal::NoStarCenter(other))) => {
                        return Err(Refusal::NoStarCenter(format!("{why}; and {other}")).into());
                    }
                    Err(e) => return Err(e),
                }
            }
            Err(e) => return Err(e),
        },
    };
    if not_star.is_none() {
        match fuse_radial(
            (a, &ca),
            (b, &cb),
            center,
            center_search,
            options,
            tol,
            &mut on_pass,
        ) {
            Err(Error::Refused(Refusal::NotStarShaped { mesh, .. })) if !options.subtract => {
                not_star = Some(mesh);
            }
            other => return other,
        }
    }
    let ((n, cn), (s, cs), names) = if not_star == Some("B") {
        ((b, &cb), (a, &ca), ["B", "A"])
    } else {
        ((a, &ca), (b, &cb), ["A", "B"])
    };
    let l = layered::fuse_layered(
        (n, cn),
        (s, cs),
        names,
        center,
        options.cells,
        backend,
        &mut on_pass,
    )?;
    let (va, vb) = (a.signed_volume().abs(), b.signed_volume().abs());
    let report = FusionReport {
        operation: "fuse",
        method: "layered",
        center: center.as_dvec3().to_array(),
        center_search,
        tolerance: tol,
        volumes: volumes(va, vb, l.mesh.signed_volume(), va + vb),
        rays: l.rays,
        passes: Vec::new(),
        containment_rounds: 0,
        outside: l.outside,
        star_shaped: false,
        layered: Some(l.report),
        vertices: l.mesh.positions.len(),
        triangles: l.mesh.triangles.len(),
    };
    Ok(Fused {
        mesh: l.mesh,
        report,
    })
}

/// The radial method: both meshes star-shaped about `center`.
fn fuse_radial(
    a: (&TriMesh, &RayCaster<'_>),
    b: (&TriMesh, &RayCaster<'_>),
    center: Vec3,
    center_search: Option<Found>,
    options: &FuseOptions,
    tol: f64,
    on_pass: &mut dyn FnMut(&Pass),
) -> Result<Fused> {
    let law = if options.subtract {
        Law::Difference
    } else {
        Law::Sum
    };
    let mut radial = Radial {
        a,
        b,
        frames: vec![Frame { center, law }],
        rays: 0,
    };
    let mut sphere = Sphere::start(options.refine.start_level, &mut radial)?;
    let mut passes = Vec::new();
    let max = options.refine.max_triangles;
    refine(
        &mut sphere,
        &mut radial,
        tol,
        max,
        HashSet::new(),
        &mut passes,
        on_pass,
    )?;

    let (mut rounds, mut outside) = (0, 0);
    if !options.subtract {
        let points: Vec<Vec3> = used_positions(a.0)
            .into_iter()
            .chain(used_positions(b.0))
            .collect();
        loop {
            let c = sphere.mesh(0);
            let bvh_c = Bvh::build(&c)?;
            let cc = RayCaster::new(&bvh_c, a.1.backend())?;
            let out = contain::outside(&c, &cc, center, &points)?;
            outside = out.len();
            if out.is_empty() || rounds == CONTAINMENT_ROUNDS {
                break;
            }
            rounds += 1;
            let extra: HashSet<Edge> = out
                .iter()
                .filter(|o| o.triangle != u32::MAX)
                .flat_map(|o| {
                    let t = sphere.tris[o.triangle as usize];
                    (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])))
                })
                .collect();
            if extra.is_empty() {
                break;
            }
            refine(
                &mut sphere,
                &mut radial,
                tol,
                max,
                extra,
                &mut passes,
                on_pass,
            )?;
        }
    }

    let mesh = sphere.mesh(0);
    let (va, vb) = (a.0.signed_volume().abs(), b.0.signed_volume().abs());
    let target = if options.subtract { va - vb } else { va + vb };
    let report = FusionReport {
        operation: if options.subtract { "subtract" } else { "fuse" },
        method: "radial",
        center: center.as_dvec3().to_array(),
        center_search,
        tolerance: tol,
        volumes: volumes(va, vb, mesh.signed_volume(), target),
        rays: radial.rays,
        passes,
        containment_rounds: rounds,
        outside,
        star_shaped: true,
        layered: None,
        vertices: mesh.positions.len(),
        triangles: mesh.triangles.len(),
    };
    Ok(Fused { mesh, report })
}

/// Options of [`morph`].
#[derive(Debug, Clone, PartialEq)]
pub struct MorphOptions {
    /// H at t = 0; `None`: searched ([`find_center`]).
    pub center: Option<Vec3>,
    /// H at t = 1 (H moves linearly in t); `None`: H stays.
    pub center_end: Option<Vec3>,
    /// Number of frames (t = k/(frames − 1)), at least 2.
    pub frames: usize,
    pub refine: RefineOptions,
}

/// Per frame of a morph.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MorphFrame {
    pub t: f64,
    pub center: [f64; 3],
    pub volumes: Volumes,
}

/// What a morph did.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MorphReport {
    pub center_search: Option<Found>,
    pub tolerance: f64,
    pub rays: usize,
    pub passes: Vec<Pass>,
    pub frames: Vec<MorphFrame>,
    pub vertices: usize,
    pub triangles: usize,
}

/// The frames of a morph: one triangle list, positions per frame.
#[derive(Debug, Clone)]
pub struct Morph {
    pub frames: Vec<TriMesh>,
    pub report: MorphReport,
}

/// Morphs `a` into `b` (eq. 8) over `options.frames` frames with one mesh
/// connectivity, refined until every frame is within the tolerance;
/// `on_pass` sees each refinement pass.
///
/// Errors: as [`fuse`]; fewer than 2 frames.
pub fn morph(
    a: &TriMesh,
    b: &TriMesh,
    options: &MorphOptions,
    backend: Backend<'_>,
    mut on_pass: impl FnMut(&Pass),
) -> Result<Morph> {
    if options.frames < 2 {
        return Err(Error::param("frames", options.frames, "at least 2"));
    }
    let tol = options.refine.tolerance_for(a, b)?;
    let (bvh_a, bvh_b) = bvhs(a, b)?;
    let (ca, cb) = (
        RayCaster::new(&bvh_a, backend)?,
        RayCaster::new(&bvh_b, backend)?,
    );
    let (start, center_search) = center_of(a, b, options.center)?;
    let end = options.center_end.unwrap_or(start);
    let last = (options.frames - 1) as f64;
    let frames: Vec<Frame> = (0..options.frames)
        .map(|k| {
            let t = k as f64 / last;
            let center = if end == start {
                start
            } else {
                (start.as_dvec3() + t * (end - start).as_dvec3()).as_vec3()
            };
            Frame {
                center,
                law: Law::Morph(t),
            }
        })
        .collect();
    let mut radial = Radial {
        a: (a, &ca),
        b: (b, &cb),
        frames,
        rays: 0,
    };
    let mut sphere = Sphere::start(options.refine.start_level, &mut radial)?;
    let mut passes = Vec::new();
    refine(
        &mut sphere,
        &mut radial,
        tol,
        options.refine.max_triangles,
        HashSet::new(),
        &mut passes,
        &mut on_pass,
    )?;
    let (va, vb) = (a.signed_volume().abs(), b.signed_volume().abs());
    let meshes: Vec<TriMesh> = (0..sphere.n_frames()).map(|k| sphere.mesh(k)).collect();
    let report_frames = radial
        .frames
        .iter()
        .zip(&meshes)
        .map(|(f, m)| {
            let Law::Morph(t) = f.law else {
                unreachable!("morph frames")
            };
            MorphFrame {
                t,
                center: f.center.as_dvec3().to_array(),
                volumes: volumes(va, vb, m.signed_volume(), (1.0 - t) * va + t * vb),
            }
        })
        .collect();
    let report = MorphReport {
        center_search,
        tolerance: tol,
        rays: radial.rays,
        passes,
        frames: report_frames,
        vertices: meshes[0].positions.len(),
        triangles: meshes[0].triangles.len(),
    };
    Ok(Morph {
        frames: meshes,
        report,
    })
}
