//! Shared by every bench binary.

/// Smoke mode: `CHISEL_BENCH_QUICK=1`, or the binary runs under
/// `cargo test` (criterion's test mode runs each benchmark once, without
/// `--bench`), so the test suite never builds the full-size problems.
pub fn quick() -> bool {
    std::env::var("CHISEL_BENCH_QUICK").is_ok_and(|v| v == "1" || v == "true")
        || !std::env::args().any(|a| a == "--bench")
}

/// A benchmark group with the house timing: 10 samples after 300 ms of
/// warm-up over 2 s (smoke mode: 20 ms, 60 ms).
#[allow(dead_code, reason = "not every bench binary measures in groups")]
pub fn group<'a>(
    c: &'a mut criterion::Criterion,
    name: &str,
) -> criterion::BenchmarkGroup<'a, criterion::measurement::WallTime> {
    use std::time::Duration;
    let mut g = c.benchmark_group(name);
    if quick() {
        g.sample_size(10)
            .warm_up_time(Duration::from_millis(20))
            .measurement_time(Duration::from_millis(60));
    } else {
        g.sample_size(10)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(2));
    }
    g
}

/// The GPU the benches run on (the adapter printed), or `None` with a note
/// when there is none: the GPU rows are then left out.
#[allow(dead_code, reason = "not every bench binary runs GPU rows")]
pub fn gpu() -> Option<chisel::gpu::Gpu> {
    match chisel::gpu::Gpu::new() {
        Ok(g) => {
            eprintln!("adapter: {}", g.describe());
            Some(g)
        }
        Err(e) => {
            eprintln!("no adapter, GPU benches skipped: {e}");
            None
        }
    }
}
