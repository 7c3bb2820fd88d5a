"""Statistics, hulls, polyhedra, cuts and relaxations from Python equal
the command line's on the real data."""

import numpy as np
import pytest

import chisel
from conftest import REPO, ball, phantoms


def test_volume_and_mesh_stats_equal_the_command_line(data, cli):
    path = data("headsq/quarter.nhdr")
    mine = chisel.stats(chisel.read_volume(path), level=1150)
    theirs = cli("stats", path, "--backend", "cpu", "--level", "1150")
    assert mine["stats"] == {k: v for k, v in theirs["stats"].items() if k in mine["stats"]}
    assert mine["level"]["components"] == theirs["level"]["components"]
    bunny = data("bunny.ply")
    m = chisel.stats(chisel.read_mesh(bunny))
    t = cli("stats", bunny, "--backend", "cpu")
    assert m["topology"] == t["topology"]
    assert len(m["self_intersections"]["pairs"]) == t["self_intersections"]["pairs"]


def test_hull_equals_the_command_line(data, cli):
    path = data("froggy/frogtissue.mhd")
    h = chisel.hull(chisel.read_volume(path), label=4)
    theirs = cli("hull", path, "--label", "4")
    assert h.summary == theirs["hull"]
    assert h.zkh == theirs["zkh"]
    assert h.object == theirs["object"]
    assert len(h.faces) == h.summary["faces"] == len(h.planes)
    # Every hull vertex lies on or inside every face plane, exactly.
    assert (h.vertices @ h.planes[:, :3].T <= h.planes[:, 3]).all()
    # Voxel centres are odd combinatorial coordinates.
    assert (h.vertices % 2 == 1).all()
    assert len(h.mesh.triangles) == h.summary["triangles"]


def test_polyhedrize_equals_the_command_line(tmp_path, cli):
    torus = phantoms(tmp_path)[1]
    p = chisel.polyhedrize(chisel.read_volume(torus), level=500)
    theirs = cli("polyhedrize", torus, "--level", "500", "--backend", "cpu")
    assert p.summary == theirs["polyhedron"]
    assert p.zkh == theirs["zkh"]
    assert p.mesh_kind == theirs["mesh"]
    assert p.zkh and p.zkh[0]["class"] == "tunnel"
    assert len(p.cells["shells"]) == p.summary["shells"]


def test_cut_equals_the_command_line(tmp_path, data, cli):
    path = data("bunny.ply")
    bunny = chisel.read_mesh(path)
    pieces, stats = chisel.cut(bunny, plane=((0, 0.1, 0), (0, 1, 0)), cap=True)
    theirs = cli("cut", path, "--plane", "0,0.1,0,0,1,0", "--cap", "-o", tmp_path / "pieces")
    assert [(p.side, len(p.mesh.triangles)) for p in pieces] == [
        (q["side"], q["triangles"]) for q in theirs["pieces"]
    ]
    for p, q in zip(pieces, theirs["pieces"]):
        written = chisel.read_mesh(q["file"])
        np.testing.assert_array_equal(p.mesh.triangles, written.triangles)
        assert chisel.stats(p.mesh)["topology"]["closed"] == q["closed"]
    timings = ("locate_seconds", "assemble_seconds")
    strip = lambda d: {k: v for k, v in d.items() if k not in timings}
    assert strip(stats) == strip(theirs["stats"])
    # Two knives at once, a plane and a sphere, in the command line's order.
    two, _ = chisel.cut(bunny, plane=[((0, 0.1, 0), (0, 1, 0))], sphere=((0, 0.1, 0), 0.03))
    assert len(two) > len(pieces)
    with pytest.raises(chisel.ParameterError, match="knives"):
        chisel.cut(bunny)


def test_relax_equals_the_command_line(tmp_path, data, cli):
    path = data("fran_cut.vtk")
    plan = REPO / "src" / "tissue" / "plans" / "fran_chin_advance.toml"
    r = chisel.relax(chisel.read_mesh(path), plan=plan)
    theirs = cli("relax", path, "--plan", plan, "--backend", "cpu", "-o", tmp_path / "r.ply")
    for key in ("iterations", "status", "max_displacement", "solver"):
        assert r.report["relax"][key] == theirs["relax"][key], key
    written = chisel.read_mesh(tmp_path / "r.ply")
    np.testing.assert_array_equal(r.mesh.vertices, written.vertices)
    assert r.displacement.shape == (len(r.mesh.vertices),)
    assert abs(float(r.displacement.max()) - r.report["relax"]["max_displacement"]) < 1e-7


def test_relax_takes_a_plan_dict():
    sphere = chisel.marching_cubes(ball(24, (12, 12, 12), 9), level=0.5).mesh
    plan = {
        "step": [
            {"select": {"sphere": {"center": [12.0, 12.0, 3.0], "radius": 4.0}},
             "translate": [0.0, 0.0, 0.5], "iterations": 200}
        ]
    }
    r = chisel.relax(sphere, plan=plan)
    assert r.report["relax"]["iterations"] > 0 and r.displacement.max() > 0
    with pytest.raises(chisel.FormatError, match="unknown variant `cube`"):
        chisel.relax(sphere, plan={"step": [{"select": {"cube": 1}}]})


def test_hull_scan_counts_equal_the_scan_and_the_gpu(data):
    frog = chisel.read_volume(data("froggy/frogtissue.mhd"))
    hs = chisel.hull_scan(frog, label=4, component="all")
    report = chisel.scan(frog, labels=True, min_voxels=1000)
    row = next(r for r in report["rows"] if r["label"] == 4.0)
    counts = hs.counts()
    assert {k: row["scan"][k] for k in counts} == counts
    assert list(hs.origin) == row["scan"]["box"]["origin"]
    assert hs.sides.shape == tuple(reversed(row["scan"]["box"]["dims"]))
    # Every voxel of the label lies inside or on its hull.
    x, y, z = hs.origin
    nz, ny, nx = hs.sides.shape
    window = frog.array[z : z + nz, y : y + ny, x : x + nx] == 4
    assert (hs.sides[window] > 0).all()
    gpu = chisel.hull_scan(frog, label=4, component="all", backend="gpu")
    np.testing.assert_array_equal(gpu.sides, hs.sides)
