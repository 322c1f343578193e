"""The solver interface and the table of named solvers: :func:`register_solver`, :func:`get_solver`.

Every backend, srdda's own included, is one entry of the table, added by :func:`register_solver`
(srdda's by the modules that define them: :mod:`._direct`, :mod:`._iterative`, :mod:`._auto`,
:mod:`._gpu`), so that a new backend plugs in from its own module without editing a table here.
"""
from __future__ import annotations

import importlib.util
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, Protocol

import numpy as np

if TYPE_CHECKING:
    from ..assembly.system import BlockSystem

__all__ = ["LinearSolver", "SolverError", "SolverFactory", "DEFAULT_TOLERANCE", "DEVICES", "register_solver",
           "get_solver", "available_solvers", "best_direct", "check_finite", "solves_inexactly"]

# The iterative backends stop when every unknown of the increment is estimated within this of the exact
# solution (m; rad and 1 for rotations and strains, i.e. m per m of block size): 1e-9 m keeps 200 steps
# of the 1,000-block slope within the 1e-6 m of the direct run even if the errors all added up.
DEFAULT_TOLERANCE = 1e-9
DEVICES = ("cpu", "gpu")  # where a registered factory's solves run


class SolverError(RuntimeError):
    """The global system could not be solved (singular or not finite)."""


class LinearSolver(Protocol):
    """A backend: ``solve`` returns the increments of ``system`` for ``rhs``.

    A backend that stops at a displacement tolerance also has
    ``inexact(system) -> bool`` (True where it stops that system at one) and
    takes ``tolerance`` (m), one solve's tolerance in place of its own (a
    Newton iteration asks for a looser one while its contacts still change
    state, :func:`solves_inexactly`); one without ``inexact`` is exact and is
    never passed a tolerance.
    """

    name: str

    def solve(self, system: BlockSystem, rhs: np.ndarray, tolerance: float | None = None) -> np.ndarray: ...


def solves_inexactly(solver: LinearSolver, system: BlockSystem) -> bool:
    """Whether ``solver`` stops ``system`` at a tolerance (its ``inexact``; a backend without one is exact)."""
    inexact = getattr(solver, "inexact", None)
    return bool(inexact(system)) if inexact is not None else False


def takes_springs(solver: LinearSolver, n_blocks: int) -> bool:
    """Whether ``solver`` applies a system's penalty springs itself, unsummed (its ``takes_springs``, for
    systems of ``n_blocks`` blocks; a backend without one reads the assembled matrix)."""
    takes = getattr(solver, "takes_springs", None)
    return bool(takes(n_blocks)) if takes is not None else False


SolverFactory = Callable[[float], LinearSolver]  # the displacement tolerance (m) -> a solver for one run


@dataclass(frozen=True)
class _Entry:
    factory: SolverFactory
    requires: str | None  # the module the backend needs (find_spec), None for none


_TABLE: dict[tuple[str, str], _Entry] = {}


def register_solver(name: str, factory: SolverFactory, *, device: Literal["cpu", "gpu"] = "cpu",
                    requires: str | None = None, replace: bool = False) -> None:
    """Add the backend ``name``: ``factory(tolerance)`` makes one solver for one run.

    ``tolerance`` (m) is the run's ``solver_tolerance``, the stopping rule of an iterative backend (a
    direct one ignores it). ``device``: where its solves run (``get_solver(..., device=...)``).
    ``requires``: the module it imports, so that :func:`available_solvers` lists it only where that
    module is installed. A name already registered for the device is a ValueError unless ``replace``.
    """
    if device not in DEVICES:
        raise ValueError(f"unknown device {device!r} for a solver; choose one of {', '.join(DEVICES)}")
    if (name, device) in _TABLE and not replace:
        raise ValueError(f"solver {name!r} is already registered for device {device!r} (replace=True replaces it)")
    _TABLE[name, device] = _Entry(factory, requires)


def _names(device: str) -> list[str]:
    return [n for n, d in _TABLE if d == device]


def available_solvers() -> list[str]:
    """Names of the backends usable on this machine (the CPU's, in the order they were registered)."""
    return [n for n in _names("cpu")
            if _TABLE[n, "cpu"].requires is None or importlib.util.find_spec(str(_TABLE[n, "cpu"].requires))]


def get_solver(name: str = "auto", tolerance: float = DEFAULT_TOLERANCE, device: str = "cpu") -> LinearSolver:
    """The backend called ``name`` (see the package doc); ``tolerance`` (m) is the iterative backends' stopping rule.

    ``device="gpu"``: ``cg-jacobi``, or ``auto`` with its conjugate gradient, on a CUDA GPU through CuPy
    (:func:`srdda.solvers.gpu_solver`; ``RunSettings.resolved_device`` chooses).
    """
    if name not in _names("cpu") + _names("gpu"):
        raise ValueError(f"unknown solver {name!r}; choose one of {sorted(set(_names('cpu') + _names('gpu')))}")
    if device not in DEVICES:
        raise ValueError(f"unknown device {device!r} for a solver; choose 'cpu' or 'gpu'")
    if device == "gpu":
        if (name, "gpu") not in _TABLE:
            raise ValueError(f"solver {name!r} has no GPU backend; with device 'gpu' choose one of "
                             f"{', '.join(_names('gpu'))}")
        return _TABLE[name, "gpu"].factory(tolerance)
    if name not in available_solvers():
        raise ValueError(f"solver {name!r} is not installed (pip install srdda[{name}])")
    return _TABLE[name, "cpu"].factory(tolerance)


def best_direct() -> LinearSolver:
    """The fastest installed direct backend for large systems (measured in docs/performance.md)."""
    return get_solver(next(n for n in ("pardiso", "cholmod", "block-cholesky") if n in available_solvers()))


def check_finite(x: np.ndarray) -> np.ndarray:
    """``x``, or a :class:`SolverError` if an entry is not finite (a singular or ill-posed system)."""
    if not np.all(np.isfinite(x)):
        raise SolverError("the solution is not finite: the system is singular or ill-posed")
    return x
