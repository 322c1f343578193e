"""The run: ``run(model, settings)`` steps a model and records it; a pure function of its inputs.

Each step is :meth:`srdda.step.Stepper.step` (predict, iterate over the terms,
commit); this loop only takes its outcome: an accepted step is recorded, a cut
step is repeated with the smaller Δt (the run stops when Δt falls below
``min_dt``), a diverged step ends the run with its message. Every step before
the end stays recorded. A model with stages runs them one after the other
(:func:`srdda.staging.run_stages`, each stage by :func:`run_single`);
:func:`settle` runs a model until it is at rest under its loads.
"""
from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace

import numpy as np

from .equilibrium import (RATIO_TOLERANCE, SETTLE_VELOCITY_RATIO, UnbalancedForceTerm, reached, unbalanced_force,
                          without_ratio)
from .ledger import CONTACT_ADVICE, POINT_UPDATE_ADVICE, EnergyWatch, energies
from .contact.law import ContactLaw
from .model import Model, ModelArrays
from .results import Recorder, Result
from .settings import RunSettings
from .solvers import blas_threads_for_steps, get_solver
from .staging import run_stages
from .state import State, initial_state
from .step import Stepper, default_terms, time_step_advice
from .term import CUT_CAUSES, Term

__all__ = ["run", "run_single", "settle", "Settled", "EnergyWarning", "TimeStepWarning"]


class EnergyWarning(UserWarning):
    """A run whose energy ledger shows energy created (:class:`srdda.ledger.EnergyWatch`)."""


class TimeStepWarning(UserWarning):
    """A time step far too large for the model (:func:`srdda.step.time_step_advice`)."""


def run(model: Model | ModelArrays, settings: RunSettings, progress: Callable[[int], None] | None = None,
        state: State | None = None, recorders: Sequence[Recorder] = (), keep_history: bool = True,
        stop: Callable[[State], bool] | None = None, keep_vertices: bool = True,
        extra_terms: Sequence[Term] = (), contact_law: ContactLaw | None = None) -> Result:
    """Run ``model`` for ``settings.n_steps`` steps or to ``settings.end_time``; pure (no global state).

    A model with stages (``Model.stages``) runs them one after the other
    (:func:`srdda.staging.run_stages`; ``stop`` is asked in its dynamic
    stages and ends the whole run); one without runs as :func:`run_single`
    describes.
    """
    arrays = model.arrays() if isinstance(model, Model) else model
    if arrays.stages:
        return run_stages(arrays, settings, progress, state, recorders, keep_history, keep_vertices, extra_terms,
                          contact_law, stop, run_stage=run_single)
    return run_single(arrays, settings, progress, state, recorders, keep_history, stop, keep_vertices, extra_terms,
                      contact_law)


