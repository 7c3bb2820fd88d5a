//! Construction of the layered spring network (SPEC §1.1; seed 000 §4.1.1,
//! §4.1.2, eq. 4.1) and its CSR form for the kernels.
//!
//! Nodes are numbered layer by layer: epidermis `0..n` (the input mesh's
//! vertices, same order), subcutis `n..2n` (vertex i of the input at
//! `n + i`), bone `2n..2n + n_bone`. The first `2n` nodes are *free*; bone
//! nodes are fixed (B_i = 0) and only move when a plan moves them.
//!
//! Split by phase: the types and limits live here, `surface` has the
//! input surface's origin, edges and rings, `build` constructs the
//! layers, links and materials, `csr` packs the gather adjacency and
//! answers queries on a built network.

mod build;
mod csr;
mod surface;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::selector::Selector;

pub use csr::SpringCsr;
pub use surface::{default_origin, unique_edges};

/// The seed's five spring classes (three layers + two intermediate layers)
/// and, beyond the seed, bend springs across the epidermis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpringClass {
    /// Edges of the epidermis T2.
    Epidermis,
    /// Dermis (korium) links T2 → T1: p_i–q_i and the face diagonals p_j–q_i.
    Dermis,
    /// Edges of the subcutis T1.
    Subcutis,
    /// Muscle/fascia links T1 → T0 (eq. 4.1).
    Muscle,
    /// Edges of the bone T0 (both ends fixed: no force on any free node).
    Bone,
    /// Beyond the seed: flexion springs across each interior edge of the
    /// epidermis, between the two apexes of its triangles (Provot 1995's
    /// bend springs). Folding a triangle over its neighbour shortens them.
    Bending,
}

impl SpringClass {
    /// All classes; the index is the default material id.
    pub const ALL: [SpringClass; 6] = [
        SpringClass::Epidermis,
        SpringClass::Dermis,
        SpringClass::Subcutis,
        SpringClass::Muscle,
        SpringClass::Bone,
        SpringClass::Bending,
    ];

    fn index(self) -> usize {
        self as usize
    }
}

/// A spring law: force magnitude `c1·e + (c2 − c1)·max(e − knee·l, 0)` for
/// extension `e = |r| − l` (seed §4.1.2, biphasic after \[WT90\]). With
/// `c2 = c1` it is a linear spring; the force is continuous in `e`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Stiffness below the knee (force per length).
    pub c1: f32,
    /// Stiffness beyond the knee.
    pub c2: f32,
    /// Strain at which `c2` takes over (0.1 = 10 %).
    pub knee: f32,
}

impl Material {
    /// A linear spring of stiffness `c`.
    pub fn linear(c: f32) -> Self {
        Material {
            c1: c,
            c2: c,
            knee: 0.0,
        }
    }

    /// The largest tangent stiffness the law reaches.
    pub fn c_max(&self) -> f32 {
        self.c1.max(self.c2)
    }

    /// `[c1, c2 − c1, knee, c_max]`: the kernels' material table row.
    pub fn table_row(&self) -> [f32; 4] {
        [self.c1, self.c2 - self.c1, self.knee, self.c_max()]
    }

    fn scaled(&self, s: f32) -> Self {
        Material {
            c1: self.c1 * s,
            c2: self.c2 * s,
            knee: self.knee,
        }
    }
}

/// Per-class stiffness (SPEC §1.1 defaults: medium 1.0, biphasic 1.0/5.0 at
/// 10 %, low 0.3, high 3.0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Stiffness {
    pub epidermis: Material,
    pub dermis: Material,
    pub subcutis: Material,
    pub muscle: Material,
    pub bone: Material,
    /// Bend springs (not in the seed): c = 0 builds none.
    pub bending: Material,
}

impl Default for Stiffness {
    fn default() -> Self {
        Stiffness {
            epidermis: Material::linear(1.0),
            dermis: Material {
                c1: 1.0,
                c2: 5.0,
                knee: 0.1,
            },
            subcutis: Material::linear(0.3),
            muscle: Material::linear(3.0),
            bone: Material::linear(1.0),
            bending: Material::linear(0.0),
        }
    }
}

impl Stiffness {
    fn of(&self, class: SpringClass) -> Material {
        match class {
            SpringClass::Epidermis => self.epidermis,
            SpringClass::Dermis => self.dermis,
            SpringClass::Subcutis => self.subcutis,
            SpringClass::Muscle => self.muscle,
            SpringClass::Bone => self.bone,
            SpringClass::Bending => self.bending,
        }
    }
}

