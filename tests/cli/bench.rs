//! `chisel bench relax`: rates and equilibrium, refined grids, the exported
//! network, and argument checks.

use serde_json::Value;

use crate::common;
use crate::support::{assert_clean_error, ok_json, path_str, plan_file};

/// `chisel bench relax` on fran_cut: rates of both step kernels on both
/// backends in one run, the traffic figures they imply, and the time to
/// equilibrium after the chin plan's first increment (the explicit kernel
/// is bit-exact on lavapipe, so its GPU run lands on the CPU state).
#[test]
fn bench_relax_reports_rates_and_equilibrium() {
    let Some(gpu) = common::gpu() else { return };
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let report = tmp.path().join("bench.json");
    let fran = dir.join("fran_cut.vtk");
    let plan = plan_file("fran_chin_advance.toml");
    let v = ok_json(&[
        "bench",
        "relax",
        path_str(&fran),
        "--plan",
        &plan,
        "--seconds",
        "0.05",
        "--approach",
        "--json",
        "--report",
        path_str(&report),
    ]);
    let written: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(written, v);
    assert!(v["machine"]["threads"].as_u64().unwrap() >= 1);
    let net = &v["networks"][0];
    assert_eq!(net["nodes"], 6615);
    assert_eq!(net["free_nodes"], 4410);
    let bytes = net["bytes_per_iteration"].as_u64().unwrap();
    // 84 bytes per free node, 32 per bone node, 4 per CSR entry.
    let entries = net["csr_entries"].as_u64().unwrap();
    assert_eq!(bytes, 4410 * 84 + 2205 * 32 + entries * 4);
    let rates = net["rates"].as_array().unwrap();
    let runs: Vec<(&str, &str)> = rates
        .iter()
        .map(|r| {
            (
                r["solver"].as_str().unwrap(),
                r["backend"].as_str().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        runs,
        [
            ("explicit", "cpu"),
            ("explicit", "gpu"),
            ("chebyshev", "cpu"),
            ("chebyshev", "gpu")
        ]
    );
    for r in rates {
        let (n, s) = (
            r["iterations"].as_f64().unwrap(),
            r["seconds"].as_f64().unwrap(),
        );
        assert!(n >= 8.0 && s > 0.0, "{r}");
        let rate = r["iterations_per_second"].as_f64().unwrap();
        assert!((rate - n / s).abs() <= 1e-9 * rate, "{r}");
        let gbs = r["effective_gb_per_second"].as_f64().unwrap();
        assert!((gbs - rate * bytes as f64 / 1e9).abs() <= 1e-9 * gbs, "{r}");
    }
    let settled = net["time_to_equilibrium"].as_array().unwrap();
    assert_eq!(settled.len(), 4);
    for s in settled {
        assert_eq!(s["status"], "converged", "{s}");
        // Both solvers reach the same state within their stop tests.
        assert!(s["gap_percent"].as_f64().unwrap() < 3.0, "{s}");
    }
    // The explicit kernel is bit-exact with its mirror on a software adapter;
    // a GPU whose compiler fuses multiply-adds settles to the same state
    // within rounding (NVIDIA H200: 0.0015 % apart).
    if gpu.is_software() {
        assert_eq!(settled[1]["gap_percent"], 0.0, "explicit GPU vs CPU");
        assert_eq!(settled[0]["iterations"], settled[1]["iterations"]);
    } else {
        let gap = settled[1]["gap_percent"].as_f64().unwrap();
        assert!(gap < 0.1, "explicit GPU vs CPU: {gap} %");
    }
    let approach = &net["approach"];
    assert_eq!(approach["reference_status"], "converged");
    for a in approach["runs"].as_array().unwrap() {
        assert_eq!(a["reached"], true, "{a}");
        assert!(a["gap_percent"].as_f64().unwrap() <= 1.0, "{a}");
    }
}

/// `--grid` and `--refine` build the refined networks of the benchmarks:
/// fran_cut refined 2× has 89 × 97 vertices per layer.
#[test]
fn bench_relax_refines_the_scan_grid() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let fran = dir.join("fran_cut.vtk");
    let v = ok_json(&[
        "bench",
        "relax",
        path_str(&fran),
        "--grid",
        "45,49",
        "--refine",
        "1,2",
        "--backend",
        "cpu",
        "--solver",
        "explicit",
        "--seconds",
        "0.02",
        "--json",
    ]);
    let nodes: Vec<u64> = (v["networks"].as_array().unwrap().iter())
        .map(|n| n["nodes"].as_u64().unwrap())
        .collect();
    assert_eq!(nodes, [6615, 3 * 89 * 97]);
    for n in v["networks"].as_array().unwrap() {
        assert_eq!(n["rates"].as_array().unwrap().len(), 1);
        assert!(n["time_to_equilibrium"].is_null());
        assert!(n["spectrum"].is_null());
    }
}

/// `--export` writes the network the rates run on: the arrays equal the
/// network built here, the bone carries the plan's first increment, and
/// the header's counts match the files.
#[test]
fn bench_relax_exports_the_network() {
    use chisel::tissue::{NetworkParams, SpringNetwork};
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let fran = dir.join("fran_cut.vtk");
    let plan = plan_file("fran_chin_advance.toml");
    let out = tmp.path().join("nets");
    let v = ok_json(&[
        "bench",
        "relax",
        path_str(&fran),
        "--backend",
        "cpu",
        "--solver",
        "explicit",
        "--seconds",
        "0.02",
        "--plan",
        &plan,
        "--export",
        path_str(&out),
        "--json",
    ]);
    let lanes = v["machine"]["cpu_lanes"].as_str().unwrap();
    assert!(["four", "eight", "sixteen"].contains(&lanes), "{lanes}");
    let x1 = out.join("x1");
    let words = |name: &str| -> Vec<u32> {
        let b = std::fs::read(x1.join(name)).unwrap();
        assert_eq!(b.len() % 4, 0, "{name}");
        b.chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    let mesh = chisel::io::read_mesh(&fran).unwrap();
    let net = SpringNetwork::build(&mesh, None, &NetworkParams::default()).unwrap();
    let bits =
        |rows: &[[f32; 4]]| -> Vec<u32> { rows.iter().flatten().map(|x| x.to_bits()).collect() };
    assert_eq!(words("rest.f32"), bits(&net.rest));
    assert_eq!(words("offsets.u32"), net.csr.offsets);
    assert_eq!(words("entries.u32"), net.csr.entries);
    let mut table = vec![[0.0f32; 4]; 16];
    for (row, m) in table.iter_mut().zip(&net.materials) {
        *row = m.table_row();
    }
    assert_eq!(words("materials.f32"), bits(&table));
    let u: Vec<f32> = words("displacement.f32")
        .into_iter()
        .map(f32::from_bits)
        .collect();
    assert_eq!(u.len(), 4 * net.n_nodes());
    let (free, bone) = u.split_at(4 * net.n_free);
    assert!(
        free.chunks(4)
            .all(|p| p == [0.0, 0.0, 0.0, 1.0 / net.params.mass])
    );
    let moved = bone.chunks(4).filter(|p| p[..3] != [0.0; 3]).count();
    assert!(
        moved > 10 && bone.chunks(4).all(|p| p[3] == 0.0),
        "{moved} bone nodes moved"
    );
    let header: Value =
        serde_json::from_slice(&std::fs::read(x1.join("network.json")).unwrap()).unwrap();
    assert_eq!(header["nodes"], 6615);
    assert_eq!(header["free"], 4410);
    assert_eq!(header["entries"], net.csr.entries.len());
    assert!(header["dt"].as_f64().unwrap() > 0.0);
}

#[test]
fn bench_relax_arguments_are_checked() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let fran = dir.join("fran_cut.vtk");
    let fran = path_str(&fran);
    let run = |extra: &[&str], names: &str| {
        let mut args = vec!["bench", "relax", fran, "--backend", "cpu"];
        args.extend(extra);
        assert_clean_error(&args, names);
    };
    run(&["--refine", "8"], "--grid COLS,ROWS");
    run(
        &["--grid", "10,10"],
        "fran_cut.vtk: --grid 10,10 needs 100 vertices",
    );
    run(&["--grid", "45"], "--grid takes COLS,ROWS");
    run(&["--refine", "0"], "--refine factors are 1..=64");
    run(&["--seconds", "0"], "--seconds takes a positive number");
    let cut_plan = plan_file("ct_phantom_jaw_advance.toml");
    run(
        &["--plan", &cut_plan],
        "ct_phantom_jaw_advance.toml: the plan cuts the bone",
    );
    assert_clean_error(
        &[
            "bench",
            "relax",
            "/nonexistent/skin.ply",
            "--backend",
            "cpu",
        ],
        "/nonexistent/skin.ply",
    );
}