def run_single(model: Model | ModelArrays, settings: RunSettings, progress: Callable[[int], None] | None = None,
               state: State | None = None, recorders: Sequence[Recorder] = (), keep_history: bool = True,
               stop: Callable[[State], bool] | None = None, keep_vertices: bool = True,
               extra_terms: Sequence[Term] = (), contact_law: ContactLaw | None = None) -> Result:
    """Run ``model`` (its stages left aside) for ``settings.n_steps`` steps or to ``settings.end_time``.

    Steps are recorded every ``settings.record_every`` steps (and the first and
    last) into the returned :class:`Result` and every extra ``recorders``.
    ``keep_history=False`` keeps only the first and last recorded step in the
    Result (stream long runs to a :class:`~srdda.io.results_store.ResultsStore`);
    ``keep_vertices=False`` leaves the vertices out of its histories (large models).
    A run that cannot go on (singular system, non-finite values, Δt below its
    minimum) ends with ``result.status`` saying why. ``extra_terms`` join the
    step after the default ones (:func:`srdda.step.default_terms`; a term's
    carried state lives in ``State.carried[term.name]``); ``contact_law``
    replaces the joints' Mohr-Coulomb law (docs/architecture.md). ``stop(state)``, called after every
    accepted step, ends the run (completed, that step recorded) when it returns True.
    """
    arrays = model.arrays() if isinstance(model, Model) else model
    terms = [*default_terms(arrays, settings, contact_law), *extra_terms]
    solver = get_solver(settings.solver, settings.solver_tolerance, settings.resolved_device(arrays.n_unknowns))
    stepper = Stepper(arrays, settings, solver, terms)
    state = state if state is not None else initial_state(arrays, stepper.method)
    result = Result(arrays.block_names, stepper.method.name, keep_history, keep_vertices=keep_vertices)
    sinks: list[Recorder] = [result, *recorders]

    def record(state: State, solves: int, energy: dict[str, float]) -> None:
        for sink in sinks:
            sink.record(arrays, state, solves, energy)

    advice = time_step_advice(arrays, settings)
    if advice is not None:
        warnings.warn(advice, TimeStepWarning, stacklevel=2)
    summary = WarningSummary()
    try:
        energy = energies(stepper.terms, arrays, state)
        record(state, 0, energy)
        # contacts must never create energy; dda0's and dda1's rotation artefacts (the paper's Tables 1-5) do
        m = stepper.method  # dda1: points moved by the exact rotation of a solve linearised at the start
        point_update = (m.kinematics, m.linearization) == ("exact-rotation", "start")
        advice = POINT_UPDATE_ADVICE if point_update else CONTACT_ADVICE
        watch = EnergyWatch(energy, advice=advice) if any(t.energy_kind == "contact" for t in stepper.terms) else None
        with blas_threads_for_steps():
            status, state = _steps(stepper, settings, state, record, watch, progress, stop, summary)
    except BaseException as exc:  # Ctrl-C, an error: a recorder that holds something lets it go
        for sink in sinks:
            abandon = getattr(sink, "abandon", None)
            if abandon is not None:
                abandon(f"interrupted ({type(exc).__name__})")
        raise
    for sink in sinks:
        sink.finish(status, state)
    summary.emit()
    return result


def _steps(stepper: Stepper, settings: RunSettings, state: State,
           record: Callable[[State, int, dict[str, float]], None],
           watch: EnergyWatch | None, progress: Callable[[int], None] | None, stop: Callable[[State], bool] | None,
           summary: WarningSummary) -> tuple[str, State]:
    """The steps of :func:`run`: returns (status, last accepted state)."""
    arrays = stepper.arrays
    last_step = state.step + settings.last_step_limit
    end_time = settings.end_time
    min_dt = settings.min_dt if settings.min_dt is not None else 1e-6 * settings.dt
    status = "completed"
    dt = state.dt_next if state.dt_next is not None else settings.dt
    while state.step < last_step and (end_time is None or not _reached(state.time, end_time, settings.dt)):
        step_dt = dt if end_time is None else min(dt, end_time - state.time)
        with summary.collect(state.step + 1):
            outcome = stepper.step(state, step_dt)
        if outcome.status == "diverged":
            status = f"diverged: {outcome.reason}"
            break
        dt = outcome.dt_next
        if outcome.status == "cut":
            state = replace(state, cuts=state.cuts + (np.array(CUT_CAUSES) == outcome.cause))
            if dt < min_dt:
                status = (f"stopped: {outcome.reason}; the time step {dt:.3g} s fell below the minimum "
                          f"{min_dt:.3g} s")
                break
            continue
        assert outcome.state is not None
        before, state = state, replace(outcome.state, dt_next=dt, cuts=state.cuts)
        overflow = _non_finite(state, ("stress", "acceleration", "points", "rotation"))
        if overflow is not None:
            status, state = f"diverged: step {state.step}: {overflow}", before
            break
        stopped = stop is not None and stop(state)
        recorded = stopped or state.step % settings.record_every == 0 or state.step == last_step or (
            end_time is not None and _reached(state.time, end_time, settings.dt))
        if watch is not None or recorded:  # the ledger every step only where it is watched
            energy = energies(stepper.terms, arrays, state)
            overflow = _non_finite(energy, [k for k, v in energy.items() if not math.isfinite(v)])
            if overflow is not None:
                status, state = f"diverged: step {state.step}: {overflow}", before
                break
            for created in watch.check(energy, arrays, before, state) if watch is not None else ():
                warnings.warn(created, EnergyWarning, stacklevel=2)
            if recorded:
                record(state, outcome.solves, energy)
        if progress is not None:
            progress(state.step)
        if stopped:
            break
    return status, state


