"""Reading a results file (:mod:`srdda.io.results_store` writes it): its histories, model and checkpoints.

:func:`read_results` reads every intact step into a :class:`StoredResult`
(the same histories as an in-memory :class:`~srdda.results.Result`),
:func:`model_arrays_from_file` the stored model, :func:`load_checkpoint` the
state of the last intact checkpoint. A step counts once every dataset of its
group holds it (the layout and the three-phase flush are in the store's module
doc and docs/results.md).

Every file is checked as it is read (:func:`inspect_results`): its header
(attributes present, of the right kind, matching their checksums), then the
rows of every dataset (Fletcher32 checksums, :mod:`srdda.io.integrity`), the
order of the steps and the lengths of the datasets against each other. A
damaged file gives one line naming what is damaged and the last intact step
(:class:`ResultsDamageWarning`, and ``StoredResult.damage``) and reads up to
that step; a file whose header or model is damaged cannot be read
(:class:`ResultsFileError`).
"""
from __future__ import annotations

import dataclasses
import json
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np
from pydantic import ValidationError

from ..constraints.data import links_from_flat
from ..geometry.polyhedron import PolyhedronMesh
from ..integrators.methods import METHODS
from ..ledger import ENERGY_NAMES
from ..modeldata.arrays import AttachedPoints, Load, ModelArrays
from ..modeldata.materials import JointTable
from ..settings import RunSettings
from ..stages import StagePlan
from ..state import State
from .checkpoint import CheckpointVersionError, intact_checkpoints, read_checkpoint
from .integrity import (CutShortFile, DamagedError, describe_error, ordered_prefix, read_attr, read_intact,
                        read_json, read_text)
from .outputlock import lock_holder

__all__ = ["FORMAT", "FORMAT_VERSION", "ResultsFileError", "ResultsInUseError", "ResultsDamageWarning",
           "StoredResult", "Header", "Intact", "read_results", "load_checkpoint", "checkpoint_state", "model_arrays_from_file", "open_results",
           "read_header", "inspect_results", "READ_ERRORS"]

FORMAT = "srdda-results"
FORMAT_VERSION = 2  # 2: one contact set for 2D and 3D, the joint table (1: srdda 0.1.0)
# what a damaged part of the file breaks when read: h5py and numpy report it in all these ways
READ_ERRORS = (DamagedError, OSError, RuntimeError, ValueError, TypeError, KeyError, IndexError, AttributeError)


class ResultsFileError(ValueError):
    """The file is not an srdda results file, lacks what is asked of it, or is damaged where it cannot be read."""


class ResultsInUseError(ResultsFileError):
    """Another run is writing the file (HDF5 refuses to open it): the message names that run."""


class ResultsDamageWarning(UserWarning):
    """A results file is damaged after some intact steps: they are read, the message says what and up to where."""


def _damaged(path: str | Path, what: str) -> ResultsFileError:
    return ResultsFileError(f"{path}: damaged: {what}; it cannot be read or resumed: run the model again")


def _what(exc: BaseException) -> str:
    """What a read error says, in few words (h5py's long messages shortened)."""
    return str(exc) if isinstance(exc, DamagedError) else describe_error(exc)


@dataclass(frozen=True)
class Header:
    """The attributes of a results file that say how its run was made (``problems``: the damaged optional ones)."""

    format_version: int
    method: str
    status: str
    last_step: int
    flush_every: int
    contact_every: int
    settings: RunSettings
    problems: tuple[str, ...] = ()


def _int_attr(f: h5py.File, name: str, low: int) -> int:
    value = read_attr(f, name)
    if not isinstance(value, (int, np.integer)) or isinstance(value, (bool, np.bool_)) or value < low:
        raise DamagedError(f"the attribute {name!r} of / is not an integer >= {low}")
    return int(value)


