//! Parity of `kernels/dms_surface.wgsl` against `dms::surface::cpu` on
//! synthetic rows and fran_cut's identified rows, the gather from a device
//! buffer, and negative controls.

use chisel::TriMesh;
use chisel::dms::basis::{BasisRows, cpu as basis_cpu};
use chisel::dms::fit::ControlMap;
use chisel::dms::surface::gpu::SurfaceBuffers;
use chisel::dms::surface::{SurfaceInput, SurfacePoints, cpu};
use chisel::dms::{Projection, parametrise};
use chisel::gpu::{Gpu, GpuArray};
use chisel::parity::{compare_vec, find_sentinel};

use super::dms_basis::{input_of, jittered};
use crate::common;

fn gpu_surface(gpu: &Gpu, what: &str, input: &SurfaceInput, sources: &[[f32; 4]]) -> SurfacePoints {
    let buffers = SurfaceBuffers::upload(gpu, input).unwrap();
    let src = GpuArray::from_slice(gpu, "sources", sources).unwrap();
    let mut encoder = gpu.encoder("dms_surface");
    buffers.record(gpu, &mut encoder, &src).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let out = SurfacePoints {
        positions: buffers.positions.read(gpu).unwrap(),
        normals: buffers.normals.read(gpu).unwrap(),
    };
    assert_eq!(
        find_sentinel(&out.positions, [f32::NAN; 4]),
        None,
        "{what}: positions"
    );
    assert_eq!(
        find_sentinel(&out.normals, [f32::NAN; 4]),
        None,
        "{what}: normals"
    );
    out
}

/// The rows of `mesh` over `uv` at accuracy `n` and its identification controls.
fn rows_of(uv: &[glam::DVec2], mesh: &TriMesh, n: u32) -> (SurfaceInput, Vec<[f32; 4]>) {
    let (d, input) = input_of(uv, mesh, n);
    let basis = BasisRows {
        weights: basis_cpu::dms_basis(&input),
        rows: input.rows,
    };
    let rows = SurfaceInput::over_controls(&basis, d.n_controls());
    let src = ControlMap::identify(&d)
        .apply(&mesh.positions)
        .iter()
        .map(|p| [p.x as f32, p.y as f32, p.z as f32, 0.0])
        .collect();
    (rows, src)
}

fn extent(src: &[[f32; 4]]) -> f32 {
    src.iter()
        .flat_map(|p| p[..3].iter().map(|x| x.abs()))
        .fold(0.0, f32::max)
}

fn check(gpu: &Gpu, what: &str, rows: &SurfaceInput, src: &[[f32; 4]]) {
    let want = cpu::dms_surface(rows, src);
    let got = gpu_surface(gpu, what, rows, src);
    let tol = cpu::position_tolerance(extent(src));
    compare_vec(
        &format!("dms_surface/{what}/positions"),
        &want.positions,
        &got.positions,
        tol,
    )
    .unwrap_or_else(|m| panic!("{m}"));
    compare_vec(
        &format!("dms_surface/{what}/normals"),
        &want.normals,
        &got.normals,
        cpu::NORMAL_TOL,
    )
    .unwrap_or_else(|m| panic!("{m}"));
}

#[test]
fn synthetic() {
    let Some(gpu) = common::gpu() else { return };
    for (cols, rows, seed, n) in [(3, 3, 1, 2), (7, 6, 5, 4), (10, 9, 6, 7)] {
        let (uv, mesh) = jittered(cols, rows, seed);
        let (r, src) = rows_of(&uv, &mesh, n);
        check(gpu, &format!("grid{cols}x{rows}/n{n}"), &r, &src);
    }
}

