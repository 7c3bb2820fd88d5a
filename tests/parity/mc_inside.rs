//! Parity of `mc_inside` against `mc::mirror::mc_inside`: the bit rows are
//! integers and compare exactly, on every fixture of [`super::mc_kernels`]
//! (the whole grid the classification reads, and the emission slab's
//! window of layers).

use chisel::mc::gpu;
use chisel::parity::compare_exact;

use super::mc_kernels::fixtures;
use crate::common;

#[test]
fn mc_inside_matches_its_mirror() {
    let Some(g) = common::gpu() else { return };
    for s in fixtures() {
        let runs = [
            (
                "classify",
                &s.classify_inside,
                &s.classify_samples,
                &s.classify_bits,
            ),
            ("emission", &s.emit_inside, &s.emit_samples, &s.emit_bits),
        ];
        for (pass, params, samples, bits) in runs {
            let got = gpu::mc_inside(g, params, samples).unwrap();
            compare_exact(&format!("mc_inside {pass} {}", s.what), bits, &got)
                .unwrap_or_else(|m| panic!("{m}"));
        }
    }
}

/// The flags are the samples compared with the level: every word has its
/// bits past the row's end clear, and a flipped bit is reported at its word,
/// once.
#[test]
fn mc_inside_negative_control() {
    let Some(g) = common::gpu() else { return };
    let s = &fixtures()[0];
    let mut got = gpu::mc_inside(g, &s.classify_inside, &s.classify_samples).unwrap();
    let (nx, row_words) = (s.classify_inside.grid.nx, s.classify_inside.row_words);
    let tail = nx % 32;
    if tail != 0 {
        let last = (row_words - 1) as usize;
        assert!(
            got.iter()
                .skip(last)
                .step_by(row_words as usize)
                .all(|w| w >> tail == 0),
            "bits past nx = {nx} are set"
        );
    }
    let k = got.iter().position(|&w| w != 0).unwrap();
    got[k] ^= 1 << got[k].trailing_zeros();
    let m = compare_exact("flipped", &s.classify_bits, &got).unwrap_err();
    assert_eq!((m.index, m.count), (k, 1));
}
