//! Parity of `mc_triangles` against `mc::mirror::mc_triangles` on the
//! mirror's block offsets and `vert_base`: triangles (vertex ids and cell)
//! compare exactly.

use chisel::mc::gpu;
use chisel::parity::{compare_exact, find_sentinel};

use super::mc_kernels::{Stages, fixtures};
use crate::common;

fn run(g: &chisel::gpu::Gpu, s: &Stages) -> Vec<[u32; 4]> {
    gpu::mc_triangles(
        g,
        &s.triangles_params,
        &s.emit_bits,
        &s.table,
        &s.triangle_offsets,
        &s.vert_base,
        s.triangles.len(),
    )
    .unwrap()
}

#[test]
fn mc_triangles_matches_its_mirror() {
    let Some(g) = common::gpu() else { return };
    for s in fixtures() {
        let got = run(g, &s);
        assert_eq!(find_sentinel(&got, [u32::MAX; 4]), None, "{}", s.what);
        compare_exact(&format!("mc_triangles {}", s.what), &s.triangles, &got)
            .unwrap_or_else(|m| panic!("{m}"));
    }
}

/// Two vertices of one triangle swapped (a flipped triangle) is reported at
/// its index, once.
#[test]
fn mc_triangles_negative_control() {
    let Some(g) = common::gpu() else { return };
    let s = &fixtures()[0];
    let mut got = run(g, s);
    let k = got.len() / 2;
    got[k].swap(0, 1);
    let m = compare_exact("flipped", &s.triangles, &got).unwrap_err();
    assert_eq!((m.index, m.count), (k, 1));
}
