//! Running the `chisel` binary and reading its reports, for every
//! command's module.

use std::path::Path;
use std::process::Output;

use serde_json::Value;

use crate::common;

pub fn chisel(args: &[&str]) -> Output {
    common::run_chisel(env!("CARGO_BIN_EXE_chisel"), args)
}

/// Runs chisel and asserts it succeeded.
pub fn ok(args: &[&str]) -> Output {
    let out = chisel(args);
    assert!(
        out.status.success(),
        "chisel {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

pub fn ok_json(args: &[&str]) -> Value {
    let out = ok(args);
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "chisel {args:?}: stdout is not JSON ({e}): {}",
            String::from_utf8_lossy(&out.stdout)
        )
    })
}

/// A failing run must exit with status 1 (not 101 = panic) and name the file.
pub fn assert_clean_error(args: &[&str], names: &str) {
    let out = chisel(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "chisel {args:?}: {stderr}");
    assert!(
        stderr.contains(names),
        "error should name {names}: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
}

/// A plan shipped in `src/tissue/plans/`.
pub fn plan_file(name: &str) -> String {
    format!("{}/src/tissue/plans/{name}", env!("CARGO_MANIFEST_DIR"))
}

pub fn path_str(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// The pieces' signed volumes of a `cut --json` report add up to the
/// input's within 1e-6 relative.
pub fn assert_volume_conserved(cut: &Value, what: &str) {
    let total: f64 = cut["pieces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["signed_volume"].as_f64().unwrap())
        .sum();
    let original = cut["input_signed_volume"].as_f64().unwrap();
    assert!(
        ((total - original) / original).abs() < 1e-6,
        "{what}: {total} vs {original}"
    );
}
