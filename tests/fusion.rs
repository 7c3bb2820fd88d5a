//! Fusion, subtraction and morphing (SPEC §3.4, seed 001 §2) and their
//! guarantees: vol(C) → vol(A) + vol(B) with order ≥ 1.8, A ∪ B ⊆ C by an
//! exact point-in-mesh test, C closed, outward and free of
//! self-intersections, concentric spheres fusing to ∛(r_A³ + r_B³), the
//! morph's volume linear in t with C(0) on A and C(1) on B, and refusals
//! that name the failing rays. The layered fusion of a mesh that is not
//! star-shaped (§2.6.2): its fills, its surface, its refusals. Real data:
//! star-shaped foot bones, and the largest bone (no kernel) by layers.

use chisel::fusion::{FuseOptions, MorphOptions, RefineOptions, find_center, fuse, morph};
use chisel::mesh::distance::DistanceGrid;
use chisel::mesh::{Side, Topology, point_side, self_intersections};
use chisel::ray_cast::{Bvh, ray_cast};
use chisel::{Backend, Error, Refusal, TriMesh};
use glam::Vec3;

mod common;

fn sphere(level: u32, r: f32, at: Vec3) -> TriMesh {
    let mut m = common::icosphere(level);
    for p in &mut m.positions {
        *p = *p * r + at;
    }
    m
}

fn options(tolerance: f64) -> FuseOptions {
    FuseOptions {
        refine: RefineOptions {
            tolerance: Some(tolerance),
            ..RefineOptions::default()
        },
        ..FuseOptions::default()
    }
}

/// Two spheres of radius 0.5 side by side (centres 2 apart): from inside
/// the first, rays towards the second cross the mesh three times.
fn two_spheres() -> TriMesh {
    let mut a = sphere(3, 0.5, Vec3::ZERO);
    let second = sphere(3, 0.5, Vec3::new(2.0, 0.0, 0.0));
    let n = a.positions.len() as u32;
    a.positions.extend(&second.positions);
    a.triangles
        .extend(second.triangles.iter().map(|t| t.map(|v| v + n)));
    a
}

/// The same triangles, positions within 10⁻⁵ (a CPU and a GPU run).
fn assert_same_mesh(cpu: &TriMesh, gpu: &TriMesh) {
    assert_eq!(cpu.triangles, gpu.triangles);
    let worst = cpu
        .positions
        .iter()
        .zip(&gpu.positions)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0f32, f32::max);
    assert!(worst <= 1e-5, "positions differ by {worst}");
}

/// C is a closed, outward, self-intersection-free genus-0 surface.
fn assert_valid_surface(what: &str, c: &TriMesh) {
    let topo = Topology::of(c);
    assert!(
        topo.closed && topo.is_manifold(),
        "{what}: not a closed manifold"
    );
    assert!(
        topo.consistently_oriented,
        "{what}: not consistently oriented"
    );
    assert_eq!(topo.components.len(), 1, "{what}: components");
    assert_eq!(topo.euler, 2, "{what}: genus");
    assert!(c.signed_volume() > 0.0, "{what}: wound inward");
    let crossing = self_intersections(c);
    assert!(
        crossing.pairs.is_empty(),
        "{what}: {} crossing pairs",
        crossing.pairs.len()
    );
    assert!(
        crossing.degenerate.is_empty(),
        "{what}: zero-area triangles"
    );
}

/// No vertex of `m` lies outside `c`, by the general exact test.
fn assert_contains(what: &str, c: &TriMesh, m: &TriMesh) {
    for (i, p) in m.positions.iter().enumerate() {
        let side = point_side(c, p.as_dvec3().to_array());
        assert!(
            matches!(side, Some(Side::Inside | Side::Surface)),
            "{what}: vertex {i} at {p} is {side:?}"
        );
    }
}

