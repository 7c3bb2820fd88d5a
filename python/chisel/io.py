"""Readers and writers of every format the engine supports; the format
follows the file's content, then its extension, as on the command line."""

from __future__ import annotations

import json
import warnings
from typing import List, Optional, Union

import numpy as np

from . import _chisel
from .types import Mesh, Volume, as_volume, f32_mesh, vec3

def read_volume(path, series: Optional[str] = None) -> Volume:
    """Reads a volume file (NRRD, MetaImage, NIfTI, VTK, VTK XML ``.vti``,
    raw with a header, DICOM file or directory — ``series`` picks one of
    several) into a :class:`Volume` in the file's own sample type."""
    array, (spacing, origin, axes, space), notes = _chisel.read_volume(str(path), series)
    for note in notes:  # what the command line prints as `note:` lines
        warnings.warn(f"{path}: {note}", stacklevel=2)
    x, y, z = axes
    return Volume(array, vec3(spacing), vec3(origin), (vec3(x), vec3(y), vec3(z)), space)


def write_volume(path, volume: Union[Volume, np.ndarray]) -> None:
    """Writes a volume atomically; the format follows the extension."""
    v = as_volume(volume)
    _chisel.write_volume(str(path), v.array, v._frame())


def read_mesh(path) -> Mesh:
    """Reads a mesh file (PLY, STL, OBJ, BYU, VTK, VTK XML ``.vtp``)."""
    vertices, triangles, scalars = _chisel.read_mesh(str(path))
    return Mesh(vertices, triangles, dict(scalars))


def write_mesh(path, mesh: Mesh) -> None:
    """Writes a mesh with its ``scalars`` (PLY, VTK and VTP carry them)
    atomically; the format follows the extension."""
    scalars = {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in mesh.scalars.items()}
    _chisel.write_mesh(str(path), *f32_mesh(mesh), scalars)


def dicom_series(directory) -> List[dict]:
    """The DICOM series under ``directory`` (up to four levels down): UID,
    description, modality, files, frames, rows, columns, transfer syntax —
    pass a ``uid`` to :func:`read_volume` as ``series``."""
    return json.loads(_chisel.dicom_series(str(directory)))
