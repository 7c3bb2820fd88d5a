//! Volume statistics and 6-connected component labelling, checked against a
//! plain breadth-first flood fill and the real volumes' figures from
//! `../shared/data/README.md`.

mod common;

use std::collections::VecDeque;

use chisel::Volume;
use chisel::volume::analysis::MAX_LISTED_SIZES;
use chisel::volume::{
    LabelCount, ScalarType, VolumeData, VolumeStats, label_6_connected, label_components,
    threshold_components,
};
use common::real_volume;

/// Reference labelling: BFS flood fill seeded in file order, so components
/// are numbered by their first voxel. Returns (labels, sizes).
fn flood_fill(dims: [usize; 3], mask: &[bool]) -> (Vec<u32>, Vec<u64>) {
    let [nx, ny, nz] = dims;
    let mut labels = vec![0u32; mask.len()];
    let mut sizes = Vec::new();
    let mut queue = VecDeque::new();
    for seed in 0..mask.len() {
        if !mask[seed] || labels[seed] != 0 {
            continue;
        }
        sizes.push(0u64);
        let label = sizes.len() as u32;
        labels[seed] = label;
        queue.push_back(seed);
        while let Some(i) = queue.pop_front() {
            *sizes.last_mut().unwrap() += 1;
            let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
            let mut visit = |j: usize| {
                if mask[j] && labels[j] == 0 {
                    labels[j] = label;
                    queue.push_back(j);
                }
            };
            if x > 0 {
                visit(i - 1);
            }
            if x + 1 < nx {
                visit(i + 1);
            }
            if y > 0 {
                visit(i - nx);
            }
            if y + 1 < ny {
                visit(i + nx);
            }
            if z > 0 {
                visit(i - nx * ny);
            }
            if z + 1 < nz {
                visit(i + nx * ny);
            }
        }
    }
    (labels, sizes)
}

fn volume(dims: [usize; 3], data: VolumeData) -> Volume {
    Volume::new(dims, [1.0; 3], [0.0; 3], data).unwrap()
}

fn descending(mut sizes: Vec<u64>) -> Vec<u64> {
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    sizes
}

#[test]
fn labelling_matches_flood_fill_on_random_masks() {
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    };
    for dims in [
        [1, 1, 1],
        [7, 1, 1],
        [1, 9, 1],
        [1, 1, 11],
        [13, 11, 1],
        [9, 8, 7],
        [20, 17, 9],
    ] {
        for percent in [10, 35, 50, 65, 90] {
            let n = dims.iter().product();
            let mask: Vec<bool> = (0..n).map(|_| next() % 100 < percent).collect();
            let got = label_6_connected(dims, |i| mask[i]).unwrap();
            let (labels, sizes) = flood_fill(dims, &mask);
            assert_eq!(got.labels, labels, "{dims:?} {percent}%");
            assert_eq!(got.sizes, sizes, "{dims:?} {percent}%");
            assert_eq!(got.n_components(), sizes.len());
        }
    }
}

#[test]
fn diagonal_neighbours_are_separate_and_u_shapes_merge() {
    // 6-connectivity: voxels touching only along an edge or corner are apart.
    // Four alternate corners of a 2×2×2 block: no two share a face.
    let diag = [true, false, false, true, false, true, true, false];
    let got = label_6_connected([2, 2, 2], |i| diag[i]).unwrap();
    assert_eq!(got.labels, vec![1, 0, 0, 2, 0, 3, 4, 0]);
    // A U whose arms meet only in the last row: one component, numbered 1.
    #[rustfmt::skip]
    let u = [
        true, false, true,
        true, false, true,
        true, true,  true,
    ];
    let got = label_6_connected([3, 3, 1], |i| u[i]).unwrap();
    assert_eq!(got.sizes, vec![7]);
    assert!(got.labels.iter().zip(u).all(|(&l, m)| l == u32::from(m)));
    // The same through z: two columns joined in the top slice.
    let pillars = |i: usize| matches!(i % 4, 0 | 3) || i >= 8;
    let got = label_6_connected([2, 2, 3], pillars).unwrap();
    assert_eq!(got.sizes, vec![8]);
    let empty = label_6_connected([0, 4, 4], |_| true).unwrap();
    assert!(empty.labels.is_empty() && empty.sizes.is_empty());
}

