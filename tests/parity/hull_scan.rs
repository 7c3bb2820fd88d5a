//! Parity of the inside-hull scan kernels (`hull_scan`, `hull_scan_i32x2`,
//! `hull_rows`, `hull_rows_i32x2`) against `hull_scan::cpu` and the independent
//! i128 oracle `hull_scan::brute`: bit for bit, with native i64 (lavapipe has
//! `SHADER_INT64`) and with the exact emulated fallback (device opened
//! `portable`), in one binding and in z slabs, on synthetic polytopes and
//! the thresholded CT head; the row kernels also with per-layer face lists
//! culled by the faces' z ranges, on exact hulls of random lattice points
//! and of the CT head's bone; sentinel-filled outputs; negative controls.

use chisel::Backend;
use chisel::gpu::Gpu;
use chisel::hull::{ConvexHull, HullOptions};
use chisel::hull_scan::gpu::{Arithmetic, HullScanInput, ROWS_SENTINEL};
use chisel::hull_scan::{self, HalfSpace, RowSpans, Side, VoxelBox, brute, cpu, zkh};
use chisel::parity::{compare_exact, find_sentinel};
use chisel::volume::analysis::label_6_connected;
use chisel::voxel::{CandidateKind, Component, DigitalObject, Selection};

use crate::common;
#[path = "../hscan_fixtures/mod.rs"]
mod hscan_fixtures;
use hscan_fixtures::{Polytope, Rng, directions, random_half_spaces, supporting};

/// The test device as found (i64 kernels where the adapter has
/// `SHADER_INT64`) and seen portable (emulated kernels), optionally with
/// capped bindings: views of the one device, not new devices.
fn devices(cap: Option<u64>) -> Option<Vec<Gpu>> {
    let gpu = common::gpu()?;
    let (native, portable) = (gpu.view(cap, false), gpu.view(cap, true));
    assert_eq!(Arithmetic::of(&portable), Arithmetic::I32x2);
    if Arithmetic::of(&native) != Arithmetic::Int64 {
        eprintln!("note: adapter lacks SHADER_INT64; only the fallback runs");
    }
    Some(vec![native, portable])
}

/// GPU rows and GPU brute force on `gpu` against the CPU mirror and the
/// i128 oracle, exactly, with no surviving sentinel.
fn check(gpu: &Gpu, what: &str, faces: &[HalfSpace], bbox: &VoxelBox) {
    let arith = Arithmetic::of(gpu);
    let what = format!("{what} ({arith:?})");
    let input = HullScanInput::upload(gpu, faces, bbox).unwrap();
    let truth = brute::classify(faces, bbox).unwrap();

    let spans = input.rows(gpu, arith).unwrap();
    assert_eq!(
        find_sentinel(&spans.spans, ROWS_SENTINEL),
        None,
        "{what}: row sentinel survived"
    );
    let want = cpu::hull_rows(faces, bbox);
    compare_exact(&format!("hull_rows/{what}"), &want.spans, &spans.spans)
        .unwrap_or_else(|m| panic!("{m}"));
    let rows = spans.to_classification().unwrap();
    compare_exact(
        &format!("hull_rows/{what} expanded"),
        &truth.sides,
        &rows.sides,
    )
    .unwrap_or_else(|m| panic!("{m}"));

    let scan = input.scan(gpu, arith).unwrap();
    assert_eq!(
        find_sentinel(&scan.sides, 0xFF),
        None,
        "{what}: scan sentinel survived"
    );
    compare_exact(&format!("hull_scan/{what}"), &truth.sides, &scan.sides)
        .unwrap_or_else(|m| panic!("{m}"));
}

