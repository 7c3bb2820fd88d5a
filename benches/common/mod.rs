//! Shared by every bench binary.

/// Smoke mode: `CHISEL_BENCH_QUICK=1`, or the binary runs under
/// `cargo test` (criterion's test mode runs each benchmark once, without
/// `--bench`), so the test suite never builds the full-size problems.
pub fn quick() -> bool {
    std::env::var("CHISEL_BENCH_QUICK").is_ok_and(|v| v == "1" || v == "true")
        || !std::env::args().any(|a| a == "--bench")
}
