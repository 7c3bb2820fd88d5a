"""Hull scans and polyhedra of many volume files, one task per file, on
Dask.

``scan(paths, client=None, **options)`` reads and scans every path (one
``dask.distributed`` task each on ``client``; serially in this process when
``client`` is None) and returns one report per path, in input order: the
dict ``chisel scan PATH --json`` prints with those options, or, for a file
that failed, ``{"volume": path, "error": {"type": ..., "message": ...}}``
— one failure never stops the batch (an unknown option name is raised at
once, before any task). ``polyhedrize(paths, ...)`` does
the same for :func:`chisel.polyhedrize`. ``table(reports)`` flattens scans into
one row per structure (a pandas DataFrame when pandas is installed).

The same code runs on any Dask cluster; only the client changes::

    from dask.distributed import Client
    client = Client("tcp://scheduler:8786")          # dask-jobqueue, Kubernetes, ...
    reports = chisel.batch.scan(paths, client=client, level=500)

With ``backend="gpu"``, tasks ask for the worker resource ``GPU`` when the
cluster's workers advertise one (``dask worker --resources GPU=1``), so
they run only where a GPU is.
"""

from __future__ import annotations

import uuid
from typing import Iterable, List, Optional

from . import hulls
from .hulls import POLYHEDRIZE_OPTIONS, SCAN_OPTIONS, check_options, scan_file
from .io import read_volume
from .errors import ChiselError

GPU_RESOURCE = "GPU"


def _scan_one(path: str, options: dict) -> dict:
    try:
        return scan_file(path, **options)
    except ChiselError as e:
        return _failed(path, e)


def _polyhedrize_one(path: str, options: dict) -> dict:
    try:
        volume = read_volume(path, series=options.pop("series", None))
        p = hulls.polyhedrize(volume, **options)
    except ChiselError as e:
        return _failed(path, e)
    return {
        "volume": path,
        "object": p.object,
        "topology": p.topology,
        "options": p.options,
        "polyhedron": p.summary,
        "zkh": p.zkh,
        "mesh": p.mesh_kind,
        "merge_refused": p.merge_refused,
    }


def _failed(path: str, e: ChiselError) -> dict:
    return {"volume": path, "error": {"type": type(e).__name__, "message": str(e)}}


def _gpu_resources(client, options: dict) -> Optional[dict]:
    if options.get("backend") != "gpu":
        return None
    try:  # every worker (newer distributed lists only the first few by default)
        info = client.scheduler_info(n_workers=-1)
    except TypeError:
        info = client.scheduler_info()
    workers = info.get("workers", {}).values()
    if any(GPU_RESOURCE in w.get("resources", {}) for w in workers):
        return {GPU_RESOURCE: 1}
    return None


def _map(task, name: str, paths: Iterable, client, options: dict) -> List[dict]:
    paths = [str(p) for p in paths]
    if client is None:
        return [task(p, dict(options)) for p in paths]
    resources = _gpu_resources(client, options)
    batch = uuid.uuid4().hex[:12]  # keys of concurrent batches never meet
    futures = [
        client.submit(
            task, p, dict(options), key=f"chisel-{name}-{batch}-{i}", resources=resources, pure=False
        )
        for i, p in enumerate(paths)
    ]
    return client.gather(futures)


def scan(paths: Iterable, client=None, **options) -> List[dict]:
    """One :func:`chisel.scan_file` report per path, in input order (see the
    module docs); ``options`` as :func:`chisel.scan_file` takes them."""
    check_options(options, SCAN_OPTIONS + ("level", "labels", "series"), "scan")
    return _map(_scan_one, "scan", paths, client, options)


def polyhedrize(paths: Iterable, client=None, **options) -> List[dict]:
    """One polyhedron per path (:func:`chisel.polyhedrize` of the volume
    read from it, ``series`` choosing a DICOM series), in input order: its
    ``object``, ``topology``, ``options``, ``polyhedron`` summary,
    ``zkh`` table, ``mesh`` kind and ``merge_refused`` — the fields of
    ``chisel polyhedrize --json`` — or the file's error."""
    known = POLYHEDRIZE_OPTIONS + (
        "level", "label", "component", "slice", "overlapping_siblings", "balls", "press_in", "series",
    )
    check_options(options, known, "polyhedrize")
    return _map(_polyhedrize_one, "polyhedrize", paths, client, options)


def table(reports: Iterable[dict]):
    """One row per scanned structure (path, id, label, voxels, hull faces,
    inside/on/outside, convexity, ZKH count), plus one row per failed
    file with its error: a pandas DataFrame when pandas is installed, else
    a list of dicts."""
    rows = []
    for r in reports:
        if "error" in r:
            rows.append({"volume": r["volume"], "error": r["error"]["message"]})
            continue
        for row in r["rows"]:
            hull = row.get("hull") or {}
            scan_ = row.get("scan") or {}
            zkh = row.get("zkh") or {}
            rows.append(
                {
                    "volume": r["volume"],
                    "id": row["id"],
                    "label": row["label"],
                    "voxels": row["object"]["voxels"],
                    "degenerate": row.get("degenerate"),
                    "hull_faces": hull.get("faces"),
                    "hull_volume_world": hull.get("volume_world"),
                    "inside": scan_.get("inside"),
                    "on": scan_.get("on"),
                    "outside": scan_.get("outside"),
                    "convexity": (row.get("convexity") or {}).get("digital"),
                    "zkh": zkh.get("count"),
                    "error": None,
                }
            )
    try:
        import pandas
    except ImportError:
        return rows
    return pandas.DataFrame(rows)
