"""Array backends (numpy on the CPU, CuPy on a CUDA GPU) and the choice of ``RunSettings.device``.

An :class:`ArrayBackend` names the array module ``xp`` and its sparse module; code written on
them (:mod:`srdda.solvers._gpu`) uses only what numpy and CuPy share, so the same
lines run on numpy in CI and on CuPy on a GPU. The array API standard (and ``array-api-compat``)
has no sparse matrices, which the solve needs, so the backend pairs the two modules itself.

CuPy is optional (``pip install srdda[gpu]``, see docs/dependencies.md) and imported only when a
GPU is asked for, or when ``device = "auto"`` meets a model of at least :data:`GPU_MIN_UNKNOWNS`
unknowns and CuPy is installed.
"""
from __future__ import annotations

import functools
import importlib.util
from dataclasses import dataclass
from types import ModuleType
from typing import Any, Literal, get_args

import numpy as np
import scipy.sparse

__all__ = ["ArrayBackend", "DEVICES", "DeviceName", "GPU_MIN_UNKNOWNS", "GPU_SOLVERS", "GpuUnavailable", "cupy_backend",
           "gpu_problem", "numpy_backend", "resolve_device"]

DeviceName = Literal["cpu", "gpu", "auto"]
DEVICES: tuple[DeviceName, ...] = get_args(DeviceName)
# solvers with a GPU backend: the block-Jacobi conjugate gradient, and ``auto``, whose large systems use it
GPU_SOLVERS = ("auto", "cg-jacobi")
# ``device = "auto"`` takes the GPU for models of at least this many unknowns (blocks × ndof): measured on an H200
# machine against its 16 cores, the 10,051-block 2D wall (60,306 unknowns) ran slower on the GPU (4.15 against
# 5.07 steps a second), the 3D wall of 10,000 blocks (120,000) and the 2D wall of 100,000 blocks (600,000) as fast
# or faster (docs/gpu.md)
GPU_MIN_UNKNOWNS = 100_000


class GpuUnavailable(ValueError):
    """A GPU was asked for where CuPy or a CUDA device is missing (bad input for this machine)."""


@dataclass(frozen=True)
class ArrayBackend:
    """An array module ``xp`` (numpy or cupy) and its sparse-matrix module (scipy.sparse or cupyx.scipy.sparse)."""

    name: Literal["numpy", "cupy"]
    xp: ModuleType
    sparse: ModuleType

    def to_device(self, array: np.ndarray) -> Any:
        """``array`` (host) on this backend's device: a copy to the GPU for CuPy, the array itself for numpy."""
        return self.xp.asarray(array)

    def to_host(self, array: Any) -> np.ndarray:
        """``array`` as a numpy array (a copy from the GPU for CuPy)."""
        return array.get() if self.name == "cupy" else np.asarray(array)

    def scatter_add(self, target: Any, index: Any, values: Any) -> None:
        """``target[index[i]] += values[i]`` for every i, repeated indices summed (atomically on a GPU, so in no
        fixed order there)."""
        if self.name == "cupy":
            import cupyx

            cupyx.scatter_add(target, index, values)
        else:
            np.add.at(target, index, values)

    def cholesky(self, blocks: Any) -> Any:
        """The lower Cholesky factors of symmetric blocks (n, m, m); ``numpy.linalg.LinAlgError`` where one is not
        positive definite (CuPy says so only when asked: its default gives a factor of garbage)."""
        if self.name == "cupy":
            import cupyx

            with cupyx.errstate(linalg="raise"):
                return self.xp.linalg.cholesky(blocks)
        return np.linalg.cholesky(blocks)

    def synchronize(self) -> None:
        """Wait until the device has done the work queued so far (for timings); nothing to wait for on numpy."""
        if self.name == "cupy":
            self.xp.cuda.Device().synchronize()

    def device_name(self) -> str:
        """The device the arrays live on: "cpu", or the GPU's name as CUDA reports it."""
        if self.name == "numpy":
            return "cpu"
        props = self.xp.cuda.runtime.getDeviceProperties(self.xp.cuda.Device().id)
        name = props["name"]
        return name.decode() if isinstance(name, bytes) else str(name)

    def memory_high_water_bytes(self) -> int | None:
        """Bytes CuPy's memory pool holds: it keeps every block it got, so this is its high-water mark.

        None on numpy (the process's resident peak covers it).
        """
        return int(self.xp.get_default_memory_pool().total_bytes()) if self.name == "cupy" else None


def numpy_backend() -> ArrayBackend:
    """The CPU backend: numpy and scipy.sparse."""
    return ArrayBackend("numpy", np, scipy.sparse)


@functools.cache
def gpu_problem() -> str | None:
    """Why no GPU can be used here (CuPy missing, or no CUDA device), or None when one can."""
    if importlib.util.find_spec("cupy") is None:
        return "CuPy is not installed: pip install srdda[gpu] (CUDA 12) or srdda[gpu-cuda13] (CUDA 13)"
    try:
        import cupy

        count = cupy.cuda.runtime.getDeviceCount()
    except Exception as exc:  # ImportError of a broken install, CUDARuntimeError without a driver
        return f"CuPy cannot reach a CUDA device ({type(exc).__name__}: {exc})"
    if count < 1:
        return "CuPy found no CUDA device"
    return None


def cupy_backend() -> ArrayBackend:
    """The GPU backend (CuPy and cupyx.scipy.sparse); :class:`GpuUnavailable` saying why when there is none."""
    problem = gpu_problem()
    if problem is not None:
        raise GpuUnavailable(f"no GPU: {problem}")
    import cupy
    import cupyx.scipy.sparse

    return ArrayBackend("cupy", cupy, cupyx.scipy.sparse)


def resolve_device(device: str, solver: str, unknowns: int) -> Literal["cpu", "gpu"]:
    """Where a run of ``n_blocks`` blocks solves: ``device`` itself, or for "auto" the GPU when the solver has
    a GPU backend, the model has at least :data:`GPU_MIN_UNKNOWNS` unknowns and a GPU is present.

    "gpu" where there is none raises :class:`GpuUnavailable` saying why, naming the setting.
    """
    if device not in DEVICES:
        raise ValueError(f"unknown device {device!r}; choose one of {', '.join(DEVICES)}")
    if device == "auto":
        wanted = solver in GPU_SOLVERS and unknowns >= GPU_MIN_UNKNOWNS
        return "gpu" if wanted and gpu_problem() is None else "cpu"
    if device == "gpu" and gpu_problem() is not None:
        raise GpuUnavailable(f"device = 'gpu' was asked for, but {gpu_problem()}; use device 'cpu' or 'auto'")
    return "gpu" if device == "gpu" else "cpu"
