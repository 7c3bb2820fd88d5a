//! The standing fuzz corpus and its mutation harness (stable Rust, no
//! fuzzing toolchain): every reader — the mesh formats, the volume formats,
//! plans and scenes — on mutants of valid seeds ([`corpus`]) by the
//! mutators of [`mutate`].
//!
//! Each batch of cases runs in a child process (this test binary again,
//! test `fuzz_child`) under an address-space limit (`ulimit -v`) with a
//! small input budget and a time bound; the child reports each case on its
//! own line as it finishes. A case the child did not report is the one that
//! killed it (a panic outside the reader, an abort, running out of the
//! address space) or hung it, and it is a finding; so is a panic, an error
//! that does not name the file, and a strict seed (binary, length fixed by
//! its header) that accepts a truncation or appended bytes. Findings are
//! kept under `target/tmp/fuzz-findings/` for minimising into regression
//! files: `regressions/`, named after what broke, each read by
//! [`regression_files_read_as_they_should`].
//!
//! `fuzz_slice` (in every `cargo test`) runs a fixed-seed slice;
//! `cargo test --release --test fuzz -- --ignored` runs the long campaign
//! (`CHISEL_FUZZ_MUTANTS` per reader, split over its seeds, default 10⁵;
//! the seed of the random numbers from `CHISEL_FUZZ_SEED`).

#![cfg(unix)]

#[path = "../common/mod.rs"]
mod common;

mod corpus;
mod mutate;

use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use chisel::Error;
use mutate::{Mutation, Rng};

/// Address space of a child (KiB): readers must stay far below.
const CHILD_ADDRESS_SPACE_KIB: u64 = 3 << 20;
/// The input budget of a child (bytes).
const CHILD_BUDGET: &str = "67108864";
/// Cases per child.
const BATCH: usize = 400;
/// Time a batch may take per case (plus 100 cases' worth).
const PER_CASE: Duration = Duration::from_millis(300);

/// Reads `path` with the reader its name picks (`*.selftest`: the
/// harness's own negative controls, which misbehave as their stem says).
fn read_any(path: &Path) -> Result<(), Error> {
    let name = path.file_name().unwrap().to_string_lossy().to_string();
    if let Some(stem) = name.strip_suffix(".selftest") {
        match stem {
            "abort" => std::process::abort(),
            "panic" => panic!("a panic in a reader"),
            "oom" => {
                let big = vec![1u8; 8 << 30];
                std::hint::black_box(big);
            }
            "hang" => loop {
                std::thread::sleep(Duration::from_secs(1));
            },
            _ => {}
        }
        return Ok(());
    }
    if name.ends_with("plan.toml") || name.ends_with("plan.json") {
        chisel::tissue::plan::Plan::from_path(path).map(|_| ())
    } else if name.ends_with("scene.toml") {
        chisel::implicit::Scene::from_path(path).map(|_| ())
    } else if chisel::io::is_volume(path)? {
        chisel::io::read_volume(path).map(|_| ())
    } else {
        chisel::io::read_mesh(path).map(|_| ())
    }
}

/// One case: the file, the mutation, and whether it must be refused.
struct Case {
    file: PathBuf,
    mutation: Mutation,
    must_fail: bool,
}

/// What happened to a case that is a finding.
#[derive(Debug)]
struct Finding {
    file: PathBuf,
    mutation: Mutation,
    what: String,
}

/// The child: reads the cases listed in `$CHISEL_FUZZ_BATCH/cases.txt` and
/// prints `case <i> <outcome>` after each.
#[test]
fn fuzz_child() {
    let Some(dir) = std::env::var_os("CHISEL_FUZZ_BATCH") else {
        return;
    };
    let dir = PathBuf::from(dir);
    let list = std::fs::read_to_string(dir.join("cases.txt")).unwrap();
    let out = std::io::stdout();
    for (i, line) in list.lines().enumerate() {
        let (must_fail, name) = line.split_once(' ').unwrap();
        let path = dir.join(name);
        let r = std::panic::catch_unwind(|| read_any(&path));
        let outcome = match r {
            Err(p) => {
                let msg = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                format!("panic {msg}")
            }
            Ok(Ok(())) if must_fail == "1" => "accepted a corrupt file".to_string(),
            Ok(Ok(())) => "ok".into(),
            Ok(Err(e)) => {
                let msg = e.to_string();
                if msg.contains(name) {
                    "err".into()
                } else {
                    format!("unclear error: {msg}")
                }
            }
        };
        let mut o = out.lock();
        writeln!(o, "case {i} {}", outcome.replace('\n', " ")).unwrap();
        o.flush().unwrap();
    }
}

