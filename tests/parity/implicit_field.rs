//! Parity of `kernels/implicit_field.wgsl` (with `shared/skeletal_field.wgsl`)
//! against `implicit::field::cpu`: a mixed scene of every skeleton,
//! influence and blend, and the five example scenes at several times, at
//! random points, on-surface points (marching-cubes vertices) and points
//! outside the cull grid. Negative controls: a mirror that skips one listed
//! primitive, and one that drops F_t's skeleton term.

use chisel::Backend;
use chisel::gpu::Gpu;
use chisel::implicit::field::gpu::{FieldBuffers, PointBuffers};
use chisel::implicit::field::{FieldInput, Sample, cpu};
use chisel::implicit::scene::EXAMPLES;
use chisel::implicit::{Scene, grid};
use chisel::parity::{compare_by, find_sentinel};
use glam::DVec3;

use crate::common;

const MIXED: &str = r#"
iso = 0.5
blend = "weighted"
[[primitive]]
skeleton = { point = [0.1, 0.2, -0.1] }
influence = { blobby = { a = 2.0, b = 1.2 } }
weight = 1.5
[[primitive]]
skeleton = { segment = [[-1.0, 0.0, 0.0], [0.5, 0.8, 0.3]] }
influence = { wyvill = { radius = 1.1, strength = 0.9 } }
weight = 0.8
[[primitive]]
skeleton = { polyline = [[0.0, -1.0, 0.0], [0.8, -0.6, 0.2], [1.2, 0.1, -0.3], [0.4, 0.5, -0.6]], closed = true }
influence = { metaball = { radius = 0.9, strength = 1.1 } }
weight = 1.0
[[primitive]]
skeleton = { segment = [[0.3, 0.3, 0.6], [0.4, -0.2, 0.7]] }
influence = { blobby = { a = 6.0, b = -0.4 } }
weight = 1.2
[[key]]
time = 1.0
primitive = 0
skeleton = { point = [0.4, 0.0, 0.1] }
influence = { blobby = { a = 2.6, b = 0.9 } }
weight = 1.1
[[key]]
time = 1.0
primitive = 2
skeleton = { polyline = [[0.1, -1.1, 0.0], [0.8, -0.5, 0.3], [1.1, 0.2, -0.2], [0.4, 0.6, -0.5]], closed = true }
influence = { metaball = { radius = 1.0 } }
"#;

/// GPU samples with the NaN sentinel check.
fn gpu_samples(gpu: &Gpu, what: &str, input: &FieldInput, points: &[[f32; 4]]) -> Vec<Sample> {
    let field = FieldBuffers::upload(gpu, input).unwrap();
    let batch = PointBuffers::upload(gpu, points).unwrap();
    let mut encoder = gpu.encoder("implicit_field");
    batch.record(gpu, &mut encoder, &field).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let samples = batch.samples.read(gpu).unwrap();
    assert_eq!(
        find_sentinel(&samples, [f32::NAN; 4]),
        None,
        "{what}: NaN sentinel survived"
    );
    let rates = batch.rates.read(gpu).unwrap();
    assert_eq!(
        find_sentinel(&rates, f32::NAN),
        None,
        "{what}: NaN sentinel survived"
    );
    batch.read(gpu).unwrap()
}

/// Mirror samples with their scales, from `mirror`.
type Mirror<'a> = &'a dyn Fn(&FieldInput, [f32; 3]) -> (Sample, cpu::Scales);

fn compare(
    what: &str,
    input: &FieldInput,
    points: &[[f32; 4]],
    mirror: Mirror<'_>,
    got: &[Sample],
) -> Result<(), String> {
    let want: Vec<(Sample, cpu::Scales)> = points
        .iter()
        .map(|p| mirror(input, [p[0], p[1], p[2]]))
        .collect();
    let got: Vec<(Sample, cpu::Scales)> = got.iter().zip(&want).map(|(g, w)| (*g, w.1)).collect();
    let iso = input.params.iso;
    compare_by(
        &format!("implicit_field/{what}"),
        &want,
        &got,
        |a, b| !cpu::accepts(&a.0, a.1, iso, &b.0),
        |x| format!("{:?}", x.0),
    )
    .map_err(|m| m.to_string())
}

/// Random points around the pose's surface (half a box beyond), its
/// marching-cubes vertices, and points outside the cull grid.
fn points(scene: &Scene, t: f64, seed: u64) -> Vec<[f32; 4]> {
    let pose = scene.pose(t);
    let (lo, hi) = grid::surface_bounds(&pose).unwrap();
    let pad = 0.5 * (hi - lo);
    let mut rng = common::xorshift(seed);
    let mut u = move || (rng() >> 11) as f64 / (1u64 << 53) as f64;
    let mut out: Vec<[f32; 4]> = (0..3000)
        .map(|_| {
            let x = lo - pad + (hi - lo + 2.0 * pad) * DVec3::new(u(), u(), u());
            [x.x as f32, x.y as f32, x.z as f32, 0.0]
        })
        .collect();
    let h = (hi - lo).max_element() / 40.0;
    let surface = grid::marching_cubes(&pose, h, Backend::Cpu).unwrap();
    out.extend(
        surface
            .mesh
            .positions
            .iter()
            .step_by(3)
            .map(|p| [p.x, p.y, p.z, 0.0]),
    );
    out.push([1e6, -1e6, 3e5, 0.0]);
    out
}

