//! Network construction: takes an epidermis (and optional bone) mesh with
//! [`NetworkParams`], or explicit nodes and springs, and returns a
//! [`SpringNetwork`] with its layers, eq. 4.1 k-d tree links, materials
//! (stiffness regions included) and CSR.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::super::kdtree::KdTree;
use super::surface::{default_origin, dvec, edge_apexes, one_rings, unique_edges};
use super::{
    MAX_MATERIALS, MAX_NODES, Material, NetworkParams, Spring, SpringClass, SpringCsr,
    SpringNetwork,
};
use crate::mesh::TriMesh;
use crate::{Error, Result};

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
            return Err(Error::empty("epidermis mesh triangles"));
        }
        for (name, v) in [
            ("subcutis_scale", params.subcutis_scale),
            ("bone_scale", params.bone_scale),
            ("mass", params.mass),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::param(name, v, "must be finite and > 0"));
            }
        }
        if !(params.damping.is_finite() && params.damping >= 0.0) {
            return Err(Error::param(
                "damping",
                params.damping,
                "must be finite and ≥ 0",
            ));
        }
        let origin = match params.origin {
            Some(o) if o.iter().all(|c| c.is_finite()) => Vec3::from_array(o),
            Some(o) => {
                return Err(Error::param("origin", format!("{o:?}"), "must be finite"));
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
                    return Err(Error::empty("bone mesh vertices"));
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
            return Err(Error::limit("spring network nodes", n_nodes, MAX_NODES));
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
                    return Err(Error::param(
                        "subcutis_depth",
                        d,
                        if bone.is_none() {
                            "needs a bone mesh (none was given)"
                        } else {
                            "must lie in (0, 1)"
                        },
                    ));
                }
                let normals =
                    crate::vertex_normals::vertex_normals(epidermis, crate::gpu::Backend::Cpu)?;
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
            return Err(Error::param(
                "projection_scale",
                s,
                "must be finite and > 0",
            ));
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
                return Err(Error::param(
                    "region",
                    reg.region.describe(),
                    "stiffness regions take a sphere, box or half_space",
                )
                .within(what));
            }
            if !(reg.scale.is_finite() && reg.scale > 0.0) {
                return Err(Error::param("scale", reg.scale, "must be finite and > 0").within(what));
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
                            return Err(Error::limit(
                                "distinct spring materials of the stiffness regions",
                                MAX_MATERIALS + 1,
                                MAX_MATERIALS,
                            ));
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
            return Err(if positions.len() > MAX_NODES {
                Error::limit("spring network nodes", positions.len(), MAX_NODES)
            } else {
                Error::param(
                    "n_free",
                    n_free,
                    format!("must be at most the {} nodes", positions.len()),
                )
            });
        }
        if materials.is_empty() || materials.len() > MAX_MATERIALS {
            return Err(Error::param(
                "materials",
                materials.len(),
                format!("need 1..={MAX_MATERIALS} materials"),
            ));
        }
        for m in materials {
            check_material(m, "material")?;
        }
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::data(
                "spring network",
                "node",
                i,
                format!("position {} is not finite", positions[i]),
            ));
        }
        let rest: Vec<[f32; 4]> = positions.iter().map(|p| [p.x, p.y, p.z, 0.0]).collect();
        let mut list = Vec::with_capacity(springs.len());
        for (i, &(a, b, m)) in springs.iter().enumerate() {
            if a == b || a as usize >= rest.len() || b as usize >= rest.len() {
                return Err(Error::data(
                    "spring network",
                    "spring",
                    i,
                    format!("({a}, {b}) is a loop or names a missing node"),
                ));
            }
            if m as usize >= materials.len() {
                return Err(Error::data(
                    "spring network",
                    "spring",
                    i,
                    format!("({a}, {b}) uses material {m} of {}", materials.len()),
                ));
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
            return Err(if mass.is_finite() && mass > 0.0 {
                Error::param("damping", damping, "must be finite and ≥ 0")
            } else {
                Error::param("mass", mass, "must be finite and > 0")
            });
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
}

fn check_material(m: &Material, what: &str) -> Result<()> {
    let ok = |v: f32| v.is_finite() && v >= 0.0;
    if !(ok(m.c1) && ok(m.c2) && ok(m.knee)) || m.c_max() == 0.0 {
        return Err(Error::param(
            "c1, c2, knee",
            format!("{}, {}, {}", m.c1, m.c2, m.knee),
            "must be finite and ≥ 0 with c1 or c2 > 0",
        )
        .within(what));
    }
    Ok(())
}