def _non_finite(values: State | dict[str, float], names: Sequence[str]) -> str | None:
    """What of ``names`` (fields of a state, or keys of the energies) is not finite, or None if all are.

    The step itself checks the displacements and velocities; values that overflow later (a stress, an
    energy) end the run too, before the step is recorded: a run never ends "completed" with them.
    """
    bad = [n for n in names if not np.all(np.isfinite(values[n] if isinstance(values, dict) else getattr(values, n)))]
    if not bad:
        return None
    what = "energies" if isinstance(values, dict) else "values"
    return f"non-finite {what}: {', '.join(bad)} (they overflowed); the steps before it are kept"


class WarningSummary:
    """The warnings of a run's steps, collected and given once each with their count (no flood)."""

    def __init__(self) -> None:
        self.seen: dict[tuple[type[Warning], str], list[int]] = {}  # (category, message) -> [count, first step]

    @contextmanager
    def collect(self, step: int) -> Iterator[None]:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            yield
        for w in caught:
            entry = self.seen.setdefault((w.category, str(w.message)), [0, step])
            entry[0] += 1

    def emit(self) -> None:
        for (category, message), (count, first) in self.seen.items():
            times = "once" if count == 1 else f"{count} times"
            warnings.warn(f"{message} ({times} in the run, first at step {first})", category, stacklevel=3)


def _reached(time: float, end_time: float, dt: float) -> bool:
    """True once ``time`` is at ``end_time`` (to a millionth of the step, against rounding)."""
    return time >= end_time - 1e-6 * dt


@dataclass(frozen=True)
class Settled:
    """What :func:`settle` reached: the last state, its ratio, the steps taken and whether it got below the
    tolerance; ``status`` is the run's (``completed``, or why it stopped)."""

    state: State
    ratio: float
    steps: int
    reached: bool
    status: str


def settle(model: Model | ModelArrays, settings: RunSettings, state: State | None = None,
           tolerance: float = RATIO_TOLERANCE, max_steps: int = 20000,
           velocity_ratio: float | None = SETTLE_VELOCITY_RATIO,
           recorders: Sequence[Recorder] = (), extra_terms: Sequence[Term] = (),
           contact_law: ContactLaw | None = None, progress: Callable[[int], None] | None = None) -> Settled:
    """Bring ``model`` to rest under its loads from ``state`` (default: its initial state).

    Damped dynamic steps (``velocity_ratio``, 0.8 by default; 0 is Shi's static mode, None keeps the
    settings') until the unbalanced-force ratio (:mod:`srdda.equilibrium`) falls below ``tolerance`` or ``max_steps``
    steps are taken. ``settings`` give Δt, the method and the contact model; their steps and end time
    are replaced by ``max_steps``. ``recorders``, ``extra_terms`` and ``contact_law`` are those of
    :func:`srdda.simulation.run`. Returns the last state, the ratio it reached, the steps taken and
    whether the ratio fell below ``tolerance``.
    """
    arrays = model.arrays() if isinstance(model, Model) else model
    chosen = replace(settings, n_steps=max_steps, end_time=None)
    if velocity_ratio is not None:
        chosen = replace(chosen, velocity_ratio=velocity_ratio)
    start = state.step if state is not None else 0
    state = without_ratio(state) if state is not None else None
    result = run_single(arrays, chosen, progress=progress, state=state, recorders=recorders, keep_history=False,
                        stop=lambda s: reached(s, tolerance), extra_terms=[*extra_terms, UnbalancedForceTerm()],
                        contact_law=contact_law)
    final = result.final_state
    assert final is not None
    carried = unbalanced_force(final)
    ratio = carried.ratio if carried is not None else float("nan")
    return Settled(final, ratio, final.step - start, carried is not None and ratio < tolerance, result.status)
