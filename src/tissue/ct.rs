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
//! apart (no springs of rest length 0), but leaves slivers with edges down
//! to 2⁻¹⁰ of a voxel where the surface passes near a sample; springs
//! carry no bending, so under shear such a sliver flips over its
//! neighbours. The epidermis therefore has its edges shorter than
//! [`CtParams::skin_min_edge`] collapsed ([`collapse_short_edges`]; default
//! [`SKIN_MIN_EDGE_FACTOR`] × the largest voxel spacing, which leaves the
//! in-plane resolution of an anisotropic CT). The subcutis is then placed
//! between skin and bone ([`CT_SUBCUTIS_DEPTH`]).

use serde::Serialize;

use crate::gpu::Backend;
use crate::mc::{IsoSpec, McOptions, Surface, marching_cubes};
use crate::mesh::{Topology, collapse_short_edges};
use crate::{Error, Refusal, Result, TriMesh, Volume};

/// Where the subcutis lies between a CT's skin and bone: q_i = p_i +
/// d·(b_i − p_i) with d = 0.5 (see [`super::NetworkParams::subcutis_depth`]).
pub const CT_SUBCUTIS_DEPTH: f32 = 0.5;

/// Stiffness of the bend springs (see [`super::SpringClass::Bending`])
/// across the epidermis of a CT network: the stiffness of the epidermis's
/// own edges. Relative to the skin's edges a bone fragment's border moves
/// abruptly, and without them the skin folds there (headsq's chin
/// advance after the short-edge collapse: 30 crossing triangle pairs
/// without, 0 with; README).
pub const CT_BENDING: f32 = 1.0;

/// Default shortest epidermis edge of a CT skin, in units of the largest
/// voxel spacing. On the demo phantom (5 mm voxels) a 6 mm jaw advance
/// leaves 35 crossing skin triangle pairs without collapsing, 2 at 0.2 and
/// 0 from 0.4 on; on headsq (3.2 × 3.2 × 1.5 mm) the chin advance needs
/// 0.6 and bend springs (README, known limits).
pub const SKIN_MIN_EDGE_FACTOR: f32 = 0.6;

/// How the layers are taken from a CT.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CtParams {
    /// Iso level of the skin surface (CT numbers: air < skin ≤ soft tissue).
    pub skin_level: f32,
    /// Iso level of the bone surface (`> skin_level`).
    pub bone_level: f32,
    /// Epidermis edges shorter than this are collapsed (world units;
    /// 0 keeps the marching-cubes skin as it is).
    pub skin_min_edge: f32,
}

impl CtParams {
    /// The levels with the default shortest skin edge for `volume`
    /// ([`SKIN_MIN_EDGE_FACTOR`] × its largest spacing).
    pub fn for_volume(volume: &Volume, skin_level: f32, bone_level: f32) -> CtParams {
        let largest = volume.spacing.into_iter().fold(0.0, f64::max);
        CtParams {
            skin_level,
            bone_level,
            skin_min_edge: SKIN_MIN_EDGE_FACTOR * largest as f32,
        }
    }

    fn check(&self) -> Result<()> {
        let (s, b) = (self.skin_level, self.bone_level);
        if !(s.is_finite() && b.is_finite() && s < b) {
            return Err(Error::param(
                "skin and bone levels",
                format!("{s}, {b}"),
                "need skin < bone, both finite",
            ));
        }
        if !(self.skin_min_edge.is_finite() && self.skin_min_edge >= 0.0) {
            return Err(Error::param(
                "skin_min_edge",
                self.skin_min_edge,
                "must be finite and ≥ 0",
            ));
        }
        Ok(())
    }
}

/// What the extraction found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CtFigures {
    pub skin_level: f32,
    pub bone_level: f32,
    /// Groups of the skin surface, and the triangles of those left out.
    pub skin_groups: usize,
    pub skin_triangles_dropped: usize,
    /// The short-edge collapse of the epidermis.
    pub skin_collapse: SkinCollapse,
    /// Epidermis (after the collapse): vertices, triangles, boundary edges
    /// (open where the body leaves the volume).
    pub skin_vertices: usize,
    pub skin_triangles: usize,
    pub skin_boundary_edges: u32,
    /// Bone: groups, vertices, triangles.
    pub bone_groups: usize,
    pub bone_vertices: usize,
    pub bone_triangles: usize,
}

/// What collapsing the epidermis's short edges did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SkinCollapse {
    /// Threshold (world units; 0 = off).
    pub min_edge: f32,
    /// Vertices of the marching-cubes skin group.
    pub vertices_before: usize,
    /// Edges collapsed, and those left short (collapse refused).
    pub collapsed_edges: usize,
    pub short_edges_left: usize,
    /// Shortest edge before and after.
    pub shortest_before: f32,
    pub shortest_after: f32,
    /// Runs of the collapse, and the skin's crossing triangle pairs after
    /// it (0: the guard of [`collapse_short_edges`] kept it embedded).
    pub rounds: usize,
    pub crossing_pairs: usize,
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
/// honoured) with marching cubes on `backend`.
pub fn layers_from_ct(
    volume: &Volume,
    params: &CtParams,
    backend: Backend<'_>,
) -> Result<CtLayers> {
    params.check()?;
    let opts = McOptions::default();
    let skin = marching_cubes(volume, IsoSpec::Level(params.skin_level), &opts, backend)?;
    let bone = marching_cubes(volume, IsoSpec::Level(params.bone_level), &opts, backend)?;
    CtLayers::from_surfaces(&skin, &bone, params)
}

impl CtLayers {
    /// The layers from the marching-cubes surfaces of one volume at the
    /// skin and the bone level of `params`.
    pub fn from_surfaces(
        skin_surface: &Surface,
        bone_surface: &Surface,
        params: &CtParams,
    ) -> Result<CtLayers> {
        params.check()?;
        let (skin_level, bone_level) = (params.skin_level, params.bone_level);
        let group = largest_group(skin_surface).ok_or(Refusal::NoSurface {
            layer: "skin",
            level: skin_level as f64,
        })?;
        if bone_surface.mesh.triangles.is_empty() {
            return Err(Refusal::NoSurface {
                layer: "bone",
                level: bone_level as f64,
            }
            .into());
        }
        let skin_triangles_dropped = skin_surface.mesh.n_triangles() - group.n_triangles();
        let collapsed = collapse_short_edges(&group, params.skin_min_edge);
        let skin = collapsed.mesh;
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
            skin_collapse: SkinCollapse {
                min_edge: params.skin_min_edge,
                vertices_before: group.n_vertices(),
                collapsed_edges: collapsed.collapsed,
                short_edges_left: collapsed.short_edges_left,
                shortest_before: collapsed.min_edge_before,
                shortest_after: collapsed.min_edge_after,
                rounds: collapsed.rounds,
                crossing_pairs: collapsed.crossing_pairs,
            },
            skin_vertices: skin.n_vertices(),
            skin_triangles: skin.n_triangles(),
            skin_boundary_edges: Topology::of(&skin).boundary_edges as u32,
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
/// mesh.
fn largest_group(s: &Surface) -> Option<TriMesh> {
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
    Some(parts.swap_remove(0))
}
