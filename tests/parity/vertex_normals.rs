//! Parity of `kernels/vertex_normals.wgsl` against `vertex_normals::cpu`, plus an
//! independent f64 oracle (textbook area-weighted normals) checked against
//! analytic cases and against the f32 results.

use chisel::TriMesh;
use chisel::gpu::Gpu;
use chisel::parity::{Tolerance, compare_vec, find_sentinel};
use chisel::vertex_normals::gpu::NormalsBuffers;
use chisel::vertex_normals::{NormalsInput, cpu};
use glam::{DVec3, Vec3};

use crate::common;

/// Textbook area-weighted vertex normals in f64: each triangle adds
/// (b − a) × (c − a) to its three corners, then every sum is normalised.
fn oracle(mesh: &TriMesh) -> Vec<DVec3> {
    let mut sums = vec![DVec3::ZERO; mesh.n_vertices()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize].as_dvec3());
        let n = (b - a).cross(c - a);
        for v in t {
            sums[*v as usize] += n;
        }
    }
    sums.into_iter().map(DVec3::normalize_or_zero).collect()
}

/// GPU normals with the NaN sentinel check.
fn gpu_normals(gpu: &Gpu, what: &str, input: &NormalsInput) -> Vec<[f32; 4]> {
    let buffers = NormalsBuffers::upload(gpu, input).unwrap();
    let mut encoder = gpu.encoder("vertex_normals");
    buffers.record(gpu, &mut encoder).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let out = buffers.normals.read(gpu).unwrap();
    assert_eq!(
        find_sentinel(&out, [f32::NAN; 4]),
        None,
        "{what}: NaN sentinel survived"
    );
    out
}

/// GPU vs mirror under `cpu::TOL`.
fn check(gpu: &Gpu, what: &str, mesh: &TriMesh) {
    let input = NormalsInput::new(mesh);
    let want = cpu::vertex_normals(&input);
    let got = gpu_normals(gpu, what, &input);
    compare_vec(&format!("vertex_normals/{what}"), &want, &got, cpu::TOL)
        .unwrap_or_else(|m| panic!("{m}"));
}

/// Largest component difference between the f32 normals and the oracle,
/// over vertices whose oracle normal is defined.
fn max_oracle_error(mesh: &TriMesh, normals: &[[f32; 4]]) -> f64 {
    oracle(mesh)
        .iter()
        .zip(normals)
        .filter(|(o, _)| *o != &DVec3::ZERO)
        .map(|(o, n)| {
            (Vec3::new(n[0], n[1], n[2]).as_dvec3() - *o)
                .abs()
                .max_element()
        })
        .fold(0.0, f64::max)
}

#[test]
fn oracle_cube_corners_follow_face_areas() {
    // Corner c of the unit cube touches three faces; each face adds its
    // outward normal times the area of the triangles at c: 1 when c is on
    // the face's split diagonal (both triangles), 1/2 otherwise. The fixture
    // splits quad [q0, q1, q2, q3] along q0–q2.
    let quads: [([usize; 4], DVec3); 6] = [
        ([0, 2, 3, 1], DVec3::NEG_Z),
        ([4, 5, 7, 6], DVec3::Z),
        ([0, 1, 5, 4], DVec3::NEG_Y),
        ([2, 6, 7, 3], DVec3::Y),
        ([0, 4, 6, 2], DVec3::NEG_X),
        ([1, 3, 7, 5], DVec3::X),
    ];
    let normals = oracle(&common::cube());
    for (c, n) in normals.iter().enumerate() {
        let expected = quads
            .iter()
            .filter(|(q, _)| q.contains(&c))
            .map(|(q, f)| if c == q[0] || c == q[2] { *f } else { *f * 0.5 })
            .sum::<DVec3>()
            .normalize();
        assert!(
            (*n - expected).length() < 1e-15,
            "corner {c}: {n} vs {expected}"
        );
        let octant = DVec3::new(
            if c & 1 == 1 { 1.0 } else { -1.0 },
            if c & 2 == 2 { 1.0 } else { -1.0 },
            if c & 4 == 4 { 1.0 } else { -1.0 },
        );
        assert!(
            n.signum() == octant,
            "corner {c}: {n} not in octant {octant}"
        );
    }
    // Corners 0 and 7 lie on all three diagonals: exactly the cube diagonal.
    let d = DVec3::ONE.normalize();
    assert!((normals[0] + d).length() < 1e-15);
    assert!((normals[7] - d).length() < 1e-15);
}

