//! Parity of `mc_classify` against `mc::mirror::mc_classify`: the
//! block counts are integers and compare exactly, on every fixture of
//! [`super::mc_kernels`].

use chisel::mc::gpu;
use chisel::parity::{compare_exact, find_sentinel};

use super::mc_kernels::fixtures;
use crate::common;

#[test]
fn mc_classify_matches_its_mirror() {
    let Some(g) = common::gpu() else { return };
    for s in fixtures() {
        let got = gpu::mc_classify(g, &s.classify, &s.classify_bits, &s.table).unwrap();
        assert_eq!(find_sentinel(&got, [u32::MAX; 2]), None, "{}", s.what);
        compare_exact(&format!("mc_classify {}", s.what), &s.block_counts, &got)
            .unwrap_or_else(|m| panic!("{m}"));
    }
}

/// One block count off by one is reported at its index, once.
#[test]
fn mc_classify_negative_control() {
    let Some(g) = common::gpu() else { return };
    let s = &fixtures()[0];
    let mut got = gpu::mc_classify(g, &s.classify, &s.classify_bits, &s.table).unwrap();
    let k = got.iter().position(|c| c[1] > 0).unwrap();
    got[k][1] += 1;
    let m = compare_exact("corrupted", &s.block_counts, &got).unwrap_err();
    assert_eq!((m.index, m.count), (k, 1));
}