#[test]
fn concentric_spheres_fuse_to_the_cube_root_radius() {
    // Same-shaped polyhedra about one centre: ρ_A = r_A·g(d), ρ_B = r_B·g(d),
    // so C is exactly the shape scaled by R = ∛(r_A³ + r_B³).
    let unit = sphere(3, 1.0, Vec3::ZERO);
    let (ra, rb) = (1.0f32, 0.8f32);
    let big = (ra.powi(3) + rb.powi(3)).cbrt();
    let a = sphere(3, ra, Vec3::ZERO);
    let b = sphere(3, rb, Vec3::ZERO);
    let mut o = options(1e-4);
    o.center = Some(Vec3::ZERO);
    let f = fuse(&a, &b, &o, Backend::Cpu, |_| {}).unwrap();
    let bvh = Bvh::build(&unit).unwrap();
    let dirs: Vec<[f32; 4]> = f
        .mesh
        .positions
        .iter()
        .map(|p| {
            let d = p.normalize();
            [d.x, d.y, d.z, 0.0]
        })
        .collect();
    let hits = ray_cast(&bvh, Vec3::ZERO, &dirs, Backend::Cpu).unwrap();
    for (p, h) in f.mesh.positions.iter().zip(&hits) {
        let expected = f64::from(h.far) * f64::from(big);
        let got = f64::from(p.length());
        assert!(
            (got - expected).abs() < 2e-6,
            "{p}: |p| {got} vs R·g(d) {expected}"
        );
    }
    let expected = f64::from(big).powi(3) * unit.signed_volume();
    assert!(
        (f.mesh.signed_volume() - expected).abs() / expected < 2e-4,
        "volume {} vs {expected}",
        f.mesh.signed_volume()
    );
    assert_valid_surface("concentric", &f.mesh);
}

#[test]
fn volume_converges_with_order_two() {
    // Two overlapping spheres (82k triangles each); the centre is searched.
    let a = sphere(6, 1.0, Vec3::ZERO);
    let b = sphere(6, 0.7, Vec3::new(0.8, 0.1, 0.0));
    let mut last: Option<(usize, f64)> = None;
    let mut orders = Vec::new();
    for tol in [4e-3, 1e-3, 2.5e-4] {
        let f = fuse(&a, &b, &options(tol), Backend::Cpu, |_| {}).unwrap();
        let r = &f.report;
        let target = a.signed_volume() + b.signed_volume();
        assert!((r.volumes.target - target).abs() < 1e-12 * target);
        assert_eq!(r.outside, 0);
        assert!(r.center_search.is_some());
        let (n, err) = (r.triangles, r.volumes.relative_error);
        if let Some((n0, e0)) = last {
            // Error against the mean edge h ∝ N^(−1/2).
            orders.push((e0 / err).ln() / (0.5 * (n as f64 / n0 as f64).ln()));
        }
        last = Some((n, err));
        if (10_000..=20_000).contains(&n) {
            assert!(err <= 1.5e-3, "{n} triangles: error {err:e}");
        }
    }
    let (n, err) = last.unwrap();
    assert!(err < 4e-4, "{n} triangles: error {err:e}");
    assert!(
        orders.iter().all(|&o| o >= 1.8),
        "convergence orders {orders:?}"
    );
}

#[test]
fn fused_surface_is_closed_and_contains_both() {
    let a = sphere(3, 1.0, Vec3::ZERO);
    let b = sphere(3, 0.6, Vec3::new(0.9, 0.2, -0.1));
    let f = fuse(&a, &b, &options(1e-3), Backend::Cpu, |_| {}).unwrap();
    assert_valid_surface("two spheres", &f.mesh);
    assert_contains("A in C", &f.mesh, &a);
    assert_contains("B in C", &f.mesh, &b);
    assert_eq!(f.report.outside, 0);
}

#[test]
fn coarse_fusion_refines_until_both_inputs_are_inside() {
    // A loose tolerance leaves chords that cut A's corners; the exact
    // containment rounds refine there until no vertex is outside.
    let a = sphere(2, 1.0, Vec3::ZERO);
    let b = sphere(2, 0.5, Vec3::new(0.8, 0.0, 0.0));
    let mut o = options(0.05);
    o.refine.start_level = 0;
    let f = fuse(&a, &b, &o, Backend::Cpu, |_| {}).unwrap();
    assert!(
        f.report.containment_rounds > 0,
        "no round was needed: weak test"
    );
    assert_eq!(f.report.outside, 0);
    assert_contains("A in C", &f.mesh, &a);
    assert_contains("B in C", &f.mesh, &b);
    assert_valid_surface("coarse", &f.mesh);
}