#[test]
fn oracle_icosphere_normals_are_radial() {
    // A plane through three points of the unit sphere has its normal along
    // the triangle's circumcentre, at angle asin(r) from each corner's
    // radius (r = circumradius). An area-weighted sum of such normals stays
    // in that cone: angle(n_v, p_v) ≤ asin(max r over v's triangles).
    let mesh = common::icosphere(4);
    let normals = oracle(&mesh);
    let mut cone = vec![0.0f64; mesh.n_vertices()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize].as_dvec3());
        let area2 = (b - a).cross(c - a).length();
        let r = (b - a).length() * (c - b).length() * (a - c).length() / (2.0 * area2);
        for v in t {
            cone[*v as usize] = cone[*v as usize].max(r.asin());
        }
    }
    for (v, (n, p)) in normals.iter().zip(&mesh.positions).enumerate() {
        let angle = n.angle_between(p.as_dvec3());
        // The 12 icosahedron corners have 5-fold symmetric fans: radial up
        // to the f32 rounding of the positions.
        let bound = if v < 12 { 1e-6 } else { cone[v] };
        assert!(angle <= bound, "vertex {v}: {angle} rad > {bound}");
    }
    // The regular tetrahedron's vertex normals point exactly along its vertices.
    let tetra = common::tetra();
    for (n, p) in oracle(&tetra).iter().zip(&tetra.positions) {
        assert!((*n - p.as_dvec3().normalize()).length() < 1e-15);
    }
}

#[test]
fn synthetic() {
    let Some(gpu) = common::gpu() else { return };
    check(gpu, "tetra", &common::tetra());
    check(gpu, "cube", &common::cube());
    check(gpu, "icosphere4", &common::icosphere(4));
    for seed in [1, 2, 3] {
        check(
            gpu,
            &format!("random{seed}"),
            &common::random_mesh(seed, 500, 2000),
        );
    }
    // A vertex no triangle uses and a zero-area triangle: both give 0 normals.
    let degenerate = TriMesh::new(
        vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::ONE,
            Vec3::new(2.0, 0.0, 0.0),
        ],
        vec![[0, 1, 2], [0, 1, 4]],
    )
    .unwrap();
    check(gpu, "degenerate", &degenerate);
    let got = gpu_normals(gpu, "degenerate", &NormalsInput::new(&degenerate));
    assert_eq!(got[3], [0.0; 4], "unused vertex");
    assert_eq!(got[4], [0.0; 4], "vertex of a zero-area triangle only");
    // No triangles at all, and no vertices at all.
    check(
        gpu,
        "points",
        &TriMesh::new(vec![Vec3::ONE; 3], vec![]).unwrap(),
    );
    check(gpu, "empty", &TriMesh::default());
}

#[test]
fn f32_mirror_meets_tol_against_oracle() {
    // TOL bounds the f32 rounding error of one side; check it against the
    // f64 oracle on well-shaped meshes (synthetic here, real data below).
    for (what, mesh) in [
        ("tetra", common::tetra()),
        ("cube", common::cube()),
        ("icosphere4", common::icosphere(4)),
    ] {
        let err = max_oracle_error(&mesh, &cpu::vertex_normals(&NormalsInput::new(&mesh)));
        assert!(err <= f64::from(cpu::TOL.abs), "{what}: {err}");
    }
}

