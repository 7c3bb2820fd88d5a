//! Parity of `mc_vertices` against `mc::mirror::mc_vertices` on the
//! mirror's own block offsets: `vert_base` and the edge ids exactly, the
//! positions bit for bit on a software adapter (correctly rounded division)
//! and within `mc::mirror::TOL_POSITION_ULPS` elsewhere.

use chisel::gpu::Gpu;
use chisel::mc::gpu;
use chisel::mc::mirror::TOL_POSITION_ULPS;
use chisel::parity::compare_exact;

use super::mc_kernels::{Stages, compare_positions, fixtures};
use crate::common;

fn ulps_on(g: &Gpu) -> u32 {
    if g.is_software() {
        0
    } else {
        TOL_POSITION_ULPS
    }
}

fn run(g: &Gpu, s: &Stages) -> (Vec<u32>, Vec<[f32; 4]>) {
    gpu::mc_vertices(
        g,
        &s.vertices,
        &s.emit_samples,
        &s.emit_bits,
        &s.vertex_offsets,
        s.positions.len(),
    )
    .unwrap()
}

#[test]
fn mc_vertices_matches_its_mirror() {
    let Some(g) = common::gpu() else { return };
    for s in fixtures() {
        let (vert_base, positions) = run(g, &s);
        assert!(
            positions
                .iter()
                .all(|p| p[..3].iter().all(|c| c.is_finite())),
            "{}: a position sentinel survived",
            s.what
        );
        compare_exact(
            &format!("mc_vertices vert_base {}", s.what),
            &s.vert_base,
            &vert_base,
        )
        .unwrap_or_else(|m| panic!("{m}"));
        compare_positions(
            &format!("mc_vertices positions {}", s.what),
            &s.positions,
            &positions,
            ulps_on(g),
        )
        .unwrap_or_else(|m| panic!("{m}"));
    }
}

/// One coordinate one ulp off is a mismatch at 0 ulps and passes at the
/// bound; one past the bound fails it; a wrong edge id always fails.
#[test]
fn mc_vertices_negative_control() {
    let Some(g) = common::gpu() else { return };
    let s = &fixtures()[0];
    let (_, mut got) = run(g, s);
    let ulps = ulps_on(g);
    compare_positions("unchanged", &s.positions, &got, ulps).unwrap();
    let k = got.len() / 2;
    let bump = |v: f32, n: u32| f32::from_bits(v.to_bits() + n);
    got[k][1] = bump(s.positions[k][1], 1);
    let m = compare_positions("1 ulp", &s.positions, &got, 0).unwrap_err();
    assert_eq!((m.index, m.count), (k, 1));
    compare_positions("1 ulp", &s.positions, &got, TOL_POSITION_ULPS).unwrap();
    got[k][1] = bump(s.positions[k][1], TOL_POSITION_ULPS + 1);
    let m = compare_positions("past the bound", &s.positions, &got, TOL_POSITION_ULPS).unwrap_err();
    assert_eq!((m.index, m.count), (k, 1));
    got[k] = s.positions[k];
    got[k][3] = f32::from_bits(got[k][3].to_bits() + 1);
    let m = compare_positions("edge id", &s.positions, &got, TOL_POSITION_ULPS).unwrap_err();
    assert_eq!((m.index, m.count), (k, 1));
}
