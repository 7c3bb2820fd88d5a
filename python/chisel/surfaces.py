"""Surfaces from volumes: marching cubes with the seed's grouping."""

from __future__ import annotations

import json
from typing import Optional, Union

import numpy as np

from . import _chisel
from .types import Mesh, Surface, Volume, as_volume

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
    v = as_volume(volume)
    vertices, triangles, tri_groups, figures = _chisel.marching_cubes(
        v.array, v._frame(), level, label, close_border, groups, backend, adapter
    )
    return Surface(Mesh(vertices, triangles), tri_groups, json.loads(figures))
