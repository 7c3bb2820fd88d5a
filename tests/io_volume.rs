//! Volume readers on the real data and writer round trips (SPEC §0.5).

mod common;

use chisel::Volume;
use chisel::volume::VolumeData;

fn histogram_u8(v: &Volume) -> [usize; 256] {
    let VolumeData::U8(d) = &v.data else {
        panic!("expected u8 samples, got {:?}", v.data.scalar_type())
    };
    let mut h = [0usize; 256];
    for &x in d {
        h[x as usize] += 1;
    }
    h
}

fn mean(v: &Volume) -> f64 {
    (0..v.len()).map(|i| v.data.get_f64(i)).sum::<f64>() / v.len() as f64
}

#[test]
fn headsq_multi_file_nrrd() {
    let Some(v) = common::real_volume("headsq/quarter.nhdr") else {
        return;
    };
    assert_eq!(v.dims, [64, 64, 93]);
    assert_eq!(v.spacing, [3.2, 3.2, 1.5]);
    assert_eq!(v.origin, [0.0; 3]);
    let VolumeData::I16(d) = &v.data else {
        panic!("expected i16, got {:?}", v.data.scalar_type())
    };
    assert_eq!(*d.iter().min().unwrap(), 0);
    assert_eq!(*d.iter().max().unwrap(), 3926);
    assert_eq!(d.iter().filter(|&&x| x == 0).count(), 58_590);
    assert!((mean(&v) - 507.69).abs() < 0.01, "{}", mean(&v));
}

#[test]
fn frogtissue_inflates_past_wrong_compressed_size() {
    let Some(v) = common::real_volume("froggy/frogtissue.mhd") else {
        return;
    };
    assert_eq!(v.dims, [500, 470, 136]);
    assert_eq!(v.spacing, [1.0, 1.0, 1.5]);
    let h = histogram_u8(&v);
    let expected: [(usize, usize); 26] = [
        (0, 30_803_043),
        (1, 35_279),
        (2, 19_172),
        (3, 38_129),
        (4, 37_146),
        (5, 16_085),
        (6, 37_030),
        (7, 27_807),
        (8, 39_181),
        (9, 51_297),
        (10, 204_672),
        (11, 47_626),
        (12, 24_263),
        (13, 440_722),
        (14, 3_891),
        (15, 133_880),
        (16, 252),
        (17, 38),
        (20, 29),
        (21, 4),
        (23, 6),
        (24, 239),
        (25, 121),
        (26, 16),
        (27, 32),
        (29, 40),
    ];
    for (label, count) in expected {
        assert_eq!(h[label], count, "label {label}");
    }
    assert_eq!(h.iter().filter(|&&c| c > 0).count(), 26);
}

#[test]
fn foot_mha_2d_with_separate_data() {
    let Some(v) = common::real_volume("foot/foot.mha") else {
        return;
    };
    assert_eq!(v.dims, [256, 256, 1]);
    assert_eq!(v.spacing, [1.0, 1.0, 1.0]);
    let h = histogram_u8(&v);
    assert_eq!(v.len() - h[0], 65_153);
    assert_eq!(h.iter().filter(|&&c| c > 0).count(), 165);
}

#[test]
fn head_mr_volume_three_digit_exponents() {
    let Some(v) = common::real_volume("HeadMRVolume.mhd") else {
        return;
    };
    assert_eq!(v.dims, [48, 62, 42]);
    assert_eq!(v.spacing, [4.0; 3]);
    assert!((mean(&v) - 24.468).abs() < 0.001, "{}", mean(&v));
    let h = histogram_u8(&v);
    assert_eq!(v.len() - h[0], 123_631);
    assert_eq!(h[254], 0);
}