fn random_cases() -> Vec<(String, Vec<HalfSpace>, VoxelBox)> {
    let mut rng = Rng::new(2024);
    let mut cases = Vec::new();
    for case in 0..24 {
        let bbox = VoxelBox {
            origin: [rng.range(-30, 30), rng.range(-30, 30), rng.range(-30, 30)],
            dims: [
                rng.range(1, 40) as usize,
                rng.range(1, 24) as usize,
                rng.range(1, 16) as usize,
            ],
        };
        let k = [1, 4, 1000, 2_000_000_000][case % 4];
        let n = rng.range(0, 30) as usize;
        let faces = random_half_spaces(&mut rng, n, &bbox, k);
        cases.push((format!("random {case}"), faces, bbox));
    }
    // Range limits: normals near ±(2³¹ − 1), boxes at both ends of ±2¹⁵.
    let m = hull_scan::MAX_NORMAL;
    for origin in [[-32768; 3], [32768 - 17, 32768 - 11, 32768 - 5]] {
        let bbox = VoxelBox {
            origin,
            dims: [17, 11, 5],
        };
        let faces = (0..8)
            .map(|_| {
                let normal = [rng.range(-m, m), rng.range(-m, m), rng.range(-m, m)];
                let p = bbox.centre([
                    rng.range(0, 16) as usize,
                    rng.range(0, 10) as usize,
                    rng.range(0, 4) as usize,
                ]);
                HalfSpace {
                    normal,
                    offset: normal[0] * p[0]
                        + normal[1] * p[1]
                        + normal[2] * p[2]
                        + rng.range(-1, 1),
                }
            })
            .collect();
        cases.push((format!("limits at {origin:?}"), faces, bbox));
    }
    // A digital ball inside 124 supporting planes.
    let (obj, bbox) = hscan_fixtures::digital_ball(24, 21);
    let pts = hscan_fixtures::extreme_centres(&obj, &bbox);
    cases.push(("ball".into(), supporting(&pts, &directions(2)), bbox));
    cases
}

#[test]
fn synthetic_polytopes() {
    let Some(gpus) = devices(None) else { return };
    for gpu in &gpus {
        for (what, faces, bbox) in random_cases() {
            check(gpu, &what, &faces, &bbox);
        }
    }
}

#[test]
fn slabs_over_the_binding_limit() {
    // 2 KiB bindings: 40·30 = 1200 bytes per z layer of side codes (one
    // layer per slab), 30 · 16 = 480 bytes of spans (4 layers per slab).
    let Some(gpus) = devices(Some(2048)) else {
        return;
    };
    let bbox = VoxelBox {
        origin: [-5, 3, -9],
        dims: [40, 30, 25],
    };
    let mut rng = Rng::new(5);
    for gpu in &gpus {
        assert_eq!(gpu.max_binding_bytes(), 2048);
        for case in 0..3 {
            let faces = random_half_spaces(&mut rng, 12, &bbox, 7);
            check(gpu, &format!("slabs {case}"), &faces, &bbox);
        }
        // One z layer larger than a binding is refused, not truncated.
        let wide = VoxelBox {
            origin: [0; 3],
            dims: [64, 64, 2],
        };
        assert!(matches!(
            hull_scan::classify_voxels(&[], &wide, Backend::Gpu(gpu)),
            Err(chisel::Error::Limit { .. })
        ));
    }
}

#[test]
fn negative_control() {
    let Some(gpus) = devices(None) else { return };
    let (_, faces, bbox) = random_cases().pop().unwrap();
    for gpu in &gpus {
        let truth = brute::classify(&faces, &bbox).unwrap();
        let mut got = hull_scan::classify_voxels(&faces, &bbox, Backend::Gpu(gpu)).unwrap();
        compare_exact("hull_scan", &truth.sides, &got.sides).unwrap();
        let i = got.sides.len() / 2 + 3;
        got.sides[i] = (got.sides[i] + 1) % 3;
        let m = compare_exact("hull_scan", &truth.sides, &got.sides).unwrap_err();
        assert_eq!((m.index, m.count), (i, 1));

        let want = cpu::hull_rows(&faces, &bbox);
        let mut spans: RowSpans = hull_scan::row_spans(&faces, &bbox, Backend::Gpu(gpu)).unwrap();
        compare_exact("hull_rows", &want.spans, &spans.spans).unwrap();
        let r = spans.spans.iter().position(|s| s[2] <= s[3]).unwrap();
        spans.spans[r][2] = spans.spans[r][3] + 1;
        let m = compare_exact("hull_rows", &want.spans, &spans.spans).unwrap_err();
        assert_eq!(m.index, r);
        assert!(
            compare_exact(
                "expanded",
                &truth.sides,
                &spans.to_classification().unwrap().sides
            )
            .is_err()
        );
    }
}

/// The largest 6-connected component of `headsq/quarter` ≥ 1150 (bone) as a
/// mask over the whole 64 × 64 × 93 volume.
fn ct_bone() -> Option<(Vec<bool>, VoxelBox)> {
    let v = common::real_volume("headsq/quarter.nhdr")?;
    let bone: Vec<bool> = (0..v.len()).map(|i| v.data.get_f64(i) >= 1150.0).collect();
    let l = label_6_connected(v.dims, |i| bone[i]).unwrap();
    let largest = (0..l.sizes.len()).max_by_key(|&c| l.sizes[c]).unwrap() as u32 + 1;
    let mask = l.labels.iter().map(|&x| x == largest).collect();
    Some((
        mask,
        VoxelBox {
            origin: [0; 3],
            dims: v.dims,
        },
    ))
}

