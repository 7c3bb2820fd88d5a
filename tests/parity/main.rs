#[path = "../common/mod.rs"]
mod common;
mod mc_surface;

#[test]
fn smoke_vertex_normals() {
    let Some(gpu) = common::gpu() else { return };
    eprintln!("{}", gpu.describe());
    let m = common::icosphere(3);
    let a = chisel::normals::vertex_normals(&m, chisel::Backend::Cpu).unwrap();
    let b = chisel::normals::vertex_normals(&m, chisel::Backend::Gpu(&gpu)).unwrap();
    chisel::parity::compare_vec("ico", &a, &b, chisel::normals::cpu::TOL).unwrap();
    let t = gpu.timed_pass("x", |_| {}).unwrap();
    eprintln!("{t:?} {:?}", gpu.features);
}
