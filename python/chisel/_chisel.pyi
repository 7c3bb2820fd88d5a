# Type stubs of the native module chisel._chisel (python/src/). Users call
# the package `chisel`, whose wrappers are typed in __init__.py.
from typing import Callable, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

__version__: str

Vec3 = Tuple[float, float, float]
# (spacing, origin, axes, space), each in the engine's (x, y, z) order.
Frame = Tuple[Vec3, Vec3, Tuple[Vec3, Vec3, Vec3], Optional[str]]
Progress = Callable[[int, int], object]

def gpu_info(adapter: Optional[str] = None) -> str: ...
def read_volume(path: str, series: Optional[str] = None) -> Tuple[np.ndarray, Frame, List[str]]: ...
def write_volume(path: str, array: np.ndarray, frame: Frame) -> None: ...
def read_mesh(
    path: str,
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32], Dict[str, npt.NDArray[np.float32]]]: ...
def write_mesh(path: str, vertices: npt.NDArray[np.float32], triangles: np.ndarray) -> None: ...
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