#[test]
fn fran_cut() {
    let Some(mesh) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let p = parametrise(&mesh, &Projection::Cylinder).unwrap();
    let (r, src) = rows_of(&p.uv, &mesh, 5);
    let Some(gpu) = common::gpu() else { return };
    check(gpu, "fran_cut/n5", &r, &src);
    // Moved vertices (a relaxation frame) through the same rows.
    let moved: Vec<[f32; 4]> = src
        .iter()
        .map(|q| [q[0] + 0.01 * (q[1] * 40.0).sin(), q[1], q[2] - 0.005, 0.0])
        .collect();
    check(gpu, "fran_cut/moved", &r, &moved);
}

#[test]
fn negative_controls() {
    let Some(gpu) = common::gpu() else { return };
    let (uv, mesh) = jittered(6, 6, 3);
    let (r, src) = rows_of(&uv, &mesh, 4);
    let want = cpu::dms_surface(&r, &src);
    let mut got = gpu_surface(gpu, "control", &r, &src);
    let tol = cpu::position_tolerance(extent(&src));
    compare_vec("dms_surface/control", &want.positions, &got.positions, tol).unwrap();
    let k = got.positions.len() / 3;
    got.positions[k][2] += 4.0 * tol.abs;
    let m = compare_vec("dms_surface/control", &want.positions, &got.positions, tol).unwrap_err();
    assert_eq!((m.index, m.count), (k, 1), "{m}");
    // Sources one vertex off (the wrong buffer) are caught.
    let mut shifted = src.clone();
    shifted.rotate_left(1);
    let got = gpu_surface(gpu, "shifted", &r, &shifted);
    assert!(compare_vec("dms_surface/shifted", &want.positions, &got.positions, tol).is_err());
    // Too few sources on the device is an error, not a read past the end.
    let buffers = SurfaceBuffers::upload(gpu, &r).unwrap();
    let few = GpuArray::from_slice(gpu, "few", &src[..src.len() - 1]).unwrap();
    let mut encoder = gpu.encoder("few");
    assert!(matches!(
        buffers.record(gpu, &mut encoder, &few),
        Err(chisel::Error::Mismatch { .. })
    ));
}

/// A relaxation frame's skin on the device: the quasi-interpolation map
/// gathers controls from the vertex buffer, the lattice rows gather the
/// points from the controls' buffer, with no read-back between; equal to
/// the CPU's two gathers.
#[test]
fn the_skin_chain_stays_on_the_device() {
    use chisel::dms::SplineDomain;
    let Some(mesh) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let sd = SplineDomain::new(&mesh, &Projection::Cylinder, 4, chisel::gpu::Backend::Cpu).unwrap();
    let map = sd
        .control_map(&chisel::dms::Fit::Quasi)
        .unwrap()
        .gather_input(mesh.n_vertices());
    let rows = sd.control_rows();
    let src: Vec<[f32; 4]> = mesh
        .positions
        .iter()
        .map(|p| [p.x, p.y + 0.01 * p.x, p.z, 0.0])
        .collect();
    let want = sd
        .skin(&map, &rows, &src, chisel::gpu::Backend::Cpu)
        .unwrap();
    let Some(gpu) = common::gpu() else { return };
    let vertices = GpuArray::from_slice(gpu, "vertices", &src).unwrap();
    let first = SurfaceBuffers::upload(gpu, &map).unwrap();
    let second = SurfaceBuffers::upload(gpu, &rows).unwrap();
    let mut encoder = gpu.encoder("skin");
    first.record(gpu, &mut encoder, &vertices).unwrap();
    second.record(gpu, &mut encoder, &first.positions).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let got = second.positions.read(gpu).unwrap();
    assert_eq!(find_sentinel(&got, [f32::NAN; 4]), None);
    let tol = cpu::position_tolerance(2.0 * extent(&src));
    compare_vec("dms_surface/skin", &want.positions, &got, tol).unwrap_or_else(|m| panic!("{m}"));
}

