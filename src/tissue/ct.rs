//! CT → tissue model (seed 000 outlook (4), SPEC §5): the epidermis and
//! the bone layer come from one CT volume by marching cubes (seed 004 §1)
//! instead of a face scan and a scaled copy of it.
//!
//! ```text
//! Volume ──MC at the skin level──▶ groups ──largest──▶ epidermis T2
//!        ──MC at the bone level──▶ every group ──────▶ bone T0
//! ```
//!
//! The skin surface of a CT holds, besides the outer skin, small closed
//! surfaces of air pockets and the like; the epidermis is the group with
//! the most triangles (reported, with what was left out). The bone keeps
//! all its groups: every one is bone the tissue may hang on. Surfaces end
//! open where the body leaves the volume (the neck of a head scan), which
//! the network handles like any open mesh. Marching cubes keeps vertices
//! apart (no springs of rest length 0). The subcutis is then placed
//! between the two ([`CT_SUBCUTIS_DEPTH`]).

use serde::Serialize;

use crate::parity::Backend;
use crate::surface::{IsoSpec, McOptions, Surface, marching_cubes};
use crate::{Error, Result, TriMesh, Volume};

/// Where the subcutis lies between a CT's skin and bone: q_i = p_i +
/// d·(b_i − p_i) with d = 0.5 (see [`super::NetworkParams::subcutis_depth`]).
pub const CT_SUBCUTIS_DEPTH: f32 = 0.5;

/// What the extraction found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CtFigures {
    pub skin_level: f32,
    pub bone_level: f32,
    /// Groups of the skin surface, and the triangles of those left out.
    pub skin_groups: usize,
    pub skin_triangles_dropped: usize,
    /// Epidermis: vertices, triangles, boundary edges (open where the body
    /// leaves the volume).
    pub skin_vertices: usize,
    pub skin_triangles: usize,
    pub skin_boundary_edges: u32,
    /// Bone: groups, vertices, triangles.
    pub bone_groups: usize,
    pub bone_vertices: usize,
    pub bone_triangles: usize,
}

/// Epidermis and bone of a CT.
#[derive(Debug, Clone)]
pub struct CtLayers {
    /// The outer skin (largest group of the skin-level surface), outward.
    pub skin: TriMesh,
    /// Every group of the bone-level surface, outward.
    pub bone: TriMesh,
    pub figures: CtFigures,
}

/// Extracts the layers of `volume` (world units: spacing and origin
/// honoured) with marching cubes on `backend`. `skin_level < bone_level`
/// (CT numbers: air < skin level ≤ soft tissue < bone level ≤ bone).
pub fn layers_from_ct(
    volume: &Volume,
    skin_level: f32,
    bone_level: f32,
    backend: Backend<'_>,
) -> Result<CtLayers> {
    check_levels(skin_level, bone_level)?;
    let opts = McOptions::default();
    let skin = marching_cubes(volume, IsoSpec::Level(skin_level), &opts, backend)?;
    let bone = marching_cubes(volume, IsoSpec::Level(bone_level), &opts, backend)?;
    CtLayers::from_surfaces(&skin, &bone, skin_level, bone_level)
}

fn check_levels(skin_level: f32, bone_level: f32) -> Result<()> {
    if skin_level.is_finite() && bone_level.is_finite() && skin_level < bone_level {
        Ok(())
    } else {
        Err(Error::InvalidInput(format!(
            "CT levels need skin < bone, both finite; got skin {skin_level}, bone {bone_level}"
        )))
    }
}

impl CtLayers {
    /// The layers from the marching-cubes surfaces of one volume at the
    /// skin and the bone level.
    pub fn from_surfaces(
        skin_surface: &Surface,
        bone_surface: &Surface,
        skin_level: f32,
        bone_level: f32,
    ) -> Result<CtLayers> {
        check_levels(skin_level, bone_level)?;
        let (skin, largest) = largest_group(skin_surface).ok_or_else(|| {
            Error::InvalidInput(format!(
                "the CT has no surface at the skin level {skin_level} (no sample on both sides)"
            ))
        })?;
        if bone_surface.mesh.triangles.is_empty() {
            return Err(Error::InvalidInput(format!(
                "the CT has no surface at the bone level {bone_level} (no sample on both sides)"
            )));
        }
        let skin_triangles_dropped = skin_surface.mesh.n_triangles() - skin.n_triangles();
        let bone = TriMesh {
            positions: bone_surface.mesh.positions.clone(),
            triangles: bone_surface.mesh.triangles.clone(),
            scalars: Vec::new(),
        };
        let figures = CtFigures {
            skin_level,
            bone_level,
            skin_groups: skin_surface.groups.len(),
            skin_triangles_dropped,
            skin_vertices: skin.n_vertices(),
            skin_triangles: skin.n_triangles(),
            skin_boundary_edges: skin_surface.groups[largest].boundary_edges,
            bone_groups: bone_surface.groups.len(),
            bone_vertices: bone.n_vertices(),
            bone_triangles: bone.n_triangles(),
        };
        Ok(CtLayers {
            skin,
            bone,
            figures,
        })
    }
}

/// The group with the most triangles (ties: the lower group id) as its own
/// mesh, and its id.
fn largest_group(s: &Surface) -> Option<(TriMesh, usize)> {
    let g = (0..s.groups.len()).max_by_key(|&g| (s.groups[g].triangles, usize::MAX - g))?;
    let keep: Vec<u32> = s
        .triangle_groups
        .iter()
        .map(|&k| u32::from(k as usize != g))
        .collect();
    let mut parts = crate::mesh::split_by_label(&s.mesh, &keep);
    if parts.is_empty() {
        return None;
    }
    Some((parts.swap_remove(0), g))
}