fn check(gpu: &Gpu, what: &str, scene: &Scene, t: f64, seed: u64) {
    let input = FieldInput::new(&scene.pose(t)).unwrap();
    let pts = points(scene, t, seed);
    let got = gpu_samples(gpu, what, &input, &pts);
    compare(what, &input, &pts, &cpu::skeletal_field, &got).unwrap_or_else(|m| panic!("{m}"));
}

#[test]
fn mixed_scene() {
    let Some(gpu) = common::gpu() else { return };
    let scene = Scene::from_toml_str(MIXED, "mixed").unwrap();
    for (k, t) in [0.0, 0.4, 1.0].into_iter().enumerate() {
        check(gpu, &format!("mixed@{t}"), &scene, t, k as u64 + 1);
    }
    // Weights are refused under max: strip them line by line.
    let refused = Scene::from_toml_str(
        &MIXED
            .replace("\"weighted\"", "\"max\"")
            .replace("b = -0.4", "b = 0.4"),
        "mixed-max",
    );
    let text: String = MIXED
        .replace("\"weighted\"", "\"max\"")
        .replace("b = -0.4", "b = 0.4")
        .lines()
        .filter(|l| !l.starts_with("weight"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert!(refused.is_err(), "weights under max are refused");
    let scene = Scene::from_toml_str(&text, "mixed-max").unwrap();
    check(gpu, "mixed-max@0.5", &scene, 0.5, 9);
}

#[test]
fn example_scenes() {
    let Some(gpu) = common::gpu() else { return };
    for (k, (name, text)) in EXAMPLES.iter().enumerate() {
        let scene = Scene::from_toml_str(text, name).unwrap();
        for t in [0.0, 0.45, 1.0] {
            check(gpu, &format!("{name}@{t}"), &scene, t, 100 + k as u64);
        }
    }
}

/// The comparison fails when the mirror skips one listed primitive or drops
/// the moving-skeleton term of F_t.
#[test]
fn negative_controls() {
    let scene = Scene::from_toml_str(MIXED, "mixed").unwrap();
    let input = FieldInput::new(&scene.pose(0.4)).unwrap();
    let pts = points(&scene, 0.4, 5);
    let reference: Vec<Sample> = pts
        .iter()
        .map(|p| cpu::skeletal_field(&input, [p[0], p[1], p[2]]).0)
        .collect();
    compare("control", &input, &pts, &cpu::skeletal_field, &reference).unwrap();
    // Skipping primitive 1 (the Wyvill segment): drop it from the cull lists.
    let mut skipped = input.clone();
    let c = skipped.params.cell_base as usize;
    let n_cells = skipped.n_cells();
    let ids_start = skipped.table[c] as usize;
    let mut lists: Vec<Vec<u32>> = (0..n_cells)
        .map(|k| {
            skipped.table[skipped.table[c + k] as usize..skipped.table[c + k + 1] as usize].to_vec()
        })
        .collect();
    lists.iter_mut().for_each(|l| l.retain(|&i| i != 1));
    skipped.table.truncate(ids_start);
    let mut at = ids_start as u32;
    for (k, l) in lists.iter().enumerate() {
        skipped.table[c + k] = at;
        at += l.len() as u32;
    }
    skipped.table[c + n_cells] = at;
    skipped.table.extend(lists.concat());
    let wrong: Vec<Sample> = pts
        .iter()
        .map(|p| cpu::skeletal_field(&skipped, [p[0], p[1], p[2]]).0)
        .collect();
    assert!(compare("skip", &input, &pts, &cpu::skeletal_field, &wrong).is_err());
    // Dropping the skeleton velocities (F_t without the q̇ term).
    let mut still = input.clone();
    let base = still.params.piece_base as usize;
    for (k, row) in still.skeleton.iter_mut().enumerate().skip(base) {
        if (k - base) % 4 >= 2 {
            *row = [0.0; 4];
        }
    }
    let wrong: Vec<Sample> = pts
        .iter()
        .map(|p| cpu::skeletal_field(&still, [p[0], p[1], p[2]]).0)
        .collect();
    let err = compare("still", &input, &pts, &cpu::skeletal_field, &wrong).unwrap_err();
    assert!(err.contains("implicit_field/still"), "{err}");
}
