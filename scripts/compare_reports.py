#!/usr/bin/env python3
"""Same outputs before and after a change: runs `stats`, `mc`, `cut`, `hull`,
`scan`, `polyhedrize`, `relax` and `demo` on the real data with two `chisel`
binaries and compares their JSON reports (timings, adapter descriptions and
paths left out) and every mesh, volume and cell file they write (byte for
byte).

    scripts/compare_reports.py OLD_CHISEL NEW_CHISEL [--data ../shared/data] [--backend cpu|gpu] [--old-cli]

Prints one line per command and exits 1 when anything differs. Build the old
binary from another checkout of the base commit (`git worktree add`), e.g.
`cargo build --bin chisel` there; both must run with the same CHISEL_ADAPTER.

`--old-cli`: the old binary predates the consistent command line of
2026-12-06 (`--threshold` for `--level`, `demo --out`, no report `schema`).
Its arguments are translated, and the report changes of that day are
undone before comparing: `schema` dropped, `threshold` read as `level`,
the fields added then (`stats`' `backend`; `relax`'s `mass`, `damping`,
`max_iterations`) dropped from the new report.
"""

import argparse
import hashlib
import json
import os
import re
import struct
import subprocess
import sys
import tempfile

# Report keys whose values depend on the run, not on the result.
VOLATILE = re.compile(
    r"(seconds|_s$|_ms$|^ms$|time|elapsed|rate|per_s|throughput|adapter|device|driver|"
    r"backend_name|gib_per_s|gb_per_s|path|file|output|out_dir|version)",
    re.IGNORECASE,
)


def normalise(value, root):
    """The report without run-dependent fields, the run's folder as `{root}`."""
    if isinstance(value, dict):
        return {
            k: normalise(v, root)
            for k, v in sorted(value.items())
            if not VOLATILE.search(k)
        }
    if isinstance(value, list):
        return [normalise(v, root) for v in value]
    if isinstance(value, str):
        return value.replace(root, "{root}")
    return value


# Fields the consistent CLI added to reports (dropped from the new one with --old-cli).
ADDED = {"schema", "mass", "damping", "max_iterations"}


def old_argv(argv):
    """The arguments of the pre-2026-12-06 command line for `argv`."""
    renames = {"--output": "--out"} if argv[0] == "demo" else {}
    if argv[0] in ("stats", "hull", "scan", "polyhedrize"):
        renames["--level"] = "--threshold"
    return [renames.get(a, a) for a in argv]


def as_new(value):
    """An old report with the 2026-12-06 renames applied (`threshold` → `level`)."""
    if isinstance(value, dict):
        return {("level" if k == "threshold" else k): as_new(v) for k, v in value.items()}
    if isinstance(value, list):
        return [as_new(v) for v in value]
    return value


def without_added(value, command):
    """A new report without the fields the old command line did not have."""
    if isinstance(value, dict):
        drop = ADDED | ({"backend"} if command.startswith("stats") else set())
        return {k: without_added(v, command) for k, v in value.items() if k not in drop}
    if isinstance(value, list):
        return [without_added(v, command) for v in value]
    return value


def commands(data, backend):
    """(name, argv, output files) of every run; `{out}` is the run's folder."""
    headsq = f"{data}/headsq/quarter.nhdr"
    fran = f"{data}/fran_cut.vtk"
    plan = "src/tissue/plans/fran_chin_advance.toml"
    return [
        ("stats mesh", ["stats", f"{data}/fsu/footbones.ply", "--json"], []),
        ("stats volume", ["stats", headsq, "--level", "1150", "--json"], []),
        (
            "mc",
            ["mc", headsq, "--level", "1150", "--close-border", "--backend", backend,
             "-o", "{out}/bone.ply", "--report", "{out}/r.json"],
            ["bone.ply"],
        ),
        (
            "cut",
            ["cut", "{out}/../mc/bone.ply", "--plane", "100,100,60,0,0.3,1", "--cap",
             "-o", "{out}/pieces", "--report", "{out}/r.json"],
            ["pieces"],
        ),
        ("phantom", ["phantom", "cylinder-tunnel", "--outer", "25", "--inner", "10",
                     "-o", "{out}/cyl.nrrd"], ["cyl.nrrd"]),
        (
            "hull",
            ["hull", "{out}/../phantom/cyl.nrrd", "--level", "1", "-o", "{out}/hull.ply",
             "--report", "{out}/r.json"],
            ["hull.ply"],
        ),
        ("scan", ["scan", headsq, "--level", "1150", "--backend", backend,
                  "--report", "{out}/r.json"], []),
        (
            "polyhedrize",
            ["polyhedrize", "{out}/../phantom/cyl.nrrd", "--level", "1", "--backend",
             backend, "-o", "{out}/cyl.cells", "--mesh", "{out}/cyl.ply", "--verify",
             "--report", "{out}/r.json"],
            ["cyl.cells", "cyl.ply"],
        ),
        (
            "relax",
            ["relax", fran, "--plan", plan, "--backend", backend, "-o", "{out}/relaxed.ply",
             "--report", "{out}/r.json"],
            ["relaxed.ply"],
        ),
        ("demo", ["demo", "--output", "{out}/demo", "--json"],
         ["demo/relaxed_skin.ply", "demo/bone_moved.ply", "demo/head_ct.nrrd"]),
    ]


