"""chisel: GPU compute for surgical-planning geometry, numpy in, numpy out.

Axis order, stated once: a volume's ``array`` has shape ``(nz, ny, nx)``
and ``array[k, j, i]`` is the sample at voxel ``(x=i, y=j, z=k)`` — the
order of ``SimpleITK.GetArrayFromImage`` and of a C-ordered stack of 2-D
slices; nibabel's ``get_fdata()`` is ``(nx, ny, nz)``, its transpose.
``spacing``, ``origin`` and the rows of ``axes`` are in (x, y, z) order,
in world units (mm), as SimpleITK's ``GetSpacing()`` / ``GetOrigin()``.
Vertices are world (x, y, z) positions.

Every call releases the GIL while the engine works; errors are
:class:`chisel.errors.ChiselError` subclasses with the engine's message.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _chisel
from .errors import (
    CancelledError,
    ChiselError,
    FormatError,
    GpuError,
    InternalError,
    IoError,
    LimitError,
    ParameterError,
    RefusedError,
)

__version__: str = _chisel.__version__

Vec3 = Tuple[float, float, float]
IDENTITY_AXES: Tuple[Vec3, Vec3, Vec3] = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


@dataclass
class Volume:
    """A scalar volume: ``array`` of shape ``(nz, ny, nx)`` (any of bool,
    uint8, int8, uint16, int16, uint32, int32, float32, float64), with
    ``spacing`` and ``origin`` in (x, y, z) world units, ``axes`` the world
    direction of the x, y and z index axes, ``space`` ``"LPS"``, ``"RAS"``
    or ``None``."""

    array: np.ndarray
    spacing: Vec3 = (1.0, 1.0, 1.0)
    origin: Vec3 = (0.0, 0.0, 0.0)
    axes: Tuple[Vec3, Vec3, Vec3] = IDENTITY_AXES
    space: Optional[str] = None

    @property
    def dims(self) -> Tuple[int, int, int]:
        """Samples per axis in the engine's order ``(nx, ny, nz)``."""
        nz, ny, nx = self.array.shape
        return (nx, ny, nz)

    def _frame(self):
        return (
            tuple(float(s) for s in self.spacing),
            tuple(float(o) for o in self.origin),
            tuple(tuple(float(c) for c in row) for row in self.axes),
            self.space,
        )


@dataclass
class Mesh:
    """A triangle mesh: ``vertices`` float32[N, 3] (world x, y, z),
    ``triangles`` uint32[M, 3] vertex indices, ``scalars`` per-vertex
    float32[N] fields by name."""

    vertices: np.ndarray
    triangles: np.ndarray
    scalars: Dict[str, np.ndarray] = field(default_factory=dict)

    def to_trimesh(self):
        """This mesh as a ``trimesh.Trimesh`` (needs trimesh)."""
        import trimesh

        return trimesh.Trimesh(self.vertices, self.triangles, process=False)

    def to_pyvista(self):
        """This mesh as a ``pyvista.PolyData`` (needs pyvista)."""
        import pyvista

        faces = np.hstack([np.full((len(self.triangles), 1), 3), self.triangles]).astype(np.int64)
        mesh = pyvista.PolyData(self.vertices, faces.ravel())
        for name, values in self.scalars.items():
            mesh.point_data[name] = values
        return mesh


@dataclass
class Surface:
    """A marching-cubes surface: its ``mesh``, the group (connected
    component) of every triangle (uint32[M], ``None`` with
    ``groups=False``) and each group's figures (triangles, vertices, bbox,
    area in mm², signed volume in mm³, boundary edges, Euler
    characteristic, genus)."""

    mesh: Mesh
    triangle_groups: Optional[np.ndarray]
    groups: List[dict]


def _volume(volume: Union[Volume, np.ndarray]) -> Volume:
    if isinstance(volume, Volume):
        return volume
    if isinstance(volume, np.ndarray):
        return Volume(volume)
    raise ParameterError(
        f"volume = {type(volume).__name__}: a chisel.Volume or a 3-D numpy array (nz, ny, nx)"
    )


def gpu_info(adapter: Optional[str] = None) -> dict:
    """The GPU adapters and the one ``adapter`` (else ``CHISEL_ADAPTER``,
    else ``auto``) opens, as ``chisel info --json`` reports them."""
    return json.loads(_chisel.gpu_info(adapter))


