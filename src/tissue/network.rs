//! Construction of the layered spring network (SPEC §1.1; seed 000 §4.1.1,
//! §4.1.2, eq. 4.1) and its CSR form for the kernels.
//!
//! Nodes are numbered layer by layer: epidermis `0..n` (the input mesh's
//! vertices, same order), subcutis `n..2n` (vertex i of the input at
//! `n + i`), bone `2n..2n + n_bone`. The first `2n` nodes are *free*; bone
//! nodes are fixed (B_i = 0) and only move when a plan moves them.

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::kdtree::KdTree;
use super::selector::Selector;
use crate::mesh::{Csr, TriMesh};
use crate::{Error, Result};

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
const INDEX_MASK: u32 = (1 << 28) - 1;

/// The kernels' gather adjacency: row `i` (a free node) lists one entry per
/// spring at `i`, sorted by neighbour id. An entry is `j | material << 28`;
/// the rest length is not stored: the kernels take l_ij = |x_rest,i −
/// x_rest,j| from the rest positions they gather anyway (rest length =
/// initial length), in f32 with the very difference that starts r_ij, so a
/// spring at rest has extension exactly 0.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SpringCsr {
    /// #free + 1 row starts.
    pub offsets: Vec<u32>,
    /// Packed entries (4 bytes each).
    pub entries: Vec<u32>,
}

impl SpringCsr {
    /// Unpacks an entry into `(neighbour, material)`.
    #[inline(always)]
    pub fn unpack(e: u32) -> (usize, usize) {
        ((e & INDEX_MASK) as usize, (e >> 28) as usize)
    }
}

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

/// The SPEC §1.1 default origin: for an open surface, the centre of the
/// back face of the bounding box along the axis of least extent, on the
/// side the surface bulges away from. The side is decided by the surface's
/// own curvature (vertex normals oriented so most point away from the
/// centroid's side), not by the file's winding, which is not trusted
/// (`fran_cut` is wound inward). For a closed surface (no boundary edge)
/// the bounding-box centre, so the layers nest.
pub fn default_origin(mesh: &TriMesh) -> Result<Vec3> {
    let (lo, hi) = mesh
        .bounds()
        .ok_or_else(|| Error::InvalidInput("epidermis mesh has no vertices".into()))?;
    let centre = (lo + hi) * 0.5;
    let edges = unique_edges(&mesh.triangles);
    let closed = !edges.is_empty() && edge_use_all_even(&mesh.triangles, &edges);
    if closed {
        return Ok(centre);
    }
    let ext = hi - lo;
    let axis = if ext.x <= ext.y && ext.x <= ext.z {
        0
    } else if ext.y <= ext.z {
        1
    } else {
        2
    };
    // Area-weighted normals by the file's winding, then orientation by
    // curvature: outward normals of a bulging patch point away from its
    // centroid on average.
    let centroid = mesh.positions.iter().copied().sum::<Vec3>() / mesh.n_vertices() as f32;
    let mut normal_sum = Vec3::ZERO;
    let mut outwardness = 0.0f64;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let n = (b - a).cross(c - a);
        normal_sum += n;
        outwardness += n.dot((a + b + c) / 3.0 - centroid) as f64;
    }
    if outwardness < 0.0 {
        normal_sum = -normal_sum;
    }
    let mut o = centre;
    o[axis] = if normal_sum[axis] >= 0.0 {
        lo[axis]
    } else {
        hi[axis]
    };
    Ok(o)
}

/// Whether every edge is used by an even number (≥ 2) of triangles.
fn edge_use_all_even(triangles: &[[u32; 3]], edges: &[(u32, u32)]) -> bool {
    let mut uses = vec![0u32; edges.len()];
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a != b {
                let key = (a.min(b), a.max(b));
                if let Ok(ix) = edges.binary_search(&key) {
                    uses[ix] += 1;
                }
            }
        }
    }
    uses.iter().all(|&u| u >= 2 && u % 2 == 0)
}

/// Sorted unique undirected edges `(min, max)` of a triangle list
/// (self-edges of degenerate triangles are skipped).
pub fn unique_edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut e: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter(|(a, b)| a != b)
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    e.par_sort_unstable();
    e.dedup();
    e
}

