//! The real volumes of `../shared/data`: the CT head's skin and bone, the MR
//! head, and the frog's tissue labels.

use chisel::Backend;
use chisel::mc::{IsoSpec, Surface, marching_cubes};
use chisel::volume::{Volume, VolumeData};

use crate::oracle::{check_closed_oriented, check_topology};
use crate::{CLOSE, common};

// ---------------------------------------------------------------- real data

fn headsq() -> Option<Volume> {
    common::real_volume("headsq/quarter.nhdr")
}

#[test]
fn headsq_skin_500_is_closed_and_matches_voxel_topology() {
    let Some(vol) = headsq() else { return };
    let iso = IsoSpec::Level(500.0);
    let s = marching_cubes(&vol, iso, &CLOSE, Backend::Cpu).unwrap();
    check_topology(&vol, iso, &s);
    eprintln!(
        "headsq 500: {} triangles, {} groups",
        s.mesh.triangles.len(),
        s.groups.len()
    );
}

#[test]
fn headsq_bone_1150_is_closed_and_matches_voxel_topology() {
    let Some(vol) = headsq() else { return };
    let iso = IsoSpec::Level(1150.0);
    let s = marching_cubes(&vol, iso, &CLOSE, Backend::Cpu).unwrap();
    check_topology(&vol, iso, &s);
    eprintln!(
        "headsq 1150: {} triangles, {} groups",
        s.mesh.triangles.len(),
        s.groups.len()
    );
}

#[test]
fn head_mr_volume_is_closed_and_matches_voxel_topology() {
    let Some(vol) = common::real_volume("HeadMRVolume.mhd") else {
        return;
    };
    let iso = IsoSpec::Level(42.0);
    let s = marching_cubes(&vol, iso, &CLOSE, Backend::Cpu).unwrap();
    check_topology(&vol, iso, &s);
}

/// Frog labels: the oracle runs on the label's bounding box (plus one
/// outside sample per side), which has the same topology as the full grid.
#[test]
fn frog_labels_are_closed_and_match_voxel_topology() {
    let Some(vol) = common::real_volume("froggy/frogtissue.mhd") else {
        return;
    };
    for label in [2.0, 4.0, 14.0, 24.0] {
        let crop = crop_to_label(&vol, label);
        let iso = IsoSpec::Label(label);
        let s = marching_cubes(&crop, iso, &CLOSE, Backend::Cpu).unwrap();
        check_topology(&crop, iso, &s);
        let full = marching_cubes(&vol, iso, &CLOSE, Backend::Cpu).unwrap();
        assert_eq!(
            full.mesh.triangles.len(),
            s.mesh.triangles.len(),
            "label {label}"
        );
        assert_eq!(full.groups.len(), s.groups.len(), "label {label}");
        let euler = |s: &Surface| {
            let mut e: Vec<i64> = s.groups.iter().map(|g| g.euler).collect();
            e.sort_unstable();
            e
        };
        assert_eq!(euler(&full), euler(&s), "label {label}");
        check_closed_oriented(&full);
        eprintln!(
            "frog label {label}: {} triangles, {} groups",
            s.mesh.triangles.len(),
            s.groups.len()
        );
    }
}

fn crop_to_label(vol: &Volume, label: f64) -> Volume {
    let [nx, ny, nz] = vol.dims;
    let (mut lo, mut hi) = ([usize::MAX; 3], [0usize; 3]);
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                if vol.data.get_f64(vol.index(x, y, z)) == label {
                    for (a, c) in [x, y, z].into_iter().enumerate() {
                        lo[a] = lo[a].min(c);
                        hi[a] = hi[a].max(c);
                    }
                }
            }
        }
    }
    let dims = [hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1];
    let mut data = Vec::with_capacity(dims.iter().product());
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                data.push(vol.data.get_f64(vol.index(x, y, z)) as u8);
            }
        }
    }
    let origin = [0, 1, 2].map(|a| vol.origin[a] + vol.spacing[a] * lo[a] as f64);
    Volume::new(dims, vol.spacing, origin, VolumeData::U8(data)).unwrap()
}
