"""numpy conventions: dtypes, C and F order, the (nz, ny, nx) axis order
against SimpleITK and nibabel on real data, round trips, pickling."""

import pickle

import numpy as np
import pytest

import chisel
from conftest import ball

DTYPES = [np.bool_, np.uint8, np.int8, np.uint16, np.int16, np.uint32, np.int32, np.float32, np.float64]


@pytest.mark.parametrize("dtype", DTYPES)
def test_every_sample_type_round_trips(tmp_path, dtype):
    rng = np.random.default_rng(7)
    array = (rng.integers(0, 2 if dtype is np.bool_ else 100, size=(5, 6, 7))).astype(dtype)
    v = chisel.Volume(array, spacing=(0.5, 0.75, 2.0), origin=(1.0, -2.0, 3.0))
    chisel.write_volume(tmp_path / "v.nrrd", v)
    back = chisel.read_volume(tmp_path / "v.nrrd")
    assert back.array.shape == (5, 6, 7)
    assert back.dims == (7, 6, 5)
    # bool is written as uint8 (the engine has no bool samples).
    want = array.astype(np.uint8) if dtype is np.bool_ else array
    assert back.array.dtype == want.dtype
    np.testing.assert_array_equal(back.array, want)
    assert back.spacing == (0.5, 0.75, 2.0)
    assert back.origin == (1.0, -2.0, 3.0)


def test_fortran_order_and_views_give_the_same_surface():
    array = ball(20, (9, 10, 11), 6) * 100
    c = chisel.marching_cubes(array, level=50)
    f = chisel.marching_cubes(np.asfortranarray(array), level=50)
    # A strided view: every other slice of a doubled stack.
    stack = np.repeat(array, 2, axis=0)[::2]
    s = chisel.marching_cubes(stack, level=50)
    for other in (f, s):
        np.testing.assert_array_equal(c.mesh.vertices, other.mesh.vertices)
        np.testing.assert_array_equal(c.mesh.triangles, other.mesh.triangles)


def test_axis_order_is_z_y_x():
    # One voxel at x=5, y=1, z=2: its surface sits around world (5, 1, 2).
    array = np.zeros((4, 3, 8), dtype=np.uint8)
    array[2, 1, 5] = 1
    s = chisel.marching_cubes(array, level=0.5)
    centre = s.mesh.vertices.mean(axis=0)
    np.testing.assert_allclose(centre, [5.0, 1.0, 2.0], atol=1e-6)
    # The same with a negative control: the transposed array puts it elsewhere.
    t = chisel.marching_cubes(np.ascontiguousarray(array.transpose(2, 1, 0)), level=0.5)
    assert not np.allclose(t.mesh.vertices.mean(axis=0), [5.0, 1.0, 2.0])


@pytest.mark.parametrize(
    "name", ["HeadMRVolume.mhd", "froggy/frogtissue.mhd", "foot/foot.mha"]
)
def test_arrays_and_frames_equal_simpleitk(data, name):
    sitk = pytest.importorskip("SimpleITK")
    path = data(name)
    image = sitk.ReadImage(str(path))
    v = chisel.read_volume(path)
    expected = sitk.GetArrayFromImage(image)
    if expected.ndim == 2:  # a single slice: SimpleITK drops the z axis
        expected = expected[np.newaxis]
    assert v.array.shape == expected.shape
    assert v.array.dtype == expected.dtype
    if name.startswith("froggy"):
        # ITK, like VTK, stops inflating at the header's wrong
        # CompressedDataSize (data README §4): 30,963,285 voxels, then
        # whatever its buffer held. chisel reads the whole zlib stream:
        # equal up to there, and the README's label counts in full.
        decoded = 30_963_285
        np.testing.assert_array_equal(v.array.ravel()[:decoded], expected.ravel()[:decoded])
        assert (v.array == 13).sum() == 440_722
        assert (v.array != 0).sum() == 1_156_957
    else:
        np.testing.assert_array_equal(v.array, expected)
    np.testing.assert_allclose(v.spacing[: image.GetDimension()], image.GetSpacing())
    np.testing.assert_allclose(v.origin[: image.GetDimension()], image.GetOrigin())


