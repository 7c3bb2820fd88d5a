//! Parity of `kernels/network_update.wgsl` against
//! `particles::network::cpu`: one step from identical inputs on the start
//! and relaxed networks of the examples (still and moving scenes, rest
//! lengths that differ per spring), under `cpu::accepts`. Negative controls:
//! a mirror step with one spring dropped, and one with F_t dropped.

use chisel::Backend;
use chisel::gpu::Gpu;
use chisel::implicit::Scene;
use chisel::implicit::field::FieldInput;
use chisel::implicit::field::gpu::FieldBuffers;
use chisel::implicit::scene::EXAMPLES;
use chisel::parity::{compare_by, find_sentinel};
use chisel::particles::NetworkOptions;
use chisel::particles::StepOutput;
use chisel::particles::animate::start_network;
use chisel::particles::network::gpu::NetworkBuffers;
use chisel::particles::network::{NetworkInput, NetworkParams, cpu};

use crate::common;

struct Case {
    field: FieldInput,
    offsets: Vec<u32>,
    springs: Vec<[u32; 2]>,
    positions: Vec<[f32; 4]>,
    params: NetworkParams,
}

impl Case {
    fn input(&self) -> NetworkInput<'_> {
        NetworkInput {
            params: self.params,
            offsets: &self.offsets,
            springs: &self.springs,
            positions: &self.positions,
        }
    }
}

fn case(name: &str, t: f64, iters: u32) -> Case {
    let text = EXAMPLES.iter().find(|e| e.0 == name).unwrap().1;
    let scene = Scene::from_toml_str(text, name).unwrap();
    let opts = NetworkOptions {
        theta: 0.2,
        ..NetworkOptions::default()
    };
    let mut net = start_network(&scene, 0.1, opts, Backend::Cpu).unwrap();
    let field = FieldInput::new(&scene.pose(t)).unwrap();
    for _ in 0..iters {
        net.iterate(&field, 0.0, Backend::Cpu).unwrap();
    }
    let (offsets, springs) = net.springs();
    Case {
        field,
        positions: net.positions.iter().map(|p| [p.x, p.y, p.z, 0.0]).collect(),
        params: NetworkParams {
            n_vertices: net.positions.len() as u32,
            dt: 0.2,
            delta: 0.01,
            kappa: 0.5,
            rho: 1.0,
            g_min2: net.g_min * net.g_min,
            step_max: 0.05,
        },
        offsets,
        springs,
    }
}

fn gpu_step(gpu: &Gpu, what: &str, c: &Case) -> StepOutput {
    let fb = FieldBuffers::upload(gpu, &c.field).unwrap();
    let b = NetworkBuffers::upload(gpu, &c.input()).unwrap();
    let mut encoder = gpu.encoder("network_update");
    b.record(gpu, &mut encoder, &fb).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let pos = b.pos_out.read(gpu).unwrap();
    let samples = b.samples.read(gpu).unwrap();
    assert_eq!(
        find_sentinel(&pos, [f32::NAN; 4]),
        None,
        "{what}: sentinel survived"
    );
    assert_eq!(
        find_sentinel(&samples, [f32::NAN; 4]),
        None,
        "{what}: sentinel survived"
    );
    (pos, samples)
}

fn compare(
    what: &str,
    u: &NetworkParams,
    want: &StepOutput,
    got: &StepOutput,
) -> Result<(), String> {
    let a: Vec<([f32; 4], [f32; 4])> = want.0.iter().copied().zip(want.1.iter().copied()).collect();
    let b: Vec<([f32; 4], [f32; 4])> = got.0.iter().copied().zip(got.1.iter().copied()).collect();
    compare_by(
        &format!("network_update/{what}"),
        &a,
        &b,
        |x, y| !cpu::accepts(u, *x, *y),
        |x| format!("{x:?}"),
    )
    .map_err(|m| m.to_string())
}

#[test]
fn example_networks() {
    let Some(gpu) = common::gpu() else { return };
    for (name, t, iters) in [
        ("dumbbell", 0.3, 0),
        ("dumbbell", 0.3, 20),
        ("torus", 0.5, 10),
        ("finger", 0.6, 10),
        ("molecule", 0.5, 3),
    ] {
        let c = case(name, t, iters);
        let what = format!("{name}@{t}/{iters}");
        let want = cpu::network_update(&c.field, &c.input());
        let got = gpu_step(gpu, &what, &c);
        compare(&what, &c.params, &want, &got).unwrap_or_else(|m| panic!("{m}"));
    }
}

#[test]
fn negative_controls() {
    let c = case("torus", 0.5, 10);
    let want = cpu::network_update(&c.field, &c.input());
    compare("control", &c.params, &want, &want).unwrap();
    // Drop the first spring of vertex 0's row (its neighbour then sees it
    // but vertex 0 does not).
    let mut offsets = c.offsets.clone();
    offsets[0] += 1;
    let mut springs = c.springs.clone();
    springs[0] = springs[1];
    let dropped = cpu::network_update(
        &c.field,
        &NetworkInput {
            offsets: &offsets,
            springs: &springs,
            ..c.input()
        },
    );
    assert!(compare("dropped-spring", &c.params, &want, &dropped).is_err());
    let still = cpu::network_update(
        &c.field,
        &NetworkInput {
            params: NetworkParams {
                delta: 0.0,
                ..c.params
            },
            ..c.input()
        },
    );
    let err = compare("no-rate", &c.params, &want, &still).unwrap_err();
    assert!(err.contains("network_update/no-rate"), "{err}");
}