#[test]
fn threshold_and_label_counts_on_a_small_label_volume() {
    // Two blocks of label 3 apart, one block of 5 touching the second one.
    let dims = [6, 4, 2];
    let mut data = vec![0u8; 48];
    for (i, d) in data.iter_mut().enumerate() {
        let (x, y) = (i % 6, (i / 6) % 4);
        *d = match (x, y) {
            (0, 0..=1) => 3,
            (3..=4, _) => 3,
            (5, 3) => 5,
            _ => 0,
        };
    }
    let v = volume(dims, VolumeData::U8(data));
    let three = label_components(&v, 3.0);
    assert_eq!(three.selection, "value == 3");
    assert_eq!((three.voxels, three.components, three.largest), (20, 2, 16));
    assert_eq!(three.sizes, vec![16, 4]);
    let above = threshold_components(&v, 3.0);
    assert_eq!(above.selection, "value >= 3");
    assert_eq!((above.voxels, above.components), (22, 2));
    assert_eq!(above.sizes, vec![18, 4]);
    let none = threshold_components(&v, 6.0);
    assert_eq!((none.voxels, none.components, none.largest), (0, 0, 0));
    assert!(none.sizes.is_empty());
}

#[test]
fn component_sizes_are_truncated_but_counted() {
    // A checkerboard in 2-D: every selected pixel is its own component.
    let dims = [20, 20, 1];
    let data = (0..400).map(|i| ((i % 20 + i / 20) % 2) as i16).collect();
    let c = threshold_components(&volume(dims, VolumeData::I16(data)), 1.0);
    assert_eq!((c.voxels, c.components, c.largest), (200, 200, 1));
    assert_eq!(c.sizes.len(), MAX_LISTED_SIZES);
}

#[test]
fn stats_of_integer_and_float_volumes() {
    let v = volume([2, 2, 2], VolumeData::I16(vec![0, -3, 7, 7, 0, 2, 7, 0]));
    let s = VolumeStats::of(&v);
    assert_eq!(s.scalar_type, ScalarType::I16);
    assert_eq!((s.voxels, s.zeros, s.non_finite), (8, 3, 0));
    assert_eq!((s.min, s.max), (Some(-3.0), Some(7.0)));
    assert_eq!(s.mean, Some(20.0 / 8.0));
    let counts = |pairs: &[(i64, u64)]| {
        pairs
            .iter()
            .map(|&(value, voxels)| LabelCount { value, voxels })
            .collect::<Vec<_>>()
    };
    assert_eq!(s.labels, Some(counts(&[(-3, 1), (0, 3), (2, 1), (7, 3)])));
    let json = serde_json::to_value(&s).unwrap();
    assert_eq!(json["scalar_type"], "i16");
    assert_eq!(json["labels"][3]["voxels"], 3);

    // Many distinct values: no histogram.
    let wide = volume([300, 1, 1], VolumeData::U16((0..300).collect()));
    assert_eq!(VolumeStats::of(&wide).labels, None);
    // Few values over a huge span: the sparse path.
    let sparse = volume([4, 1, 1], VolumeData::U32(vec![4_000_000_000, 1, 1, 0]));
    let s = VolumeStats::of(&sparse);
    assert_eq!(
        s.labels,
        Some(counts(&[(0, 1), (1, 2), (4_000_000_000, 1)]))
    );
    assert_eq!(s.mean, Some(4_000_000_002.0 / 4.0));
    let many = volume(
        [1000, 1, 1],
        VolumeData::I32((0..1000).map(|i| i * 100_000).collect()),
    );
    assert_eq!(VolumeStats::of(&many).labels, None);

    let f = volume(
        [5, 1, 1],
        VolumeData::F32(vec![1.5, f32::NAN, 0.0, -2.5, f32::INFINITY]),
    );
    let s = VolumeStats::of(&f);
    assert_eq!(
        (s.min, s.max, s.mean),
        (Some(-2.5), Some(1.5), Some(-1.0 / 3.0))
    );
    assert_eq!((s.zeros, s.non_finite, s.labels), (1, 2, None));

    let empty = VolumeStats::of(&volume([0, 0, 0], VolumeData::U8(Vec::new())));
    assert_eq!(
        (empty.min, empty.max, empty.mean, empty.labels),
        (None, None, None, None)
    );
}