def read_header(f: h5py.File, path: str | Path) -> Header:
    """The run's header; :class:`ResultsFileError` if it is missing or damaged (the file cannot be used)."""
    try:
        fmt = read_attr(f, "format", None)
    except DamagedError as exc:
        raise _damaged(path, str(exc)) from None
    if fmt not in (FORMAT, FORMAT.encode()):
        if getattr(f, "cut_short", None):
            raise _damaged(path, f"{f.cut_short}, its header with it")
        raise ResultsFileError(f"{path}: not an srdda results file (no format={FORMAT!r} attribute)")
    try:
        missing = [g for g in ("settings", "model", "history", "checkpoint", "contacts") if g not in f]
        incomplete = missing or read_attr(f, "last_step", None) is None
    except DamagedError as exc:
        raise _damaged(path, str(exc)) from None
    except READ_ERRORS as exc:
        raise _damaged(path, f"the groups of / cannot be read ({describe_error(exc)})") from None
    if incomplete:
        raise ResultsFileError(f"{path}: an incomplete results file (no {', '.join(missing) or 'last_step'}: the "
                               "run was stopped while it created the file); run the model again")
    problems = []
    try:
        version = _int_attr(f, "format_version", 1)
        if version > FORMAT_VERSION:
            raise ResultsFileError(f"{path}: written in results format version {version}, newer than this srdda "
                                   f"reads ({FORMAT_VERSION}); update srdda")
        method = read_text(f, "method")
        if method not in METHODS:
            raise DamagedError(f"the attribute 'method' of / is {method!r}, not a method")
        last_step = _int_attr(f, "last_step", -1)
        flush_every, contact_every = _int_attr(f, "flush_every", 1), _int_attr(f, "contact_every", 1)
        try:
            group = f["settings"]
        except READ_ERRORS as exc:
            raise DamagedError(f"/settings cannot be read ({_what(exc)})") from None
        settings = RunSettings(**read_json(group, "json", dict))
    except ValidationError as exc:
        raise _damaged(path, f"the run settings in /settings ({exc.errors()[0]['msg']})") from None
    except READ_ERRORS as exc:
        if isinstance(exc, ResultsFileError):
            raise
        raise _damaged(path, _what(exc)) from None
    try:
        status = read_text(f, "status")
    except DamagedError as exc:
        status = "unknown (its attribute is damaged)"
        problems.append(str(exc))
    return Header(version, method, status, last_step, flush_every, contact_every, settings, tuple(problems))


def open_results(path: str | Path) -> h5py.File:
    """The results file open for reading, its header checked (:func:`read_header`)."""
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        holder = lock_holder(Path(f"{path}.lock")) if "unable to lock" in str(exc).lower() else None
        if holder is not None:
            raise ResultsInUseError(f"{path} is being written by another run ({holder}); wait for it to end") from None
        if "truncated file" not in str(exc):
            raise ResultsFileError(f"{path}: cannot open as an HDF5 results file ({describe_error(exc)})") from None
        cut = CutShortFile(path)  # a copy that stopped, a full disk: read what lies before the cut
        try:
            f = h5py.File(cut, "r")
        except OSError:
            cut.close()
            raise ResultsFileError(f"{path}: cannot open as an HDF5 results file (it is cut short at byte "
                                   f"{cut.size} and its start is damaged too)") from None
        f.cut_short = f"the file is cut short at byte {cut.size}"
    try:
        read_header(f, path)
    except BaseException:
        f.close()
        raise
    return f


def model_arrays_from_file(path: str | Path) -> ModelArrays:
    """The :class:`ModelArrays` stored in a results file (callable loads cannot be stored)."""
    with open_results(path) as f:
        try:
            return _model_arrays(f["model"], path)
        except ResultsFileError:
            raise
        except READ_ERRORS as exc:
            raise _damaged(path, f"the stored model in /model ({_what(exc)})") from None


