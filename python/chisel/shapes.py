"""Shapes beyond marching cubes: DMS splines (seed 000 ch. 2), skeletal
implicit surfaces with particles and the spring network (seed 002),
fusion, subtraction and morphing, blobby fits (seed 001)."""

from __future__ import annotations

import json
import os
from typing import Callable, Dict, Optional, Sequence, Union

import numpy as np

from . import _chisel
from .errors import ParameterError
from .types import Animation, BlobbyModel, Fused, Mesh, Morph, Spline, f32_mesh, vec3



def spline(
    mesh: Mesh,
    n: int,
    *,
    param: str = "cylinder",
    uv: Optional[np.ndarray] = None,
    fit: str = "quasi",
    data: Optional[np.ndarray] = None,
    fairing: float = 0.0,
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> Spline:
    """The DMS spline of ``mesh`` (``chisel spline``) evaluated at ``n``
    points per parameter edge. ``param``: ``"cylinder"`` (eq. 2.12),
    ``"planar"``, or ``"given"`` with ``uv`` float64[N, 2] per vertex.
    ``fit``: ``"identify"`` (controls at the vertices), ``"quasi"``, or
    ``"lsq"`` (least squares to ``data`` float32[P, 3] or the vertices,
    with ``fairing``)."""
    if param == "given" and uv is not None:
        uv = np.asarray(uv, dtype=np.float64)
    (v, t, scalars), controls, (cv, ct), report = _chisel.spline(
        *f32_mesh(mesh), int(n), param, uv, fit,
        None if data is None else np.asarray(data, dtype=np.float32),
        float(fairing), backend, adapter,
    )
    return Spline(Mesh(v, t, dict(scalars)), controls, Mesh(cv, ct), json.loads(report))


def scene_examples() -> Dict[str, str]:
    """The built-in implicit scenes by name (TOML text)."""
    return dict(_chisel.scene_examples())


def implicit(
    scene: Union[str, os.PathLike, None] = None,
    *,
    scene_toml: Optional[str] = None,
    method: str = "particles",
    frames: int = 8,
    edge_length: Optional[float] = None,
    reports: bool = True,
    backend: str = "cpu",
    adapter: Optional[str] = None,
    progress: Optional[Callable[[int, int], None]] = None,
) -> Animation:
    """Frames of a skeletal implicit scene (``chisel implicit``): a scene
    file (``scene``) or its TOML text (``scene_toml``, e.g. from
    :func:`scene_examples` or a :class:`BlobbyModel`), sampled at
    ``frames`` times by Witkin–Heckbert particles (``method="particles"``)
    or followed by the particle spring network (``"network"``).
    ``progress(done, total)`` runs after each frame; an exception it
    raises (or Ctrl-C) stops the animation. ``reports=False`` skips the
    network's per-frame quality figures (particles report at no cost)."""
    if (scene is None) == (scene_toml is None):
        raise ParameterError("give a scene file or scene_toml, one of them")
    path = None if scene is None else str(os.fspath(scene))
    meshes, report = _chisel.implicit(
        path, scene_toml, method, int(frames), edge_length, reports, backend, adapter, progress
    )
    return Animation([Mesh(v, t, dict(s)) for v, t, s in meshes], json.loads(report))


def fuse(
    a: Mesh,
    b: Mesh,
    *,
    subtract: bool = False,
    center: Optional[Sequence[float]] = None,
    tolerance: Optional[float] = None,
    start_level: Optional[int] = None,
    max_triangles: Optional[int] = None,
    cells: Optional[int] = None,
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> Fused:
    """The volume-preserving fusion of ``a`` and ``b`` (``chisel fuse``,
    seed 001 §2): one closed mesh whose volume is the sum of theirs (the
    difference with ``subtract=True``), by rays from a common centre
    (searched when ``center`` is None)."""
    (v, t), report = _chisel.fuse(
        (*f32_mesh(a), *f32_mesh(b)), subtract,
        None if center is None else vec3(center),
        tolerance, start_level, max_triangles, cells, backend, adapter,
    )
    return Fused(Mesh(v, t), json.loads(report))


def morph(
    a: Mesh,
    b: Mesh,
    *,
    frames: int = 9,
    center: Optional[Sequence[float]] = None,
    center_end: Optional[Sequence[float]] = None,
    tolerance: Optional[float] = None,
    start_level: Optional[int] = None,
    max_triangles: Optional[int] = None,
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> Morph:
    """``a`` morphed into ``b`` (``chisel morph``, seed 001 eq. 8) over
    ``frames`` frames sharing one connectivity."""
    v, t, report = _chisel.morph(
        (*f32_mesh(a), *f32_mesh(b)), int(frames),
        None if center is None else vec3(center),
        None if center_end is None else vec3(center_end),
        tolerance, start_level, max_triangles, backend, adapter,
    )
    return Morph(v, t, json.loads(report))


def blobby_fit(
    scan: Mesh,
    *,
    primitives: int = 32,
    alpha: float = 0.5,
    beta: float = 1e-4,
    iso: float = 0.5,
    pair_iterations: int = 40,
    global_iterations: int = 80,
    energy_target: Optional[float] = None,
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> BlobbyModel:
    """A blobby model of ``primitives`` blobs fitted to a range scan
    (``chisel blobby fit``, seed 001 §3): its vertices and area-weighted
    normals (turned outward), primitives split and fitted by L-BFGS."""
    blobs, scene, report = _chisel.blobby_fit(
        *f32_mesh(scan), int(primitives), float(alpha), float(beta), float(iso),
        int(pair_iterations), int(global_iterations), energy_target, backend, adapter,
    )
    return BlobbyModel(blobs, scene, json.loads(report))
