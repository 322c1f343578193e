"""Staged analysis: one run as a sequence of stages, each changing the model at its start.

As engineers run UDEC and 3DEC: the model is brought to equilibrium under
gravity, the tunnel is excavated, bolts are installed, then comes the event.
A :class:`Stage` names what changes at its start (blocks removed, fixed or
freed, bolts installed, a base acceleration that starts with it, materials and
joint materials, run settings) and its kind: ``equilibrium`` (damped steps
until the unbalanced-force ratio falls below ``tolerance``,
:mod:`srdda.equilibrium`) or ``dynamic`` (steps or an end time, counted from
the stage's start).

Every stage runs on the same blocks, vertices and points, so the state carries
over unchanged and one results file holds the whole run: a removed block stays
in the arrays, held and touching nothing (``ModelArrays.block_removed``); a
bolt installed by a stage is in the arrays from the start, inactive until then
(``ConstraintArrays.bolt_active``), and its unstrained length is the one at its
installation. The arrays of stage k are the model's arrays with the changes
of stages 0..k (:func:`stage_arrays`); what of them depends on the state at a
stage's start (the bolts' installed axes, the time a base acceleration
starts) is the :class:`StageMark`, carried in ``State.carried["stage"]``, so a
checkpoint holds everything a resumed run needs and continues bit for bit.

The changes are the table :data:`CHANGES`, one :class:`Change` per kind: a
``resolve`` from the stage's names to indices (checked, JSON-able: a results
file keeps the resolved stages), an ``arrays`` change, and optionally a
``state`` change and a ``mark`` of what the change fixes at the stage's start.
A new kind of change is one entry.
"""
from __future__ import annotations

import dataclasses
import fnmatch
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from pydantic import ValidationError

from .equilibrium import (RATIO_TOLERANCE, SETTLE_VELOCITY_RATIO, UnbalancedForceTerm, reached, unbalanced_force,
                          without_ratio)
from .history import HistoryError, TimeHistory
from .kinematics.shape3d import elasticity_matrix_3d
from .model import JointMaterial, JointTable, Material, Model, ModelArrays, ModelError, elasticity_matrix
from .results import Result
from .settings import RunSettings
from .state import State, initial_state
from .term import Term

if TYPE_CHECKING:
    from .contact.law import ContactLaw
    from .results import Recorder

__all__ = ["Stage", "StagePlan", "StageMark", "Change", "CHANGES", "resolve_stages", "stage_arrays", "run_stages",
           "stage_mark", "STAGE_KINDS"]

STAGE_KINDS = ("equilibrium", "dynamic")
CARRIED = "stage"  # the stage term's key in State.carried


