//! What `chisel relax` (and the demo) tells of the relaxed skin beside the
//! mesh: its smooth spline before and after (`--spline`), how far it
//! overshoots the bone, and whether it crosses itself.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use serde::Serialize;

use crate::gpu::Backend;
use crate::mesh::{ScalarField, TriMesh};
use crate::tissue::network::SpringClass;
use crate::tissue::stepper::bone_displacements;
use crate::tissue::{Plan, RelaxReport, SpringNetwork};

/// The smooth skin before and after a relaxation (`relax --spline`, the
/// demo): the quadratic DMS spline at accuracy `n` with the
/// quasi-interpolation control net, whose rows are built once from the
/// skin before and gathered for both states. An open skin is splined
/// whole (cylinder parametrisation); a closed one (a CT's) as its largest
/// patch facing `front` within 60° (its plane across `front`).
#[derive(Debug, Serialize)]
pub struct SkinSpline {
    n: u32,
    /// `whole skin` or `patch facing [x, y, z]`.
    domain: String,
    patch_vertices: usize,
    points: usize,
    triangles: usize,
    knot_quality: f64,
    control_net: &'static str,
    /// Largest |F_after(u) − F_before(u)| over the points.
    max_displacement: f32,
    seconds: f64,
    /// The spline after the relaxation, with `displacement` and normals.
    #[serde(skip)]
    pub after: TriMesh,
}

/// The smallest normal component along the patch direction (cos 60°).
const PATCH_MIN_COS: f32 = 0.5;

/// [`SkinSpline`] of `before` → `after` (same connectivity).
pub fn skin_spline(
    before: &TriMesh,
    after: &[Vec3],
    n: u32,
    (front, up): (Vec3, Vec3),
    backend: Backend<'_>,
) -> anyhow::Result<SkinSpline> {
    use crate::dms::patch::facing_patch;
    use crate::dms::{Fit, Projection, SplineDomain};
    let t = Instant::now();
    let closed = crate::dms::param::boundary_edges(&before.triangles).is_empty();
    let (mesh, vertices, projection, domain) = if closed {
        let p = facing_patch(before, front, up, PATCH_MIN_COS)?;
        let d = format!("patch facing [{}, {}, {}]", front.x, front.y, front.z);
        (p.mesh, p.vertices, Projection::Given(p.uv), d)
    } else {
        let all = (0..before.n_vertices() as u32).collect();
        (
            before.clone(),
            all,
            Projection::Cylinder,
            "whole skin".into(),
        )
    };
    let sd = SplineDomain::new(&mesh, &projection, n, backend)
        .map_err(|e| anyhow::anyhow!("the skin's spline ({domain}): {e}"))?;
    let map = (sd.control_map(&Fit::Quasi))
        .ok_or_else(|| anyhow::anyhow!("quasi-interpolation is a control map"))?
        .gather_input(mesh.n_vertices());
    let rows = sd.control_rows();
    let of = |p: &[Vec3]| -> Vec<[f32; 4]> {
        vertices
            .iter()
            .map(|&v| p[v as usize].extend(0.0).to_array())
            .collect()
    };
    let s0 = sd.skin(&map, &rows, &of(&before.positions), backend)?;
    let s1 = sd.skin(&map, &rows, &of(after), backend)?;
    let moved = TriMesh {
        positions: vertices.iter().map(|&v| after[v as usize]).collect(),
        triangles: mesh.triangles.clone(),
        scalars: Vec::new(),
    };
    let mut out = sd.surface_mesh(&s1, &moved);
    let displacement: Vec<f32> = (s0.positions.iter().zip(&s1.positions))
        .map(|(a, b)| Vec3::from_slice(&a[..3]).distance(Vec3::from_slice(&b[..3])))
        .collect();
    let max_displacement = displacement.iter().copied().fold(0.0, f32::max);
    out.scalars.retain(|f| f.name != "distance");
    out.scalars.push(ScalarField {
        name: "displacement".into(),
        values: displacement,
    });
    Ok(SkinSpline {
        n,
        domain,
        patch_vertices: mesh.n_vertices(),
        points: out.n_vertices(),
        triangles: out.n_triangles(),
        knot_quality: sd.knot_quality,
        control_net: "quasi",
        max_displacement,
        seconds: t.elapsed().as_secs_f64(),
        after: out,
    })
}

