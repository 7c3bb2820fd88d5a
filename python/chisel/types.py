"""The package's data: volumes, meshes and the results of operations,
dataclasses of numpy arrays and dicts (they pickle, so Dask moves them)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple, Union

import numpy as np

from .errors import ParameterError

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
        x, y, z = self.axes
        return (vec3(self.spacing), vec3(self.origin), (vec3(x), vec3(y), vec3(z)), self.space)


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


def as_volume(volume: Union[Volume, np.ndarray]) -> Volume:
    if isinstance(volume, Volume):
        return volume
    if isinstance(volume, np.ndarray):
        return Volume(volume)
    raise ParameterError(
        f"volume = {type(volume).__name__}: a chisel.Volume or a 3-D numpy array (nz, ny, nx)"
    )


@dataclass
class Hull:
    """The exact convex hull of a digital object (seed 003 §4.1):
    ``vertices`` int64[V, 3] in combinatorial coordinates (voxel centre
    ``(i, j, k)`` is ``(2i+1, 2j+1, 2k+1)``), ``faces`` (vertex indices,
    counter-clockwise from outside), ``planes`` int64[F, 4] (outward normal,
    offset: ``n·x ≤ d``), ``mesh`` (the faces fan-triangulated, world
    units), ``cells`` (the cell list: 0-, 1-, 2-cells), ``summary``
    (counts, storage per eq. 8.2, volume and area), ``object`` and
    ``candidates`` figures, ``zkh`` (the background components inside the
    hull, by class; ``None`` with ``zkh_skipped`` saying why)."""

    vertices: np.ndarray
    faces: List[List[int]]
    planes: np.ndarray
    mesh: "Mesh"
    cells: dict
    summary: dict
    object: dict
    candidates: dict
    zkh: Optional[List[dict]]
    zkh_skipped: Optional[str]


@dataclass
class HullScan:
    """Voxels against a hull: ``sides`` uint8[nz, ny, nx] (0 outside, 1 on,
    2 inside) over the hull's voxel box, whose first voxel is ``origin``
    (x, y, z voxel indices of the volume)."""

    sides: np.ndarray
    origin: Tuple[int, int, int]

    def counts(self) -> Dict[str, int]:
        """Voxels outside, on and inside."""
        c = np.bincount(self.sides.ravel(), minlength=3)
        return {"outside": int(c[0]), "on": int(c[1]), "inside": int(c[2])}


@dataclass
class Polyhedron:
    """A lossless polyhedron of a digital object (seed 003 §4.5): ``mesh``
    (the merged surface, or the shells where they cannot be merged:
    ``mesh_kind``), ``cells`` (every shell: parent, depth, role, faces),
    ``summary`` (shells, faces, storage, exact volume), ``zkh`` (per ZKH:
    class, voxels, genus, shells), ``topology`` of the object's boundary,
    ``options`` and why merging was refused (``merge_refused``)."""

    mesh: "Mesh"
    mesh_kind: str
    cells: dict
    summary: dict
    zkh: List[dict]
    topology: dict
    object: dict
    options: dict
    merge_refused: Optional[str]


@dataclass
class Piece:
    """One piece of a cut: its ``mesh`` and its ``side`` of the knife
    (``"negative"``: behind the plane, inside the sphere; ``"positive"``;
    ``"both"``)."""

    mesh: "Mesh"
    side: str


@dataclass
class Relaxed:
    """A relaxation: the relaxed skin (``mesh``, with a ``displacement``
    scalar), the per-vertex displacement from rest (float32[N], mm) and
    the engine's ``report`` (solver, dynamics, status, iterations, steps;
    ``bone_cut`` when the plan cut the bone)."""

    mesh: "Mesh"
    displacement: np.ndarray
    report: dict


@dataclass
class Spline:
    """A DMS spline surface (seed 000 ch. 2): the evaluated lattice
    ``mesh`` (scalars ``nx, ny, nz`` unit normals, ``distance`` to the input
    mesh, ``curvature``), the ``controls`` float64[C, 3] (one per input
    vertex, then one per edge), the ``control_net`` mesh and the
    ``report`` (fit: method, rms and max distance, iterations; knot
    quality; timings)."""

    mesh: "Mesh"
    controls: np.ndarray
    control_net: "Mesh"
    report: dict


@dataclass
class Animation:
    """Frames of an implicit scene: particles (``Mesh`` without triangles,
    scalars ``nx, ny, nz, sigma``) or the spring network's closed meshes,
    and the ``report`` (setup, per-frame figures)."""

    frames: List["Mesh"]
    report: dict


@dataclass
class Fused:
    """A fusion (or subtraction): the closed ``mesh`` and the ``report``
    (centre, method, volumes a, b, result and target, passes)."""

    mesh: "Mesh"
    report: dict


@dataclass
class Morph:
    """A morph: ``vertices`` float32[frames, V, 3] over one ``triangles``
    uint32[T, 3] connectivity, and the ``report`` (per frame t, centre,
    volumes)."""

    vertices: np.ndarray
    triangles: np.ndarray
    report: dict

    def frame(self, k: int) -> "Mesh":
        """Frame ``k`` as a mesh."""
        return Mesh(self.vertices[k], self.triangles)


@dataclass
class BlobbyModel:
    """A blobby model fitted to a range scan: ``blobs`` float64[N, 5]
    (centre x, y, z, decay a, strength b), the ``scene`` TOML text that
    :func:`chisel.implicit` reads, and the ``report`` (options, stages with
    their energy terms)."""

    blobs: np.ndarray
    scene: str
    report: dict


def vec3(x) -> Vec3:
    """Three floats (a point, a direction, a spacing)."""
    a, b, c = (float(v) for v in x)
    return (a, b, c)


def f32_mesh(mesh: "Mesh") -> Tuple[np.ndarray, np.ndarray]:
    """A mesh's arrays as the engine takes them: float32[N, 3] vertices,
    integer[M, 3] triangles (any integer dtype; floats are refused, not
    truncated)."""
    v = np.asarray(mesh.vertices, dtype=np.float32)
    t = np.asarray(mesh.triangles)
    if v.ndim != 2 or v.shape[1] != 3:
        raise ParameterError(f"vertices = shape {v.shape}: vertices are float32[N, 3]")
    if t.size == 0:
        t = t.reshape(0, 3).astype(np.uint32)
    if t.dtype.kind not in "iu" or t.ndim != 2 or t.shape[1] != 3:
        raise ParameterError(
            f"triangles = {t.dtype}, shape {t.shape}: triangles are integer[M, 3] vertex indices"
        )
    return v, t
