"""Stages of a staged analysis: what a stage changes at its start, resolved against the model.

A :class:`Stage` names what changes at its start (blocks removed, fixed or
freed, bolts installed, a base acceleration that starts with it, materials and
joint materials, run settings) and its kind: ``equilibrium`` (damped steps
until the unbalanced-force ratio falls below ``tolerance``,
:mod:`srdda.equilibrium`) or ``dynamic`` (steps or an end time, counted from
the stage's start). :mod:`srdda.staging` runs them.

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
A new kind of change is a field of :class:`Stage` (and of ``[[stages]]``,
:class:`srdda.io.schema.StageSection`) and one entry of :data:`CHANGES`.
"""
from __future__ import annotations

import dataclasses
import fnmatch
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Literal, Protocol

import numpy as np
from pydantic import ValidationError

from .equilibrium import RATIO_TOLERANCE
from .history import HistoryError, TimeHistory
from .kinematics.shape3d import elasticity_matrix_3d
from .modeldata.arrays import ModelArrays
from .modeldata.materials import JointMaterial, JointTable, Material, ModelError, elasticity_matrix
from .modeldata.stages import StagePlan
from .modeldata.water import WaterTable, water_table
from .settings import RunSettings
from .state import State

__all__ = ["Stage", "StagePlan", "StagedModel", "StageMark", "Change", "CHANGES", "STAGE_KINDS", "resolve_stages",
           "initial_mark", "stage_mark", "stage_arrays", "at_rest"]

STAGE_KINDS = ("equilibrium", "dynamic")
CARRIED = "stage"  # the stage mark's key in State.carried (srdda.staging.StageTerm carries it)


class _Named(Protocol):
    @property
    def name(self) -> str: ...


class StagedModel(Protocol):
    """What a stage's names are resolved against: the model's blocks, bolts, materials, joint materials, water
    and gravity (:class:`srdda.model.Model` is one; the builder compiles its stages with :func:`resolve_stages`,
    so this module names the builder only through this protocol)."""

    @property
    def blocks(self) -> Sequence[_Named]: ...

    @property
    def bolts(self) -> Sequence[_Named]: ...

    @property
    def materials(self) -> Mapping[str, Material]: ...

    @property
    def joint_materials(self) -> Mapping[str, JointMaterial]: ...

    @property
    def water(self) -> WaterTable | None: ...

    @property
    def gravity(self) -> Sequence[float]: ...

    @property
    def dim(self) -> int: ...