# The arrays of the stored model (/model): dataset name -> the ModelArrays field it holds ("attached.": a field
# of the attached points). The names are the file format's, as srdda 0.1.0 wrote them (the fields were renamed
# since); the mesh, the joint table and the links are stored as "mesh.<field>", "joints.<field>", "links.<field>".
MODEL_DATASETS: dict[str, str] = {
    "vertices": "vertex_position", "block_ptr": "block_ptr", "density": "block_density",
    "elasticity": "block_elasticity", "velocity": "block_velocity", "stress": "block_stress", "gravity": "gravity",
    "points": "attached.point_position", "point_block": "attached.point_block", "fixed_rows": "attached.fixed_rows",
    "fixed_stiffness": "attached.fixed_stiffness", "load_rows": "attached.load_rows",
    "spring_rows_a": "attached.point_spring_rows_a", "spring_rows_b": "attached.point_spring_rows_b",
    "spring_stiffness": "attached.point_spring_stiffness", "measured_rows": "attached.measured_rows",
    "vertex_block": "vertex_block", "next_vertex": "vertex_next", "compliance": "block_compliance",
    "block_fixed": "block_fixed", "block_material": "block_material", "edge_joint": "edge_joint",
    "joint_by_materials": "material_joint", "face_joint": "face_joint", "block_removed": "block_removed",
}


def _model_arrays(g: h5py.Group, path: str | Path) -> ModelArrays:
    loads_json = read_json(g, "loads", list)
    if any(ld is None for ld in loads_json):
        raise ResultsFileError(f"{path}: the model has a point load given as a Python function, which a file "
                               "cannot hold; pass the model to resume(..., model=...)")
    optional = {f_.name for f_ in dataclasses.fields(ModelArrays) if f_.default is None}  # face_joint, ...

    def lacks(name: str) -> ResultsFileError:
        return ResultsFileError(f"{path}: the stored model lacks field {name!r} (written by another srdda "
                                "version?); pass the model to resume(..., model=...)")

    kwargs: dict[str, Any] = {}
    attached: dict[str, Any] = {"load_force": tuple(Load.from_json(ld) for ld in loads_json)}
    for name, field_ in MODEL_DATASETS.items():
        record, _, field_ = field_.rpartition(".")
        columns = attached if record else kwargs
        if name in g:
            columns[field_] = g[name][()]
        elif field_ in optional:  # an optional array (face_joint: 3D faces naming joint materials)
            columns[field_] = None
        else:
            raise lacks(name)
    kwargs["attached"] = AttachedPoints(**attached)
    kwargs["block_names"] = tuple(str(n) for n in read_json(g, "block_names", list))
    if "links" not in g.attrs:
        raise lacks("links")
    meta = read_json(g, "links", dict)
    if any(s is None for s in meta.get("sources", ())) or (meta.get("has_base_acceleration")
                                                           and meta.get("base_acceleration") is None):
        raise ResultsFileError(f"{path}: a prescribed-motion or base-acceleration history is a Python "
                               "function, which a file cannot hold; pass the model to resume(..., model=...)")
    kwargs["links"] = links_from_flat({k[6:]: g[k][()] for k in g if k.startswith("links.")}, meta)
    mesh = {k[5:]: g[k][()] for k in g if k.startswith("mesh.")}
    kwargs["mesh"] = PolyhedronMesh(**mesh) if mesh else None
    if "joints.friction_angle" in g:
        columns = {k[7:]: g[k][()] for k in g if k.startswith("joints.")}
        columns.setdefault("restitution", np.full(len(columns["friction_angle"]), np.nan))  # older files: none
        kwargs["joints"] = JointTable(**columns)
    elif "joint_properties" in g:  # files of srdda 0.1.0: (nj, 3) columns
        table = g["joint_properties"][()]
        nan = np.full(len(table), np.nan)
        kwargs["joints"] = JointTable(table[:, 0], table[:, 1], table[:, 2], nan, nan.copy(), nan.copy())
    else:
        raise lacks("joints")
    kwargs["stages"] = stage_plans(g)  # the resolved stages of a staged run (srdda.stages)
    return ModelArrays(**kwargs)


def stage_plans(g: h5py.Group) -> tuple[StagePlan, ...]:
    """The resolved stages stored with the model ``g`` (() for a run without stages)."""
    if "stages" not in g.attrs:
        return ()
    return tuple(StagePlan.from_json(plan) for plan in read_json(g, "stages", list))


