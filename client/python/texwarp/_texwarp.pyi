"""Type stubs of texwarp's C++ extension (_texwarp): Client, Job, run_local / submit_local, warp / map_points."""

from typing import Any, Callable, Literal, TypeVar, overload

import numpy as np
import numpy.typing as npt

__version__: str

JobDict = dict[str, Any]  # a job in the job JSON form (the body of POST /v1/jobs)
Result = dict[str, Any]  # {"job_id": str, "state": str, "files": list[str], "report": dict}
Progress = Callable[[float, str], object]  # progress(fraction 0–1, state)
Features = dict[str, Any] | list[dict[str, Any]]  # the feature-file form, or its "features" list alone

# The dtypes warp takes; it returns the same for integers, float32 for floats. numpy's stubs count a narrower float as
# a subtype of a wider one (float16 < float32 < float64): float64 arrays have the first overloads, which give float32,
# float16 ones fall to ImageArray's float32.
ImageArray = TypeVar("ImageArray", npt.NDArray[np.uint8], npt.NDArray[np.uint16], npt.NDArray[np.float32])

class Job:
    @property
    def id(self) -> str: ...
    @property
    def state(self) -> str: ...
    @property
    def progress(self) -> float: ...
    @property
    def done(self) -> bool: ...
    @property
    def error(self) -> dict[str, Any] | None: ...
    def poll(self) -> bool: ...
    def wait(self, timeout: float | None = None, progress: Progress | None = None) -> str: ...
    def cancel(self) -> None: ...
    def fetch(self, out_dir: str) -> Result: ...

class Client:
    def __init__(self, server_url: str = "http://127.0.0.1:8080", token: str = "", retry_budget: float = 60.0,
                 request_timeout: float = 60.0) -> None: ...
    @property
    def server_url(self) -> str: ...
    def submit(self, job: JobDict) -> Job: ...
    def run(self, job: JobDict, out_dir: str, timeout: float | None = None,
            progress: Progress | None = None) -> Result: ...
    def upload_file(self, path: str) -> str: ...
    def status(self, job_id: str) -> dict[str, Any]: ...
    def ready(self) -> dict[str, Any]: ...

def submit_local(job: JobDict, base_dir: str | None = None) -> Job: ...
def run_local(job: JobDict, out_dir: str, base_dir: str | None = None, timeout: float | None = None,
              progress: Progress | None = None) -> Result: ...

@overload
def warp(  # type: ignore[misc]  # the float overloads "overlap" only by numpy's nbit subtyping (above)
         image: npt.NDArray[np.float64], features: Features, *, width: int | None = None, height: int | None = None,
         interpolation: Literal["bilinear", "bicubic"] = "bilinear",
         border: Literal["transparent", "clamp", "repeat"] = "transparent",
         filter: Literal["footprint", "point"] = "footprint", role: Literal["color", "data", "normal"] | None = None,
         color_space: str | None = None, normal_convention: Literal["opengl", "directx"] = "opengl",
         tolerance_px: float = 0.05, exact: bool = False, backend: str = "opencl", threads: int = 0,
         alpha: float | None = None, prealign: Literal["similarity", "none"] | None = None,
         return_report: Literal[False] = False) -> npt.NDArray[np.float32]: ...
@overload
def warp(  # type: ignore[misc]  # the float overloads "overlap" only by numpy's nbit subtyping (above)
         image: npt.NDArray[np.float64], features: Features, *, width: int | None = None, height: int | None = None,
         interpolation: Literal["bilinear", "bicubic"] = "bilinear",
         border: Literal["transparent", "clamp", "repeat"] = "transparent",
         filter: Literal["footprint", "point"] = "footprint", role: Literal["color", "data", "normal"] | None = None,
         color_space: str | None = None, normal_convention: Literal["opengl", "directx"] = "opengl",
         tolerance_px: float = 0.05, exact: bool = False, backend: str = "opencl", threads: int = 0,
         alpha: float | None = None, prealign: Literal["similarity", "none"] | None = None,
         return_report: Literal[True]) -> tuple[npt.NDArray[np.float32], dict[str, Any]]: ...
@overload
def warp(image: ImageArray, features: Features, *, width: int | None = None, height: int | None = None,
         interpolation: Literal["bilinear", "bicubic"] = "bilinear",
         border: Literal["transparent", "clamp", "repeat"] = "transparent",
         filter: Literal["footprint", "point"] = "footprint", role: Literal["color", "data", "normal"] | None = None,
         color_space: str | None = None, normal_convention: Literal["opengl", "directx"] = "opengl",
         tolerance_px: float = 0.05, exact: bool = False, backend: str = "opencl", threads: int = 0,
         alpha: float | None = None, prealign: Literal["similarity", "none"] | None = None,
         return_report: Literal[False] = False) -> ImageArray: ...
@overload
def warp(image: ImageArray, features: Features, *, width: int | None = None, height: int | None = None,
         interpolation: Literal["bilinear", "bicubic"] = "bilinear",
         border: Literal["transparent", "clamp", "repeat"] = "transparent",
         filter: Literal["footprint", "point"] = "footprint", role: Literal["color", "data", "normal"] | None = None,
         color_space: str | None = None, normal_convention: Literal["opengl", "directx"] = "opengl",
         tolerance_px: float = 0.05, exact: bool = False, backend: str = "opencl", threads: int = 0,
         alpha: float | None = None, prealign: Literal["similarity", "none"] | None = None,
         return_report: Literal[True]) -> tuple[ImageArray, dict[str, Any]]: ...

def map_points(points: npt.ArrayLike, features: Features, *, inverse: bool = False, backend: str = "opencl",
               threads: int = 0) -> npt.NDArray[np.float64]: ...