/// Runs `cases` (all in `dir`) in children; returns the findings and how
/// many cases ended `ok` and `err`.
fn run_cases(dir: &Path, cases: &[Case], per_case: Duration) -> (Vec<Finding>, usize, usize) {
    let exe = std::env::current_exe().unwrap();
    let mut findings = Vec::new();
    let (mut ok, mut err) = (0, 0);
    let mut start = 0;
    while start < cases.len() {
        let batch = &cases[start..(start + BATCH).min(cases.len())];
        let list: String = batch
            .iter()
            .map(|c| {
                let name = c.file.file_name().unwrap().to_string_lossy().into_owned();
                format!("{} {name}\n", u8::from(c.must_fail))
            })
            .collect();
        std::fs::write(dir.join("cases.txt"), list).unwrap();
        let mut child = Command::new("sh")
            .arg("-c")
            .arg(format!(
                "ulimit -v {CHILD_ADDRESS_SPACE_KIB} && exec \"$0\" fuzz_child --exact \
                 --test-threads=1 --nocapture"
            ))
            .arg(&exe)
            .env("CHISEL_FUZZ_BATCH", dir)
            .env("CHISEL_MAX_INPUT_BYTES", CHILD_BUDGET)
            .env("RUST_BACKTRACE", "0")
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let stdout = child.stdout.take().unwrap();
        let lines = std::thread::spawn(move || {
            std::io::BufReader::new(stdout)
                .lines()
                .map_while(Result::ok)
                // (libtest may print `test fuzz_child ... ` before the first.)
                .filter_map(|l| l.find("case ").map(|k| l[k + 5..].to_string()))
                .collect::<Vec<String>>()
        });
        // A time bound per batch: generous for the slowest reader.
        let limit = per_case * (batch.len() as u32 + 100);
        let t = Instant::now();
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break Some(s);
            }
            if t.elapsed() > limit {
                child.kill().ok();
                child.wait().ok();
                break None;
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        let lines = lines.join().unwrap();
        let mut done = 0;
        for line in &lines {
            let (i, outcome) = line.split_once(' ').unwrap();
            let i = i.parse::<usize>().unwrap();
            assert_eq!(i, done, "the child reports its cases in order");
            done += 1;
            let case = &batch[i];
            match outcome {
                "ok" => ok += 1,
                "err" => err += 1,
                what => findings.push(Finding {
                    file: case.file.clone(),
                    mutation: case.mutation,
                    what: what.to_string(),
                }),
            }
        }
        if done < batch.len() {
            let what = match status {
                None => "hung (killed at the time bound)".to_string(),
                Some(s) => format!("killed the reader ({s}: an abort or the address space)"),
            };
            findings.push(Finding {
                file: batch[done].file.clone(),
                mutation: batch[done].mutation,
                what,
            });
        }
        start += done + 1;
    }
    (findings, ok, err)
}