def read_volume(path, series: Optional[str] = None) -> Volume:
    """Reads a volume file (NRRD, MetaImage, NIfTI, VTK, VTK XML ``.vti``,
    raw with a header, DICOM file or directory — ``series`` picks one of
    several) into a :class:`Volume` in the file's own sample type."""
    array, (spacing, origin, axes, space), _notes = _chisel.read_volume(str(path), series)
    return Volume(array, tuple(spacing), tuple(origin), tuple(map(tuple, axes)), space)


def write_volume(path, volume: Union[Volume, np.ndarray]) -> None:
    """Writes a volume atomically; the format follows the extension."""
    v = _volume(volume)
    _chisel.write_volume(str(path), v.array, v._frame())


def read_mesh(path) -> Mesh:
    """Reads a mesh file (PLY, STL, OBJ, BYU, VTK, VTK XML ``.vtp``)."""
    vertices, triangles, scalars = _chisel.read_mesh(str(path))
    return Mesh(vertices, triangles, dict(scalars))


def write_mesh(path, mesh: Mesh) -> None:
    """Writes a mesh atomically; the format follows the extension."""
    _chisel.write_mesh(str(path), np.asarray(mesh.vertices, dtype=np.float32), mesh.triangles)


def marching_cubes(
    volume: Union[Volume, np.ndarray],
    level: Optional[float] = None,
    label: Optional[float] = None,
    *,
    close_border: bool = False,
    groups: bool = True,
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> Surface:
    """The iso-surface at ``level`` (samples ≥ level inside) or the boundary
    of the voxels equal to ``label``, welded and wound outward, in world
    units, with the seed's grouping (``groups=False``: the mesh alone,
    faster). ``backend`` is ``"cpu"``, ``"gpu"`` or ``"auto"``;
    ``adapter`` as ``chisel --adapter``."""
    v = _volume(volume)
    vertices, triangles, tri_groups, figures = _chisel.marching_cubes(
        v.array, v._frame(), level, label, close_border, groups, backend, adapter
    )
    return Surface(Mesh(vertices, triangles), tri_groups, json.loads(figures))


_SCAN_DEFAULTS = dict(
    min_voxels=1,
    corners="local26",
    vertices="voxels",
    coplanar="merge",
    order="furthest",
    backend="cpu",
    adapter=None,
)


def scan(
    volume: Union[Volume, np.ndarray],
    level: Optional[float] = None,
    labels: bool = False,
    *,
    name: str = "<array>",
    progress: Optional[Callable[[int, int], None]] = None,
    **options,
) -> dict:
    """The large-volume hull scan (``chisel scan``): every structure's exact
    convex hull, inside/on/outside voxel counts and ZKHs by class, as the
    report dict ``chisel scan --json`` prints (``volume`` is ``name``).
    Structures are the 6-components of samples ≥ ``level``, or the non-zero
    labels with ``labels=True``. Options: ``min_voxels``, ``corners``
    (local6/local18/local26/convex), ``vertices`` (voxels/corners),
    ``coplanar`` (merge/visible/invisible), ``order``
    (furthest/extreme/lexicographic), ``backend``, ``adapter``.
    ``progress(done, total)`` runs after each structure; an exception it
    raises (or Ctrl-C) stops the scan."""
    v = _volume(volume)
    kw = _scan_options(options)
    return json.loads(
        _chisel.scan(v.array, v._frame(), name, level, labels, progress=progress, **kw)
    )


def scan_file(
    path,
    level: Optional[float] = None,
    labels: bool = False,
    *,
    series: Optional[str] = None,
    progress: Optional[Callable[[int, int], None]] = None,
    **options,
) -> dict:
    """Reads and scans a volume file: the report of ``chisel scan PATH
    --json`` with these options (see :func:`scan`)."""
    kw = _scan_options(options)
    return json.loads(
        _chisel.scan_file(str(path), level, labels, series=series, progress=progress, **kw)
    )


def _scan_options(options: dict) -> dict:
    unknown = set(options) - set(_SCAN_DEFAULTS)
    if unknown:
        raise ParameterError(
            f"unknown scan option(s) {sorted(unknown)}; known: {sorted(_SCAN_DEFAULTS)}"
        )
    return {**_SCAN_DEFAULTS, **options}


__all__ = [
    "Volume",
    "Mesh",
    "Surface",
    "gpu_info",
    "read_volume",
    "write_volume",
    "read_mesh",
    "write_mesh",
    "marching_cubes",
    "scan",
    "scan_file",
    "batch",
    "ChiselError",
    "IoError",
    "FormatError",
    "LimitError",
    "ParameterError",
    "RefusedError",
    "GpuError",
    "CancelledError",
    "InternalError",
]

# `chisel.batch`: scans over many files (Dask).
from . import batch  # noqa: E402