/// The gather in ranges of points (bindings capped at 8 KiB) equals one
/// dispatch.
#[test]
fn chunked_gathers_equal_one() {
    let Some(base) = common::gpu() else { return };
    let (uv, mesh) = jittered(9, 8, 12);
    let (r, src) = rows_of(&uv, &mesh, 5);
    let small = base.view(Some(8 << 10), false);
    let whole = gpu_surface(base, "whole", &r, &src);
    let chunked = chisel::dms::surface::gpu::dms_surface(&small, &r, &src).unwrap();
    assert!(r.weights.len() * 16 > 4 * (8 << 10));
    assert_eq!(whole, chunked);
}

/// The smooth skin of a relaxation on the device: the two gathers read the
/// GPU stepper's state buffer (x − x_rest per node) directly, with the rest
/// skin's controls as base, and match the CPU chain on the read-back
/// positions.
#[test]
fn the_live_skin_reads_the_relaxation_state() {
    use chisel::dms::{Fit, LiveSkin, SplineDomain};
    use chisel::tissue::{NetworkParams, RelaxOptions, Simulation, SpringNetwork};
    let Some(mesh) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let Some(gpu) = common::gpu() else { return };
    let net = SpringNetwork::build(&mesh, None, &NetworkParams::default()).unwrap();
    let mut sim = Simulation::new(
        &net,
        &RelaxOptions::default(),
        chisel::gpu::Backend::Gpu(gpu),
    )
    .unwrap();
    let bone: Vec<[f32; 4]> = net
        .bone_rest()
        .iter()
        .map(|p| [p[0] + 0.003, p[1], p[2] - 0.002, p[3]])
        .collect();
    sim.set_bone(&bone).unwrap();
    sim.step(40).unwrap();
    let sd = SplineDomain::new(&mesh, &Projection::Cylinder, 3, chisel::gpu::Backend::Cpu).unwrap();
    let map = sd.control_map(&Fit::Quasi).unwrap();
    let nv = mesh.n_vertices();
    let nodes: Vec<u32> = (0..nv as u32).collect();
    let live = LiveSkin::new(gpu, &sd, &map, &nodes, &mesh.positions).unwrap();
    let mut encoder = gpu.encoder("live skin");
    live.record(gpu, &mut encoder, sim.device_state().expect("a GPU state"))
        .unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let (pos, nrm) = live.output();
    let (pos, nrm) = (pos.read(gpu).unwrap(), nrm.read(gpu).unwrap());
    assert_eq!(find_sentinel(&pos, [f32::NAN; 4]), None);
    // The CPU chain on the read-back absolute positions.
    let all = sim.positions().unwrap();
    let want = sd
        .skin(
            &map.gather_input(nv),
            &sd.control_rows(),
            &all[..nv],
            chisel::gpu::Backend::Cpu,
        )
        .unwrap();
    let moved = want
        .positions
        .iter()
        .zip(&pos)
        .map(|(a, b)| (a[0] - b[0]).abs().max((a[2] - b[2]).abs()))
        .fold(0.0f32, f32::max);
    let tol = cpu::position_tolerance(2.0 * extent(&all[..nv]));
    compare_vec("dms_surface/live_skin", &want.positions, &pos, tol)
        .unwrap_or_else(|m| panic!("{m}"));
    compare_vec(
        "dms_surface/live_skin/normals",
        &want.normals,
        &nrm,
        cpu::NORMAL_TOL,
    )
    .unwrap_or_else(|m| panic!("{m}"));
    // The skin moved (the comparison is not of two rest states).
    let rest = sd
        .skin(
            &map.gather_input(nv),
            &sd.control_rows(),
            &mesh
                .positions
                .iter()
                .map(|p| [p.x, p.y, p.z, 0.0])
                .collect::<Vec<_>>(),
            chisel::gpu::Backend::Cpu,
        )
        .unwrap();
    let shift = rest
        .positions
        .iter()
        .zip(&pos)
        .map(|(a, b)| (a[0] - b[0]).abs())
        .fold(0.0f32, f32::max);
    assert!(shift > 1e-4, "the skin did not move: {shift} ({moved})");
}