#[test]
fn real_ct_head_bone() {
    // The hull stand-in: supporting planes of the bone's run-extreme voxel
    // centres in the 98 primitive directions with components in −2..=2,
    // reduced to the real faces of their polytope (exact vertex
    // enumeration) — a convex polyhedron around the bone whose faces all
    // touch it, until `src/hull` provides the exact hull.
    let Some((bone, bbox)) = ct_bone() else {
        return;
    };
    let pts = hscan_fixtures::extreme_centres(&bone, &bbox);
    let poly = Polytope::new(&supporting(&pts, &directions(2)));
    assert!(poly.faces.len() > 40, "{} faces", poly.faces.len());
    let truth = brute::classify(&poly.faces, &bbox).unwrap();
    assert!(
        bone.iter()
            .zip(&truth.sides)
            .all(|(b, s)| !b || *s != Side::Outside as u8)
    );
    let [_, on, inside] = truth.counts();
    assert!(on > 0 && inside > 100_000, "{:?}", truth.counts());
    // ZKHs of the bone inside that polyhedron: many, of several classes.
    let z = zkh::analyse(&bone, &truth, &poly.faces, &poly.adjacency).unwrap();
    let classes: std::collections::BTreeSet<_> = z.components.iter().map(|c| c.class).collect();
    assert!(z.components.len() > 10 && classes.len() >= 2, "{classes:?}");
    eprintln!(
        "headsq bone: {} faces, counts {:?}, {} ZKHs, classes {classes:?}",
        poly.faces.len(),
        truth.counts(),
        z.components.len()
    );
    let Some(gpus) = devices(None) else { return };
    for gpu in &gpus {
        check(gpu, "headsq bone", &poly.faces, &bbox);
    }
    // And in slabs, both arithmetics.
    let Some(capped) = devices(Some(64 * 64 * 16)) else {
        return;
    };
    for gpu in &capped {
        check(gpu, "headsq bone, slabs", &poly.faces, &bbox);
    }
}

/// GPU rows with face lists culled by `z_extents` on `gpu` against the CPU's
/// culled rows and the full CPU rows, exactly, with no surviving sentinel.
fn check_culled(
    gpu: &Gpu,
    what: &str,
    faces: &[HalfSpace],
    z_extents: &[[i64; 2]],
    bbox: &VoxelBox,
) {
    let arith = Arithmetic::of(gpu);
    let what = format!("{what} ({arith:?}, culled)");
    let spans = HullScanInput::upload(gpu, faces, bbox)
        .and_then(|i| i.culled(z_extents))
        .and_then(|i| i.rows(gpu, arith))
        .unwrap();
    assert_eq!(
        find_sentinel(&spans.spans, ROWS_SENTINEL),
        None,
        "{what}: row sentinel survived"
    );
    let want = cpu::hull_rows_culled(faces, z_extents, bbox);
    compare_exact(&format!("hull_rows/{what}"), &want.spans, &spans.spans)
        .unwrap_or_else(|m| panic!("{m}"));
    compare_exact(
        &format!("hull_rows/{what} vs every face"),
        &cpu::hull_rows(faces, bbox).spans,
        &spans.spans,
    )
    .unwrap_or_else(|m| panic!("{m}"));
}

/// A named hull: its half-spaces, their faces' z ranges and a box.
type HullCase = (String, Vec<HalfSpace>, Vec<[i64; 2]>, VoxelBox);

/// Exact hulls of random lattice points (some flat) with their faces' z
/// ranges, in boxes reaching past them in x, y and at the top, and past or
/// into them at the bottom (layers the hull misses, layers it fills).
fn hull_cases() -> Vec<HullCase> {
    let mut rng = Rng::new(77);
    let mut cases = Vec::new();
    for case in 0..12 {
        let spread = rng.range(2, 14);
        let flat = case % 4 == 3;
        let points: Vec<[i64; 3]> = (0..rng.range(4, 60))
            .map(|_| {
                let z = if flat {
                    2 * spread + 1
                } else {
                    rng.range(0, 4 * spread)
                };
                [rng.range(0, 4 * spread), rng.range(0, 4 * spread), z]
            })
            .collect();
        let Ok(hull) = ConvexHull::build(&points, Default::default()) else {
            continue;
        };
        let faces = hull
            .half_spaces()
            .into_iter()
            .map(HalfSpace::from)
            .collect();
        let bbox = VoxelBox {
            origin: [-2, -1, rng.range(-3, 2)],
            dims: [
                2 * spread as usize + 5,
                2 * spread as usize + 3,
                2 * spread as usize + 4,
            ],
        };
        cases.push((format!("hull {case}"), faces, hull.face_z_extents(), bbox));
    }
    assert!(cases.len() >= 10, "{} hulls", cases.len());
    cases
}

