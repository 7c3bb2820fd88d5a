"""The engine's operations from Python equal the command line's on the
real data; GPU results match the CPU's; errors are typed exceptions."""

import errno
import json
import threading

import numpy as np
import pytest

import chisel
from conftest import ball, without_timings


def test_gpu_info_reports_the_adapter():
    info = chisel.gpu_info()
    assert info["schema"] == "chisel.info/1"
    assert info["chisel"] == chisel.__version__
    assert info["adapters"], "no GPU adapter (lavapipe in CI)"
    assert "name" in info["chosen"], info["chosen"]


def test_marching_cubes_equals_the_command_line(tmp_path, data, cli):
    path = data("headsq/quarter.nhdr")
    s = chisel.marching_cubes(chisel.read_volume(path), level=1150)
    report = cli("mc", path, "--level", "1150", "--backend", "cpu", "-o", tmp_path / "head.ply")
    written = chisel.read_mesh(tmp_path / "head.ply")
    np.testing.assert_array_equal(s.mesh.vertices, written.vertices)
    np.testing.assert_array_equal(s.mesh.triangles, written.triangles)
    assert report["group_count"] == len(s.groups)
    assert s.triangle_groups.shape == (len(s.mesh.triangles),)
    assert sum(g["triangles"] for g in s.groups) == len(s.mesh.triangles)
    # groups=False: the same mesh, no grouping.
    bare = chisel.marching_cubes(chisel.read_volume(path), level=1150, groups=False)
    np.testing.assert_array_equal(bare.mesh.triangles, s.mesh.triangles)
    assert bare.triangle_groups is None and bare.groups == []


def test_marching_cubes_gpu_matches_cpu(data):
    v = chisel.read_volume(data("headsq/quarter.nhdr"))
    cpu = chisel.marching_cubes(v, level=500)
    gpu = chisel.marching_cubes(v, level=500, backend="gpu")
    assert gpu.mesh.triangles.shape == cpu.mesh.triangles.shape
    # The same welded surface, vertex for vertex (order may differ).
    order = lambda m: m.vertices[np.lexsort(m.vertices.T)]
    np.testing.assert_allclose(order(gpu.mesh), order(cpu.mesh), rtol=0, atol=1e-4)
    assert [g["triangles"] for g in gpu.groups] == [g["triangles"] for g in cpu.groups]


def test_label_surface(data):
    frog = chisel.read_volume(data("froggy/frogtissue.mhd"))
    s = chisel.marching_cubes(frog, label=4)
    assert len(s.mesh.triangles) > 0
    with pytest.raises(chisel.ParameterError, match="exactly one"):
        chisel.marching_cubes(frog, level=1, label=4)


def test_scan_equals_the_command_line(data, cli):
    path = data("froggy/frogtissue.mhd")
    mine = chisel.scan_file(path, labels=True, min_voxels=500)
    theirs = cli("scan", path, "--labels", "--min-voxels", "500", "--backend", "cpu")
    assert without_timings(mine) == without_timings(theirs)
    # From an array: the same rows.
    from_array = chisel.scan(chisel.read_volume(path), labels=True, min_voxels=500, name=str(path))
    assert from_array["rows"] == theirs["rows"]
    gpu = chisel.scan_file(path, labels=True, min_voxels=500, backend="gpu")
    assert gpu["rows"] == theirs["rows"] and gpu["backend"] == "gpu"


def test_scan_progress_and_stopping(data):
    path = data("froggy/frogtissue.mhd")
    seen = []
    chisel.scan_file(path, labels=True, min_voxels=500, progress=lambda d, t: seen.append((d, t)))
    assert seen and seen[-1][0] == seen[-1][1] and [d for d, _ in seen] == list(range(1, len(seen) + 1))

    def interrupt(done, total):
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        chisel.scan_file(path, labels=True, min_voxels=500, progress=interrupt)


def test_errors_are_typed_with_the_engine_message(tmp_path, data):
    with pytest.raises(chisel.IoError) as e:
        chisel.read_volume(tmp_path / "missing.nrrd")
    assert isinstance(e.value, OSError) and "missing.nrrd" in str(e.value)
    bad = tmp_path / "bad.nrrd"
    bad.write_text("NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2\n\n")
    with pytest.raises(chisel.FormatError, match="bad.nrrd"):
        chisel.read_volume(bad)
    with pytest.raises(chisel.FormatError, match="expected a volume"):
        chisel.read_volume(data("bunny.ply"))
    with pytest.raises(chisel.ParameterError, match="backend"):
        chisel.marching_cubes(ball(8, (4, 4, 4), 2), level=0.5, backend="tpu")
    with pytest.raises(chisel.ParameterError, match="3-D numpy array"):
        chisel.marching_cubes(np.zeros((4, 4)), level=0.5)
    with pytest.raises(chisel.ParameterError, match="spacing"):
        chisel.marching_cubes(chisel.Volume(ball(8, (4, 4, 4), 2), spacing=(1, 0, 1)), level=0.5)
    with pytest.raises(chisel.ParameterError, match="nothing to scan"):
        chisel.scan(np.zeros((4, 4, 4), np.uint8), labels=True)
    with pytest.raises(ValueError):  # ParameterError is a ValueError
        chisel.scan(np.zeros((4, 4, 4), np.uint8), level=1, labels=True)
    for cls in (chisel.IoError, chisel.FormatError, chisel.LimitError, chisel.GpuError):
        assert issubclass(cls, chisel.ChiselError)