#[test]
fn headsq_stats_and_bone_components() {
    let Some(v) = real_volume("headsq/quarter.nhdr") else {
        return;
    };
    let s = VolumeStats::of(&v);
    assert_eq!(s.dims, [64, 64, 93]);
    assert_eq!(s.spacing, [3.2, 3.2, 1.5]);
    assert_eq!(s.scalar_type, ScalarType::I16);
    assert_eq!((s.voxels, s.zeros), (380_928, 58_590));
    assert_eq!((s.min, s.max), (Some(0.0), Some(3926.0)));
    assert!((s.mean.unwrap() - 507.69).abs() < 0.005, "{:?}", s.mean);
    assert_eq!(s.labels, None);

    let bone = threshold_components(&v, 1150.0);
    let mask: Vec<bool> = (0..v.len()).map(|i| v.data.get_f64(i) >= 1150.0).collect();
    let (_, sizes) = flood_fill(v.dims, &mask);
    assert_eq!(bone.voxels, mask.iter().filter(|&&m| m).count() as u64);
    assert_eq!(bone.components, sizes.len());
    let sizes = descending(sizes);
    assert_eq!(bone.largest, sizes[0]);
    assert_eq!(bone.sizes, sizes[..bone.sizes.len()]);
    // Pinned from an independent Python flood fill over the raw slices.
    assert_eq!(
        (bone.voxels, bone.components, bone.largest),
        (34_295, 64, 33_898)
    );
    assert_eq!(bone.sizes[..4], [33_898, 155, 24, 23]);
}

#[test]
fn frogtissue_labels_and_label_13_components() {
    let Some(v) = real_volume("froggy/frogtissue.mhd") else {
        return;
    };
    let s = VolumeStats::of(&v);
    assert_eq!(s.dims, [500, 470, 136]);
    assert_eq!(s.voxels, 31_960_000);
    assert_eq!(s.zeros, 30_803_043);
    let expected: Vec<LabelCount> = common::FROG_LABELS
        .into_iter()
        .map(|(value, voxels)| LabelCount { value, voxels })
        .collect();
    assert_eq!(s.labels.as_deref(), Some(expected.as_slice()));

    let c = label_components(&v, 13.0);
    assert_eq!(c.voxels, 440_722);
    let mask: Vec<bool> = (0..v.len()).map(|i| v.data.get_f64(i) == 13.0).collect();
    let (ref_labels, ref_sizes) = flood_fill(v.dims, &mask);
    assert_eq!(c.components, ref_sizes.len());
    assert_eq!(c.components, LABEL_13_COMPONENTS);
    assert_eq!(c.sizes[..3], [216_856, 61_378, 56_924]);
    let sorted = descending(ref_sizes.clone());
    assert_eq!(c.largest, sorted[0]);
    assert_eq!(c.sizes, sorted[..c.sizes.len()]);
    let full = label_6_connected(v.dims, |i| mask[i]).unwrap();
    assert_eq!(full.sizes, ref_sizes);
    assert!(
        full.labels == ref_labels,
        "labelling differs from the flood fill"
    );
}

/// 6-connected components of frogtissue label 13 (largest 216,856 voxels),
/// from an independent Python flood fill over the zlib-inflated file.
const LABEL_13_COMPONENTS: usize = 289;

#[test]
fn small_metaimages() {
    if let Some(v) = real_volume("foot/foot.mha") {
        let s = VolumeStats::of(&v);
        assert_eq!(s.dims, [256, 256, 1]);
        assert_eq!((s.min, s.max), (Some(0.0), Some(218.0)));
        assert!((s.mean.unwrap() - 31.361).abs() < 5e-4, "{:?}", s.mean);
        assert_eq!(s.voxels - s.zeros, 65_153);
        assert_eq!(s.labels.map(|l| l.len()), Some(165));
        let c = threshold_components(&v, 1.0);
        let mask: Vec<bool> = (0..v.len()).map(|i| v.data.get_f64(i) >= 1.0).collect();
        assert_eq!(c.components, flood_fill(v.dims, &mask).1.len());
    }
    if let Some(v) = real_volume("HeadMRVolume.mhd") {
        let s = VolumeStats::of(&v);
        assert_eq!(s.dims, [48, 62, 42]);
        assert_eq!(s.spacing, [4.0; 3]);
        assert_eq!((s.min, s.max), (Some(0.0), Some(255.0)));
        assert!((s.mean.unwrap() - 24.468).abs() < 5e-4, "{:?}", s.mean);
        assert_eq!(s.voxels - s.zeros, 123_631);
        let labels = s.labels.unwrap();
        assert_eq!(labels.len(), 255);
        assert!(labels.iter().all(|l| l.value != 254));
        let c = threshold_components(&v, 42.0);
        let mask: Vec<bool> = (0..v.len()).map(|i| v.data.get_f64(i) >= 42.0).collect();
        let (_, sizes) = flood_fill(v.dims, &mask);
        assert_eq!(
            (c.components, c.sizes),
            (sizes.len(), {
                let d = descending(sizes);
                d[..d.len().min(MAX_LISTED_SIZES)].to_vec()
            })
        );
    }
}
