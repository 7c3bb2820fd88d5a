"""Statistics of a volume or a mesh (``chisel stats``)."""

from __future__ import annotations

import json
from typing import Optional, Union

import numpy as np

from . import _chisel
from .errors import ParameterError
from .types import Mesh, Volume, as_volume, f32_mesh


def stats(
    obj: Union[Volume, Mesh, np.ndarray],
    level: Optional[float] = None,
    label: Optional[float] = None,
) -> dict:
    """A volume's sample type, range, mean, zeros, non-finite samples and
    label table (``stats``), with ``level`` or ``label`` its 6-connected
    components (``level``/``label``: count, voxels, largest, sizes); or a
    mesh's topology (edges, boundary loops, components, Euler
    characteristic, orientation, area, signed volume) and its
    self-intersecting triangle pairs."""
    if isinstance(obj, Mesh):
        if level is not None or label is not None:
            raise ParameterError("level and label select voxels: a mesh has none")
        return json.loads(_chisel.mesh_stats(*f32_mesh(obj)))
    v = as_volume(obj)
    return json.loads(_chisel.volume_stats(v.array, v._frame(), level, label))