def test_the_gil_is_released_while_the_engine_works(data):
    import sys
    import time

    v = chisel.read_volume(data("froggy/frogtissue.mhd"))
    stamps = []
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            stamps.append(time.perf_counter())

    thread = threading.Thread(target=spin)
    thread.start()
    try:
        time.sleep(0.05)  # the spinner is running
        t0 = time.perf_counter()
        chisel.marching_cubes(v, level=1)  # ~0.2 s of engine work
        t1 = time.perf_counter()
    finally:
        stop.set()
        thread.join()
    # Held, the GIL would let the spinner run at most one switch interval
    # after the call began and after it ended; stamps well inside the call
    # prove the engine ran without it.
    margin = 2 * sys.getswitchinterval()
    assert t1 - t0 > 4 * margin, "the call is too short to tell"
    inside = [t for t in stamps if t0 + margin < t < t1 - margin]
    assert len(inside) > 1000, (len(inside), t1 - t0)


def test_ctrl_c_stops_a_scan_between_structures(data):
    import _thread
    import signal

    # Python installs this handler at start-up unless SIGINT was ignored
    # (as in a shell's background job): install it for the test.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        ctrl_c_stops_a_scan(data("froggy/frogtissue.mhd"), _thread.interrupt_main)
    finally:
        signal.signal(signal.SIGINT, previous)


def ctrl_c_stops_a_scan(path, interrupt_main):
    seen = []

    def progress(done, total):
        seen.append(done)
        if done == 1:
            interrupt_main()  # what Ctrl-C does: SIGINT pending in the main thread

    with pytest.raises(KeyboardInterrupt):
        chisel.scan_file(path, labels=True, min_voxels=500, progress=progress)
    # Stopped at the check after the structure the signal arrived in.
    assert seen == [1] or seen == [1, 2], seen


def test_the_readme_example_runs_as_written(tmp_path, data):
    import os
    import re
    import subprocess
    import sys

    from conftest import DATA, REPO

    readme = (REPO / "README.md").read_text()
    section = readme[readme.index("## Python") :]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    # The example's paths are relative to the repository root: ../shared/data.
    cwd = tmp_path / "repo"
    cwd.mkdir()
    (tmp_path / "shared").symlink_to(DATA.parent, target_is_directory=True)
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True, env=os.environ
    )
    assert out.returncode == 0, out.stderr
    assert (cwd / "bone.ply").exists()
    assert "(39420, 3) 76" in out.stdout


def test_inputs_the_command_line_refuses_are_refused(tmp_path):
    sphere = chisel.marching_cubes(ball(12, (6, 6, 6), 4), level=0.5).mesh
    with pytest.raises(chisel.ParameterError, match="NaN"):
        chisel.hull(ball(8, (4, 4, 4), 2), level=float("nan"))
    with pytest.raises(chisel.ParameterError, match="NaN"):
        chisel.scan(ball(8, (4, 4, 4), 2), level=float("nan"))
    with pytest.raises(chisel.ParameterError, match="integer"):
        chisel.stats(chisel.Mesh(sphere.vertices, sphere.triangles.astype(np.float64)))
    with pytest.raises(chisel.ParameterError, match="a mesh has none"):
        chisel.stats(sphere, level=1)
    with pytest.raises(chisel.ParameterError, match="uv"):
        chisel.spline(sphere, 3, param="given", uv=np.zeros((len(sphere.vertices), 1)))
    with pytest.raises(chisel.IoError, match="missing.toml") as e:  # an OSError with its errno
        chisel.implicit(tmp_path / "missing.toml")
    assert e.value.errno == errno.ENOENT
    with pytest.raises(chisel.ParameterError, match="unknown scan option"):
        chisel.batch.scan([tmp_path / "a.nrrd", tmp_path / "b.nrrd"], level=1, corner="local6")


def test_scalars_are_written_with_the_mesh(tmp_path):
    s = chisel.marching_cubes(ball(12, (6, 6, 6), 4), level=0.5).mesh
    s.scalars["height"] = s.vertices[:, 2].copy()
    for ext in ("ply", "vtk", "vtp"):
        chisel.write_mesh(tmp_path / f"h.{ext}", s)
        back = chisel.read_mesh(tmp_path / f"h.{ext}")
        np.testing.assert_array_equal(back.scalars["height"], s.scalars["height"])
    s.scalars["short"] = np.zeros(3, np.float32)
    with pytest.raises(chisel.ChiselError, match="short"):
        chisel.write_mesh(tmp_path / "bad.ply", s)
