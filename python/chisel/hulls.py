"""Exact convex hulls, large-volume hull scans and lossless polyhedra of
digital objects (seed 003)."""

from __future__ import annotations

import json
from typing import Callable, Optional, Union

import numpy as np

from . import _chisel
from .errors import ParameterError
from .types import Hull, HullScan, Mesh, Polyhedron, Volume, as_volume

# The option names each function takes; their defaults are the engine's
# (the command line's), applied in the native module.
SCAN_OPTIONS = ("min_voxels", "corners", "vertices", "coplanar", "order", "backend", "adapter")
HULL_OPTIONS = ("corners", "vertices", "coplanar", "order")
POLYHEDRIZE_OPTIONS = ("corners", "vertices", "coplanar", "order", "backend", "adapter")


def check_options(options: dict, known: tuple, what: str) -> dict:
    """``options`` when every name is one of ``known``."""
    unknown = set(options) - set(known)
    if unknown:
        raise ParameterError(f"unknown {what} option(s) {sorted(unknown)}; known: {sorted(known)}")
    return options


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
    v = as_volume(volume)
    kw = check_options(options, SCAN_OPTIONS, "scan")
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
    kw = check_options(options, SCAN_OPTIONS, "scan")
    return json.loads(
        _chisel.scan_file(str(path), level, labels, series=series, progress=progress, **kw)
    )


def hull(
    volume: Union[Volume, np.ndarray],
    level: Optional[float] = None,
    label: Optional[float] = None,
    *,
    component: Union[str, int] = "largest",
    zkh: bool = True,
    **options,
) -> Hull:
    """The exact convex hull of the object (``chisel hull``): samples ≥
    ``level`` or == ``label``, its ``component`` (``"largest"``, ``"all"``
    or a 1-based number in file order), with its ZKHs. Options as
    :func:`scan`: ``corners``, ``vertices``, ``coplanar``, ``order``."""
    v = as_volume(volume)
    kw = check_options(options, HULL_OPTIONS, "hull")
    figures, vertices, faces, (mv, mt) = _chisel.hull(
        v.array, v._frame(), level, label, str(component), zkh, **kw
    )
    f = json.loads(figures)
    planes = np.array(
        [[*p["normal"], p["offset"]] for p in f["planes"]], dtype=np.int64
    ).reshape(-1, 4)
    return Hull(
        vertices, faces, planes, Mesh(mv, mt), f["cells"], f["hull"], f["object"],
        f["candidates"], f["zkh"], f["zkh_skipped"],
    )


def polyhedrize(
    volume: Union[Volume, np.ndarray],
    level: Optional[float] = None,
    label: Optional[float] = None,
    *,
    component: Union[str, int] = "largest",
    slice: Optional[int] = None,
    overlapping_siblings: bool = False,
    balls: bool = False,
    press_in: bool = False,
    **options,
) -> Polyhedron:
    """The object's lossless polyhedron (``chisel polyhedrize``): nested
    convex shells whose signed union is exactly the object's voxels
    (seed 003 §4.5), their cells and ZKH table, and the merged surface.
    ``slice=z`` polyhedrizes one z slice (2-D). Options: ``corners``,
    ``coplanar``, ``order``, ``backend``, ``adapter``."""
    v = as_volume(volume)
    kw = check_options(options, POLYHEDRIZE_OPTIONS, "polyhedrize")
    figures, (mv, mt), kind = _chisel.polyhedrize(
        v.array, v._frame(), level, label, str(component), slice, overlapping_siblings,
        balls, press_in, **kw
    )
    f = json.loads(figures)
    return Polyhedron(
        Mesh(mv, mt), kind, f["cells"], f["polyhedron"], f["zkh"], f["topology"],
        f["object"], f["options"], f["merge_refused"],
    )


def hull_scan(
    volume: Union[Volume, np.ndarray],
    level: Optional[float] = None,
    label: Optional[float] = None,
    *,
    component: Union[str, int] = "largest",
    backend: str = "cpu",
    adapter: Optional[str] = None,
    **options,
) -> HullScan:
    """Every voxel of the object's hull box classified against the object's
    exact convex hull (the ``hull_rows`` kernel on the GPU, its CPU mirror
    otherwise; exact either way): ``sides`` uint8 (0 outside, 1 on, 2
    inside) in the volume's (z, y, x) order, starting at voxel
    ``origin`` (x, y, z). Options as :func:`hull`."""
    v = as_volume(volume)
    kw = check_options(options, HULL_OPTIONS, "hull")
    sides, origin = _chisel.hull_scan(
        v.array, v._frame(), level, label, str(component), backend=backend, adapter=adapter, **kw
    )
    x, y, z = origin
    return HullScan(sides, (int(x), int(y), int(z)))
