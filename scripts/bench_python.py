"""Figures of the Python package (docs/python.md), in one run:

1. call overhead: `chisel.marching_cubes` on headsq at 1150 from an
   in-memory array (numpy in, numpy out; median of a steady loop) against
   the engine's own time for the same work, the `marching_cubes` stage
   that `chisel mc --json` reports (median of as many fresh processes),
   and the fixed cost of a call (the same function on a 2×2×2 volume);
2. the Dask batch: `chisel.batch.scan` over the shared and generated
   volumes on a LocalCluster of 2 worker processes against the serial loop
   (throughput in volumes/s, results compared).

Run with the package installed (scripts/test-python.sh makes the venv):
    target/py-venv/bin/python scripts/bench_python.py [--rounds N]
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import chisel

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
sys.path.insert(0, str(REPO / "python" / "tests"))
from conftest import phantoms  # noqa: E402


def median_ms(fn, rounds):
    times = []
    for _ in range(rounds):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times) * 1e3


def overhead(rounds, binary):
    path = DATA / "headsq" / "quarter.nhdr"
    volume = chisel.read_volume(path)
    chisel.marching_cubes(volume, level=1150)  # warm
    python_ms = median_ms(lambda: chisel.marching_cubes(volume, level=1150), rounds)
    # The fixed cost of a call: the same function on a 2×2×2 volume.
    tiny = chisel.Volume(volume.array[:2, :2, :2].copy())
    fixed_ms = median_ms(lambda: chisel.marching_cubes(tiny, level=1150), rounds)
    engine = []
    env = {**os.environ, "XDG_RUNTIME_DIR": os.environ.get("XDG_RUNTIME_DIR", "/tmp")}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(rounds):
            out = subprocess.run(
                [binary, "mc", str(path), "--level", "1150", "--backend", "cpu",
                 "-o", f"{tmp}/h.ply", "--json"],
                check=True, capture_output=True, text=True, env=env,
            )
            engine.append(json.loads(out.stdout)["timings_s"]["marching_cubes"])
    return {
        "python_call_ms": python_ms,
        "cli_engine_stage_ms": statistics.median(engine) * 1e3,
        "fixed_call_cost_ms": fixed_ms,
    }


def batch(rounds):
    import distributed

    with tempfile.TemporaryDirectory() as tmp:
        shared = [DATA / n for n in ("headsq/quarter.nhdr", "froggy/frogtissue.mhd",
                                     "HeadMRVolume.mhd", "foot/foot.mha")]
        paths = (shared + phantoms(Path(tmp))) * rounds
        options = dict(level=5, min_voxels=20)
        t = time.perf_counter()
        serial = chisel.batch.scan(paths, **options)
        serial_s = time.perf_counter() - t
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                      dashboard_address=":0") as cluster, \
                distributed.Client(cluster) as client:
            # Warm: every worker process loads the package and runs each
            # kind of volume once (the first frogtissue scan in a fresh
            # process costs about a second more); then the timed batch.
            chisel.batch.scan(paths[:8] * 2, client=client, **options)
            t = time.perf_counter()
            parallel = chisel.batch.scan(paths, client=client, **options)
            cluster_s = time.perf_counter() - t
    strip = lambda rs: [{k: v for k, v in r.items() if k != "timings_s"} for r in rs]
    return {
        "volumes": len(paths),
        "serial_per_s": len(paths) / serial_s,
        "local_cluster_per_s": len(paths) / cluster_s,
        "speedup": serial_s / cluster_s,
        "identical": strip(serial) == strip(parallel),
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--batch-rounds", type=int, default=10,
                    help="copies of the 8 volumes in the batch (frogtissue is most of the work)")
    ap.add_argument("--bin", default=str(REPO / "target" / "debug" / "chisel"))
    args = ap.parse_args()
    report = {"overhead": overhead(args.rounds, args.bin), "batch": batch(args.batch_rounds)}
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
