//! Parity of `kernels/ray_cast.wgsl` against `ray_cast::cpu`: exact hit
//! counts and triangle ids, distances within `DISTANCE_ULPS`, on an
//! icosphere (rays through its vertices and along its edges included, which
//! the watertight test must count once), a random triangle soup (many hits
//! per ray), the foot bones and the bunny. An f64 oracle (brute force over
//! every triangle, Möller–Trumbore) checks the mirror's counts and
//! distances on rays that pass no edge closely. Negative controls: a hit
//! moved to another triangle, a count off by one, a distance a few hundred
//! ulps off.

use chisel::TriMesh;
use chisel::gpu::Gpu;
use chisel::parity::find_sentinel;
use chisel::ray_cast::gpu::{BvhBuffers, RayBuffers};
use chisel::ray_cast::{Bvh, DISTANCE_ULPS, RayHit, cpu};
use glam::{DVec3, Vec3};

use crate::common;

fn gpu_hits(gpu: &Gpu, what: &str, bvh: &Bvh, origin: Vec3, dirs: &[[f32; 4]]) -> Vec<RayHit> {
    let nodes = BvhBuffers::upload(gpu, bvh).unwrap();
    let rays = RayBuffers::upload(gpu, &nodes, origin, dirs).unwrap();
    let mut encoder = gpu.encoder("ray_cast");
    rays.record(gpu, &nodes, &mut encoder).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let hits = rays.hits.read(gpu).unwrap();
    let sentinel = hits
        .iter()
        .position(|h| h.count == u32::MAX || h.near.is_nan());
    assert_eq!(sentinel, None, "{what}: sentinel survived");
    assert_eq!(
        find_sentinel(
            &hits,
            RayHit {
                near: f32::NAN,
                far: f32::NAN,
                near_tri: u32::MAX,
                far_tri: u32::MAX,
                count: u32::MAX
            }
        ),
        None
    );
    hits
}

/// Whether `b` is within `ulps` units in the last place of `a`.
pub(crate) fn close(a: f32, b: f32, ulps: u32) -> bool {
    a == b || (a.signum() == b.signum() && a.to_bits().abs_diff(b.to_bits()) <= ulps)
}

/// The first ray where GPU and mirror disagree, as a message.
fn compare(what: &str, want: &[RayHit], got: &[RayHit]) -> Result<(), String> {
    assert_eq!(want.len(), got.len());
    for (i, (w, g)) in want.iter().zip(got).enumerate() {
        if w.count != g.count || w.near_tri != g.near_tri || w.far_tri != g.far_tri {
            return Err(format!("{what}: ray {i}: mirror {w:?}, GPU {g:?}"));
        }
        if !close(w.near, g.near, DISTANCE_ULPS) || !close(w.far, g.far, DISTANCE_ULPS) {
            return Err(format!("{what}: ray {i}: distances {w:?} vs {g:?}"));
        }
    }
    Ok(())
}

pub(crate) fn dirs_of(v: &[DVec3]) -> Vec<[f32; 4]> {
    v.iter()
        .map(|d| {
            let d = d.as_vec3();
            [d.x, d.y, d.z, 0.0]
        })
        .collect()
}

fn check(gpu: &Gpu, what: &str, mesh: &TriMesh, origin: Vec3, dirs: &[[f32; 4]]) -> Vec<RayHit> {
    let bvh = Bvh::build(mesh).unwrap();
    let want = cpu::ray_cast(&bvh, origin.to_array(), dirs);
    let got = gpu_hits(gpu, what, &bvh, origin, dirs);
    compare(what, &want, &got).unwrap_or_else(|m| panic!("{m}"));
    want
}

/// Every hit of the ray in f64 (Möller–Trumbore), and the smallest
/// barycentric margin of any triangle the ray's line passes (a measure of
/// how close it comes to an edge).
fn oracle(mesh: &TriMesh, o: DVec3, d: DVec3) -> (Vec<(f64, u32)>, f64) {
    let mut hits = Vec::new();
    let mut margin = f64::INFINITY;
    for (id, t) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize].as_dvec3());
        let (e1, e2) = (b - a, c - a);
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-300 {
            continue;
        }
        let s = o - a;
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = d.dot(q) / det;
        let w = 1.0 - u - v;
        let m = u.min(v).min(w);
        let t_hit = e2.dot(q) / det;
        if m.abs() < margin && t_hit > 0.0 {
            margin = margin.min(m.abs());
        }
        if m >= 0.0 && t_hit > 0.0 {
            hits.push((t_hit, id as u32));
        }
    }
    (hits, margin)
}

/// The mirror against the oracle on rays that keep 10⁻⁴ (barycentric) away
/// from every edge: the same count and nearest/farthest triangles, and
/// distances within 10⁻⁵ of (distance + the mesh's diagonal).
fn check_oracle(what: &str, mesh: &TriMesh, origin: Vec3, dirs: &[[f32; 4]], hits: &[RayHit]) {
    let (lo, hi) = mesh.bounds().unwrap();
    let diagonal = f64::from((hi - lo).length());
    let mut checked = 0;
    for (d, h) in dirs.iter().zip(hits) {
        let dv = Vec3::new(d[0], d[1], d[2]).as_dvec3();
        let (all, margin) = oracle(mesh, origin.as_dvec3(), dv);
        if margin < 1e-4 {
            continue;
        }
        checked += 1;
        assert_eq!(all.len() as u32, h.count, "{what}: count along {d:?}");
        if let (Some(near), Some(far)) = (
            all.iter().min_by(|a, b| a.0.total_cmp(&b.0)),
            all.iter().max_by(|a, b| a.0.total_cmp(&b.0)),
        ) {
            assert_eq!(
                (near.1, far.1),
                (h.near_tri, h.far_tri),
                "{what}: triangles along {d:?}"
            );
            // f32 arithmetic on coordinates of the mesh's size: an error
            // bound relative to the distance plus the diagonal.
            let bound = |t: f64| 1e-5 * (t + diagonal);
            assert!(
                (near.0 - f64::from(h.near)).abs() <= bound(near.0),
                "{what}: near {near:?} vs {h:?}"
            );
            assert!(
                (far.0 - f64::from(h.far)).abs() <= bound(far.0),
                "{what}: far {far:?} vs {h:?}"
            );
        }
    }
    assert!(
        checked * 2 > dirs.len(),
        "{what}: only {checked} rays away from edges"
    );
}

