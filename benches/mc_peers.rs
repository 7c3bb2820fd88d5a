//! Marching cubes against its peers, side by side in one run: chisel's CPU
//! path at one thread and at all threads (with grouping, per-group figures
//! and the forest, and `mesh_only` without them) alternating, round by
//! round and each round starting one tool later, with VTK's
//! `vtkFlyingEdges3D` and `vtkMarchingCubes` and
//! scikit-image's `marching_cubes`, timed in a Python worker
//! (`scripts/mc_peers.py`) on the same samples. Medians of the rounds; the
//! point and triangle counts are compared with Flying Edges'. Then the
//! peak memory of one run on the 512³ phantom, each tool in a fresh
//! process. The table goes to stderr and a JSON report to
//! `target/mc_peers/report.json`.
//!
//! Volumes: the CT head (headsq at 500 and 1150), the 256³ and 512³ head
//! phantoms of the `mc` bench (i16, level 1300) and a smooth 256³ field of
//! Gaussian blobs (f32, level 0.5). All tools see the open surface (no
//! border closing, as Flying Edges).
//!
//! One command from a fresh checkout: `scripts/bench-mc-peers.sh` (makes
//! the Python environment with VTK and scikit-image, then runs this with
//! `CHISEL_PEER_PYTHON` set). Arguments: volume names to run (substrings;
//! all when none), `--rounds N` (7), `--chisel-only` (no peers, no memory
//! probe: for profiling). Without `--bench` (the test suite's smoke run)
//! it runs chisel once on 64³ volumes and leaves the peers out.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::time::Instant;

use chisel::Backend;
use chisel::mc::{IsoSpec, McOptions, marching_cubes};
use chisel::volume::{Volume, VolumeData};
use serde_json::{Value, json};

#[path = "common/mod.rs"]
mod bench_common;
use bench_common::{blob_field, head_phantom, quick};

type Error = Box<dyn std::error::Error>;

/// One volume of the comparison.
struct Case {
    name: String,
    volume: Volume,
    level: f32,
}

/// The chisel variants timed (the first tools of the first round).
const CHISEL: [(&str, bool, bool); 3] = [
    ("chisel_1_thread", true, false),
    ("chisel_all_threads", false, false),
    ("chisel_mesh_only_1_thread", true, true),
];

/// The peer tools, after chisel's in the first round.
const PEERS: [&str; 3] = ["flying_edges", "marching_cubes", "skimage"];

