"""Scalpels and soft tissue: cutting meshes, relaxing the face over a
moved bone."""

from __future__ import annotations

import json
import os
from typing import Optional, Sequence, Union

import numpy as np

from . import _chisel
from .errors import DivergedError, ParameterError
from .types import Mesh, Piece, Relaxed, f32_mesh, vec3


def _is_point(x) -> bool:
    try:
        return len(x) == 3 and all(np.isscalar(c) for c in x)
    except TypeError:
        return False


def _many(knife) -> list:
    """One knife (a tuple whose first item is a point) or a list of them."""
    if knife is None:
        return []
    return [knife] if _is_point(knife[0]) else list(knife)



def cut(
    mesh: Mesh,
    *,
    plane=None,
    rect=None,
    sphere=None,
    knife: Union[Mesh, Sequence[Mesh], None] = None,
    cap: bool = False,
) -> tuple:
    """Cuts ``mesh`` (``chisel cut``) with planes ``(point, normal)``,
    rectangles ``(centre, normal, u_axis, (half_u, half_v))``, spheres
    ``(centre, radius)`` and triangulated knives (meshes), in that order,
    each knife cutting every piece of the one before; each argument takes
    one knife or a list. ``cap=True`` closes every piece with the knife's
    surface. Returns ``(pieces, stats)``: a list of :class:`Piece` and the
    cut's statistics."""
    planes = [(vec3(p), vec3(n)) for p, n in _many(plane)]
    rects = [
        (vec3(c), vec3(n), vec3(u), (float(h[0]), float(h[1])))
        for c, n, u, h in _many(rect)
    ]
    spheres = [(vec3(c), float(r)) for c, r in _many(sphere)]
    knives = [] if knife is None else [knife] if isinstance(knife, Mesh) else list(knife)
    pieces, stats = _chisel.cut(
        *f32_mesh(mesh), planes, rects, spheres, [f32_mesh(k) for k in knives], cap
    )
    return [Piece(Mesh(v, t), side) for v, t, side in pieces], json.loads(stats)


def relax(
    skin: Mesh,
    bone: Optional[Mesh] = None,
    *,
    plan: Union[dict, str, os.PathLike],
    solver: str = "explicit",
    force_dt: bool = False,
    bending: Optional[float] = None,
    subcutis_depth: Optional[float] = None,
    origin: Optional[Sequence[float]] = None,
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> Relaxed:
    """Relaxes the soft tissue between ``skin`` and ``bone`` (``chisel
    relax``; without a bone, the skin scaled inward stands for it) as
    ``plan`` cuts and moves the bone: a plan file (TOML or JSON) or a dict
    of the same fields (``step``: ``select``, ``translate``, ``rotate``,
    ``increments``, ``iterations``; ``cut``; ``dynamics``). ``solver`` is
    ``"explicit"`` or ``"chebyshev"``; ``force_dt`` keeps a ``dt`` above the
    stability limit. A relaxation that diverges raises
    :class:`DivergedError`, whose ``report`` says where."""
    if isinstance(plan, dict):
        path, text = None, json.dumps(plan)
    elif isinstance(plan, (str, os.PathLike)):
        path, text = os.fspath(plan), None
    else:
        raise ParameterError(f"plan = {type(plan).__name__}: a dict or a path")
    (v, t), displacement, report = _chisel.relax(
        *f32_mesh(skin),
        None if bone is None else f32_mesh(bone),
        path,
        text,
        solver,
        force_dt,
        bending,
        subcutis_depth,
        None if origin is None else vec3(origin),
        backend,
        adapter,
    )
    report = json.loads(report)
    if report["relax"]["status"] == "diverged" or not np.isfinite(v).all():
        raise DivergedError(
            f"the relaxation diverged after {report['relax']['iterations']} iterations "
            "(use more increments, or a smaller dt)",
            report,
        )
    return Relaxed(Mesh(v, t, {"displacement": displacement}), displacement, report)