#[test]
fn culled_rows_on_lattice_hulls() {
    let Some(gpus) = devices(None) else { return };
    for gpu in &gpus {
        for (what, faces, extents, bbox) in hull_cases() {
            check_culled(gpu, &what, &faces, &extents, &bbox);
        }
    }
    // In slabs: 2 KiB bindings hold the spans of 4 layers of 30 rows.
    let Some(capped) = devices(Some(2048)) else {
        return;
    };
    for gpu in &capped {
        for (what, faces, extents, bbox) in hull_cases() {
            check_culled(gpu, &format!("{what}, slabs"), &faces, &extents, &bbox);
        }
    }
}

#[test]
fn culled_face_lists_split_slabs() {
    // 400 half-spaces, each said to span every layer: a layer's list takes
    // 402 words (1,608 bytes), so 16 KiB bindings hold 10 layers per slab
    // although their spans (8 rows, 128 bytes per layer) would allow 128.
    let Some(gpus) = devices(Some(16 << 10)) else {
        return;
    };
    let bbox = VoxelBox {
        origin: [-4, 0, -2],
        dims: [20, 8, 25],
    };
    let mut rng = Rng::new(9);
    let faces = random_half_spaces(&mut rng, 400, &bbox, 5);
    let everywhere = vec![[i64::MIN, i64::MAX]; faces.len()];
    for gpu in &gpus {
        check_culled(gpu, "400 faces, every layer", &faces, &everywhere, &bbox);
        // One range per face, or an error.
        assert!(matches!(
            HullScanInput::upload(gpu, &faces, &bbox).and_then(|i| i.culled(&everywhere[1..])),
            Err(chisel::Error::Mismatch { expected, found, .. })
                if expected == faces.len() as u64 && found + 1 == expected
        ));
    }
}

#[test]
fn culled_rows_negative_control() {
    // The cube's +x face said to span one layer only is missing from the
    // other layers' lists, whose rows then run to the box's end: the GPU
    // agrees with the CPU on those wrong spans, so the lists are read.
    let (faces, mut extents, bbox) = hscan_fixtures::cube_hull();
    let side = faces.iter().position(|f| f.normal == [1, 0, 0]).unwrap();
    extents[side] = [9, 9];
    let Some(gpus) = devices(None) else { return };
    for gpu in &gpus {
        let got = HullScanInput::upload(gpu, &faces, &bbox)
            .and_then(|i| i.culled(&extents))
            .and_then(|i| i.rows(gpu, Arithmetic::of(gpu)))
            .unwrap();
        compare_exact(
            "culled, wrong range",
            &cpu::hull_rows_culled(&faces, &extents, &bbox).spans,
            &got.spans,
        )
        .unwrap();
        let m = compare_exact(
            "culled vs every face",
            &cpu::hull_rows(&faces, &bbox).spans,
            &got.spans,
        )
        .unwrap_err();
        assert!(m.count > 0);
    }
}

#[test]
fn culled_rows_real_ct_head_bone() {
    // The exact hull of the CT head's bone (≥ 1150, largest component):
    // every layer tests only the faces meeting it.
    let Some(v) = common::real_volume("headsq/quarter.nhdr") else {
        return;
    };
    let o =
        DigitalObject::from_volume(&v, Selection::Threshold(1150.0), Component::Largest).unwrap();
    let hull = ConvexHull::of_object(&o, CandidateKind::Local26, HullOptions::default()).unwrap();
    let faces: Vec<HalfSpace> = hull.half_spaces().into_iter().map(Into::into).collect();
    let extents = hull.face_z_extents();
    assert!(faces.len() > 100, "{} faces", faces.len());
    let bbox = VoxelBox {
        origin: [0; 3],
        dims: v.dims,
    };
    let Some(gpus) = devices(None) else { return };
    for gpu in &gpus {
        check_culled(gpu, "headsq bone hull", &faces, &extents, &bbox);
    }
    let Some(capped) = devices(Some(64 * 64 * 16)) else {
        return;
    };
    for gpu in &capped {
        check_culled(gpu, "headsq bone hull, slabs", &faces, &extents, &bbox);
    }
}