fn main() {
    if let Err(e) = run() {
        eprintln!("mc_peers: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("memory") {
        return memory_probe(&args[2..]);
    }
    let out_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/mc_peers");
    std::fs::create_dir_all(&out_dir)?;
    let opts = Options::parse(&args[1..])?;
    let cases = cases(&opts.names)?;
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let threads = rayon::current_num_threads();
    let mut worker = if quick() {
        eprintln!("mc_peers: smoke run (no --bench): chisel only, 64³ volumes, peers left out");
        None
    } else if opts.chisel_only {
        None
    } else {
        Some(Worker::start()?)
    };
    let versions = match &mut worker {
        Some(w) => w.call(&json!({"cmd": "versions"}))?,
        None => Value::Null,
    };
    eprintln!("mc_peers: {threads} threads; peers {versions}");
    let rounds = if quick() { 1 } else { opts.rounds };
    let mut rows = Vec::new();
    for case in &cases {
        let raw = write_raw(&out_dir, case)?;
        if let Some(w) = &mut worker {
            w.call(
                &json!({"cmd": "load", "path": raw, "dims": case.volume.dims,
                           "dtype": dtype(&case.volume)?}),
            )?;
        }
        let iso = IsoSpec::Level(case.level);
        let mut times: Vec<Vec<f64>> = vec![Vec::new(); CHISEL.len() + PEERS.len()];
        let mut counts: Vec<(usize, usize)> = vec![(0, 0); CHISEL.len() + PEERS.len()];
        // Big volumes: the slow peers (vtkMarchingCubes, scikit-image) take
        // seconds a run, so they get fewer rounds.
        let slow_rounds = if case.volume.len() > 1 << 25 {
            3
        } else {
            rounds
        };
        // Each round starts one tool later, so that every tool takes every
        // place in the order: a run right after the slow peers' (which
        // churn hundreds of megabytes) is not always the same tool's.
        let n_tools = CHISEL.len() + PEERS.len();
        for round in 0..rounds {
            for k in (0..n_tools).map(|i| (i + round) % n_tools) {
                if let Some(&(_, single, mesh_only)) = CHISEL.get(k) {
                    let opts = McOptions {
                        close_border: false,
                        mesh_only,
                    };
                    let go = || {
                        let start = Instant::now();
                        let s = marching_cubes(&case.volume, iso, &opts, Backend::Cpu)?;
                        Ok::<_, chisel::Error>((start.elapsed().as_secs_f64(), s))
                    };
                    let (t, s) = if single { one.install(go)? } else { go()? };
                    times[k].push(t);
                    counts[k] = (s.mesh.n_vertices(), s.mesh.triangles.len());
                    continue;
                }
                let Some(w) = &mut worker else { continue };
                let tool = PEERS[k - CHISEL.len()];
                if tool != "flying_edges" && round >= slow_rounds {
                    continue;
                }
                let r = w.call(&json!({"cmd": "run", "tool": tool, "level": case.level}))?;
                times[k].push(r["seconds"].as_f64().ok_or("worker: no seconds")?);
                counts[k] = (
                    r["points"].as_u64().ok_or("worker: no points")? as usize,
                    r["triangles"].as_u64().ok_or("worker: no triangles")? as usize,
                );
            }
        }
        let names = CHISEL.iter().map(|c| c.0).chain(PEERS);
        let mut tools = serde_json::Map::new();
        for (k, name) in names.enumerate() {
            if times[k].is_empty() {
                continue;
            }
            let m = median(&mut times[k]);
            tools.insert(
                name.into(),
                json!({"median_s": m, "runs": times[k].len(), "points": counts[k].0,
                       "triangles": counts[k].1,
                       "m_voxels_per_s": case.volume.len() as f64 / m / 1e6}),
            );
        }
        let row = json!({"volume": case.name, "dims": case.volume.dims, "level": case.level,
                         "dtype": dtype(&case.volume)?, "tools": tools});
        print_row(&row);
        rows.push(row);
    }
    drop(worker);
    let memory = if quick() || opts.chisel_only {
        Value::Null
    } else {
        peak_memory(&out_dir, &cases)?
    };
    let report = json!({
        "threads": threads,
        "commit": commit(),
        "peers": versions,
        "rows": rows,
        "peak_memory_512": memory,
    });
    // The smoke run keeps its report apart from a full run's.
    let path = out_dir.join(if quick() {
        "smoke-report.json"
    } else {
        "report.json"
    });
    std::fs::write(&path, serde_json::to_string_pretty(&report)?)?;
    eprintln!("mc_peers: report {}", path.display());
    Ok(())
}

/// The command line after the program name (cargo's `--bench` ignored).
struct Options {
    names: Vec<String>,
    rounds: usize,
    chisel_only: bool,
}

impl Options {
    fn parse(args: &[String]) -> Result<Self, Error> {
        let mut o = Options {
            names: Vec::new(),
            rounds: 7,
            chisel_only: false,
        };
        let mut it = args.iter();
        while let Some(a) = it.next() {
            match a.as_str() {
                "--bench" => {}
                "--chisel-only" => o.chisel_only = true,
                "--rounds" => {
                    o.rounds = it
                        .next()
                        .and_then(|n| n.parse().ok())
                        .filter(|&n| n > 0)
                        .ok_or("--rounds takes a positive number")?
                }
                s if s.starts_with('-') => return Err(format!("unknown option {s}").into()),
                s => o.names.push(s.to_string()),
            }
        }
        Ok(o)
    }
}

/// The volumes whose names contain one of `names` (all when empty); only
/// those are made.
fn cases(names: &[String]) -> Result<Vec<Case>, Error> {
    let head = || {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/headsq/quarter.nhdr");
        chisel::io::read_volume(&path)
    };
    let (n_small, n_big, n_blobs) = if quick() {
        (64, 0, 64)
    } else {
        (256, 512, 256)
    };
    type Make = Box<dyn Fn() -> chisel::Result<Volume>>;
    let mut all: Vec<(String, f32, Make)> = vec![
        (
            format!("phantom_{n_small}_bone"),
            1300.0,
            Box::new(move || Ok(head_phantom(n_small))),
        ),
        (
            format!("blobs_{n_blobs}"),
            0.5,
            Box::new(move || Ok(blob_field(n_blobs))),
        ),
    ];
    if !quick() {
        all.insert(0, ("headsq_500".into(), 500.0, Box::new(head)));
        all.insert(1, ("headsq_1150".into(), 1150.0, Box::new(head)));
        all.insert(
            3,
            (
                format!("phantom_{n_big}_bone"),
                1300.0,
                Box::new(move || Ok(head_phantom(n_big))),
            ),
        );
    }
    all.into_iter()
        .filter(|(name, _, _)| names.is_empty() || names.iter().any(|n| name.contains(n)))
        .map(|(name, level, make)| {
            Ok(Case {
                name,
                volume: make()?,
                level,
            })
        })
        .collect()
}

/// The Python worker (`scripts/mc_peers.py`), one JSON line each way.
struct Worker {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
}

impl Worker {
    fn start() -> Result<Self, Error> {
        let mut child = Command::new(python())
            .arg(script())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| {
                format!(
                    "cannot start the peer worker with {:?} ({e}); run scripts/bench-mc-peers.sh, \
                     which makes a Python environment with VTK and scikit-image",
                    python()
                )
            })?;
        let stdin = child.stdin.take().ok_or("worker: no stdin")?;
        let stdout = BufReader::new(child.stdout.take().ok_or("worker: no stdout")?);
        Ok(Worker {
            child,
            stdin,
            stdout,
        })
    }

    fn call(&mut self, request: &Value) -> Result<Value, Error> {
        writeln!(self.stdin, "{request}")?;
        self.stdin.flush()?;
        let mut line = String::new();
        if self.stdout.read_line(&mut line)? == 0 {
            return Err(format!(
                "the peer worker ended on {request} (is VTK installed for {:?}? \
                 run scripts/bench-mc-peers.sh)",
                python()
            )
            .into());
        }
        let answer: Value = serde_json::from_str(&line)?;
        if let Some(e) = answer.get("error") {
            return Err(format!("peer worker on {request}: {e}").into());
        }
        Ok(answer)
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn python() -> String {
    std::env::var("CHISEL_PEER_PYTHON").unwrap_or_else(|_| "python3".into())
}

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/mc_peers.py")
}

fn dtype(v: &Volume) -> Result<&'static str, Error> {
    match v.data {
        VolumeData::I16(_) => Ok("int16"),
        VolumeData::F32(_) => Ok("float32"),
        _ => Err("mc_peers: only i16 and f32 volumes are handed to the peers".into()),
    }
}