/// The two apexes of each edge shared by exactly two triangles, as
/// `(min, max)` pairs in edge order (edges whose apexes coincide skipped).
fn edge_apexes(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut corners: Vec<(u32, u32, u32)> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3], t[(k + 2) % 3])))
        .filter(|&(a, b, c)| a != b && b != c && a != c)
        .map(|(a, b, c)| (a.min(b), a.max(b), c))
        .collect();
    corners.par_sort_unstable();
    corners
        .chunk_by(|x, y| (x.0, x.1) == (y.0, y.1))
        .filter(|run| run.len() == 2 && run[0].2 != run[1].2)
        .map(|run| (run[0].2, run[1].2))
        .collect()
}

/// 1-ring neighbours (sorted) of `n` vertices from unique edges.
fn one_rings(n: usize, edges: &[(u32, u32)]) -> Csr {
    let mut csr = Csr::from_pairs(n, edges.iter().flat_map(|&(a, b)| [(a, b), (b, a)]));
    for i in 0..n {
        let (s, e) = (csr.offsets[i] as usize, csr.offsets[i + 1] as usize);
        csr.targets[s..e].sort_unstable();
    }
    csr
}

fn dvec(p: [f32; 4]) -> DVec3 {
    DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

impl SpringNetwork {
    /// Builds the network over the epidermis `epidermis` (T2) and an
    /// optional bone mesh (T0; default: T2 scaled by `bone_scale` about O).
    ///
    /// Springs (SPEC §1.1): epidermis edges; dermis p_i–q_i and p_j–q_i for
    /// every 1-ring neighbour j of i; subcutis edges; muscle q_i–b,
    /// q_i–(1-ring of b in T0), b–(1-ring of q_i in T1) with b the bone
    /// vertex nearest to O + s·(q_i − O) (eq. 4.1, k-d tree, O(n log n));
    /// bone edges. Duplicates are merged; rest length = initial length.
    /// Works for open, closed and multi-component meshes; vertices no
    /// triangle uses keep their dermis and muscle links.
    pub fn build(
        epidermis: &TriMesh,
        bone: Option<&TriMesh>,
        params: &NetworkParams,
    ) -> Result<SpringNetwork> {
        epidermis.validate()?;
        let n = epidermis.n_vertices();
        if n == 0 || epidermis.n_triangles() == 0 {
            return Err(Error::InvalidInput(
                "epidermis mesh needs at least one triangle".into(),
            ));
        }
        for (name, v) in [
            ("subcutis_scale", params.subcutis_scale),
            ("bone_scale", params.bone_scale),
            ("mass", params.mass),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidInput(format!(
                    "network parameter {name} must be finite and > 0, got {v}"
                )));
            }
        }
        if !(params.damping.is_finite() && params.damping >= 0.0) {
            return Err(Error::InvalidInput(format!(
                "damping must be finite and ≥ 0, got {}",
                params.damping
            )));
        }
        let origin = match params.origin {
            Some(o) if o.iter().all(|c| c.is_finite()) => Vec3::from_array(o),
            Some(o) => {
                return Err(Error::InvalidInput(format!(
                    "origin must be finite, got {o:?}"
                )));
            }
            None => default_origin(epidermis)?,
        };
        let o = origin.as_dvec3();
        let scaled = |p: Vec3, s: f32| -> [f32; 4] {
            let q = o + (p.as_dvec3() - o) * s as f64;
            [q.x as f32, q.y as f32, q.z as f32, 0.0]
        };
        let (bone_pos, bone_triangles): (Vec<[f32; 4]>, Vec<[u32; 3]>) = match bone {
            Some(b) => {
                b.validate()?;
                if b.n_vertices() == 0 {
                    return Err(Error::InvalidInput("bone mesh has no vertices".into()));
                }
                (
                    b.positions.iter().map(|p| [p.x, p.y, p.z, 0.0]).collect(),
                    b.triangles.clone(),
                )
            }
            None => (
                epidermis
                    .positions
                    .iter()
                    .map(|&p| scaled(p, params.bone_scale))
                    .collect(),
                epidermis.triangles.clone(),
            ),
        };
        let n_bone = bone_pos.len();
        let n_nodes = 2 * n + n_bone;
        if n_nodes > MAX_NODES {
            return Err(Error::InvalidInput(format!(
                "network would have {n_nodes} nodes; at most {MAX_NODES} are supported"
            )));
        }
        let tree = KdTree::new(bone_pos.iter().map(|&p| dvec(p)).collect());
        let mut rest: Vec<[f32; 4]> = Vec::with_capacity(n_nodes);
        rest.extend(epidermis.positions.iter().map(|p| [p.x, p.y, p.z, 0.0]));
        match params.subcutis_depth {
            None => rest.extend(
                epidermis
                    .positions
                    .iter()
                    .map(|&p| scaled(p, params.subcutis_scale)),
            ),
            Some(d) => {
                if bone.is_none() || !(d.is_finite() && d > 0.0 && d < 1.0) {
                    return Err(Error::InvalidInput(format!(
                        "subcutis_depth needs a bone mesh and a value in (0, 1), got {d}{}",
                        if bone.is_none() {
                            " without a bone mesh"
                        } else {
                            ""
                        }
                    )));
                }
                let normals =
                    crate::normals::vertex_normals(epidermis, crate::parity::Backend::Cpu)?;
                let placed: Vec<[f32; 4]> = epidermis
                    .positions
                    .par_iter()
                    .zip(&normals)
                    .map(|(&p, n)| {
                        let p = p.as_dvec3();
                        let b = tree.nearest(p).map_or(p, |k| dvec(bone_pos[k as usize]));
                        let n = DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
                        let inward = if n.dot(b - p) < 0.0 { -n } else { n };
                        let q = p + inward * (d as f64 * p.distance(b));
                        [q.x as f32, q.y as f32, q.z as f32, 0.0]
                    })
                    .collect();
                rest.extend(placed);
            }
        }
        rest.extend_from_slice(&bone_pos);

        let surface_edges = unique_edges(&epidermis.triangles);
        let bone_edges = unique_edges(&bone_triangles);
        let ring = one_rings(n, &surface_edges);
        let bone_ring = one_rings(n_bone, &bone_edges);

        // eq. 4.1: nearest bone vertex to O + s·(q_i − O).
        let s = match params.subcutis_depth {
            Some(_) => 1.0,
            None => params
                .projection_scale
                .unwrap_or(params.bone_scale / params.subcutis_scale) as f64,
        };
        if !(s.is_finite() && s > 0.0) {
            return Err(Error::InvalidInput(format!(
                "projection_scale must be finite and > 0, got {s}"
            )));
        }
        let nearest: Vec<u32> = (0..n)
            .into_par_iter()
            .map(|i| {
                let q = dvec(rest[n + i]);
                tree.nearest(o + (q - o) * s).unwrap_or(0)
            })
            .collect();

        let (ep, sub, bo) = (0u32, n as u32, 2 * n as u32);
        let mut pairs: Vec<(u32, u32, SpringClass)> = Vec::new();
        let mut push = |a: u32, b: u32, c: SpringClass| {
            if a != b {
                pairs.push((a.min(b), a.max(b), c));
            }
        };
        for &(a, b) in &surface_edges {
            push(ep + a, ep + b, SpringClass::Epidermis);
            push(sub + a, sub + b, SpringClass::Subcutis);
        }
        for (i, &b) in nearest.iter().enumerate() {
            let qi = sub + i as u32;
            push(ep + i as u32, qi, SpringClass::Dermis);
            for &j in ring.row(i) {
                push(ep + j, qi, SpringClass::Dermis);
            }
            push(qi, bo + b, SpringClass::Muscle);
            for &bj in bone_ring.row(b as usize) {
                push(qi, bo + bj, SpringClass::Muscle);
            }
            for &j in ring.row(i) {
                push(bo + b, sub + j, SpringClass::Muscle);
            }
        }
        for &(a, b) in &bone_edges {
            push(bo + a, bo + b, SpringClass::Bone);
        }
        if params.stiffness.bending.c_max() > 0.0 {
            for (c, d) in edge_apexes(&epidermis.triangles) {
                push(ep + c, ep + d, SpringClass::Bending);
            }
        }
        pairs.par_sort_unstable_by_key(|&(a, b, c)| (a, b, c.index()));
        pairs.dedup_by_key(|&mut (a, b, _)| (a, b));

        let mut materials: Vec<Material> = SpringClass::ALL
            .iter()
            .map(|&c| params.stiffness.of(c))
            .collect();
        for (k, m) in materials.iter().enumerate() {
            let class = SpringClass::ALL[k];
            // Bend springs are off at c1 = c2 = 0; every other law must hold.
            let off = class == SpringClass::Bending && m.c1 == 0.0 && m.c2 == 0.0;
            if !(off && m.knee.is_finite() && m.knee >= 0.0) {
                check_material(m, &format!("stiffness of {class:?}"))?;
            }
        }
        let mut region_material: Vec<Vec<Option<u8>>> =
            vec![vec![None; SpringClass::ALL.len()]; params.regions.len()];
        for (r, reg) in params.regions.iter().enumerate() {
            let what = format!("stiffness region {}", r + 1);
            reg.region.validate(&what)?;
            if reg.region.contains(Vec3::ZERO).is_none() {
                return Err(Error::InvalidInput(format!(
                    "{what}: regions take a sphere, box or half_space"
                )));
            }
            if !(reg.scale.is_finite() && reg.scale > 0.0) {
                return Err(Error::InvalidInput(format!(
                    "{what}: scale must be finite and > 0, got {}",
                    reg.scale
                )));
            }
        }
        let mut springs = Vec::with_capacity(pairs.len());
        for &(a, b, class) in &pairs {
            let (pa, pb) = (dvec(rest[a as usize]), dvec(rest[b as usize]));
            let mid = ((pa + pb) * 0.5).as_vec3();
            let mut material = class.index() as u8;
            for (r, reg) in params.regions.iter().enumerate() {
                if reg.class.is_some_and(|c| c != class) || reg.region.contains(mid) != Some(true) {
                    continue;
                }
                let slot = &mut region_material[r][class.index()];
                material = match *slot {
                    Some(m) => m,
                    None => {
                        if materials.len() == MAX_MATERIALS {
                            return Err(Error::InvalidInput(format!(
                                "stiffness regions need more than {MAX_MATERIALS} distinct spring materials"
                            )));
                        }
                        materials.push(params.stiffness.of(class).scaled(reg.scale));
                        let m = (materials.len() - 1) as u8;
                        *slot = Some(m);
                        m
                    }
                };
            }
            springs.push(Spring {
                a,
                b,
                class,
                material,
                rest: pa.distance(pb) as f32,
            });
        }
        let mut net = SpringNetwork {
            params: params.clone(),
            origin,
            n_surface: n,
            n_free: 2 * n,
            rest,
            surface_triangles: epidermis.triangles.clone(),
            bone_triangles,
            springs,
            materials,
            csr: SpringCsr::default(),
        };
        net.csr = net.gather_csr();
        Ok(net)
    }

    /// A network from explicit parts (analytic test cases, chains): nodes
    /// `0..n_free` free, the rest fixed; springs `(a, b, material)` with rest
    /// length = initial length; duplicates merged (first wins). All springs
    /// get [`SpringClass::Muscle`] unless both ends are fixed.
    pub fn from_parts(
        positions: &[Vec3],
        n_free: usize,
        springs: &[(u32, u32, u8)],
        materials: &[Material],
        mass: f32,
        damping: f32,
    ) -> Result<SpringNetwork> {
        if n_free > positions.len() || positions.len() > MAX_NODES {
            return Err(Error::InvalidInput(format!(
                "{n_free} free nodes of {} (at most {MAX_NODES} nodes)",
                positions.len()
            )));
        }
        if materials.is_empty() || materials.len() > MAX_MATERIALS {
            return Err(Error::InvalidInput(format!(
                "need 1..={MAX_MATERIALS} materials, got {}",
                materials.len()
            )));
        }
        for m in materials {
            check_material(m, "material")?;
        }
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(Error::InvalidInput("non-finite node position".into()));
        }
        let rest: Vec<[f32; 4]> = positions.iter().map(|p| [p.x, p.y, p.z, 0.0]).collect();
        let mut list = Vec::with_capacity(springs.len());
        for &(a, b, m) in springs {
            if a == b || a as usize >= rest.len() || b as usize >= rest.len() {
                return Err(Error::InvalidInput(format!(
                    "spring ({a}, {b}) is a loop or names a missing node"
                )));
            }
            if m as usize >= materials.len() {
                return Err(Error::InvalidInput(format!(
                    "spring ({a}, {b}) uses material {m} of {}",
                    materials.len()
                )));
            }
            let (a, b) = (a.min(b), a.max(b));
            let class = if a as usize >= n_free {
                SpringClass::Bone
            } else {
                SpringClass::Muscle
            };
            list.push(Spring {
                a,
                b,
                class,
                material: m,
                rest: dvec(rest[a as usize]).distance(dvec(rest[b as usize])) as f32,
            });
        }
        list.sort_by_key(|s| (s.a, s.b));
        list.dedup_by_key(|s| (s.a, s.b));
        let params = NetworkParams {
            mass,
            damping,
            ..NetworkParams::default()
        };
        if !(mass.is_finite() && mass > 0.0 && damping.is_finite() && damping >= 0.0) {
            return Err(Error::InvalidInput(format!(
                "mass must be > 0 and damping ≥ 0, got {mass}, {damping}"
            )));
        }
        let mut net = SpringNetwork {
            params,
            origin: Vec3::ZERO,
            n_surface: 0,
            n_free,
            rest,
            surface_triangles: Vec::new(),
            bone_triangles: Vec::new(),
            springs: list,
            materials: materials.to_vec(),
            csr: SpringCsr::default(),
        };
        net.csr = net.gather_csr();
        Ok(net)
    }

    fn gather_csr(&self) -> SpringCsr {
        let nf = self.n_free as u32;
        let entry = |j: u32, s: &Spring| j | (u32::from(s.material) << 28);
        // Springs are sorted by (a, b): row i receives its (x, i) springs in
        // increasing x before its (i, y) springs in increasing y, so every
        // row comes out sorted by neighbour id.
        let pairs: Vec<(u32, u32)> = self
            .springs
            .iter()
            .flat_map(|s| {
                let ab = (s.a < nf).then(|| (s.a, entry(s.b, s)));
                let ba = (s.b < nf).then(|| (s.b, entry(s.a, s)));
                ab.into_iter().chain(ba)
            })
            .collect();
        let mut counts = vec![0u32; self.n_free + 1];
        for &(r, _) in &pairs {
            counts[r as usize + 1] += 1;
        }
        for i in 0..self.n_free {
            counts[i + 1] += counts[i];
        }
        let offsets = counts.clone();
        let mut entries = vec![0u32; pairs.len()];
        for (r, e) in pairs {
            let slot = &mut counts[r as usize];
            entries[*slot as usize] = e;
            *slot += 1;
        }
        SpringCsr { offsets, entries }
    }

    /// The kernels' material table: row m is material m's
    /// [`Material::table_row`], unused rows zero.
    pub fn material_table(&self) -> [[f32; 4]; MAX_MATERIALS] {
        let mut table = [[0.0f32; 4]; MAX_MATERIALS];
        for (row, m) in table.iter_mut().zip(&self.materials) {
            *row = m.table_row();
        }
        table
    }

    /// Total number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.rest.len()
    }

    /// Number of fixed (bone) nodes.
    pub fn n_bone(&self) -> usize {
        self.rest.len() - self.n_free
    }

    /// Rest positions of the bone layer (bone vertex ids `0..n_bone`).
    pub fn bone_rest(&self) -> &[[f32; 4]] {
        &self.rest[self.n_free..]
    }

    /// Spring count per class, in [`SpringClass::ALL`] order.
    pub fn class_counts(&self) -> [usize; 6] {
        let mut c = [0; 6];
        for s in &self.springs {
            c[s.class.index()] += 1;
        }
        c
    }

    /// Σ_j c_max,ij over the springs of each free node (the largest nodal
    /// stiffness).
    pub fn nodal_stiffness(&self) -> Vec<f32> {
        let cmax: Vec<f32> = self.materials.iter().map(Material::c_max).collect();
        (0..self.n_free)
            .into_par_iter()
            .map(|i| {
                let (s, e) = (
                    self.csr.offsets[i] as usize,
                    self.csr.offsets[i + 1] as usize,
                );
                self.csr.entries[s..e]
                    .iter()
                    .map(|&en| cmax[SpringCsr::unpack(en).1] as f64)
                    .sum::<f64>() as f32
            })
            .collect()
    }

    /// Length of the rest bounding-box diagonal (scale for default thresholds).
    pub fn diagonal(&self) -> f32 {
        let (lo, hi) = self.rest.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| {
                let v = Vec3::new(p[0], p[1], p[2]);
                (lo.min(v), hi.max(v))
            },
        );
        (hi - lo).length()
    }

    /// The bytes one iteration of the step kernels must move at least:
    /// per free node the row offset (4), own rest position, displacement
    /// and velocity read (48), displacement and velocity written (32); per
    /// CSR entry 4 bytes; the fixed nodes' rest positions and displacements
    /// (32) read once. Other neighbour reads are assumed cached (compulsory
    /// traffic only).
    pub fn bytes_per_iteration(&self) -> u64 {
        self.n_free as u64 * (4 + 48 + 32)
            + self.n_bone() as u64 * 32
            + self.csr.entries.len() as u64 * 4
    }
}

fn check_material(m: &Material, what: &str) -> Result<()> {
    let ok = |v: f32| v.is_finite() && v >= 0.0;
    if !(ok(m.c1) && ok(m.c2) && ok(m.knee)) || m.c_max() == 0.0 {
        return Err(Error::InvalidInput(format!(
            "{what}: c1, c2, knee must be finite and ≥ 0 with c1 or c2 > 0, got {m:?}"
        )));
    }
    Ok(())
}