def stage_table(f: h5py.File) -> list[dict]:
    """The stage table of a results file: one row per stage begun (name, kind, first step, ...; [] without)."""
    return read_json(f, "stages", list) if "stages" in f.attrs else []


def _check_model(g: h5py.Group) -> list[str]:
    """Read every part of the stored model: DamagedError if one is damaged; the damaged model text (not needed)."""
    data = {}
    for name in g:
        rows = read_intact(g, name)
        if rows.problem is not None:
            raise DamagedError(rows.problem)
        data[name] = rows.data
    names = read_json(g, "block_names", list)
    read_json(g, "loads", list)
    if "links" in g.attrs:
        read_json(g, "links", dict)
    ptr, nv = data.get("block_ptr", np.zeros(0)), len(data.get("vertices", ()))
    nb = len(ptr) - 1
    if nb < 1 or ptr[0] != 0 or ptr[-1] != nv or np.any(np.diff(ptr) < 3) or len(names) != nb or any(
            len(data.get(n, ())) != nb for n in ("density", "velocity", "stress", "block_fixed", "block_material")):
        raise DamagedError("the block arrays of /model do not agree in size")
    try:
        if "model_text" in g.attrs:
            read_text(g, "model_text")
    except DamagedError as exc:
        return [str(exc)]
    return []


# -- what a file holds intact -------------------------------------------------------
@dataclass(frozen=True)
class Intact:
    """What of a results file reads back whole, up to its last intact step (:func:`inspect_results`)."""

    last_step: int  # -1: no step
    histories: dict[str, np.ndarray]  # rows up to last_step
    contacts: dict[str, np.ndarray]  # records up to last_step: step (k), offsets (k+1), rows
    checkpoint_steps: np.ndarray  # the steps of the complete checkpoints
    checkpoint_intact: np.ndarray  # which of them read back whole
    problems: tuple[str, ...]  # what is damaged, one phrase each
    energy_names: tuple[str, ...] = ENERGY_NAMES  # the columns of the energy history
    versions: dict[str, str] = dataclasses.field(default_factory=dict)  # the versions that wrote the file

    def message(self, path: str | Path, then: str = "") -> str | None:
        """One line naming what is damaged and the last intact step (None for an intact file)."""
        if not self.problems:
            return None
        shown = "; ".join(self.problems[:3]) + (f"; and {len(self.problems) - 3} more" if len(self.problems) > 3
                                                 else "")
        kept = (f"it keeps every step up to step {self.last_step} intact" if self.last_step >= 0
                else "it keeps no intact step")
        return f"{path}: damaged: {shown}; {kept}{then}"


def _histories(hist: h5py.Group, record_every: int, names: Sequence[str] | None, keep: bool
               ) -> tuple[dict[str, np.ndarray], int, list[str]]:
    """The intact rows of the histories ``names`` (all by default; ``keep=False``: only ``step`` is kept, the
    others checked), how many, and what is damaged (within the rows the steps make count)."""
    problems = _missing(hist)
    keys = [k for k in hist if names is None or k in names or k == "step"]
    if "step" not in keys:
        return {}, 0, problems
    data, good, lost = {}, {}, {}
    for k in keys:
        rows = read_intact(hist, k, keep=keep or k == "step")
        data[k], good[k], lost[k] = rows.data, rows.good, rows.problem
    n, out_of_order = ordered_prefix(data["step"][:good["step"]], record_every)
    if lost["step"] is not None:
        problems.append(lost["step"])
    if out_of_order:
        problems.append(f"/history/step out of order at row {n} (step {data['step'][n]} after {data['step'][n - 1]})")
    for k in keys:
        if good[k] < n:
            problems.append(lost[k] or f"/history/{k} holds {good[k]} rows, /history/step {n}")
            n = good[k]
    return data, 0 if problems and _missing(hist) else n, problems  # a missing history: none of its rows


def _missing(group: h5py.Group) -> list[str]:
    """The datasets the group's list (attribute ``datasets``) names that it lacks: each is damage."""
    if "datasets" not in group.attrs:  # a file written before the lists
        return []
    listed = read_json(group, "datasets", list)
    return [f"{group.name}/{name} is missing" for name in listed if name not in group]