/// The cases of one seed: `mutants` byte mutants (the mutators in turn)
/// and two device cases, written into `dir` in batches of [`BATCH`] and
/// run; findings are copied to `keep`. Returns the findings and the
/// counts read and refused.
fn fuzz_seed(
    dir: &Path,
    s: &corpus::Seed,
    mutants: usize,
    rng: &mut Rng,
    keep: &Path,
) -> (Vec<Finding>, usize, usize) {
    let (mut findings, mut ok, mut err) = (Vec::new(), 0, 0);
    let total = mutants + 2;
    let mut k = 0;
    while k < total {
        let mut cases = Vec::new();
        for k in k..(k + BATCH).min(total) {
            let file = dir.join(format!("c{k}_{}", s.name));
            let m = if k >= mutants {
                let dev = ["/dev/zero", "/dev/urandom"][k - mutants];
                std::os::unix::fs::symlink(dev, &file).unwrap();
                Mutation::Device
            } else {
                let m = Mutation::BYTES[k % Mutation::BYTES.len()];
                let mut b = s.bytes.clone();
                mutate::mutate(rng, &mut b, m);
                std::fs::write(&file, &b).unwrap();
                m
            };
            let must_fail = s.strict && matches!(m, Mutation::Truncate | Mutation::Append);
            cases.push(Case {
                file,
                mutation: m,
                must_fail,
            });
        }
        k += cases.len();
        let (f, o, e) = run_cases(dir, &cases, PER_CASE);
        for f in &f {
            let to = keep.join(f.file.file_name().unwrap());
            std::fs::create_dir_all(keep).unwrap();
            // A device case is kept as its link (reading it never ends).
            match std::fs::read_link(&f.file) {
                Ok(target) => std::fs::write(to, target.to_string_lossy().as_bytes()).unwrap(),
                Err(_) => {
                    std::fs::copy(&f.file, to).unwrap();
                }
            }
        }
        for c in &cases {
            std::fs::remove_file(&c.file).unwrap();
        }
        findings.extend(f);
        (ok, err) = (ok + o, err + e);
    }
    (findings, ok, err)
}

/// About `per_reader` mutants per reader (split over its seeds), with
/// random numbers from `seed`; panics with the findings (copied to
/// `target/tmp/fuzz-findings/`).
fn campaign(per_reader: usize, seed: u64) {
    let dir = tempfile::tempdir().unwrap();
    let scratch = tempfile::tempdir().unwrap();
    let seeds = corpus::seeds(scratch.path());
    corpus::data_files(dir.path());
    let keep = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-findings");
    let mut rng = Rng::new(seed);
    let t = Instant::now();
    let (mut findings, mut ok, mut err) = (Vec::new(), 0, 0);
    let mut per: std::collections::BTreeMap<&str, usize> = Default::default();
    for s in &seeds {
        // The seed itself is valid.
        let p = dir.path().join(format!("seed_{}", s.name));
        std::fs::write(&p, &s.bytes).unwrap();
        read_any(&p).unwrap_or_else(|e| panic!("seed {}: {e}", s.name));
        let siblings = seeds.iter().filter(|o| o.reader == s.reader).count();
        let mutants = per_reader.div_ceil(siblings);
        let (f, o, e) = fuzz_seed(dir.path(), s, mutants, &mut rng, &keep);
        *per.entry(s.reader).or_default() += mutants + 2;
        findings.extend(f);
        (ok, err) = (ok + o, err + e);
    }
    eprintln!(
        "fuzz: {} cases over {} seeds (per reader: {per:?}), seed {seed:#x}: {ok} read, {err} \
         refused, {} findings, {:.1} s",
        per.values().sum::<usize>(),
        seeds.len(),
        findings.len(),
        t.elapsed().as_secs_f64()
    );
    if !findings.is_empty() {
        let list: Vec<String> = findings
            .iter()
            .take(20)
            .map(|f| format!("{} ({:?}): {}", f.file.display(), f.mutation, f.what))
            .collect();
        panic!(
            "{} findings (kept in {}):\n{}",
            findings.len(),
            keep.display(),
            list.join("\n")
        );
    }
    // Both outcomes occur: the mutants reach the error paths and past them.
    assert!(ok > 0 && err > 0, "ok {ok}, err {err}");
}

/// Negative controls: the harness reports a case that aborts, runs out of
/// the address space, hangs or panics, and the cases after it still run.
#[test]
fn harness_catches_aborts_hangs_and_panics() {
    if std::env::var_os("CHISEL_FUZZ_BATCH").is_some() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let names = ["fine", "abort", "fine2", "oom", "panic", "hang", "fine3"];
    let cases: Vec<Case> = names
        .iter()
        .map(|n| {
            let file = dir.path().join(format!("{n}.selftest"));
            std::fs::write(&file, b"").unwrap();
            Case {
                file,
                mutation: Mutation::Flip,
                must_fail: false,
            }
        })
        .collect();
    let (findings, ok, err) = run_cases(dir.path(), &cases, Duration::from_millis(20));
    let found: Vec<(String, &str)> = findings
        .iter()
        .map(|f| {
            let n = f.file.file_stem().unwrap().to_string_lossy().into_owned();
            let kind = if f.what.starts_with("panic") {
                "panic"
            } else if f.what.starts_with("hung") {
                "hang"
            } else {
                "killed"
            };
            (n, kind)
        })
        .collect();
    let want = [
        ("abort".to_string(), "killed"),
        ("oom".to_string(), "killed"),
        ("panic".to_string(), "panic"),
        ("hang".to_string(), "hang"),
    ];
    assert_eq!(found, want, "{findings:?}");
    assert_eq!((ok, err), (3, 0));
}