def test_nifti_written_by_nibabel_reads_transposed(tmp_path, data):
    nib = pytest.importorskip("nibabel")
    head = chisel.read_volume(data("headsq/quarter.nhdr"))
    xyz = np.ascontiguousarray(head.array.transpose(2, 1, 0))  # nibabel's (nx, ny, nz)
    affine = np.diag([*head.spacing, 1.0])
    nib.save(nib.Nifti1Image(xyz, affine), str(tmp_path / "head.nii"))
    back = chisel.read_volume(tmp_path / "head.nii")
    np.testing.assert_array_equal(back.array, head.array)
    np.testing.assert_allclose(back.spacing, head.spacing)
    # And the other way: nibabel reads chisel's NIfTI as (nx, ny, nz).
    chisel.write_volume(tmp_path / "mine.nii", head)
    np.testing.assert_array_equal(np.asanyarray(nib.load(str(tmp_path / "mine.nii")).dataobj), xyz)


def test_meshes_round_trip_and_convert(tmp_path, data):
    bunny = chisel.read_mesh(data("bunny.ply"))
    assert bunny.vertices.dtype == np.float32 and bunny.vertices.shape[1] == 3
    assert bunny.triangles.dtype == np.uint32 and bunny.triangles.shape[1] == 3
    for ext in ("ply", "stl", "obj", "vtp"):
        chisel.write_mesh(tmp_path / f"b.{ext}", bunny)
        back = chisel.read_mesh(tmp_path / f"b.{ext}")
        assert back.triangles.shape == bunny.triangles.shape
    # int64 triangles are accepted.
    m = chisel.Mesh(bunny.vertices, bunny.triangles.astype(np.int64))
    chisel.write_mesh(tmp_path / "i64.ply", m)
    np.testing.assert_array_equal(chisel.read_mesh(tmp_path / "i64.ply").triangles, bunny.triangles)
    trimesh = pytest.importorskip("trimesh")
    t = bunny.to_trimesh()
    assert isinstance(t, trimesh.Trimesh) and len(t.faces) == len(bunny.triangles)


def test_results_pickle():
    array = ball(16, (8, 8, 8), 5)
    v = chisel.Volume(array, (0.5, 0.5, 0.5))
    s = chisel.marching_cubes(v, level=0.5)
    r = chisel.scan(v, level=1)
    for obj in (v, s, s.mesh, r):
        back = pickle.loads(pickle.dumps(obj))
        assert type(back) is type(obj)
    back = pickle.loads(pickle.dumps(s))
    np.testing.assert_array_equal(back.mesh.triangles, s.mesh.triangles)
    assert back.groups == s.groups


def test_dicom_directories_list_their_series_and_read_one():
    from conftest import REPO

    folder = REPO / "tests" / "data" / "dicom" / "two_series"
    series = chisel.dicom_series(folder)
    assert len(series) == 2
    assert all(s["files"] == 2 and s["rows"] == 5 and s["columns"] == 6 for s in series)
    with pytest.raises(chisel.ChiselError, match=series[1]["uid"]):
        chisel.read_volume(folder)
    v = chisel.read_volume(folder, series=series[1]["uid"])
    assert v.array.shape == (2, 5, 6) and v.space == "LPS"


def test_meshes_convert_to_pyvista(data):
    pyvista = pytest.importorskip("pyvista")
    bunny = chisel.read_mesh(data("bunny.ply"))
    p = bunny.to_pyvista()
    assert isinstance(p, pyvista.PolyData)
    np.testing.assert_array_equal(np.asarray(p.points), bunny.vertices)
    np.testing.assert_array_equal(p.faces.reshape(-1, 4)[:, 1:], bunny.triangles)
    np.testing.assert_array_equal(p.point_data["intensity"], bunny.scalars["intensity"])
