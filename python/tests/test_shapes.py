"""DMS splines, implicit scenes, fusion, morphing and blobby fits from
Python equal the command line's."""

import json

import numpy as np
import pytest

import chisel
from conftest import ball


def two_balls(tmp_path):
    a = chisel.marching_cubes(ball(24, (12, 12, 10), 7), level=0.5).mesh
    b = chisel.marching_cubes(ball(24, (12, 12, 15), 6), level=0.5).mesh
    chisel.write_mesh(tmp_path / "a.ply", a)
    chisel.write_mesh(tmp_path / "b.ply", b)
    return a, b


def test_spline_equals_the_command_line(tmp_path, data, cli):
    path = data("fran_cut.vtk")
    s = chisel.spline(chisel.read_mesh(path), 3)
    theirs = cli("spline", path, "--n", "3", "--backend", "cpu", "-o", tmp_path / "s.ply")
    assert s.report["fit"] == theirs["fit"]
    written = chisel.read_mesh(tmp_path / "s.ply")
    np.testing.assert_array_equal(s.mesh.vertices, written.vertices)
    np.testing.assert_array_equal(s.mesh.triangles, written.triangles)
    assert set(s.mesh.scalars) >= {"nx", "ny", "nz", "distance", "curvature"}
    assert s.controls.dtype == np.float64 and s.controls.shape[1] == 3
    with pytest.raises(chisel.ParameterError, match="uv"):
        chisel.spline(chisel.read_mesh(path), 3, param="given")


def test_implicit_particles_and_network_equal_the_command_line(tmp_path, cli):
    scene = chisel.scene_examples()["dumbbell"]
    (tmp_path / "dumbbell.toml").write_text(scene)
    for method in ("particles", "network"):
        out = tmp_path / method
        theirs = cli(
            "implicit", tmp_path / "dumbbell.toml", "--frames", "2", "--method", method,
            "--backend", "cpu", "-o", out,
        )
        mine = chisel.implicit(tmp_path / "dumbbell.toml", frames=2, method=method)
        assert len(mine.frames) == 2
        for k, frame in enumerate(mine.frames):
            written = chisel.read_mesh(out / f"frame_{k:04d}.ply")
            np.testing.assert_array_equal(frame.vertices, written.vertices)
            np.testing.assert_array_equal(frame.triangles, written.triangles)
        frames = mine.report["particle_frames" if method == "particles" else "network_frames"]
        assert [f["frame"] for f in frames] == [f["frame"] for f in theirs["frames"]]


def test_implicit_progress_stops_between_frames():
    scene = chisel.scene_examples()["dumbbell"]

    def stop(done, total):
        raise RuntimeError(f"stop at {done}/{total}")

    with pytest.raises(RuntimeError, match="stop at 1/3"):
        chisel.implicit(scene_toml=scene, frames=3, progress=stop)
    with pytest.raises(chisel.FormatError, match="<scene_toml>"):
        chisel.implicit(scene_toml="[[primitive]]\nkind = 'nothing'\n")


def test_fuse_and_morph_equal_the_command_line(tmp_path, cli):
    a, b = two_balls(tmp_path)
    f = chisel.fuse(a, b, tolerance=0.05)
    theirs = cli(
        "fuse", tmp_path / "a.ply", tmp_path / "b.ply", "--tolerance", "0.05",
        "--backend", "cpu", "-o", tmp_path / "f.ply",
    )
    written = chisel.read_mesh(tmp_path / "f.ply")
    np.testing.assert_array_equal(f.mesh.vertices, written.vertices)
    assert f.report["volumes"] == theirs["volumes"]
    assert abs(f.report["volumes"]["relative_error"]) < 0.01
    m = chisel.morph(a, b, frames=3, tolerance=0.05)
    assert m.vertices.shape[0] == 3 and m.vertices.shape[2] == 3
    theirs = cli(
        "morph", tmp_path / "a.ply", tmp_path / "b.ply", "--frames", "3", "--tolerance", "0.05",
        "--backend", "cpu", "-o", tmp_path / "morph",
    )
    assert [fr["volumes"] for fr in m.report["frames"]] == [
        fr["volumes"] for fr in theirs["frames"]
    ]
    assert m.frame(0).triangles.shape == m.triangles.shape


def test_blobby_fit_equals_the_command_line(tmp_path, data, cli):
    path = data("fran_cut.vtk")
    model = chisel.blobby_fit(chisel.read_mesh(path), primitives=4)
    theirs = cli(
        "blobby", "fit", path, "--primitives", "4", "--backend", "cpu", "-o", tmp_path / "m.toml"
    )
    assert model.blobs.shape == (4, 5)
    assert [s["terms"] for s in model.report["stages"]] == [s["terms"] for s in theirs["stages"]]
    # The scene it writes is one the implicit room reads.
    frames = chisel.implicit(scene_toml=model.scene, frames=1, method="network", reports=False)
    assert len(frames.frames[0].triangles) > 0
