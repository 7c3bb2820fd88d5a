use chisel::surface::*;
use chisel::volume::*;
fn main() {
    let n = 512usize;
    let c = (n as f32 - 1.0) / 2.0;
    let mut data = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let (dx, dy, dz) = (x as f32 - c, y as f32 - c, z as f32 - c);
                let r = (dx * dx + dy * dy + dz * dz).sqrt();
                let v = 1000.0 - 4.0 * r
                    + 30.0
                        * ((x as f32 * 0.05).sin() * (y as f32 * 0.07).cos()
                            + (z as f32 * 0.03).sin());
                data.push(v as i16);
            }
        }
    }
    let vol = Volume::new([n; 3], [1.0; 3], [0.0; 3], VolumeData::I16(data)).unwrap();
    for _ in 0..3 {
        let t = std::time::Instant::now();
        let s = marching_cubes(
            &vol,
            IsoSpec::Level(300.0),
            &McOptions::default(),
            chisel::Backend::Cpu,
        )
        .unwrap();
        let dt = t.elapsed().as_secs_f64();
        println!(
            "{} tris {} groups {:.3}s {:.1} Mvox/s",
            s.mesh.triangles.len(),
            s.groups.len(),
            dt,
            (n * n * n) as f64 / dt / 1e6
        );
    }
    let field = Field::new(&vol, IsoSpec::Level(300.0), false).unwrap();
    let t = std::time::Instant::now();
    let raw = cpu::marching_cubes(&field).unwrap();
    println!(
        "core {:.3}s {}",
        t.elapsed().as_secs_f64(),
        raw.triangles.len()
    );
    let t = std::time::Instant::now();
    let _s = finish(&field, raw);
    println!("finish {:.3}s", t.elapsed().as_secs_f64());
}
