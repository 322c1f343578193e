"""Factor of safety by shear strength reduction, as UDEC and 3DEC compute it (docs/factor-of-safety.md).

The joints' strength is divided by a trial factor F: cohesion c/F, friction
φ_F = arctan(tan φ / F), and the tensile strength T/F like the cohesion (3DEC
reduces tension with cohesion). The reduced model is brought to rest from its
initial state by an equilibrium run (:func:`settle_displacements`, the one run
that is judged) and judged by :class:`FailureCriterion`: it *fails* when the
largest displacement of its movable blocks keeps growing at a rate that does
not decay, it is *stable* when it settles. The factor of safety FS is the F
between the largest stable and the smallest failed factor: the bracket is found
from ``initial`` by doubling (or halving), then narrowed until it is narrower
than ``tolerance`` × F. Each round tries ``points`` factors (1: bisection); they
are independent runs, so they may run in parallel on Dask (``workers``), and the
trials and FS depend on ``points``, never on ``workers``.
"""
from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from ..model import JointTable, Model, ModelArrays, ModelError
from ..settings import RunSettings, ContactSolverName
from ..simulation import run_single
from ..step import shi_step_bound

__all__ = ["FailureCriterion", "FactorOfSafety", "FosError", "Trial", "factor_of_safety", "reduce_strength",
           "settle_displacements", "settle_dt", "judge", "rest_threshold", "try_factor"]

# the bracket search doubles (halves) F from ``initial`` this many times at most before giving up
SEARCH_DOUBLINGS = 10


class FosError(ValueError):
    """The factor of safety cannot be found (the message says why: no failure, no stable factor, bad input)."""


@dataclass(frozen=True)
class FailureCriterion:
    """How a reduced model is run and judged (docs/factor-of-safety.md, *The failure criterion*).

    The run: ``steps`` steps of Shi's static analysis (``velocity_ratio = 0``:
    each step starts at rest, so a block moves only as far as the unbalanced
    force takes it in one step) with Δt = ``dt`` (None: Shi's bound
    sqrt(2·g2·w0/|g|), the largest step the displacement limit allows, which
    settles a stable model in a few steps) and the contact solve
    ``contact_solver`` (Newton: the open-close iteration lets the wedge creep
    in static steps at F = 1, its FS being 1.2). D(k): the largest centroid
    displacement of a movable block from the start, after step k. With the
    window w = steps // 3, growth = D(N) − D(N − w) and previous =
    D(N − w) − D(N − 2w): the model fails when growth ≥ ``decay`` × previous
    (the rate is not decaying) and growth exceeds the threshold
    ``acceleration`` × |g| × ½Δt² × w, the growth of a block whose unbalanced
    acceleration is that fraction of gravity (a static step from rest moves a
    block ½ a Δt²). A run that stops (diverged, Δt below its minimum) fails too.
    """

    steps: int = 60
    dt: float | None = None
    contact_solver: ContactSolverName = "newton"
    decay: float = 0.5
    acceleration: float = 1e-4

    def __post_init__(self) -> None:
        if self.steps < 6:
            raise FosError(f"criterion steps must be at least 6 (three windows of 2), got {self.steps}")
        if self.dt is not None and not 0.0 < self.dt < math.inf:
            raise FosError(f"criterion dt must be a positive time step (s), got {self.dt}")
        if not 0.0 < self.decay <= 1.0:
            raise FosError(f"criterion decay must lie in (0, 1], got {self.decay}")
        if not 0.0 < self.acceleration < math.inf:
            raise FosError(f"criterion acceleration must be a positive fraction of g, got {self.acceleration}")

    @property
    def window(self) -> int:
        return self.steps // 3


@dataclass(frozen=True)
class Trial:
    """One reduced run: its factor F, its verdict and the measure it was judged by (m)."""

    factor: float
    failed: bool
    growth: float  # D(N) − D(N − w): displacement gained over the last window (m)
    previous: float  # D(N − w) − D(N − 2w): over the window before (m)
    threshold: float  # the growth (m) below which the model is at rest: acceleration × |g| × ½Δt² × w
    displacement: float  # D(N) (m)
    status: str  # the run's status ("completed", or why it stopped)
    seconds: float
    notes: tuple[str, ...] = ()  # the run's warnings, once each

    @property
    def rate_ratio(self) -> float:
        """growth / previous: about 1 for a block sliding steadily, 0 for one at rest (nan when both are 0)."""
        return self.growth / self.previous if self.previous > 0.0 else (math.inf if self.growth > 0 else math.nan)


