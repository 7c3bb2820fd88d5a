#!/usr/bin/env python3
"""Marching-cubes peers for `cargo bench --bench mc_peers`: VTK's
vtkFlyingEdges3D and vtkMarchingCubes and scikit-image's marching_cubes,
timed in this process on the volumes the bench hands over.

The bench (benches/mc_peers.rs) starts this script once as a worker and
alternates its own runs with the peers' runs. The worker reads one JSON
request per line on stdin and answers one JSON line on stdout:

  {"cmd": "load", "path": P, "dims": [nx, ny, nz], "dtype": "int16"}
      reads the raw little-endian samples (x fastest) into memory, as a
      vtkImageData sharing the numpy array and, for scikit-image, as float32
      (the type it computes in; the conversion is not timed)
      -> {"ok": true}
  {"cmd": "run", "tool": T, "level": L}
      one run of T in {"flying_edges", "marching_cubes", "skimage"}
      -> {"seconds": s, "points": n, "triangles": m}
  {"cmd": "versions"} -> {"vtk": "...", "skimage": "...", "numpy": "...",
      "vtk_threads": "..."}

`python3 mc_peers.py memory P nx ny nz dtype level tool` instead runs T once
in a fresh process and prints the growth of the resident set over the call
(peak minus the resident set before, with the peak reset through
/proc/self/clear_refs) as {"peak_bytes": b, "points": n, "triangles": m}.
"""

import json
import sys
import time

import numpy as np
import vtk
from vtk.util import numpy_support

try:
    import skimage
    from skimage.measure import marching_cubes as sk_marching_cubes
except ImportError:  # the bench reports the missing peer
    skimage = None


class Volume:
    def __init__(self, path, dims, dtype):
        nx, ny, nz = dims
        count = nx * ny * nz
        self.array = np.fromfile(path, dtype=np.dtype(dtype).newbyteorder("<"), count=count)
        if self.array.size != count:
            raise ValueError(f"{path}: {self.array.size} samples, expected {count}")
        self.array = self.array.astype(np.dtype(dtype), copy=False)
        self.image = vtk.vtkImageData()
        self.image.SetDimensions(nx, ny, nz)
        scalars = numpy_support.numpy_to_vtk(self.array, deep=False)
        scalars.SetName("samples")
        self.image.GetPointData().SetScalars(scalars)
        # scikit-image indexes (z, y, x) in C order; it computes in float.
        self.dims = dims
        self._f32 = None

    def f32(self):
        if self._f32 is None:
            nx, ny, nz = self.dims
            self._f32 = self.array.reshape(nz, ny, nx).astype(np.float32)
        return self._f32


def run(volume, tool, level):
    if tool in ("flying_edges", "marching_cubes"):
        f = vtk.vtkFlyingEdges3D() if tool == "flying_edges" else vtk.vtkMarchingCubes()
        f.SetInputData(volume.image)
        f.SetValue(0, level)
        f.ComputeNormalsOff()
        f.ComputeGradientsOff()
        f.ComputeScalarsOff()
        start = time.perf_counter()
        f.Update()
        seconds = time.perf_counter() - start
        out = f.GetOutput()
        return seconds, out.GetNumberOfPoints(), out.GetNumberOfCells()
    if tool == "skimage":
        if skimage is None:
            raise RuntimeError("scikit-image is not installed")
        a = volume.f32()
        start = time.perf_counter()
        verts, faces, _, _ = sk_marching_cubes(a, level=level, allow_degenerate=True)
        seconds = time.perf_counter() - start
        return seconds, len(verts), len(faces)
    raise ValueError(f"unknown tool {tool!r}")


def status(field):
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1]) * 1024
    raise RuntimeError(f"/proc/self/status has no {field}")


def memory(argv):
    path, nx, ny, nz, dtype, level, tool = argv
    volume = Volume(path, [int(nx), int(ny), int(nz)], dtype)
    if tool == "skimage":
        volume.f32()
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
    before = status("VmRSS")
    _, points, triangles = run(volume, tool, float(level))
    peak = status("VmHWM")
    print(json.dumps({"peak_bytes": peak - before, "points": points, "triangles": triangles}))


def worker():
    volume = None
    for line in sys.stdin:
        req = json.loads(line)
        try:
            if req["cmd"] == "load":
                volume = None
                volume = Volume(req["path"], req["dims"], req["dtype"])
                answer = {"ok": True}
            elif req["cmd"] == "run":
                seconds, points, triangles = run(volume, req["tool"], float(req["level"]))
                answer = {"seconds": seconds, "points": points, "triangles": triangles}
            elif req["cmd"] == "versions":
                threader = vtk.vtkSMPTools()
                answer = {
                    "vtk": vtk.vtkVersion.GetVTKVersion(),
                    "vtk_threads": f"{threader.GetBackend()} backend, "
                    f"{threader.GetEstimatedNumberOfThreads()} threads",
                    "skimage": skimage.__version__ if skimage else None,
                    "numpy": np.__version__,
                }
            else:
                answer = {"error": f"unknown command {req['cmd']!r}"}
        except Exception as e:  # reported to the bench, which stops
            answer = {"error": f"{type(e).__name__}: {e}"}
        print(json.dumps(answer), flush=True)


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "memory":
        memory(sys.argv[2:])
    else:
        worker()