@dataclass(frozen=True)
class Stage:
    """One stage of a staged analysis (module doc); SI units.

    ``remove_blocks``, ``fix_blocks``, ``free_blocks``: block names or shell patterns (``"tunnel*"``: a
    group). ``install_bolts``: names of the model's bolts, inactive until this stage, installed in the
    configuration at its start. ``base_acceleration``: a ground acceleration (m/s²) whose time 0 is the
    stage's start. ``materials`` / ``joint_materials``: new properties of named (existing) ones.
    ``water_level``: the phreatic surface moved to this elevation (m, against gravity; a drawdown or a
    filling: :meth:`srdda.constraints.water.WaterTable.at_level`), or a horizontal one at it where the
    model has none (docs/water.md).
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
    water_level: float | None = None

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

    resolve: Callable[[StagedModel, Any, str], Any]
    arrays: Callable[[ModelArrays, Any, StageMark], ModelArrays] | None = None
    state: Callable[[ModelArrays, State, Any], State] | None = None
    mark: Callable[[StageMark, ModelArrays, State, Any], StageMark] | None = None
    empty: Callable[[Any], bool] = lambda value: not value  # a value that changes nothing (left out)


# -- the changes -------------------------------------------------------------------------------------------
def _blocks(model: StagedModel, names: Sequence[str], where: str) -> list[int]:
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


def at_rest(blocks: np.ndarray, state: State) -> State:
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
    return at_rest(_mask(arrays.n_blocks, value), state)


def _resolve_bolts(model: StagedModel, names: Sequence[str], where: str) -> list[int]:
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


def _resolve_history(model: StagedModel, value: TimeHistory, where: str) -> dict[str, Any]:
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


def _resolve_named(names: list[str], value: Mapping[str, Any], kind: type[Material] | type[JointMaterial], what: str,
                   where: str, first_row: int = 0) -> dict[str, dict[str, Any]]:
    """New properties of named materials (``kind`` Material or JointMaterial) by their row (JSON keys)."""
    out = {}
    for name, properties in value.items():
        if name not in names:
            raise ModelError(f"{where}.{name}: no {what} named {name!r}")
        if not isinstance(properties, kind):
            raise ModelError(f"{where}.{name}: give a srdda.{kind.__name__}")
        out[str(names.index(name) + first_row)] = dataclasses.asdict(properties)
    return out


def _resolve_materials(model: StagedModel, value: Mapping[str, Material], where: str) -> dict[str, dict[str, Any]]:
    return _resolve_named(list(model.materials), value, Material, "material", where)


def _materials(arrays: ModelArrays, value: dict[str, dict[str, Any]], mark: StageMark) -> ModelArrays:
    density, elasticity = arrays.block_density.copy(), arrays.block_elasticity.copy()
    for index, fields in value.items():
        material = Material(**fields)
        blocks = arrays.block_material == int(index)
        density[blocks] = material.density
        elasticity[blocks] = elasticity_matrix_3d(material.young, material.poisson) if arrays.mesh is not None \
            else elasticity_matrix(material)
    return replace(arrays, block_density=density, block_elasticity=elasticity,
                   block_compliance=np.linalg.inv(elasticity))


def _resolve_joints(model: StagedModel, value: Mapping[str, JointMaterial], where: str) -> dict[str, dict[str, Any]]:
    return _resolve_named(list(model.joint_materials), value, JointMaterial, "joint material", where,
                          first_row=1)  # row 0 of the joint table is the default joint


def _joints(arrays: ModelArrays, value: dict[str, dict[str, Any]], mark: StageMark) -> ModelArrays:
    columns = {f.name: getattr(arrays.joints, f.name).copy() for f in dataclasses.fields(JointTable)}
    for row, fields in value.items():
        new = JointTable.of([JointMaterial(**fields)])
        for name, column in columns.items():
            column[int(row)] = getattr(new, name)[0]
    return replace(arrays, joints=JointTable(**columns))


def _resolve_water_level(model: StagedModel, value: float, where: str) -> float:
    if not np.isfinite(value):
        raise ModelError(f"{where}: must be a finite elevation (m), got {value}")
    try:
        (model.water if model.water is not None else water_table(model.gravity, level=0.0)).at_level(value)
    except ValueError as exc:
        raise ModelError(f"{where}: {exc}") from None
    return float(value)


def _water_level(arrays: ModelArrays, value: float, mark: StageMark) -> ModelArrays:
    table = arrays.water if arrays.water is not None else water_table(arrays.gravity, level=value)
    return replace(arrays, water=table.at_level(value))


CHANGES: dict[str, Change] = {
    "remove_blocks": Change(_blocks, arrays=_remove, state=_hold),
    "fix_blocks": Change(_blocks, arrays=_fix, state=_hold),
    "free_blocks": Change(_blocks, arrays=_free),
    "install_bolts": Change(_resolve_bolts, mark=_install),
    "base_acceleration": Change(_resolve_history, arrays=_base_acceleration, mark=_base_time,
                                empty=lambda value: value is None),
    "materials": Change(_resolve_materials, arrays=_materials),
    "joint_materials": Change(_resolve_joints, arrays=_joints),
    "water_level": Change(_resolve_water_level, arrays=_water_level, empty=lambda value: value is None),
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


def resolve_stages(model: StagedModel, stages: Sequence[Stage]) -> tuple[StagePlan, ...]:
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