/// The fixed-seed slice every test run makes.
#[test]
fn fuzz_slice() {
    if std::env::var_os("CHISEL_FUZZ_BATCH").is_some() {
        return;
    }
    campaign(160, 0x00C0_FFEE);
}

/// The long campaign: `cargo test --release --test fuzz -- --ignored`.
#[test]
#[ignore = "long: run with --ignored"]
fn fuzz_campaign() {
    if std::env::var_os("CHISEL_FUZZ_BATCH").is_some() {
        return;
    }
    let mutants = std::env::var("CHISEL_FUZZ_MUTANTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(100_000);
    let seed = std::env::var("CHISEL_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x5EED);
    campaign(mutants, seed);
}

/// Regression files (`tests/fuzz/regressions/`), named after what broke,
/// with a fragment their error must contain (`None`: a valid file that
/// must read); every file there is listed.
const REGRESSIONS: &[(&str, Option<&str>)] = &[
    ("stl_count_below_data.stl", Some("byte 134")),
    ("stl_count_zero_with_facets.stl", Some("byte 84")),
    ("stl_trailing_newline.stl", Some("more data")),
    ("ply_binary_trailing_newline.ply", Some("more data")),
    (
        "mha_bytes_after_zlib_stream.mha",
        Some("after the zlib stream"),
    ),
    (
        "nrrd_space_origin_2_of_3.nrrd",
        Some("`space origin` of 3 components"),
    ),
    ("nii_vox_offset_3e38.nii", Some("vox_offset")),
    (
        "nrrd_gzip_announces_1gib_holds_1mib.nrrd",
        Some("after decompression"),
    ),
    ("obj_vertices_no_faces.obj", Some("a mesh with triangles")),
    // Found by the long campaign: a form feed before the component count
    // made the line tokenizer push empty tokens without end (24 GB).
    ("vtk_form_feed_before_scalar_components.vtk", None),
    // Found by the DICOM seeds' first campaign: dicom-rs zero-fills an
    // element's announced length before reading it, and its RLE decoder
    // indexes past a short segment.
    (
        "dicom_element_length_4gib_in_1kb.dcm",
        Some("announcing 4294967280 bytes"),
    ),
    (
        "dicom_rle_segment_short_of_frame.dcm",
        Some("segment 0 decoding to 30 bytes"),
    ),
    // Found by the first campaign with VTK seeds: a dimension product that
    // overflowed (a panic), a point count past 32-bit indices reported
    // without the file.
    (
        "vtk_structured_points_dimensions_overflow.vtk",
        Some("point count fits 64 bits"),
    ),
    ("vtp_points_past_32_bit_indices.vtp", Some("32-bit indices")),
];

#[test]
fn regression_files_read_as_they_should() {
    if std::env::var_os("CHISEL_FUZZ_BATCH").is_some() {
        return;
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz/regressions");
    let mut listed: Vec<&str> = REGRESSIONS.iter().map(|r| r.0).collect();
    listed.sort_unstable();
    let mut present: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "README.md")
        .collect();
    present.sort_unstable();
    assert_eq!(present, listed, "every regression file is listed once");
    for (name, fragment) in REGRESSIONS {
        let path = dir.join(name);
        let r = if chisel::io::is_volume(&path).unwrap() {
            chisel::io::read_volume(&path).map(|_| ())
        } else {
            chisel::io::read_surface(&path).map(|_| ())
        };
        match fragment {
            None => r.unwrap_or_else(|e| panic!("{name}: {e}")),
            Some(fragment) => {
                let msg = r.expect_err(name).to_string();
                assert!(msg.contains(name), "{name}: {msg}");
                assert!(
                    msg.contains(fragment),
                    "{name}: `{fragment}` missing: {msg}"
                );
            }
        }
    }
}