@dataclass(frozen=True)
class FactorOfSafety:
    """FS = the middle of the bracket [stable, failed], the trials that found it, and how they were judged."""

    factor_of_safety: float
    stable: float  # the largest factor at which the model settled
    failed: float  # the smallest factor at which it failed
    tolerance: float
    joints: tuple[str, ...]  # the joint materials reduced
    criterion: FailureCriterion
    trials: tuple[Trial, ...] = field(default_factory=tuple)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-able dictionary (``srdda fos --json``)."""
        out = asdict(self)
        out["trials"] = [{**asdict(t), "rate_ratio": t.rate_ratio} for t in self.trials]
        return out


def _joint_rows(model: Model, joints: Sequence[str] | None) -> tuple[np.ndarray, tuple[str, ...]]:
    """Rows of the joint table to reduce (all: the default joint and every joint material) and their names."""
    names = list(model.joint_materials)
    if joints is None:
        return np.arange(len(names) + 1), ("default", *names)
    if not joints:
        raise FosError("joints: name at least one joint material (or give None: all)")
    unknown = [j for j in joints if j not in model.joint_materials]
    if unknown:
        raise FosError(f"joints: unknown joint material {', '.join(map(repr, unknown))}; the model's are: "
                       f"{', '.join(map(repr, names)) or 'none'}")
    return np.array([names.index(j) + 1 for j in joints]), tuple(joints)


def reduce_strength(arrays: ModelArrays, rows: np.ndarray, factor: float) -> ModelArrays:
    """``arrays`` with the joints of ``rows`` reduced by ``factor``: c/F, arctan(tan φ / F), T/F."""
    j = arrays.joints
    friction, cohesion, tension = j.friction_angle.copy(), j.cohesion.copy(), j.tensile_strength.copy()
    friction[rows] = np.arctan(np.tan(friction[rows]) / factor)
    cohesion[rows] /= factor
    tension[rows] /= factor
    return replace(arrays, joints=JointTable(friction, cohesion, tension, j.normal_stiffness, j.shear_stiffness,
                                             j.restitution))


def settle_dt(arrays: ModelArrays, settings: RunSettings, criterion: FailureCriterion) -> float:
    """Δt of the equilibrium runs: the criterion's, else Shi's bound (:func:`~srdda.step.shi_step_bound`)."""
    return criterion.dt if criterion.dt is not None else shi_step_bound(arrays, settings) or settings.dt


def settle_displacements(arrays: ModelArrays, settings: RunSettings, criterion: FailureCriterion
                         ) -> tuple[np.ndarray, str]:
    """The run that is judged: the equilibrium run of ``arrays`` from rest, and D(k) after every step.

    The blocks start at rest (initial velocities are left out), in their
    initial positions and stresses. Returns (D (steps + 1,): the largest
    centroid displacement of a movable
    block from the start (m), the run's status). The one place where the
    equilibrium run is made: an equilibrium stage's settle may replace it.
    """
    dt = settle_dt(arrays, settings, criterion)
    static = replace(settings, velocity_ratio=0.0, contact_solver=criterion.contact_solver, dt=dt,
                     n_steps=criterion.steps, end_time=None, record_every=1, min_dt=None)
    at_rest = replace(arrays, block_velocity=np.zeros_like(arrays.block_velocity))  # the initial velocities left out
    result = run_single(at_rest, static, keep_vertices=False)  # the model as built (its stages left aside)
    movable = ~arrays.block_fixed
    centroid = result.array("centroid")[:, movable]
    moved = np.linalg.norm(centroid - centroid[0], axis=-1)
    return (moved.max(axis=1) if moved.shape[1] else np.zeros(len(moved))), result.status


def judge(factor: float, displacement: np.ndarray, status: str, criterion: FailureCriterion, threshold: float,
          seconds: float = 0.0, notes: tuple[str, ...] = ()) -> Trial:
    """The verdict of :class:`FailureCriterion` on the displacements D(k) of a run at ``factor``
    (``threshold``: :func:`rest_threshold`)."""
    last = len(displacement) - 1
    middle = last - criterion.window  # the steps ending the two windows judged
    first = middle - criterion.window
    completed = status == "completed" and first >= 0
    growth = float(displacement[last] - displacement[middle]) if completed else math.nan
    previous = float(displacement[middle] - displacement[first]) if completed else math.nan
    failed = not completed or (growth > threshold and growth >= criterion.decay * previous)
    return Trial(float(factor), bool(failed), growth, previous, threshold, float(displacement[-1]), status, seconds,
                 notes)


def rest_threshold(arrays: ModelArrays, settings: RunSettings, criterion: FailureCriterion) -> float:
    """The growth over a window (m) below which a model is at rest: acceleration × |g| × ½Δt² × w."""
    dt = settle_dt(arrays, settings, criterion)
    return criterion.acceleration * float(np.linalg.norm(arrays.gravity)) * 0.5 * dt * dt * criterion.window


def try_factor(arrays: ModelArrays, settings: RunSettings, rows: np.ndarray, factor: float,
               criterion: FailureCriterion) -> Trial:
    """Reduce the joints of ``rows`` by ``factor``, run the settle and judge it (a Dask task)."""
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        displacement, status = settle_displacements(reduce_strength(arrays, rows, factor), settings, criterion)
    notes = tuple(sorted({str(w.message) for w in caught}))
    return judge(factor, displacement, status, criterion, rest_threshold(arrays, settings, criterion),
                 time.perf_counter() - start, notes)


def _next_factors(stable: float | None, failed: float | None, initial: float, points: int) -> list[float]:
    """The factors of the next round: doubling up from the largest stable, halving down from the smallest
    failed, or ``points`` equally spaced inside the bracket."""
    if stable is None and failed is None:
        return [initial * 2.0**i for i in range(points)]
    if failed is None:
        assert stable is not None
        return [stable * 2.0 ** (i + 1) for i in range(points)]
    if stable is None:
        return [failed * 0.5 ** (i + 1) for i in range(points)]
    return [stable + (failed - stable) * (i + 1) / (points + 1) for i in range(points)]


def factor_of_safety(model: Model, settings: RunSettings, joints: Sequence[str] | None = None,
                     tolerance: float = 0.005, initial: float = 1.0, points: int = 1,
                     criterion: FailureCriterion | None = None, workers: int | None = None,
                     scheduler: str | None = None, processes: bool = True,
                     progress: Callable[[Trial], None] | None = None) -> FactorOfSafety:
    """The factor of safety of ``model`` by shear strength reduction (module doc).

    ``joints``: the joint materials to reduce (None: all, the default joint
    included); ``tolerance``: the bracket [stable, failed] is narrowed until
    failed − stable ≤ tolerance × stable; ``initial``: the first factor tried;
    ``points``: factors tried per round. ``workers`` (processes of a local
    Dask cluster; ``processes=False``: threads of this process, for tests) or
    ``scheduler`` (a running one's address) run each round's factors in
    parallel; without them they run here, one after the other.
    ``progress(trial)`` is called after each trial.
    """
    criterion = criterion or FailureCriterion()
    if not 0.0 < tolerance < 1.0:
        raise FosError(f"tolerance must lie in (0, 1) (a fraction of F), got {tolerance}")
    if not 0.0 < initial < math.inf:
        raise FosError(f"initial must be a positive factor, got {initial}")
    if points < 1:
        raise FosError(f"points must be at least 1, got {points}")
    rows, names = _joint_rows(model, joints)
    try:
        arrays = model.arrays()
    except ModelError as exc:
        raise FosError(str(exc)) from None
    if arrays.block_fixed.all():
        raise FosError("every block is fixed: nothing can fail")
    if not np.any(arrays.gravity):
        raise FosError("the model has no gravity: strength reduction brings a model to rest under its weight")
    trials: list[Trial] = []
    stable: float | None = None
    failed: float | None = None

    def evaluate(factors: list[float], submit: Callable[[list[float]], list[Trial]]) -> None:
        nonlocal stable, failed
        for trial in submit(factors):
            trials.append(trial)
            if progress is not None:
                progress(trial)
        for trial in trials[-len(factors):]:
            if trial.failed and (failed is None or trial.factor < failed):
                failed = trial.factor
        below = [t.factor for t in trials if not t.failed and (failed is None or t.factor < failed)]
        stable = max(below) if below else None

    def search(submit: Callable[[list[float]], list[Trial]]) -> None:
        while True:
            if stable is not None and failed is not None and failed - stable <= tolerance * stable:
                return
            if stable is None and failed is not None and failed < initial * 0.5**SEARCH_DOUBLINGS:
                raise FosError(f"the model fails even with its joints' strength multiplied by {1 / failed:g} "
                               f"(F = {failed:g}): it fails under its own weight whatever the joints")
            if failed is None and stable is not None and stable > initial * 2.0**SEARCH_DOUBLINGS:
                raise FosError(f"the model stands with its joints' strength divided by {stable:g}: it does not "
                               "rest on the joints reduced (fixed blocks, bolts or other joints hold it)")
            evaluate(_next_factors(stable, failed, initial, points), submit)

    if workers is None and scheduler is None:
        search(lambda factors: [try_factor(arrays, settings, rows, f, criterion) for f in factors])
    else:
        from .ensemble.runner import dask_client

        with dask_client(workers, scheduler, processes) as client:
            def on_dask(factors: list[float]) -> list[Trial]:
                futures = [client.submit(try_factor, arrays, settings, rows, f, criterion, pure=False)
                           for f in factors]
                return [future.result() for future in futures]

            search(on_dask)
    assert stable is not None and failed is not None
    return FactorOfSafety(0.5 * (stable + failed), stable, failed, tolerance, names, criterion, tuple(trials))
