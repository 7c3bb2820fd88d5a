"""Shared fixtures: the real datasets in ../shared/data (as the Rust tests
use them: with CI=true a missing folder fails instead of skipping) and the
command line (target/debug/chisel, or CHISEL_BIN) that results must equal."""

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import chisel

REPO = Path(__file__).resolve().parents[2]
DATA = REPO.parent / "shared" / "data"
CI = os.environ.get("CI") == "true"


def need(path: Path) -> Path:
    if not path.exists():
        if CI:
            pytest.fail(f"{path} is missing (CI=true makes missing data a failure)")
        pytest.skip(f"{path} is missing")
    return path


@pytest.fixture
def data():
    return lambda name: need(DATA / name)


def without_timings(report: dict) -> dict:
    """A report without its `timings_s` (the only field two runs differ in)."""
    return {k: v for k, v in report.items() if k != "timings_s"}


@pytest.fixture
def cli():
    """Runs the chisel command line with --json and returns its report.
    The binary must be newer than every source of the library (CI builds
    it first; locally `cargo build`), or the comparison would be stale."""
    binary = Path(os.environ.get("CHISEL_BIN", REPO / "target" / "debug" / "chisel"))
    need(binary)
    newest = max(p.stat().st_mtime for p in (REPO / "src").rglob("*.rs"))
    if binary.stat().st_mtime < newest:
        message = f"{binary} is older than src/ (run `cargo build`)"
        if CI:
            pytest.fail(message)
        pytest.skip(message)

    def run(*args):
        out = subprocess.run(
            [str(binary), *map(str, args), "--json"],
            check=True,
            capture_output=True,
            text=True,
            env={**os.environ, "XDG_RUNTIME_DIR": os.environ.get("XDG_RUNTIME_DIR", "/tmp")},
        )
        return json.loads(out.stdout)

    return run


def ball(n: int, centre, radius: float) -> np.ndarray:
    """A solid ball of ones in a zeros (n, n, n) uint8 array."""
    z, y, x = np.mgrid[0:n, 0:n, 0:n]
    cz, cy, cx = centre
    return (((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) <= radius**2).astype(np.uint8)


def phantoms(folder: Path):
    """Four generated volumes of different formats and sample types, every
    structure at 7 or more (above the batch tests' level)."""
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    sphere = ball(24, (12, 12, 12), 8) * 200
    chisel.write_volume(folder / "sphere.nrrd", chisel.Volume(sphere, (0.5, 0.5, 0.5)))
    out.append(folder / "sphere.nrrd")
    z, y, x = np.mgrid[0:32, 0:32, 0:32].astype(np.float32)
    r = np.hypot(x - 16, y - 16)
    torus = ((r - 9) ** 2 + (z - 16) ** 2 <= 16).astype(np.int16) * 1000
    chisel.write_volume(folder / "torus.mha", chisel.Volume(torus, (1.0, 1.0, 2.0)))
    out.append(folder / "torus.mha")
    two = (ball(28, (8, 8, 8), 5) + ball(28, (19, 19, 19), 6)).astype(np.float32) * 50
    chisel.write_volume(folder / "two_balls.vti", chisel.Volume(two))
    out.append(folder / "two_balls.vti")
    labels = 7 * ball(30, (10, 15, 15), 7).astype(np.int32) + 9 * ball(30, (21, 15, 15), 6)
    chisel.write_volume(folder / "labels.nii", chisel.Volume(labels, (0.8, 0.8, 0.8)))
    out.append(folder / "labels.nii")
    return out