#[test]
fn edges_across_a_crease_are_split_down_to_the_floor() {
    // A cube (90° creases) and a small ball inside it: every edge of C
    // whose ends see two different cube faces is at most
    // CREASE_CHORD_OF_TOLERANCE (8) tolerances long. The chord test alone
    // leaves such edges up to 11.5 tolerances long (a crease near one end
    // barely moves the midpoint).
    let cube = common::cube();
    let ball = sphere(2, 0.2, Vec3::splat(0.5));
    let tol = 2e-3;
    let mut o = options(tol);
    o.center = Some(Vec3::splat(0.5));
    let f = fuse(&cube, &ball, &o, Backend::Cpu, |_| {}).unwrap();
    let bvh = Bvh::build(&cube).unwrap();
    let h = Vec3::splat(0.5);
    let dirs: Vec<[f32; 4]> = f
        .mesh
        .positions
        .iter()
        .map(|p| {
            let d = *p - h;
            [d.x, d.y, d.z, 0.0]
        })
        .collect();
    let hits = ray_cast(&bvh, h, &dirs, Backend::Cpu).unwrap();
    let normal = |t: u32| {
        let [a, b, c] = cube.triangles[t as usize].map(|v| cube.positions[v as usize]);
        (b - a).cross(c - a).normalize()
    };
    let floor = chisel::fusion::CREASE_CHORD_OF_TOLERANCE * tol;
    let mut across = 0;
    for t in &f.mesh.triangles {
        for k in 0..3 {
            let (u, v) = (t[k] as usize, t[(k + 1) % 3] as usize);
            if normal(hits[u].near_tri).dot(normal(hits[v].near_tri)) < 0.5 {
                across += 1;
                let chord = f64::from((f.mesh.positions[u] - f.mesh.positions[v]).length());
                assert!(
                    chord <= floor * (1.0 + 1e-6),
                    "edge {u}–{v}: chord {chord} across a crease"
                );
            }
        }
    }
    assert!(
        across > 100,
        "only {across} edges across the cube's creases"
    );
    assert_valid_surface("cube and ball", &f.mesh);
    assert!(
        f.report.volumes.relative_error < 1e-2,
        "{:?}",
        f.report.volumes
    );
}

#[test]
fn subtraction_removes_the_volume_of_b() {
    let a = sphere(5, 1.0, Vec3::ZERO);
    let b = sphere(5, 0.5, Vec3::new(0.2, 0.1, 0.0));
    let mut o = options(2e-4);
    o.subtract = true;
    o.center = Some(Vec3::new(0.1, 0.05, 0.0));
    let f = fuse(&a, &b, &o, Backend::Cpu, |_| {}).unwrap();
    let target = a.signed_volume() - b.signed_volume();
    assert!((f.report.volumes.target - target).abs() < 1e-12);
    assert!(
        f.report.volumes.relative_error < 1e-3,
        "{:?}",
        f.report.volumes
    );
    assert_valid_surface("subtraction", &f.mesh);
    // C lies inside A.
    assert_contains("C in A", &a, &f.mesh);
}