@dataclass(frozen=True)
class Stage:
    """One stage of a staged analysis (module doc); SI units.

    ``remove_blocks``, ``fix_blocks``, ``free_blocks``: block names or shell patterns (``"tunnel*"``: a
    group). ``install_bolts``: names of the model's bolts, inactive until this stage, installed in the
    configuration at its start. ``base_acceleration``: a ground acceleration (m/s²) whose time 0 is the
    stage's start. ``materials`` / ``joint_materials``: new properties of named (existing) ones.
    ``run``: fields of :class:`~srdda.settings.RunSettings` for this stage (``dt``, ``method``,
    ``contact_solver``, ...); ``n_steps`` (or ``steps``) and ``end_time`` count from the stage's start (a
    dynamic stage without them runs the model's steps or end time). An equilibrium stage stops when the
    unbalanced-force ratio falls below ``tolerance`` or after ``max_steps``. ``reset_displacements``: the
    stage starts at rest (velocities, accelerations and accumulated rotations zero; stresses and contacts
    kept) and its displacements are measured from its start.
    """

    name: str
    kind: Literal["equilibrium", "dynamic"] = "dynamic"
    remove_blocks: Sequence[str] = ()
    install_bolts: Sequence[str] = ()
    fix_blocks: Sequence[str] = ()
    free_blocks: Sequence[str] = ()
    base_acceleration: TimeHistory | None = None
    materials: Mapping[str, Material] = field(default_factory=dict)
    joint_materials: Mapping[str, JointMaterial] = field(default_factory=dict)
    run: Mapping[str, Any] = field(default_factory=dict)
    tolerance: float = RATIO_TOLERANCE
    max_steps: int = 20000
    reset_displacements: bool = False

    def __post_init__(self) -> None:
        what = f"stage {self.name!r}"
        if not isinstance(self.name, str) or not self.name:
            raise ModelError(f"{what}: name must be a non-empty string")
        if self.kind not in STAGE_KINDS:
            raise ModelError(f"{what}: kind must be one of {STAGE_KINDS}, got {self.kind!r}")
        if not 0 < self.tolerance < np.inf:
            raise ModelError(f"{what}: tolerance must be finite and > 0, got {self.tolerance}")
        if isinstance(self.max_steps, bool) or not isinstance(self.max_steps, (int, np.integer)) \
                or self.max_steps < 1:
            raise ModelError(f"{what}: max_steps must be an integer >= 1, got {self.max_steps!r}")
        for name in ("remove_blocks", "install_bolts", "fix_blocks", "free_blocks"):
            value = getattr(self, name)
            if isinstance(value, str) or not all(isinstance(v, str) for v in value):
                raise ModelError(f"{what}: {name} must be a list of names, got {value!r}")
            object.__setattr__(self, name, tuple(value))
        if self.base_acceleration is not None and not isinstance(self.base_acceleration, TimeHistory):
            try:
                object.__setattr__(self, "base_acceleration", TimeHistory.of(self.base_acceleration))
            except HistoryError as exc:
                raise ModelError(f"{what}: base_acceleration: {exc}") from None