/// A per-region stiffness override (seed outlook (1)): springs whose rest
/// midpoint lies in `region` (and of `class`, when given) get their class
/// material scaled by `scale`. Later regions win.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StiffnessRegion {
    /// A geometric selector (sphere, box or half-space).
    pub region: Selector,
    /// Restrict to one class; `None` = all classes.
    #[serde(default)]
    pub class: Option<SpringClass>,
    /// Factor on c1 and c2 (> 0).
    pub scale: f32,
}

/// Parameters of the network construction and of the nodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NetworkParams {
    /// Origin O of the layer construction; `None` = SPEC §1.1 default
    /// (see [`default_origin`]).
    pub origin: Option<[f32; 3]>,
    /// Subcutis T1 = T2 scaled by this about O (seed: about 0.8).
    pub subcutis_scale: f32,
    /// Bone T0 = T2 scaled by this about O when no bone mesh is given
    /// (seed: about 0.7).
    pub bone_scale: f32,
    /// `scale` of eq. 4.1 (projection of q_i toward O before the nearest
    /// bone search); `None` = `bone_scale / subcutis_scale`.
    pub projection_scale: Option<f32>,
    /// Subcutis between skin and a real bone (seed outlook (4): the bone
    /// must lie behind the subcutis): q_i = p_i + d·|b_i − p_i|·ν_i, b_i
    /// the bone vertex nearest to p_i, ν_i the unit vertex normal turned
    /// toward b_i, d ∈ (0, 1). Along the normal the dermis link p_i–q_i
    /// resists motion out of the skin's plane (toward b_i it can lie
    /// almost in that plane where the bone is off to the side), and q_i
    /// stays inside the ball about p_i that holds no bone vertex, so it
    /// does not pass through the bone. Eq. 4.1 then searches the bone vertex nearest to
    /// q_i itself (s = 1). Needs a bone mesh; `None` = the seed's scaling
    /// about O (for CT skulls that can put the subcutis inside the cranium).
    pub subcutis_depth: Option<f32>,
    /// Per-class spring laws.
    pub stiffness: Stiffness,
    /// Per-region overrides.
    pub regions: Vec<StiffnessRegion>,
    /// Node mass m_i (all nodes).
    pub mass: f32,
    /// Damping γ_i (all nodes), eq. 4.5.
    pub damping: f32,
}

impl Default for NetworkParams {
    fn default() -> Self {
        NetworkParams {
            origin: None,
            subcutis_scale: 0.8,
            bone_scale: 0.7,
            projection_scale: None,
            subcutis_depth: None,
            stiffness: Stiffness::default(),
            regions: Vec::new(),
            mass: 1.0,
            damping: 0.5,
        }
    }
}

/// One spring between nodes `a < b`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Spring {
    pub a: u32,
    pub b: u32,
    pub class: SpringClass,
    /// Index into [`SpringNetwork::materials`].
    pub material: u8,
    /// Rest length l_ij = initial length (f64 distance of the f32 rest
    /// positions; the kernels recompute it in f32 from the same positions).
    pub rest: f32,
}

/// Most materials a network can have (4 bits in a CSR entry).
pub const MAX_MATERIALS: usize = 16;
/// Most nodes a network can have (28 bits in a CSR entry).
pub const MAX_NODES: usize = 1 << 28;

/// The layered spring network of seed 000 §4.1.
#[derive(Debug, Clone)]
pub struct SpringNetwork {
    /// The parameters it was built with.
    pub params: NetworkParams,
    /// Origin O of the construction.
    pub origin: Vec3,
    /// Vertices per surface layer (epidermis = subcutis); 0 for networks
    /// built with [`SpringNetwork::from_parts`].
    pub n_surface: usize,
    /// Free nodes (`0..n_free`); the rest are fixed.
    pub n_free: usize,
    /// #nodes rest positions `[x, y, z, 0]`, mesh units.
    pub rest: Vec<[f32; 4]>,
    /// Epidermis (and subcutis) triangles, epidermis vertex ids.
    pub surface_triangles: Vec<[u32; 3]>,
    /// Bone triangles, bone vertex ids (`0..n_bone`).
    pub bone_triangles: Vec<[u32; 3]>,
    /// All springs, sorted by `(a, b)`, unique.
    pub springs: Vec<Spring>,
    /// Material table (≤ [`MAX_MATERIALS`]).
    pub materials: Vec<Material>,
    /// Gather adjacency of the free nodes.
    pub csr: SpringCsr,
}