#[test]
fn subtraction_refuses_where_b_reaches_out_of_a() {
    let a = sphere(3, 1.0, Vec3::ZERO);
    let b = sphere(3, 0.6, Vec3::new(0.6, 0.0, 0.0));
    let mut o = options(1e-3);
    o.subtract = true;
    o.center = Some(Vec3::new(0.5, 0.0, 0.0));
    match fuse(&a, &b, &o, Backend::Cpu, |_| {}) {
        Err(Error::Refused(Refusal::SubtractionReachesOut {
            failing, examples, ..
        })) => {
            assert!(failing > 0);
            // Every example direction points to where B is beyond A: +x.
            assert!(examples.iter().all(|d| d[0] > 0.0), "{examples:?}");
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[test]
fn subtraction_from_a_non_star_shaped_mesh_is_refused_with_its_rays() {
    let a = two_spheres();
    let b = sphere(3, 0.4, Vec3::new(0.2, 0.0, 0.0));
    // (A fusion goes on by layers; a subtraction refuses.)
    let mut o = options(1e-3);
    o.subtract = true;
    o.center = Some(Vec3::new(0.1, 0.0, 0.0));
    match fuse(&a, &b, &o, Backend::Cpu, |_| {}) {
        Err(Error::Refused(Refusal::NotStarShaped {
            mesh,
            failing,
            examples,
            ..
        })) => {
            assert_eq!(mesh, "A");
            assert!(failing > 0);
            assert!(
                examples.iter().all(|(d, hits)| d[0] > 0.9 && *hits == 3),
                "{examples:?}"
            );
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
    // And the centre search proves no centre exists.
    assert!(matches!(
        find_center(&a, &b),
        Err(Error::Refused(Refusal::NoStarCenter(_)))
    ));
}

#[test]
fn centre_search_refuses_disjoint_meshes() {
    let a = sphere(2, 1.0, Vec3::ZERO);
    let b = sphere(2, 1.0, Vec3::new(3.0, 0.0, 0.0));
    let err = find_center(&a, &b).unwrap_err().to_string();
    assert!(err.contains("do not overlap"), "{err}");
}

#[test]
fn morph_volume_is_linear_and_ends_on_a_and_b() {
    let a = sphere(5, 1.0, Vec3::ZERO);
    let mut b = sphere(5, 0.5, Vec3::new(0.3, 0.0, 0.0));
    for p in &mut b.positions {
        p.y *= 2.0; // an ellipsoid
    }
    let o = MorphOptions {
        center: Some(Vec3::new(0.1, 0.0, 0.0)),
        center_end: None,
        frames: 5,
        refine: RefineOptions {
            tolerance: Some(2e-4),
            ..RefineOptions::default()
        },
    };
    let m = morph(&a, &b, &o, Backend::Cpu, |_| {}).unwrap();
    assert_eq!(m.frames.len(), 5);
    for f in &m.frames {
        assert_eq!(f.triangles, m.frames[0].triangles, "one connectivity");
        assert_valid_surface("morph frame", f);
    }
    for f in &m.report.frames {
        assert!(
            f.volumes.relative_error < 1e-3,
            "t = {}: {:?}",
            f.t,
            f.volumes
        );
    }
    // C(0) on A, C(1) on B: every vertex on the surface (f32 hits).
    for (frame, target) in [(&m.frames[0], &a), (&m.frames[4], &b)] {
        let grid = DistanceGrid::new(target);
        let worst = frame
            .positions
            .iter()
            .map(|p| grid.distance(*p))
            .fold(0.0, f64::max);
        assert!(worst < 1e-5, "vertex {worst} from its end mesh");
    }
}

#[test]
fn morph_with_a_moving_centre_keeps_volumes_linear() {
    let a = sphere(4, 1.0, Vec3::ZERO);
    let b = sphere(4, 0.8, Vec3::new(0.5, 0.0, 0.0));
    let o = MorphOptions {
        center: Some(Vec3::new(-0.2, 0.0, 0.0)),
        center_end: Some(Vec3::new(0.6, 0.0, 0.0)),
        frames: 4,
        refine: RefineOptions {
            tolerance: Some(5e-4),
            ..RefineOptions::default()
        },
    };
    let m = morph(&a, &b, &o, Backend::Cpu, |_| {}).unwrap();
    let centers: Vec<f64> = m.report.frames.iter().map(|f| f.center[0]).collect();
    assert!(
        (centers[0] + 0.2).abs() < 1e-6 && (centers[3] - 0.6).abs() < 1e-6,
        "{centers:?}"
    );
    for f in &m.report.frames {
        assert!(
            f.volumes.relative_error < 3e-3,
            "t = {}: {:?}",
            f.t,
            f.volumes
        );
    }
}

#[test]
fn cpu_and_gpu_fusions_are_the_same_mesh() {
    let Some(gpu) = common::gpu() else { return };
    let a = sphere(4, 1.0, Vec3::ZERO);
    let b = sphere(4, 0.7, Vec3::new(0.7, 0.3, 0.0));
    let cpu = fuse(&a, &b, &options(1e-3), Backend::Cpu, |_| {}).unwrap();
    let gpu = fuse(&a, &b, &options(1e-3), Backend::Gpu(gpu), |_| {}).unwrap();
    // ray_cast is exact in triangle ids and counts, and its distances agree
    // to the bit on a device without contraction: the same refinement.
    assert_same_mesh(&cpu.mesh, &gpu.mesh);
}

/// The foot bones' components, largest first.
fn foot_bones() -> Option<Vec<TriMesh>> {
    let feet = common::real_mesh("fsu/footbones.ply")?;
    let (labels, _) = chisel::foundation::vertex_components(feet.positions.len(), &feet.triangles);
    let mut bones = chisel::mesh::split_by_label(&feet, &labels);
    bones.sort_by_key(|b| std::cmp::Reverse(b.triangles.len()));
    Some(bones)
}

#[test]
fn star_shaped_foot_bones_fuse() {
    let Some(bones) = foot_bones() else { return };
    // Bones 4 and 6 (228 and 154 triangles) have kernels (points from which
    // they are star-shaped); bone 6 is moved so that the kernels overlap.
    let a = &bones[4];
    let mut b = bones[6].clone();
    let ha = Vec3::from(find_center(a, a).unwrap().center.map(|v| v as f32));
    let hb = Vec3::from(find_center(&b, &b).unwrap().center.map(|v| v as f32));
    for p in &mut b.positions {
        *p += ha - hb + Vec3::new(0.02, 0.0, 0.0);
    }
    // Flat faces and sharp creases: the chord test refines along every
    // crease, so a tolerance of 10⁻³ of the diagonal (56k triangles).
    let (lo, hi) = a.bounds().unwrap();
    let f = fuse(
        a,
        &b,
        &options(1e-3 * f64::from((hi - lo).length())),
        Backend::Cpu,
        |_| {},
    )
    .unwrap();
    let r = &f.report;
    assert!(r.center_search.is_some_and(|c| c.clearance > 0.0));
    assert!(r.volumes.relative_error < 1e-3, "{:?}", r.volumes);
    assert_valid_surface("foot bones", &f.mesh);
    assert_contains("A in C", &f.mesh, a);
    assert_contains("B in C", &f.mesh, &b);
    // The largest bone has no kernel: refused with the reason.
    let err = find_center(&bones[0], &bones[0]).unwrap_err().to_string();
    assert!(err.contains("kernels of A and B"), "{err}");
}

/// The layered fusion's own checks on C: closed, outward, free of
/// self-intersections, the volume within `rel`, B strictly inside and A's
/// vertices outside C (where C's boundary is A's surface) at most
/// `outside_cells` cells away, as the report says.
fn assert_layered(
    what: &str,
    f: &chisel::fusion::Fused,
    b: &TriMesh,
    rel: f64,
    outside_cells: f64,
) {
    let r = &f.report;
    let l = r.layered.as_ref().expect("the layered method ran");
    assert_eq!(r.method, "layered");
    assert!(!r.star_shaped);
    assert!(r.volumes.relative_error < rel, "{what}: {:?}", r.volumes);
    let topo = Topology::of(&f.mesh);
    assert!(
        topo.closed && topo.is_manifold() && topo.consistently_oriented,
        "{what}: surface"
    );
    assert!(f.mesh.signed_volume() > 0.0, "{what}: wound inward");
    let crossing = self_intersections(&f.mesh);
    assert!(
        crossing.pairs.is_empty() && crossing.degenerate.is_empty(),
        "{what}: crossings"
    );
    assert_contains(&format!("{what}: B in C"), &f.mesh, b);
    assert!(
        l.outside_distance <= outside_cells * l.cell,
        "{what}: vertices {} cells outside",
        l.outside_distance / l.cell
    );
    assert!(l.crossing_bracket <= 0.25 * l.cell, "{what}: {l:?}");
}

#[test]
fn layers_of_a_fill_outward_in_order() {
    use chisel::fusion::layered::intervals;
    // Star-shaped A: eq. 5.
    let c = intervals(&[2.0], 1.0);
    assert_eq!(c.len(), 1);
    assert!((c[0][1] - 9f64.cbrt()).abs() < 1e-12);
    // A = [0, 1] ∪ [2, 3], B = [0, 0.5]: excess 0.125 fills [1, ∛1.125].
    let c = intervals(&[1.0, 2.0, 3.0], 0.5);
    assert_eq!(c.len(), 2, "{c:?}");
    assert!((c[0][1] - 1.125f64.cbrt()).abs() < 1e-12);
    assert_eq!(c[1], [2.0, 3.0]);
    // A = [0, 1] ∪ [1.1, 1.2] ∪ [2, 3], B = [0, 1]: excess 1 fills the gap
    // [1, 1.1] (0.331), merges, and the rest (0.669) goes past 1.2.
    let c = intervals(&[1.0, 1.1, 1.2, 2.0, 3.0], 1.0);
    assert_eq!(c.len(), 2, "{c:?}");
    let end = (1.2f64.powi(3) + 1.0 - (1.331 - 1.0)).cbrt();
    assert!((c[0][1] - end).abs() < 1e-12, "{c:?} vs {end}");
    // B reaching past A's first layer into a second.
    let c = intervals(&[1.0, 2.0, 3.0], 2.5);
    let measure: f64 = c.iter().map(|[s, e]| e.powi(3) - s.powi(3)).sum();
    assert!(
        (measure - (1.0 + 27.0 - 8.0 + 2.5f64.powi(3))).abs() < 1e-9,
        "{c:?}"
    );
}

#[test]
fn torus_fuses_with_a_sphere_by_layers() {
    // Rays from a point in the torus's tube cross it three times towards
    // the hole: not star-shaped, and its kernel is empty, so the centre is
    // the sphere's kernel point inside the torus.
    let a = common::torus(1.0, 0.35, 96, 32);
    let b = sphere(4, 0.5, Vec3::new(1.0, 0.0, 0.0));
    let o = FuseOptions {
        cells: 96,
        ..FuseOptions::default()
    };
    let f = fuse(&a, &b, &o, Backend::Cpu, |_| {}).unwrap();
    assert_layered("torus", &f, &b, 2e-3, 0.25);
    assert_eq!(Topology::of(&f.mesh).euler, 0, "a torus stays a torus");
    let h = f.report.center;
    assert!((h[0] - 1.0).abs() < 1e-3 && h[1].abs() < 1e-3, "{h:?}");
    // The same on the GPU, coarser: the same mesh.
    if let Some(gpu) = common::gpu() {
        let o = FuseOptions {
            cells: 40,
            ..FuseOptions::default()
        };
        let cpu = fuse(&a, &b, &o, Backend::Cpu, |_| {}).unwrap();
        let on_gpu = fuse(&a, &b, &o, Backend::Gpu(gpu), |_| {}).unwrap();
        assert_same_mesh(&cpu.mesh, &on_gpu.mesh);
    }
}

#[test]
fn layered_fusion_refuses_what_the_seed_excludes() {
    let a = two_spheres();
    // B meeting both spheres: A ∩ B falls into two pieces.
    let b = sphere(3, 0.8, Vec3::new(1.0, 0.0, 0.0));
    let mut o = options(1e-3);
    o.center = Some(Vec3::new(0.4, 0.0, 0.0));
    match fuse(&a, &b, &o, Backend::Cpu, |_| {}) {
        Err(Error::Refused(Refusal::IntersectionNotConnected { components, .. })) => {
            assert_eq!(components, 2)
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
    // H outside A (but inside B): every ray crosses A an even number of
    // times.
    o.center = Some(Vec3::new(1.0, 0.0, 0.0));
    assert!(matches!(
        fuse(&a, &b, &o, Backend::Cpu, |_| {}),
        Err(Error::Refused(Refusal::OpenAlongRays { mesh: "A", .. }))
    ));
    // Neither star-shaped: B is A's mirror image.
    let mirrored = TriMesh {
        positions: a
            .positions
            .iter()
            .map(|p| Vec3::new(1.0 - p.x, p.y, p.z))
            .collect(),
        triangles: a.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect(),
        scalars: Vec::new(),
    };
    let mut o = options(1e-3);
    o.center = Some(Vec3::new(0.2, 0.0, 0.0));
    let small = sphere(3, 0.2, Vec3::new(0.2, 0.0, 0.0));
    let err = fuse(&a, &mirrored, &o, Backend::Cpu, |_| {}).unwrap_err();
    assert!(
        matches!(
            err,
            Error::Refused(Refusal::NotStarShaped { mesh: "B", .. })
        ),
        "{err}"
    );
    // B inside A's first sphere: one connected A ∩ B, fused by layers.
    let f = fuse(&a, &small, &o, Backend::Cpu, |_| {}).unwrap();
    assert_layered("two spheres", &f, &small, 2e-3, 0.25);
    assert_eq!(Topology::of(&f.mesh).components.len(), 2);
}

#[test]
fn foot_bone_without_a_kernel_fuses_by_layers() {
    let Some(bones) = foot_bones() else { return };
    // The largest bone has no kernel; bone 4 (which has one) is moved so
    // that its kernel point sits at the middle of bone 0's box.
    let a = &bones[0];
    let (lo, hi) = a.bounds().unwrap();
    let mut b = bones[4].clone();
    let hb = Vec3::from(find_center(&b, &b).unwrap().center.map(|v| v as f32));
    for p in &mut b.positions {
        *p += (lo + hi) * 0.5 - hb;
    }
    let f = fuse(a, &b, &FuseOptions::default(), Backend::Cpu, |_| {}).unwrap();
    assert!(f.report.center_search.is_some_and(|c| c.clearance > 0.0));
    // Flat faces and sharp creases: corners of A up to a cell outside.
    assert_layered("foot bones", &f, &b, 2e-3, 1.0);
    assert_eq!(Topology::of(&f.mesh).euler, 2);
}
