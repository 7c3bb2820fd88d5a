//! Hostile and broken inputs for every reader (SPEC §0.5): each must give
//! an `Error` naming the file and a position — never a panic, a hang, a
//! giant allocation or a silent partial result — and the atomic-write
//! guarantees. (Mutants of valid files of every format: `tests/fuzz/`.)
//!
//! Modules: the `mesh` and `volume` readers, `atomic_writes` and the
//! `campaign`'s regressions that need more than a file; the helpers and the checks that span all readers stay
//! here (`memory_budget_is_enforced` re-runs itself by its root-level name).

#[path = "../common/mod.rs"]
mod common;

mod atomic_writes;
mod campaign;
mod mesh;
mod volume;

use std::path::{Path, PathBuf};

use chisel::Error;
use chisel::io::{read_mesh, read_volume};

fn put(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Format,
    Size,
    Unsupported,
    Io,
}

fn kind(e: &Error) -> Kind {
    match e.root() {
        Error::Format { .. } => Kind::Format,
        Error::Size { .. } => Kind::Size,
        Error::Unsupported { .. } => Kind::Unsupported,
        Error::Io { .. } => Kind::Io,
        other => panic!("unexpected error variant: {other}"),
    }
}

/// Reads `bytes` saved as `name` (mesh or volume by extension) and checks the
/// error variant and that the message names the file and contains `at`.
fn expect(name: &str, bytes: &[u8], want: Kind, at: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = put(dir.path(), name, bytes);
    expect_at(&path, want, at)
}

fn expect_at(path: &Path, want: Kind, at: &str) -> String {
    let r = if is_volume(path) {
        read_volume(path).map(|_| ())
    } else {
        read_mesh(path).map(|_| ())
    };
    let e = r.expect_err("hostile input must be rejected");
    let msg = e.to_string();
    assert_eq!(kind(&e), want, "{msg}");
    let file = path.file_name().unwrap().to_string_lossy();
    assert!(msg.contains(&*file), "message lacks the file name: {msg}");
    assert!(msg.contains(at), "message lacks `{at}`: {msg}");
    msg
}

fn is_volume(path: &Path) -> bool {
    let n = path.to_string_lossy().to_ascii_lowercase();
    [".nrrd", ".nhdr", ".mha", ".mhd", ".nii", ".nii.gz"]
        .iter()
        .any(|e| n.ends_with(e))
}

#[test]
fn unknown_extensions_are_unsupported() {
    let dir = tempfile::tempdir().unwrap();
    let p = put(dir.path(), "x.xyz", b"");
    assert_eq!(kind(&read_mesh(&p).unwrap_err()), Kind::Unsupported);
    assert_eq!(kind(&read_volume(&p).unwrap_err()), Kind::Unsupported);
}

/// The memory budget: a child run of this binary with a 1000-byte budget
/// must refuse the 780 kB headsq volume before reading it.
#[test]
fn memory_budget_is_enforced() {
    if std::env::var_os("CHISEL_BUDGET_CHILD").is_some() {
        let Some(p) = common::data("headsq/quarter.nhdr") else {
            return;
        };
        let e = read_volume(&p).unwrap_err();
        assert_eq!(kind(&e), Kind::Size, "{e}");
        assert!(e.to_string().contains("CHISEL_MAX_INPUT_BYTES"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let m = put(dir.path(), "big.obj", &[b'#'; 2000]);
        assert_eq!(kind(&read_mesh(&m).unwrap_err()), Kind::Size);
        return;
    }
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["memory_budget_is_enforced", "--exact", "--test-threads=1"])
        .env("CHISEL_BUDGET_CHILD", "1")
        .env("CHISEL_MAX_INPUT_BYTES", "1000")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "child failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("1 passed"));
}
