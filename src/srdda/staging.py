"""The run of a staged analysis: the stages of :mod:`srdda.stages` one after the other, in one run.

:func:`run_stages` begins each stage from the state the one before ended in
(its changes applied, :func:`begin_stage`), runs it with
``run_stage`` (:func:`srdda.simulation.run_single`) under its settings (:func:`stage_settings`;
an equilibrium stage until the unbalanced-force ratio of :mod:`srdda.equilibrium`
falls below its tolerance) and tells the recorders each stage's begin and end
(the stage table of the results file). The stage mark rides in the state
(:class:`StageTerm`), so a run continued from a checkpoint goes on in the stage
the checkpoint is in, bit for bit. What a stage's start changes in the stored
energy goes to the ledger's ``work_stages`` (:func:`book_stage_start`), so the
energy balance of a staged run stays closed across its stages.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from .equilibrium import SETTLE_VELOCITY_RATIO, UnbalancedForceTerm, reached, unbalanced_force, without_ratio
from .ledger import energies
from .modeldata.arrays import ModelArrays
from .results import Result
from .settings import RunSettings
from .stages import CARRIED, CHANGES, StageMark, StagePlan, at_rest, initial_mark, stage_arrays, stage_mark
from .state import State, initial_state
from .step import default_terms
from .term import LEDGER, Term

if TYPE_CHECKING:
    from .contact.law import ContactLaw
    from .results import Recorder

__all__ = ["begin_stage", "book_stage_start", "stage_settings", "StageTerm", "run_stages"]


def begin_stage(base: ModelArrays, index: int, state: State, before: StageMark) -> tuple[ModelArrays, State]:
    """Stage ``index`` begun from ``state`` (the end of the stage before, marked ``before``): its arrays and
    its first state (the changes applied, its own mark carried)."""
    plan = base.stages[index]
    mark = replace(before, index=index, first_step=state.step, start_time=state.time)
    for key, value in plan.changes.items():
        change = CHANGES[key]
        if change.mark is not None:
            mark = change.mark(mark, base, state, value)
    arrays = stage_arrays(base, mark)
    for key, value in plan.changes.items():
        change = CHANGES[key]
        if change.state is not None:
            state = change.state(arrays, state, value)
    if plan.reset_displacements:
        state = replace(at_rest(np.ones(arrays.n_blocks, dtype=bool), state),
                        rotation=arrays.block_type.initial_rotation(arrays.n_blocks))
    state = replace(without_ratio(state), dt_next=None)
    return arrays, state.carrying(CARRIED, mark)


def book_stage_start(before: tuple[ModelArrays, State], after: tuple[ModelArrays, State], settings: RunSettings,
                     extra_terms: Sequence[Term] = (), contact_law: ContactLaw | None = None) -> State:
    """The first state of a stage (``after``: its arrays and state) with what its start changed in the stored
    energy since the end of the stage before (``before``) added to the ledger's ``work_stages`` (J, per m in
    2D): the kinetic, gravitational, strain, spring and contact energy of the run's terms, each side with its
    own arrays (removed blocks, materials, bolts)."""
    def stored(arrays: ModelArrays, state: State) -> float:
        return energies([*default_terms(arrays, settings, contact_law), *extra_terms], arrays, state)["total"]

    arrays, state = after
    ledger = state.ledger.copy()
    ledger[LEDGER.index("work_stages")] += stored(arrays, state) - stored(*before)
    return replace(state, ledger=ledger)


def stage_settings(settings: RunSettings, plan: StagePlan, mark: StageMark, state: State) -> RunSettings:
    """The run settings of the rest of a stage from ``state``: the model's with the stage's, its length
    counted from the stage's start (an equilibrium stage: ``max_steps``, in the damped steps of
    :func:`srdda.simulation.settle` unless the stage gives ``velocity_ratio``)."""
    chosen = replace(settings, **{k: v for k, v in plan.run.items() if k not in ("n_steps", "end_time")})
    if plan.kind == "equilibrium":
        if "velocity_ratio" not in plan.run:
            chosen = replace(chosen, velocity_ratio=SETTLE_VELOCITY_RATIO)
        return replace(chosen, n_steps=max(0, mark.first_step + plan.max_steps - state.step), end_time=None)
    given = "n_steps" in plan.run or "end_time" in plan.run
    steps = plan.run.get("n_steps") if given else settings.n_steps
    duration = plan.run.get("end_time") if given else settings.end_time
    return replace(chosen, n_steps=None if steps is None else max(0, mark.first_step + steps - state.step),
                   end_time=None if duration is None else mark.start_time + duration)


class StageTerm(Term):
    """Carries the stage mark from step to step (adds nothing to the step's system)."""

    name = CARRIED

    def __init__(self, mark: StageMark) -> None:
        self.mark = mark

    def commit(self, new: State) -> State:
        return new.carrying(self.name, self.mark)


class _Sinks:
    """The recorders of a staged run seen by the run of each stage: a step is recorded once (a stage starts
    at the step the one before ended), the recorders finish at the end of the last stage."""

    def __init__(self, sinks: Sequence[Recorder]) -> None:
        self.sinks = list(sinks)
        self.last = -1

    def record(self, arrays: ModelArrays, state: State, solves: int, energy: Mapping[str, float]) -> None:
        if state.step > self.last or self.last < 0:
            self.last = state.step
            for sink in self.sinks:
                sink.record(arrays, state, solves, energy)

    def finish(self, status: str, state: State) -> None:
        """A stage ended: nothing to do (:func:`run_stages` finishes the recorders at the end)."""

    def abandon(self, reason: str) -> None:
        for sink in self.sinks:
            abandon = getattr(sink, "abandon", None)
            if abandon is not None:
                abandon(reason)

    def stage(self, index: int, entry: Mapping[str, Any]) -> None:
        for sink in self.sinks:
            tell = getattr(sink, "stage", None)
            if tell is not None:
                tell(int(index), entry)  # a mark read from a checkpoint holds numpy integers


def _entry(plan: StagePlan, mark: StageMark) -> dict[str, Any]:
    """The stage table's row of a stage that has begun."""
    return {"name": plan.name, "kind": plan.kind, "first_step": int(mark.first_step),
            "start_time": float(mark.start_time), "reset_displacements": plan.reset_displacements,
            "removed_blocks": [int(i) for i in plan.changes.get("remove_blocks", ())]}


def _ended(entry: dict[str, Any], plan: StagePlan, state: State, status: str) -> dict[str, Any]:
    """The row of a stage that has ended in ``state`` with the run ``status``."""
    carried = unbalanced_force(state)
    ratio = None if carried is None else float(carried.ratio)
    out = {**entry, "last_step": int(state.step), "end_time": float(state.time),
           "steps": int(state.step) - entry["first_step"], "status": status, "ratio": ratio}
    if plan.kind == "equilibrium":
        out["tolerance"] = plan.tolerance
        out["reached"] = ratio is not None and ratio < plan.tolerance
    return out


def run_stages(arrays: ModelArrays, settings: RunSettings, progress: Callable[[int], None] | None = None,
               state: State | None = None, recorders: Sequence[Recorder] = (), keep_history: bool = True,
               keep_vertices: bool = True, extra_terms: Sequence[Term] = (),
               contact_law: ContactLaw | None = None, stop: Callable[[State], bool] | None = None, *,
               run_stage: Callable[..., Result]) -> Result:
    """Run the stages of ``arrays`` (``arrays.stages``) one after the other from ``state`` (default: the initial
    state; a state of a staged run, e.g. a checkpoint, continues in the stage it carries).

    Arguments as :func:`srdda.simulation.run`; ``settings`` are the model's, each stage's changing them
    (:func:`stage_settings`). ``run_stage`` runs one stage: :func:`srdda.simulation.run_single`, whose
    module calls this one (so this module does not import it). Returns one :class:`Result` of the whole run, ``result.stages`` the stage
    table (first step, start time, end, ratio reached). The run stops at the first stage that does not
    complete (diverged, or Δt below its minimum), with that stage's status. ``stop(state)``, called after
    every accepted step of the dynamic stages, ends the whole run (completed) when it returns True.
    """
    base = arrays.base if arrays.base is not None else arrays
    plans = base.stages
    result = Result(base.block_names, settings.resolved_method().name, keep_history, keep_vertices=keep_vertices)
    sinks = _Sinks([result, *recorders])
    if state is None:
        state = initial_state(base, settings.resolved_method())
    mark = stage_mark(state)
    status = "completed"
    stopped = False

    def user_stop(s: State) -> bool:
        nonlocal stopped
        stopped = stop is not None and stop(s)
        return stopped

    try:
        if mark is None:
            first = initial_mark(base)
            begun = begin_stage(base, 0, state, first)
            stage_arrays_, state = begun[0], book_stage_start((stage_arrays(base, first), state), begun, settings,
                                                              extra_terms, contact_law)
            mark = stage_mark(state)
            assert mark is not None
        else:
            stage_arrays_ = stage_arrays(base, mark)
        while True:
            plan = plans[mark.index]
            entry = _entry(plan, mark)
            sinks.stage(mark.index, entry)
            chosen = stage_settings(settings, plan, mark, state)
            if plan.kind == "equilibrium" and reached(state, plan.tolerance):
                stage_status = "completed"  # a resumed run whose checkpoint is this stage's last state
            else:
                ends = (lambda s, tol=plan.tolerance: reached(s, tol)) if plan.kind == "equilibrium" \
                    else (user_stop if stop is not None else None)
                part = run_stage(stage_arrays_, chosen, progress=progress, state=state, recorders=[sinks],
                                 keep_history=False, stop=ends, keep_vertices=False,
                                 extra_terms=[*extra_terms, UnbalancedForceTerm(), StageTerm(mark)],
                                 contact_law=contact_law)
                assert part.final_state is not None
                state, stage_status = part.final_state, part.status
            sinks.stage(mark.index, _ended(entry, plan, state, stage_status))
            if stage_status != "completed":
                status = f"stage {plan.name!r}: {stage_status}"
                break
            if stopped or mark.index + 1 == len(plans):
                break
            begun = begin_stage(base, mark.index + 1, state, mark)
            stage_arrays_, state = begun[0], book_stage_start((stage_arrays_, state), begun, settings, extra_terms,
                                                              contact_law)
            mark = stage_mark(state)
            assert mark is not None
    except BaseException as exc:
        sinks.abandon(f"interrupted ({type(exc).__name__})")
        raise
    for sink in sinks.sinks:
        sink.finish(status, state)
    return result