@dataclass(frozen=True)
class StagePlan:
    """A stage resolved against its model: ``changes`` by :data:`CHANGES` key, as JSON-able values (indices)."""

    name: str
    kind: str
    changes: Mapping[str, Any]
    run: Mapping[str, Any]
    tolerance: float
    max_steps: int
    reset_displacements: bool

    def to_json(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    @staticmethod
    def from_json(data: Mapping[str, Any]) -> StagePlan:
        return StagePlan(**data)


@dataclass(frozen=True)
class StageMark:
    """Where a staged run is (carried in ``State.carried["stage"]``, checkpointed): the stage, its first step
    and start time, and what its changes fixed at the stages' starts (module doc)."""

    index: int
    first_step: int
    start_time: float
    base_time: float  # the start of the stage that set the base acceleration
    bolt_active: np.ndarray  # (n_bolts,) bool: installed
    bolt_axis: np.ndarray  # (n_bolts, dim) x_a - x_b at installation


@dataclass(frozen=True)
class Change:
    """One kind of stage change (module doc).

    ``resolve(model, value, where)``: the stage's value as a JSON-able one (names to indices), a
    :class:`ModelError` naming ``where`` when it is wrong; ``arrays(arrays, value, mark)``: the model arrays
    with the change; ``state(arrays, state, value)``: the state at the stage's start with it (optional);
    ``mark(mark, arrays, state, value)``: what the change fixes at the stage's start (optional).
    """

    resolve: Callable[[Model, Any, str], Any]
    arrays: Callable[[ModelArrays, Any, StageMark], ModelArrays] | None = None
    state: Callable[[ModelArrays, State, Any], State] | None = None
    mark: Callable[[StageMark, ModelArrays, State, Any], StageMark] | None = None
    empty: Callable[[Any], bool] = lambda value: not value  # a value that changes nothing (left out)


# -- the changes -------------------------------------------------------------------------------------------
def _blocks(model: Model, names: Sequence[str], where: str) -> list[int]:
    """Indices of the blocks ``names`` name (a name or a shell pattern: a group); ModelError naming ``where``."""
    all_names = [b.name for b in model.blocks]
    chosen: set[int] = set()
    for name in names:
        found = [i for i, n in enumerate(all_names) if n == name or fnmatch.fnmatchcase(n, name)]
        if not found:
            raise ModelError(f"{where}: no block named {name!r}")
        chosen.update(found)
    return sorted(chosen)


def _mask(n: int, indices: Sequence[int]) -> np.ndarray:
    out = np.zeros(n, dtype=bool)
    out[np.asarray(indices, dtype=np.int64)] = True
    return out


def _at_rest(blocks: np.ndarray, state: State) -> State:
    """``state`` with ``blocks`` (bool mask) at rest."""
    velocity, acceleration = state.velocity.copy(), state.acceleration.copy()
    velocity[blocks] = 0.0
    acceleration[blocks] = 0.0
    return replace(state, velocity=velocity, acceleration=acceleration)


def _remove(arrays: ModelArrays, value: list[int], mark: StageMark) -> ModelArrays:
    previous = arrays.block_removed if arrays.block_removed is not None else np.zeros(arrays.n_blocks, dtype=bool)
    removed = previous | _mask(arrays.n_blocks, value)
    return replace(arrays, block_removed=removed, block_fixed=arrays.block_fixed | removed)


def _fix(arrays: ModelArrays, value: list[int], mark: StageMark) -> ModelArrays:
    return replace(arrays, block_fixed=arrays.block_fixed | _mask(arrays.n_blocks, value))


def _free(arrays: ModelArrays, value: list[int], mark: StageMark) -> ModelArrays:
    freed = _mask(arrays.n_blocks, value)
    if arrays.block_removed is not None:
        freed &= ~arrays.block_removed
    return replace(arrays, block_fixed=arrays.block_fixed & ~freed)


def _hold(arrays: ModelArrays, state: State, value: list[int]) -> State:
    return _at_rest(_mask(arrays.n_blocks, value), state)


def _resolve_bolts(model: Model, names: Sequence[str], where: str) -> list[int]:
    bolt_names = [b.name for b in model.bolts]
    out = []
    for name in names:
        if name not in bolt_names:
            raise ModelError(f"{where}: no bolt named {name!r}")
        out.append(bolt_names.index(name))
    return sorted(set(out))


def _install(mark: StageMark, arrays: ModelArrays, state: State, value: list[int]) -> StageMark:
    """The bolts ``value`` become active, unstrained (but for their pretension) in the configuration now."""
    links, rows = arrays.links, np.asarray(value, dtype=np.int64)
    rb = links.bolt_rows_b[rows]
    end_b = np.where((rb >= 0)[:, None], state.points[np.maximum(rb, 0)], np.asarray(links.bolt_ground)[rows])
    active, axis = mark.bolt_active.copy(), mark.bolt_axis.copy()
    active[rows] = True
    axis[rows] = state.points[links.bolt_rows_a[rows]] - end_b
    return replace(mark, bolt_active=active, bolt_axis=axis)


def _resolve_history(model: Model, value: TimeHistory, where: str) -> dict[str, Any]:
    data = value.to_json()
    if data is None:
        raise ModelError(f"{where}: a Python function cannot be kept in a results file; give a constant, a table "
                         "or a sine")
    if len(value(0.0)) != model.dim:
        raise ModelError(f"{where}: needs {model.dim} components in a {model.dim}D model")
    return data


def _shifted(history: TimeHistory, start: float) -> TimeHistory:
    """``history`` with its time 0 at ``start``."""
    return TimeHistory(function=lambda t: history(t - start).tolist())


def _base_acceleration(arrays: ModelArrays, value: dict[str, Any], mark: StageMark) -> ModelArrays:
    history = _shifted(TimeHistory.from_json(value), mark.base_time)
    return replace(arrays, links=replace(arrays.links, base_acceleration=history))


def _base_time(mark: StageMark, arrays: ModelArrays, state: State, value: Any) -> StageMark:
    return replace(mark, base_time=state.time)


def _resolve_named(names: list[str], value: Mapping[str, Any], kind: type, what: str, where: str,
                   first_row: int = 0) -> dict[str, dict[str, Any]]:
    """New properties of named materials (``kind`` Material or JointMaterial) by their row (JSON keys)."""
    out = {}
    for name, properties in value.items():
        if name not in names:
            raise ModelError(f"{where}.{name}: no {what} named {name!r}")
        if not isinstance(properties, kind):
            raise ModelError(f"{where}.{name}: give a srdda.{kind.__name__}")
        out[str(names.index(name) + first_row)] = dataclasses.asdict(properties)  # type: ignore[call-overload]
    return out


def _resolve_materials(model: Model, value: Mapping[str, Material], where: str) -> dict[str, dict[str, Any]]:
    return _resolve_named(list(model.materials), value, Material, "material", where)


def _materials(arrays: ModelArrays, value: dict[str, dict[str, Any]], mark: StageMark) -> ModelArrays:
    density, elasticity = arrays.density.copy(), arrays.elasticity.copy()
    for index, fields in value.items():
        material = Material(**fields)
        blocks = arrays.block_material == int(index)
        density[blocks] = material.density
        elasticity[blocks] = elasticity_matrix_3d(material.young, material.poisson) if arrays.mesh is not None \
            else elasticity_matrix(material)
    return replace(arrays, density=density, elasticity=elasticity, compliance=np.linalg.inv(elasticity))


def _resolve_joints(model: Model, value: Mapping[str, JointMaterial], where: str) -> dict[str, dict[str, Any]]:
    return _resolve_named(list(model.joint_materials), value, JointMaterial, "joint material", where,
                          first_row=1)  # row 0 of the joint table is the default joint


def _joints(arrays: ModelArrays, value: dict[str, dict[str, Any]], mark: StageMark) -> ModelArrays:
    columns = {f.name: getattr(arrays.joints, f.name).copy() for f in dataclasses.fields(JointTable)}
    for row, fields in value.items():
        new = JointTable.of([JointMaterial(**fields)])
        for name, column in columns.items():
            column[int(row)] = getattr(new, name)[0]
    return replace(arrays, joints=JointTable(**columns))


CHANGES: dict[str, Change] = {
    "remove_blocks": Change(_blocks, arrays=_remove, state=_hold),
    "fix_blocks": Change(_blocks, arrays=_fix, state=_hold),
    "free_blocks": Change(_blocks, arrays=_free),
    "install_bolts": Change(_resolve_bolts, mark=_install),
    "base_acceleration": Change(_resolve_history, arrays=_base_acceleration, mark=_base_time,
                                empty=lambda value: value is None),
    "materials": Change(_resolve_materials, arrays=_materials),
    "joint_materials": Change(_resolve_joints, arrays=_joints),
}
"""Every kind of stage change by its field name in :class:`Stage` (and ``[[stages]]`` of a model file)."""


# -- resolving and applying -----------------------------------------------------------------------------------
def _run_overrides(run: Mapping[str, Any], where: str) -> dict[str, Any]:
    """The stage's run settings, checked field by field (``steps`` is ``n_steps``)."""
    out = {("n_steps" if k == "steps" else k): v for k, v in run.items()}
    known = {f.name for f in dataclasses.fields(RunSettings)}
    for name in out:
        if name not in known:
            raise ModelError(f"{where}.{name}: unknown run setting (check the spelling)")
    try:
        dataclasses.replace(RunSettings(dt=1e-3, n_steps=1), **out)
    except ValidationError as exc:
        err = exc.errors()[0]
        field_name = ".".join(str(part) for part in err["loc"]) or "(the settings)"
        raise ModelError(f"{where}.{field_name}: {err['msg'].removeprefix('Value error, ')}") from None
    return out


def resolve_stages(model: Model, stages: Sequence[Stage]) -> tuple[StagePlan, ...]:
    """The stages resolved against ``model`` (names to indices), each problem a ModelError naming its field."""
    plans, seen = [], set()
    for k, stage in enumerate(stages):
        where = f"stages[{k}]"
        if not isinstance(stage, Stage):
            raise ModelError(f"{where}: give a srdda.Stage, got {type(stage).__name__}")
        if stage.name in seen:
            raise ModelError(f"{where}.name: two stages are named {stage.name!r}")
        seen.add(stage.name)
        changes = {}
        for key, change in CHANGES.items():
            value = getattr(stage, key)
            if not change.empty(value):
                changes[key] = change.resolve(model, value, f"{where}.{key}")
        plans.append(StagePlan(stage.name, stage.kind, changes, _run_overrides(stage.run, f"{where}.run"),
                               float(stage.tolerance), int(stage.max_steps), bool(stage.reset_displacements)))
    return tuple(plans)


def initial_mark(arrays: ModelArrays) -> StageMark:
    """The mark before the first stage: the bolts some stage installs inactive, the others active."""
    links = arrays.links
    installed = [i for plan in arrays.stages for i in plan.changes.get("install_bolts", ())]
    return StageMark(-1, 0, 0.0, 0.0, ~_mask(links.n_bolts, installed),
                     np.asarray(links.bolt_axis).copy())


def stage_mark(state: State) -> StageMark | None:
    """The stage mark a state carries (None: not in a staged run)."""
    return state.carried.get(CARRIED)


def stage_arrays(base: ModelArrays, mark: StageMark) -> ModelArrays:
    """The arrays of stage ``mark.index``: the model's ``base`` with the changes of its stages up to it."""
    arrays = base
    if base.links.n_bolts:
        arrays = replace(arrays, links=replace(base.links, bolt_active=mark.bolt_active, bolt_axis=mark.bolt_axis))
    for plan in base.stages[:mark.index + 1]:
        for key, value in plan.changes.items():
            apply = CHANGES[key].arrays
            if apply is not None:
                arrays = apply(arrays, value, mark)
    return replace(arrays, stages=(), base=base)


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
        state = replace(_at_rest(np.ones(arrays.n_blocks, dtype=bool), state),
                        rotation=arrays.block_type.initial_rotation(arrays.n_blocks))
    state = replace(without_ratio(state), dt_next=None)
    return arrays, state.carrying(CARRIED, mark)


def stage_settings(settings: RunSettings, plan: StagePlan, mark: StageMark, state: State) -> RunSettings:
    """The run settings of the rest of a stage from ``state``: the model's with the stage's, its length
    counted from the stage's start (an equilibrium stage: ``max_steps``, in the damped steps of
    :func:`srdda.equilibrium.settle` unless the stage gives ``velocity_ratio``)."""
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
               contact_law: ContactLaw | None = None, stop: Callable[[State], bool] | None = None) -> Result:
    """Run the stages of ``arrays`` (``arrays.stages``) one after the other from ``state`` (default: the initial
    state; a state of a staged run, e.g. a checkpoint, continues in the stage it carries).

    Arguments as :func:`srdda.simulation.run`; ``settings`` are the model's, each stage's changing them
    (:func:`stage_settings`). Returns one :class:`Result` of the whole run, ``result.stages`` the stage
    table (first step, start time, end, ratio reached). The run stops at the first stage that does not
    complete (diverged, or Δt below its minimum), with that stage's status. ``stop(state)``, called after
    every accepted step of the dynamic stages, ends the whole run (completed) when it returns True.
    """
    from .simulation import run_single  # the run sits below the stages

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
            stage_arrays_, state = begin_stage(base, 0, state, initial_mark(base))
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
                part = run_single(stage_arrays_, chosen, progress=progress, state=state, recorders=[sinks],
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
            stage_arrays_, state = begin_stage(base, mark.index + 1, state, mark)
            mark = stage_mark(state)
            assert mark is not None
    except BaseException as exc:
        sinks.abandon(f"interrupted ({type(exc).__name__})")
        raise
    for sink in sinks.sinks:
        sink.finish(status, state)
    return result

