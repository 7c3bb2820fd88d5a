//! The particle spring network (SPEC §3.3).

use chisel::Backend;
use chisel::implicit::Scene;
use chisel::implicit::field::FieldInput;
use chisel::implicit::scene::EXAMPLES;
use chisel::mesh::intersect::self_intersections;
use chisel::particles::NetworkOptions;
use chisel::particles::animate::start_network;

#[test]
fn explore() {
    let name = std::env::var("SCENE").unwrap_or("dumbbell".into());
    let text = EXAMPLES.iter().find(|e| e.0 == name).unwrap().1;
    let scene = Scene::from_toml_str(text, &name).unwrap();
    let field = FieldInput::new(&scene.pose(0.0)).unwrap();
    let mut net = start_network(&scene, 0.05, NetworkOptions::default(), Backend::Cpu).unwrap();
    println!("start si {}", self_intersections(&net.mesh()).pairs.len());
    for k in 0..12 {
        let it = net.iterate(&field, 0.0, Backend::Cpu).unwrap();
        let si = self_intersections(&net.mesh());
        let m = net.mesh();
        for p in &si.pairs {
            let (a, b) = (m.triangles[p[0] as usize], m.triangles[p[1] as usize]);
            let shared = a.iter().filter(|v| b.contains(v)).count();
            let n = |t: [u32; 3]| {
                let [x, y, z] = t.map(|v| m.positions[v as usize]);
                (y - x).cross(z - x).normalize()
            };
            println!(
                "{k} pair {a:?} {b:?} shared {shared} cos {:.3} splits {} collapses {}",
                n(a).dot(n(b)),
                it.splits,
                it.collapses
            );
        }
    }
}