def _contacts(c: h5py.Group, keep: bool) -> tuple[dict[str, np.ndarray], int, list[str]]:
    """The intact contact records: every dataset's rows (``keep=False``: only step and offsets, the others
    checked), how many records, and what is damaged (within the records the steps make count)."""
    problems = _missing(c)
    if "step" not in c or "offsets" not in c:
        return {}, 0, problems + ([] if problems or not len(c) else ["/contacts/step or /contacts/offsets is missing"])
    data, good, lost = {}, {}, {}
    for k in c:
        rows = read_intact(c, k, keep=keep or k in ("step", "offsets"))
        data[k], good[k], lost[k] = rows.data, rows.good, rows.problem
    problems += [p for p in (lost["step"], lost["offsets"]) if p is not None]
    k, out_of_order = ordered_prefix(data["step"][:min(good["step"], max(good["offsets"] - 1, 0))])
    if out_of_order:
        problems.append(f"/contacts/step out of order at record {k}")
    offsets = data["offsets"][:k + 1]
    ordered, out_of_order = ordered_prefix(offsets, allow_equal=True)
    if out_of_order or (len(offsets) and offsets[0] != 0):
        problems.append(f"/contacts/offsets out of order at record {ordered if offsets[0] == 0 else 0}")
    k = min(k, ordered - 1) if len(offsets) and offsets[0] == 0 else 0
    columns = [r for r in c if r not in ("step", "offsets")]
    fit = min((good[r] for r in columns), default=np.iinfo(np.int64).max)
    records = int(np.searchsorted(data["offsets"][:k + 1], fit, side="right")) - 1 if k > 0 else 0
    if records < k:
        problems += [lost[r] or f"/contacts/{r} holds {good[r]} rows, the records need {int(data['offsets'][k])}"
                     for r in columns if good[r] < data["offsets"][k]]
        k = records
    return data, 0 if _missing(c) else max(k, 0), problems


def inspect_results(f: h5py.File, path: str | Path, names: Sequence[str] | None = None,
                    checkpoints: bool = True, keep: bool = True) -> Intact:
    """Read and check what the file holds: the intact histories (``names``: only those), contacts, checkpoints.

    The last intact step is the last history row before the first damaged or
    missing one, and before the first damaged contact record (its rows are
    cut back to the last intact record). ``checkpoints=False`` leaves the
    checkpoints unread (their damage is then not reported); ``keep=False``
    checks every row but keeps only the steps (and the contacts' offsets).
    """
    header = read_header(f, path)
    problems = [p for p in (getattr(f, "cut_short", None),) if p] + list(header.problems)
    try:
        problems += _check_model(f["model"])
    except READ_ERRORS as exc:
        raise _damaged(path, f"the stored model ({_what(exc)})") from None
    versions: dict[str, str] = {}
    if "versions" in f:
        try:
            versions = {k: read_text(f["versions"], k) for k in f["versions"].attrs if not k.endswith("_crc32")}
        except READ_ERRORS as exc:
            problems.append(_what(exc))
    try:
        data, n, found = _histories(f["history"], header.settings.record_every, names, keep)
    except READ_ERRORS as exc:  # its list of datasets is lost
        data, n, found = {}, 0, [f"/history cannot be read ({_what(exc)})"]
    problems += found
    energy_names: tuple[str, ...] = ENERGY_NAMES
    if "energy" in data:
        try:
            energy_names = tuple(str(n_) for n_ in read_json(f["history"]["energy"], "names", list))
            if len(energy_names) != data["energy"].shape[1]:
                raise DamagedError("the attribute 'names' of /history/energy does not match its columns")
        except READ_ERRORS as exc:
            problems.append(_what(exc))
            energy_names = ENERGY_NAMES
    last_step = int(data["step"][n - 1]) if n else -1
    try:
        contacts, k, found = _contacts(f["contacts"], keep)
    except READ_ERRORS as exc:
        contacts, k, found = {}, 0, [f"/contacts cannot be read ({_what(exc)})"]
    problems += found
    if found:  # a damaged contact record: the steps after the last intact one lack their contacts
        last_step = min(last_step, int(contacts["step"][k - 1]) if k else -1)
    intact_rows = int(np.searchsorted(data["step"][:n], last_step, side="right")) if n else 0
    histories = {name: rows[:intact_rows] for name, rows in data.items()}
    if k:
        k = int(np.searchsorted(contacts["step"][:k], last_step, side="right"))
        rows = int(contacts["offsets"][k])
        contacts = {name: v[:k] if name == "step" else v[:k + 1] if name == "offsets" else v[:rows]
                    for name, v in contacts.items()}
    elif contacts:
        contacts = {name: v[:1] if name == "offsets" else v[:0] for name, v in contacts.items()}
        contacts["offsets"] = np.zeros(1, dtype=np.int64)
    steps, intact = np.zeros(0, dtype=np.int64), np.zeros(0, dtype=bool)
    if checkpoints:
        try:
            steps, intact, found = intact_checkpoints(f["checkpoint"])
        except READ_ERRORS as exc:
            found = [f"the checkpoints cannot be read ({_what(exc)})"]
        problems += found
    return Intact(last_step, histories, contacts, steps, intact, tuple(problems), energy_names, versions)