#[test]
fn real_meshes() {
    for rel in ["fran_cut.vtk", "bunny.ply", "fsu/footbones.ply"] {
        let Some(mesh) = common::real_mesh(rel) else {
            return;
        };
        let input = NormalsInput::new(&mesh);
        let mirror = cpu::vertex_normals(&input);
        let err = max_oracle_error(&mesh, &mirror);
        assert!(
            err <= f64::from(cpu::TOL.abs),
            "{rel}: mirror vs f64 oracle {err:e} exceeds TOL"
        );
        // Without a GPU the next meshes' mirror checks still run.
        let Some(gpu) = common::gpu() else { continue };
        let got = gpu_normals(gpu, rel, &input);
        let err_gpu = max_oracle_error(&mesh, &got);
        assert!(
            err_gpu <= f64::from(cpu::TOL.abs),
            "{rel}: gpu vs oracle {err_gpu:e}"
        );
        eprintln!("{rel}: |mirror − oracle| ≤ {err:e}, |gpu − oracle| ≤ {err_gpu:e}");
        compare_vec(&format!("vertex_normals/{rel}"), &mirror, &got, cpu::TOL)
            .unwrap_or_else(|m| panic!("{m}"));
    }
}

#[test]
fn negative_control() {
    let Some(gpu) = common::gpu() else { return };
    let mesh = common::icosphere(2);
    let input = NormalsInput::new(&mesh);
    let want = cpu::vertex_normals(&input);
    let mut got = gpu_normals(gpu, "icosphere2", &input);
    compare_vec("vertex_normals/control", &want, &got, cpu::TOL).unwrap();
    let k = 97;
    got[k][1] += 4.0 * cpu::TOL.abs;
    let m = compare_vec("vertex_normals/control", &want, &got, cpu::TOL).unwrap_err();
    assert_eq!((m.index, m.count), (k, 1), "{m}");
    // And a tolerance of zero width is not what hides it: exact also fails.
    assert!(compare_vec("exact", &want, &got, Tolerance::EXACT).is_err());
}

/// The sentinel check itself can fail end to end: the kernel dispatched
/// over one vertex fewer leaves the last output at its NaN sentinel, and
/// `find_sentinel` names that index (the comparator controls above only
/// corrupt host copies).
#[test]
fn sentinel_control_catches_a_short_dispatch() {
    use chisel::gpu::{GpuArray, Kernel, UniformBuffer};
    use chisel::vertex_normals::gpu::Params;
    let Some(gpu) = common::gpu() else { return };
    assert!(
        gpu.sentinels(),
        "the test device fills outputs with sentinels"
    );
    let input = NormalsInput::new(&common::icosphere(2));
    let n = input.positions.len() as u32;
    let short = n - 1;
    let params = UniformBuffer::new(gpu, "short.params", &Params { n_vertices: short }).unwrap();
    let positions = GpuArray::from_slice(gpu, "short.positions", &input.positions).unwrap();
    let triangles = GpuArray::from_slice(gpu, "short.triangles", &input.triangles).unwrap();
    let offsets = GpuArray::from_slice(gpu, "short.offsets", &input.adjacency.offsets).unwrap();
    let tri_ids = GpuArray::from_slice(gpu, "short.tri_ids", &input.adjacency.targets).unwrap();
    let normals = GpuArray::output(gpu, "short.normals", n as usize, [f32::NAN; 4]).unwrap();
    let mut encoder = gpu.encoder("short");
    gpu.kernel(Kernel::VertexNormals)
        .unwrap()
        .uniform(&params)
        .read(&positions)
        .read(&triangles)
        .read(&offsets)
        .read(&tri_ids)
        .write(&normals)
        .bind()
        .unwrap()
        .record(gpu, &mut encoder, short, None);
    gpu.submit_and_wait(encoder).unwrap();
    let got = normals.read(gpu).unwrap();
    assert_eq!(find_sentinel(&got, [f32::NAN; 4]), Some(short as usize));
}