def differences(old, new, at="$"):
    """The paths where two normalised reports differ, with both values."""
    if isinstance(old, dict) and isinstance(new, dict):
        out = []
        for k in sorted(set(old) | set(new)):
            out += differences(old.get(k), new.get(k), f"{at}.{k}")
        return out
    if isinstance(old, list) and isinstance(new, list) and len(old) == len(new):
        out = []
        for i, (a, b) in enumerate(zip(old, new)):
            out += differences(a, b, f"{at}[{i}]")
        return out
    if old == new or same_f32(old, new):
        return []
    return [f"{at}: {json.dumps(old)} -> {json.dumps(new)}"]


def same_f32(a, b):
    """Whether two JSON numbers are one f32 printed at two precisions (a
    `serde_json::Value` widens an f32 to f64 digits; a typed report prints
    the shortest f32 digits)."""
    if not all(isinstance(x, float) for x in (a, b)):
        return False
    f32 = lambda x: struct.unpack("f", struct.pack("f", x))[0]
    try:
        return f32(a) == f32(b)
    except OverflowError:
        return False


def digest(path):
    """SHA-256 of a file, or of every file below a folder (by relative name)."""
    h = hashlib.sha256()
    if os.path.isdir(path):
        for root, _, files in sorted(os.walk(path)):
            for f in sorted(files):
                p = os.path.join(root, f)
                h.update(os.path.relpath(p, path).encode())
                with open(p, "rb") as fh:
                    h.update(fh.read())
    else:
        with open(path, "rb") as fh:
            h.update(fh.read())
    return h.hexdigest()


def run(binary, name, argv, outputs, root):
    """The normalised report (stdout JSON or the `--report` file) and output digests."""
    out = os.path.join(root, name.replace(" ", "_"))
    os.makedirs(out, exist_ok=True)
    args = [a.replace("{out}", out) for a in argv]
    proc = subprocess.run([binary, "--quiet", *args], capture_output=True, text=True)
    if proc.returncode != 0:
        return {"exit": proc.returncode, "stderr": proc.stderr.strip()}, {}
    report_file = os.path.join(out, "r.json")
    if os.path.exists(report_file):
        with open(report_file) as fh:
            report = json.load(fh)
    else:
        report = json.loads(proc.stdout) if proc.stdout.strip().startswith("{") else proc.stdout
    files = {f: digest(os.path.join(out, f)) for f in outputs}
    return normalise(report, root), files


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--data", default="../shared/data")
    ap.add_argument("--backend", default="cpu", choices=["cpu", "gpu"])
    ap.add_argument("--old-cli", action="store_true",
                    help="the old binary has the command line before 2026-12-06")
    a = ap.parse_args()
    differ = 0
    with tempfile.TemporaryDirectory() as old_root, tempfile.TemporaryDirectory() as new_root:
        for name, argv, outputs in commands(a.data, a.backend):
            argv_old = old_argv(argv) if a.old_cli else argv
            r_old, f_old = run(os.path.abspath(a.old), name, argv_old, outputs, old_root)
            r_new, f_new = run(os.path.abspath(a.new), name, argv, outputs, new_root)
            if a.old_cli:
                r_old, r_new = as_new(r_old), without_added(r_new, name)
            lines = differences(r_old, r_new) + differences(f_old, f_new, "files")
            same = not lines
            differ += not same
            detail = "".join(f"\n  {line[:300]}" for line in lines[:20])
            print(f"{'same' if same else 'DIFFERENT':9} {name}{detail}")
    print(f"{differ} of {len(commands(a.data, a.backend))} commands differ")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