#[test]
fn icosphere_rays_through_vertices_and_edges_hit_once() {
    let mesh = common::icosphere(3);
    let bvh = Bvh::build(&mesh).unwrap();
    // Through every vertex, every edge midpoint (exactly on an edge's
    // line) and along the axes, from the centre: exactly one hit each.
    let mut dirs: Vec<DVec3> = mesh.positions.iter().map(|p| p.as_dvec3()).collect();
    for t in &mesh.triangles {
        let [a, b, _] = t.map(|v| mesh.positions[v as usize]);
        dirs.push(((a + b) * 0.5).as_dvec3());
    }
    dirs.extend([
        DVec3::X,
        DVec3::Y,
        DVec3::Z,
        DVec3::NEG_X,
        DVec3::NEG_Y,
        DVec3::NEG_Z,
    ]);
    let dirs = dirs_of(&dirs);
    let hits = cpu::ray_cast(&bvh, [0.0; 3], &dirs);
    let bad: Vec<_> = hits
        .iter()
        .enumerate()
        .filter(|(_, h)| h.count != 1)
        .collect();
    assert!(
        bad.is_empty(),
        "{} rays not hitting once: {:?}",
        bad.len(),
        &bad[..bad.len().min(4)]
    );
    if let Some(gpu) = common::gpu() {
        check(gpu, "icosphere vertices", &mesh, Vec3::ZERO, &dirs);
    }
}

#[test]
fn gpu_matches_mirror_on_synthetic_meshes() {
    let Some(gpu) = common::gpu() else { return };
    let sphere = common::icosphere(4);
    let dirs = dirs_of(&common::fibonacci_sphere(4000));
    for origin in [
        Vec3::ZERO,
        Vec3::new(0.3, -0.2, 0.1),
        Vec3::new(2.0, 0.5, 0.0),
    ] {
        let hits = check(gpu, "icosphere", &sphere, origin, &dirs);
        check_oracle("icosphere", &sphere, origin, &dirs[..500], &hits[..500]);
    }
    // A soup: rays from its middle hit many triangles.
    let soup = common::random_mesh(7, 600, 2000);
    let hits = check(gpu, "soup", &soup, Vec3::new(0.05, 0.0, -0.1), &dirs);
    assert!(
        hits.iter().any(|h| h.count > 5),
        "soup: no ray with many hits"
    );
    check_oracle(
        "soup",
        &soup,
        Vec3::new(0.05, 0.0, -0.1),
        &dirs[..300],
        &hits[..300],
    );
    // A partial last workgroup and a single ray.
    check(gpu, "one ray", &sphere, Vec3::ZERO, &dirs[..1]);
    check(gpu, "65 rays", &sphere, Vec3::ZERO, &dirs[..65]);
}

#[test]
fn gpu_matches_mirror_on_real_meshes() {
    let Some(gpu) = common::gpu() else { return };
    let dirs = dirs_of(&common::fibonacci_sphere(20_000));
    if let Some(feet) = common::real_mesh("fsu/footbones.ply") {
        // From inside the foot's box: rays cross several bones.
        let hits = check(gpu, "footbones", &feet, Vec3::new(0.1, 0.2, -0.3), &dirs);
        assert!(hits.iter().any(|h| h.count >= 4));
        check_oracle(
            "footbones",
            &feet,
            Vec3::new(0.1, 0.2, -0.3),
            &dirs[..400],
            &hits[..400],
        );
    }
    if let Some(bunny) = common::real_mesh("bunny.ply") {
        let hits = check(gpu, "bunny", &bunny, Vec3::new(-0.02, 0.1, 0.0), &dirs);
        check_oracle(
            "bunny",
            &bunny,
            Vec3::new(-0.02, 0.1, 0.0),
            &dirs[..200],
            &hits[..200],
        );
    }
}

#[test]
fn comparison_catches_wrong_hits() {
    let mesh = common::icosphere(3);
    let bvh = Bvh::build(&mesh).unwrap();
    let dirs = dirs_of(&common::fibonacci_sphere(200));
    let want = cpu::ray_cast(&bvh, [0.1, 0.0, 0.0], &dirs);
    compare("same", &want, &want).unwrap();
    let mut other = want.clone();
    other[17].near_tri ^= 1;
    assert!(compare("moved", &want, &other).is_err());
    let mut other = want.clone();
    other[3].count += 1;
    assert!(compare("count", &want, &other).is_err());
    let mut other = want.clone();
    other[5].far = f32::from_bits(other[5].far.to_bits() + 300);
    assert!(compare("far", &want, &other).is_err());
    // The GPU itself, given a shifted origin, disagrees.
    if let Some(gpu) = common::gpu() {
        let got = gpu_hits(gpu, "shifted", &bvh, Vec3::new(0.1001, 0.0, 0.0), &dirs);
        assert!(compare("shifted origin", &want, &got).is_err());
    }
}