/// The samples as raw little-endian values, x fastest (the worker's input).
fn write_raw(dir: &Path, case: &Case) -> Result<PathBuf, Error> {
    let path = dir.join(format!("{}.raw", case.name));
    let bytes: Vec<u8> = match &case.volume.data {
        VolumeData::I16(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        VolumeData::F32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        _ => return Err("mc_peers: only i16 and f32 volumes".into()),
    };
    std::fs::write(&path, bytes)?;
    Ok(path)
}

/// Peak memory of one run on the 512³ phantom, each tool in a fresh
/// process: growth of the resident set over the call.
fn peak_memory(dir: &Path, cases: &[Case]) -> Result<Value, Error> {
    let Some(case) = cases.iter().find(|c| c.name == "phantom_512_bone") else {
        return Ok(Value::Null);
    };
    let raw = dir.join(format!("{}.raw", case.name));
    let d = case.volume.dims.map(|x| x.to_string());
    let mut out = serde_json::Map::new();
    let exe = std::env::current_exe()?;
    for (name, mut cmd) in [
        ("chisel_all_threads", Command::new(&exe)),
        ("flying_edges", {
            let mut c = Command::new(python());
            c.arg(script());
            c
        }),
    ] {
        let tool = if name == "flying_edges" {
            name
        } else {
            "chisel"
        };
        let o = cmd
            .arg("memory")
            .arg(&raw)
            .args(&d)
            .arg(dtype(&case.volume)?)
            .arg(case.level.to_string())
            .arg(tool)
            .output()?;
        if !o.status.success() {
            return Err(format!(
                "memory probe of {name}: {}",
                String::from_utf8_lossy(&o.stderr)
            )
            .into());
        }
        let v: Value = serde_json::from_slice(&o.stdout)?;
        eprintln!(
            "mc_peers: peak memory on {}: {name} {:.1} MiB",
            case.name,
            v["peak_bytes"].as_f64().unwrap_or(f64::NAN) / (1 << 20) as f64
        );
        out.insert(name.into(), v);
    }
    Ok(Value::Object(out))
}

/// `memory RAW nx ny nz dtype level chisel`: one run in this fresh process,
/// printing the growth of the resident set (peak reset through
/// `/proc/self/clear_refs`) as JSON.
fn memory_probe(args: &[String]) -> Result<(), Error> {
    let [raw, nx, ny, nz, dtype, level, _tool] = args else {
        return Err("memory RAW nx ny nz dtype level tool".into());
    };
    let dims = [nx.parse()?, ny.parse()?, nz.parse()?];
    let bytes = std::fs::read(raw)?;
    let data = match dtype.as_str() {
        "int16" => VolumeData::I16(
            bytes
                .chunks_exact(2)
                .map(|b| i16::from_le_bytes([b[0], b[1]]))
                .collect(),
        ),
        "float32" => VolumeData::F32(
            bytes
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect(),
        ),
        _ => return Err(format!("dtype {dtype}").into()),
    };
    drop(bytes);
    let volume = Volume::new(dims, [1.0; 3], [0.0; 3], data)?;
    std::fs::write("/proc/self/clear_refs", "5")?;
    let before = proc_status("VmRSS")?;
    let s = marching_cubes(
        &volume,
        IsoSpec::Level(level.parse()?),
        &McOptions::default(),
        Backend::Cpu,
    )?;
    let peak = proc_status("VmHWM")?;
    println!(
        "{}",
        json!({"peak_bytes": peak - before, "points": s.mesh.n_vertices(),
               "triangles": s.mesh.triangles.len()})
    );
    Ok(())
}

fn proc_status(field: &str) -> Result<u64, Error> {
    let s = std::fs::read_to_string("/proc/self/status")?;
    s.lines()
        .find_map(|l| l.strip_prefix(field)?.strip_prefix(':'))
        .and_then(|v| v.split_whitespace().next()?.parse::<u64>().ok())
        .map(|kb| kb * 1024)
        .ok_or_else(|| format!("/proc/self/status has no {field}").into())
}

/// The commit measured: `git rev-parse --short HEAD`, with `-dirty` when
/// the tree has changes.
fn commit() -> Option<String> {
    let git = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let head = git(&["rev-parse", "--short", "HEAD"])?;
    let dirty =
        git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
    Some(if dirty { format!("{head}-dirty") } else { head })
}

fn median(t: &mut [f64]) -> f64 {
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// One volume's line: each tool's median, the ratio to Flying Edges, and
/// whether the counts agree with Flying Edges'.
fn print_row(row: &Value) {
    let tools = &row["tools"];
    let fe = tools["flying_edges"]["median_s"].as_f64();
    let fe_counts = (
        tools["flying_edges"]["points"].as_u64(),
        tools["flying_edges"]["triangles"].as_u64(),
    );
    eprintln!("mc_peers {} (level {}):", row["volume"], row["level"]);
    if let Some(map) = tools.as_object() {
        for (name, t) in map {
            let m = t["median_s"].as_f64().unwrap_or(f64::NAN);
            let ratio = fe.map_or(String::new(), |f| format!(", FE/this {:.2}", f / m));
            let counts = (t["points"].as_u64(), t["triangles"].as_u64());
            let agree = match fe_counts {
                (Some(_), Some(_)) if counts == fe_counts => ", counts = FE",
                (Some(_), Some(_)) => ", counts differ from FE",
                _ => "",
            };
            eprintln!(
                "  {name:<26} {:>9.2} ms {:>8.0} M voxels/s  {} points {} triangles{ratio}{agree}",
                m * 1e3,
                t["m_voxels_per_s"].as_f64().unwrap_or(f64::NAN),
                t["points"],
                t["triangles"],
            );
        }
    }
}
