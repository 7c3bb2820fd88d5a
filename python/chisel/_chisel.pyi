# Type stubs of the native module chisel._chisel (python/src/). Users call
# the package `chisel`, whose wrappers are typed in __init__.py.
from typing import Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

__version__: str

Vec3 = Tuple[float, float, float]
# (spacing, origin, axes, space), each in the engine's (x, y, z) order;
# taken as tuples, returned as lists.
Frame = Tuple[Vec3, Vec3, Tuple[Vec3, Vec3, Vec3], Optional[str]]
FrameOut = Tuple[List[float], List[float], List[List[float]], Optional[str]]
Progress = Callable[[int, int], object]

def gpu_info(adapter: Optional[str] = None) -> str: ...
def read_volume(path: str, series: Optional[str] = None) -> Tuple[np.ndarray, FrameOut, List[str]]: ...
def write_volume(path: str, array: np.ndarray, frame: Frame) -> None: ...
def read_mesh(
    path: str,
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32], Dict[str, npt.NDArray[np.float32]]]: ...
def write_mesh(
    path: str,
    vertices: npt.NDArray[np.float32],
    triangles: np.ndarray,
    scalars: Optional[Dict[str, npt.NDArray[np.float32]]] = None,
) -> None: ...
def dicom_series(dir: str) -> str: ...
def marching_cubes(
    array: np.ndarray,
    frame: Frame,
    level: Optional[float] = None,
    label: Optional[float] = None,
    close_border: bool = False,
    groups: bool = True,
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32], Optional[npt.NDArray[np.uint32]], str]: ...
def scan(
    array: np.ndarray,
    frame: Frame,
    name: str,
    level: Optional[float] = None,
    labels: bool = False,
    min_voxels: int = 1,
    corners: str = "local26",
    vertices: str = "voxels",
    coplanar: str = "merge",
    order: str = "furthest",
    backend: str = "cpu",
    adapter: Optional[str] = None,
    progress: Optional[Progress] = None,
) -> str: ...
def scan_file(
    path: str,
    level: Optional[float] = None,
    labels: bool = False,
    min_voxels: int = 1,
    corners: str = "local26",
    vertices: str = "voxels",
    coplanar: str = "merge",
    order: str = "furthest",
    backend: str = "cpu",
    adapter: Optional[str] = None,
    series: Optional[str] = None,
    progress: Optional[Progress] = None,
) -> str: ...

MeshArrays = Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32]]
Scalars = Dict[str, npt.NDArray[np.float32]]

def volume_stats(
    array: np.ndarray, frame: Frame, level: Optional[float] = None, label: Optional[float] = None
) -> str: ...
def mesh_stats(vertices: npt.NDArray[np.float32], triangles: np.ndarray) -> str: ...
def hull(
    array: np.ndarray,
    frame: Frame,
    level: Optional[float] = None,
    label: Optional[float] = None,
    component: str = "largest",
    zkh: bool = True,
    corners: str = "local26",
    vertices: str = "voxels",
    coplanar: str = "merge",
    order: str = "furthest",
) -> Tuple[str, npt.NDArray[np.int64], List[List[int]], MeshArrays]: ...
def hull_scan(
    array: np.ndarray,
    frame: Frame,
    level: Optional[float] = None,
    label: Optional[float] = None,
    component: str = "largest",
    corners: str = "local26",
    vertices: str = "voxels",
    coplanar: str = "merge",
    order: str = "furthest",
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> Tuple[npt.NDArray[np.uint8], List[int]]: ...
def polyhedrize(
    array: np.ndarray,
    frame: Frame,
    level: Optional[float] = None,
    label: Optional[float] = None,
    component: str = "largest",
    slice: Optional[int] = None,
    overlapping_siblings: bool = False,
    balls: bool = False,
    press_in: bool = False,
    corners: str = "local26",
    vertices: str = "voxels",
    coplanar: str = "merge",
    order: str = "furthest",
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> Tuple[str, MeshArrays, str]: ...
def cut(
    vertices: npt.NDArray[np.float32],
    triangles: np.ndarray,
    planes: List[Tuple[Vec3, Vec3]] = ...,
    rects: List[Tuple[Vec3, Vec3, Vec3, Tuple[float, float]]] = ...,
    spheres: List[Tuple[Vec3, float]] = ...,
    knives: List[Tuple[npt.NDArray[np.float32], np.ndarray]] = ...,
    cap: bool = False,
) -> Tuple[List[Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32], str]], str]: ...
def relax(
    skin_vertices: npt.NDArray[np.float32],
    skin_triangles: np.ndarray,
    bone: Optional[Tuple[npt.NDArray[np.float32], np.ndarray]] = None,
    plan_path: Optional[str] = None,
    plan_json: Optional[str] = None,
    solver: str = "explicit",
    force_dt: bool = False,
    bending: Optional[float] = None,
    subcutis_depth: Optional[float] = None,
    origin: Optional[Vec3] = None,
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> Tuple[MeshArrays, npt.NDArray[np.float32], str]: ...
def spline(
    vertices: npt.NDArray[np.float32],
    triangles: np.ndarray,
    n: int,
    param: str = "cylinder",
    uv: Optional[npt.NDArray[np.float64]] = None,
    fit: str = "quasi",
    data: Optional[npt.NDArray[np.float32]] = None,
    fairing: float = 0.0,
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> Tuple[
    Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32], Scalars],
    npt.NDArray[np.float64],
    MeshArrays,
    str,
]: ...
def scene_examples() -> List[Tuple[str, str]]: ...
def implicit(
    scene_path: Optional[str],
    scene_text: Optional[str],
    method: str = "particles",
    frames: int = 8,
    edge_length: Optional[float] = None,
    reports: bool = True,
    backend: str = "cpu",
    adapter: Optional[str] = None,
    progress: Optional[Progress] = None,
) -> Tuple[List[Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32], Scalars]], str]: ...
def fuse(
    meshes: Tuple[npt.NDArray[np.float32], np.ndarray, npt.NDArray[np.float32], np.ndarray],
    subtract: bool = False,
    center: Optional[Vec3] = None,
    tolerance: Optional[float] = None,
    start_level: Optional[int] = None,
    max_triangles: Optional[int] = None,
    cells: Optional[int] = None,
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> Tuple[MeshArrays, str]: ...
def morph(
    meshes: Tuple[npt.NDArray[np.float32], np.ndarray, npt.NDArray[np.float32], np.ndarray],
    frames: int = 9,
    center: Optional[Vec3] = None,
    center_end: Optional[Vec3] = None,
    tolerance: Optional[float] = None,
    start_level: Optional[int] = None,
    max_triangles: Optional[int] = None,
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32], str]: ...
def blobby_fit(
    vertices: npt.NDArray[np.float32],
    triangles: np.ndarray,
    primitives: int = 32,
    alpha: float = 0.5,
    beta: float = 1e-4,
    iso: float = 0.5,
    pair_iterations: int = 40,
    global_iterations: int = 80,
    energy_target: Optional[float] = None,
    backend: str = "cpu",
    adapter: Optional[str] = None,
) -> Tuple[npt.NDArray[np.float64], str, str]: ...
