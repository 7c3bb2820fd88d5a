"""chisel: GPU compute for surgical-planning geometry, numpy in, numpy out.

Axis order, stated once: a volume's ``array`` has shape ``(nz, ny, nx)``
and ``array[k, j, i]`` is the sample at voxel ``(x=i, y=j, z=k)`` — the
order of ``SimpleITK.GetArrayFromImage`` and of a C-ordered stack of 2-D
slices; nibabel's ``get_fdata()`` is ``(nx, ny, nz)``, its transpose.
``spacing``, ``origin`` and the rows of ``axes`` are in (x, y, z) order,
in world units (mm), as SimpleITK's ``GetSpacing()`` / ``GetOrigin()``.
Vertices are world (x, y, z) positions.

Every call releases the GIL while the engine works; the engine's errors
are :class:`chisel.errors.ChiselError` subclasses with its message (file,
position, what was expected). Arguments of the wrong Python type raise
``TypeError`` before the engine runs.
"""

from __future__ import annotations

import json
from typing import Optional

from . import _chisel, errors
from .errors import (
    CancelledError,
    ChiselError,
    DivergedError,
    FormatError,
    GpuError,
    InternalError,
    IoError,
    LimitError,
    ParameterError,
    RefusedError,
)
from .hulls import hull, hull_scan, polyhedrize, scan, scan_file
from .io import dicom_series, read_mesh, read_volume, write_mesh, write_volume
from .shapes import blobby_fit, fuse, implicit, morph, scene_examples, spline
from .stats import stats
from .surfaces import marching_cubes
from .tissue import cut, relax
from .types import (
    Animation,
    BlobbyModel,
    Fused,
    Hull,
    HullScan,
    Mesh,
    Morph,
    Piece,
    Polyhedron,
    Relaxed,
    Spline,
    Surface,
    Volume,
)

__version__: str = _chisel.__version__


def gpu_info(adapter: Optional[str] = None) -> dict:
    """The GPU adapters and the one ``adapter`` (else ``CHISEL_ADAPTER``,
    else ``auto``) opens, as ``chisel info --json`` reports them."""
    return json.loads(_chisel.gpu_info(adapter))


__all__ = [
    "Volume",
    "Mesh",
    "Surface",
    "Hull",
    "HullScan",
    "Polyhedron",
    "Piece",
    "Relaxed",
    "Spline",
    "Animation",
    "Fused",
    "Morph",
    "BlobbyModel",
    "gpu_info",
    "read_volume",
    "write_volume",
    "read_mesh",
    "write_mesh",
    "dicom_series",
    "stats",
    "marching_cubes",
    "hull",
    "hull_scan",
    "scan",
    "scan_file",
    "polyhedrize",
    "cut",
    "relax",
    "spline",
    "implicit",
    "scene_examples",
    "fuse",
    "morph",
    "blobby_fit",
    "batch",
    *errors.__all__,
]

# `chisel.batch`: scans over many files (Dask).
from . import batch  # noqa: E402