/// `path` with `_spline` before its extension.
pub fn spline_path(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let ext = path
        .extension()
        .map_or_else(String::new, |e| format!(".{}", e.to_string_lossy()));
    path.with_file_name(format!("{stem}_spline{ext}"))
}

/// Crossing triangle pairs of the skin before and after relaxing.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Crossings {
    before: usize,
    after: usize,
}

/// The largest skin and bone displacements and their ratio.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Overshoot {
    skin_max: f32,
    bone_max: f32,
    /// `null` when the bone hardly moved.
    ratio: Option<f32>,
}

/// Skin moves above this multiple of the bone's largest move are warned about.
const OVERSHOOT_WARNING: f32 = 1.1;
/// Bone moves below this fraction of the bone layer's bounding-box diagonal
/// give no ratio (a plan that moves the bone and back, or not at all).
const OVERSHOOT_MIN_BONE_MOVE: f32 = 1e-3;

/// The largest skin and bone displacements and their ratio (`null` when
/// the bone hardly moved), with a warning when the skin moves more than
/// 10 % beyond the bone. Tissue carried by a translated bone should follow
/// it, not outrun it, so a large overshoot means the network bulged or
/// buckled. Plans that rotate are not warned about: skin farther from the
/// axis than any bone rightly moves more.
pub fn skin_overshoot(
    network: &SpringNetwork,
    plan: &Plan,
    report: &RelaxReport,
) -> anyhow::Result<Overshoot> {
    let length = |u: &[f32; 4]| Vec3::new(u[0], u[1], u[2]).length();
    let bone = bone_displacements(network.bone_rest(), &report.positions[network.n_free..])?
        .iter()
        .map(length)
        .fold(0.0f32, f32::max);
    let diagonal = crate::reduce::cpu::bounds_reduce(network.bone_rest())
        .map_or(0.0, |(lo, hi)| {
            length(&[hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 0.0])
        });
    let skin = report.max_displacement;
    let ratio = (bone > OVERSHOOT_MIN_BONE_MOVE * diagonal).then(|| skin / bone);
    let rotates = plan.steps.iter().any(|s| s.rotate.is_some());
    if let Some(r) = ratio
        && r > OVERSHOOT_WARNING
        && !rotates
    {
        let hint = if network
            .springs
            .iter()
            .any(|s| s.class == SpringClass::Bending)
        {
            ""
        } else {
            "; the network has no bend springs (--bending 1 adds them)"
        };
        eprintln!(
            "warning: the skin moves up to {skin:.4}, {:.0} % more than the bone's largest \
             move ({bone:.4}): the tissue bulges or buckles instead of following the bone{hint}",
            (r - 1.0) * 100.0
        );
    }
    Ok(Overshoot {
        skin_max: skin,
        bone_max: bone,
        ratio,
    })
}

/// Crossing triangle pairs of the skin before and after relaxing (exact,
/// [`crate::mesh::self_intersections`]), with a warning when the relaxation
/// added some: the seed's springs carry no bending, so thin triangles can
/// fold over.
pub fn skin_crossings(before: &TriMesh, after: &TriMesh) -> Crossings {
    let n = |m: &TriMesh| crate::mesh::self_intersections(m).pairs.len();
    let (b, a) = (n(before), n(after));
    if a > b {
        eprintln!(
            "warning: the relaxed skin crosses itself in {a} triangle pairs ({b} before): \
             triangles folded over; bend springs (--bending) or fewer thin triangles \
             (--skin-min-edge with --ct) prevent it"
        );
    }
    Crossings {
        before: b,
        after: a,
    }
}