# -- reading ----------------------------------------------------------------------
@dataclass
class StoredResult:
    """The histories of a results file (rows = recorded steps), like :class:`~srdda.simulation.Result`."""

    path: str
    block_names: tuple[str, ...]
    method: str
    status: str
    settings: RunSettings
    histories: dict[str, np.ndarray]
    energy_names: tuple[str, ...]
    block_ptr: np.ndarray
    block_material: np.ndarray
    block_fixed: np.ndarray
    initial_vertices: np.ndarray
    contacts: dict[str, np.ndarray]
    model_text: str | None
    versions: dict[str, str]
    bolt_names: tuple[str, ...] = ()
    damage: str | None = None  # one line naming what is damaged and the last intact step; None: intact
    stages: list[dict] = dataclasses.field(default_factory=list)  # the stage table of a staged run (srdda.staging)

    @property
    def mesh(self) -> PolyhedronMesh | None:
        """The faces of 3D blocks, read from the file (None for a 2D run)."""
        with open_results(self.path) as f:
            try:
                fields = {k[5:]: f["model"][k][()] for k in f["model"] if k.startswith("mesh.")}
                return PolyhedronMesh(**fields) if fields else None
            except READ_ERRORS as exc:
                raise _damaged(self.path, f"the stored model ({_what(exc)})") from None

    def array(self, name: str) -> np.ndarray:
        """A history as one array (first axis = recorded step); ``energy`` has columns ``energy_names``."""
        if name not in self.histories:
            raise KeyError(f"no history {name!r}; the file has {sorted(self.histories)}")
        return self.histories[name]

    def __getattr__(self, name: str) -> np.ndarray:
        hist = self.__dict__.get("histories", {})
        if name in hist:
            return hist[name]
        raise AttributeError(name)

    @property
    def completed(self) -> bool:
        return self.status == "completed"

    def contacts_at(self, index: int) -> dict[str, np.ndarray]:
        """The contact arrays of the ``index``-th contact record."""
        off = self.contacts["offsets"]
        return {k: v[off[index]:off[index + 1]] for k, v in self.contacts.items() if k not in ("offsets", "step")}


