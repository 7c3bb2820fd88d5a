//! The particle spring network (SPEC §3.3).

use chisel::Backend;
use chisel::implicit::field::FieldInput;
use chisel::implicit::scene::EXAMPLES;
use chisel::implicit::{Scene, grid};
use chisel::mesh::Topology;
use chisel::mesh::collapse::collapse_short_edges;
use chisel::particles::{Network, NetworkOptions};

#[test]
fn explore() {
    let name = std::env::var("SCENE").unwrap_or("dumbbell".into());
    let name = name.as_str();
    let text = EXAMPLES.iter().find(|e| e.0 == name).unwrap().1;
    let scene = Scene::from_toml_str(text, name).unwrap();
    let pose = scene.pose(0.0);
    let field = FieldInput::new(&pose).unwrap();
    let r: f64 = std::env::var("R")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.05);
    let mc = grid::marching_cubes(&pose, r, Backend::Cpu).unwrap();
    let start = collapse_short_edges(&mc.mesh, 0.3 * r as f32).mesh;
    let mut net = Network::new(&start, r, NetworkOptions::default(), &field).unwrap();
    for _ in 0..20 {
        net.iterate(&field, 0.0, Backend::Cpu).unwrap();
    }
    let steps = 400;
    let t0 = std::time::Instant::now();
    for k in 0..steps {
        let t = k as f64 / steps as f64;
        let field = FieldInput::new(&scene.pose(t)).unwrap();
        net.iterate(&field, (1.0 / steps as f64) as f32, Backend::Cpu)
            .unwrap();
        let field = FieldInput::new(&scene.pose(t + 1.0 / steps as f64)).unwrap();
        let cuts = net.surgery(&field);
        let top = net.check().map(|t| t.components.len());
        if cuts != Default::default() || k % 40 == 0 {
            println!(
                "k={k} t={:.4} dist={:.4} cuts={cuts:?} V={} comps={top:?} {:?}",
                t + 1.0 / steps as f64,
                0.0,
                net.positions.len(),
                t0.elapsed()
            );
        }
    }
    let t = Topology::of(&net.mesh());
    println!(
        "end: comps {} closed {} manifold {}",
        t.components.len(),
        t.closed,
        t.is_manifold()
    );
}
