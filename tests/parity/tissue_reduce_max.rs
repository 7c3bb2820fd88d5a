//! Parity of `kernels/tissue_reduce_max.wgsl` with
//! `tissue::cpu::tissue_reduce_max`, on seeded random inputs and on the
//! states of the tissue fixtures (fran_cut included) after a bone move.
//!
//! Tolerance: `tissue::cpu::TISSUE_REDUCE_MAX_TOL` on the decoded keys (see
//! its docs). A non-finite input must give a non-finite key on both.

use chisel::Backend;
use chisel::parity::{Tolerance, compare_f32, find_sentinel};
use chisel::tissue::gpu as tissue_gpu;
use chisel::tissue::{RelaxOptions, cpu, iterate};

use crate::common;
use crate::spring_step::{moved_bone, networks};

const TOL: Tolerance = cpu::TISSUE_REDUCE_MAX_TOL;

/// Velocities, positions and snapshot positions.
type Inputs = (Vec<[f32; 4]>, Vec<[f32; 4]>, Vec<[f32; 4]>);

fn inputs(n: usize, seed: u64) -> Inputs {
    let mut bits = common::xorshift(seed);
    let mut next = move || (bits() % 2_000_001) as f32 / 1_000_000.0 - 1.0;
    let mut v = Vec::with_capacity(n);
    let mut p = Vec::with_capacity(n);
    let mut q = Vec::with_capacity(n);
    for _ in 0..n {
        v.push([next(), next(), next(), 0.0]);
        let a = [next(), next(), next(), 0.0];
        p.push(a);
        q.push([a[0] + 1e-3 * next(), a[1], a[2] + 1e-3 * next(), 0.0]);
    }
    (v, p, q)
}

fn decode(k: [u32; 2]) -> Vec<f32> {
    k.iter().map(|&b| f32::from_bits(b)).collect()
}

#[test]
fn tissue_reduce_max_matches() {
    let Some(gpu) = common::gpu() else { return };
    // 70,001 > 256 · 256: the first stage strides over the grid.
    for n in [1usize, 255, 257, 70_001] {
        let (v, p, s) = inputs(n, 77 + n as u64);
        let a = cpu::tissue_reduce_max(n, &v, &p, &s);
        let b = tissue_gpu::tissue_reduce_max(gpu, &v, &p, &s).unwrap();
        assert_eq!(find_sentinel(&b, u32::MAX), None, "result not written");
        let what = format!("tissue_reduce_max n={n}");
        compare_f32(&what, &decode(a), &decode(b), TOL).unwrap_or_else(|m| panic!("{m}"));
        // Negative control: a key off by 8 ulp is caught.
        let bad = [b[0] + 8, b[1]];
        assert!(compare_f32(&what, &decode(a), &decode(bad), TOL).is_err());
    }
}

/// Real network states: on every tissue fixture (fran_cut included) after
/// a bone move, the positions after 30 explicit iterations against those
/// after 20 (the window change), and the last step's change as velocities.
#[test]
fn tissue_reduce_max_matches_on_network_states() {
    let Some(gpu) = common::gpu() else { return };
    let opts = RelaxOptions::default();
    for (name, net) in networks() {
        let bone = moved_bone(&net, 0.03);
        let at = |n| iterate(&net, &bone, &opts, n, Backend::Cpu).unwrap();
        let (s, p29, p) = (at(20), at(29), at(30));
        let v: Vec<[f32; 4]> = (p.iter().zip(&p29))
            .map(|(a, b)| {
                [
                    1e3 * (a[0] - b[0]),
                    1e3 * (a[1] - b[1]),
                    1e3 * (a[2] - b[2]),
                    0.0,
                ]
            })
            .collect();
        let n = net.n_free;
        let a = cpu::tissue_reduce_max(n, &v, &p, &s);
        let b = tissue_gpu::tissue_reduce_max(gpu, &v[..n], &p[..n], &s[..n]).unwrap();
        assert_eq!(
            find_sentinel(&b, u32::MAX),
            None,
            "{name}: result not written"
        );
        let what = format!("tissue_reduce_max on {name}");
        assert!(a[0] > 0 && a[1] > 0, "{what}: the network moved");
        compare_f32(&what, &decode(a), &decode(b), TOL).unwrap_or_else(|m| panic!("{m}"));
        let bad = [b[0], b[1] - 8];
        assert!(compare_f32(&what, &decode(a), &decode(bad), TOL).is_err());
    }
}

#[test]
fn tissue_reduce_max_flags_non_finite_values() {
    let Some(gpu) = common::gpu() else { return };
    let (mut v, p, s) = inputs(5000, 3);
    v[4321][1] = f32::NAN;
    let a = cpu::tissue_reduce_max(v.len(), &v, &p, &s);
    let b = tissue_gpu::tissue_reduce_max(gpu, &v, &p, &s).unwrap();
    assert!(a[0] >= 0x7f80_0000 && b[0] >= 0x7f80_0000, "{a:?} {b:?}");
    v[4321][1] = f32::INFINITY;
    let b = tissue_gpu::tissue_reduce_max(gpu, &v, &p, &s).unwrap();
    assert!(b[0] >= 0x7f80_0000);
}