def read_results(path: str | Path, names: Sequence[str] | None = None) -> StoredResult:
    """Read every intact step of a results file (also of a run that was killed).

    ``names`` reads only those histories (e.g. leave out the vertices of a
    large model); the checkpoints are then not checked. A damaged file gives a
    :class:`ResultsDamageWarning` naming what is damaged and reads up to its
    last intact step (``StoredResult.damage`` holds the same line); a file whose
    header or model is damaged raises :class:`ResultsFileError`.
    """
    with open_results(path) as f:
        header = read_header(f, path)
        found = inspect_results(f, path, names, checkpoints=names is None)
        g = f["model"]
        try:
            model = {k: g[k][()] for k in ("block_ptr", "block_material", "block_fixed", "vertices")}
            block_names = tuple(str(n) for n in read_json(g, "block_names", list))
            bolt_names = tuple(read_json(g, "links", dict).get("bolt_names", ())) if "links" in g.attrs else ()
        except READ_ERRORS as exc:
            raise _damaged(path, f"the stored model ({_what(exc)})") from None
        try:
            model_text = read_text(g, "model_text") if "model_text" in g.attrs else None
        except DamagedError:
            model_text = None
        try:
            stages = stage_table(f)
        except DamagedError as exc:
            raise _damaged(path, f"the stage table ({exc})") from None
    damage = found.message(path)
    if damage is not None:
        warnings.warn(damage, ResultsDamageWarning, stacklevel=2)
    return StoredResult(
        path=str(path), block_names=block_names, method=header.method, status=header.status,
        settings=header.settings, histories=found.histories, energy_names=found.energy_names,
        block_ptr=model["block_ptr"], block_material=model["block_material"], block_fixed=model["block_fixed"],
        initial_vertices=model["vertices"], contacts=found.contacts, model_text=model_text, versions=found.versions,
        bolt_names=bolt_names, damage=damage, stages=stages)


def load_checkpoint(path: str | Path, arrays: ModelArrays) -> State:
    """The :class:`State` of the last intact checkpoint of a results file."""
    with open_results(path) as f:
        try:
            steps, intact, _ = intact_checkpoints(f["checkpoint"])
        except READ_ERRORS as exc:
            raise ResultsFileError(f"{path}: damaged: the checkpoints cannot be read ({_what(exc)})") from None
        if not np.any(intact):
            raise ResultsFileError(f"{path}: no intact checkpoint was flushed; nothing to resume from")
        return checkpoint_state(f["checkpoint"], int(np.flatnonzero(intact)[-1]), arrays, path)


def checkpoint_state(group: h5py.Group, index: int, arrays: ModelArrays, path: str | Path) -> State:
    """The State of checkpoint ``index``, checked against the model (:class:`ResultsFileError` if it does not fit)."""
    def moments(vertices: np.ndarray):
        if vertices.shape != arrays.vertex_position.shape:
            raise DamagedError(f"it has {len(vertices)} vertices, the model {len(arrays.vertex_position)}")
        return arrays.moments(vertices)

    try:
        state = read_checkpoint(group, index, moments)
        _fits(state, arrays)
    except CheckpointVersionError as exc:
        raise ResultsFileError(f"{path}: {exc}") from None
    except READ_ERRORS as exc:
        raise ResultsFileError(f"{path}: the checkpoint {index} is damaged ({_what(exc)})") from None
    return state


def _number_fits(f: dataclasses.Field, value: object) -> bool:
    """False if a field declared a number (``float``, ``int``, ``bool``, optional) holds an array of values."""
    declared = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", "")
    number = declared.replace(" | None", "") in ("float", "int", "bool")
    return not (number and isinstance(value, np.ndarray) and value.ndim > 0)


def _fits(state: State, arrays: ModelArrays) -> None:
    """DamagedError unless every array of ``state`` has the shape and kind the model's initial state has."""
    from ..state import initial_state
    from ..integrators.methods import method_preset

    reference = initial_state(arrays, method_preset("srdda"))
    for f in dataclasses.fields(State):
        value, expected = getattr(state, f.name), getattr(reference, f.name)
        if isinstance(expected, np.ndarray):
            fits = isinstance(value, np.ndarray) and value.shape == expected.shape and \
                value.dtype.kind == expected.dtype.kind
        else:  # a number or None (dt_next), or a dataclass (the contact set: any number of contacts)
            fits = _number_fits(f, value) and not (dataclasses.is_dataclass(value) and not all(
                _number_fits(g, getattr(value, g.name)) for g in dataclasses.fields(value)))
        if not fits:
            raise DamagedError(f"its {f.name} does not fit the model")
    for name in ("vertices", "velocity", "acceleration", "stress", "points"):
        if not np.all(np.isfinite(getattr(state, name))):
            raise DamagedError(f"its {name} are not finite")
