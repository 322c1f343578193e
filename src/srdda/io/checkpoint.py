"""Checkpoints of the full :class:`~srdda.simulation.State` in an HDF5 group, append-only.

Generic over the State's fields, so fields other modules add (contact sets,
constraint multipliers, energy ledgers, ...) are saved and restored without
this module knowing them:

* an array field ``f`` is appended row-wise to dataset ``f`` (its first axis;
  a scalar counts as one row, attr ``scalar``), and its row count to ``f__count``;
* a field holding a dataclass (e.g. a contact set) is flattened into
  ``f.<subfield>`` datasets as above, with ``f__present`` (bool per
  checkpoint; False for None) whose attr ``class`` names the dataclass;
* a field holding a mapping of names to dataclasses (``State.carried``: what
  each term carries) stores each entry ``k`` as the field ``f.k`` above; a
  name that appears at a later checkpoint is absent from the earlier ones;
* every dataset carries HDF5's Fletcher32 checksum and the class names their
  CRC-32 (:mod:`srdda.io.integrity`); :func:`intact_checkpoints` tells which
  checkpoints read back whole;
* ``step`` and ``time`` are appended last: a checkpoint counts only when every
  per-checkpoint dataset (``step``, ``time``, ``*__count``, ``*__present``)
  has its row, so one cut short by a kill is ignored. A writer may append
  ``step`` separately (:func:`commit_checkpoint`), after the rest is on disk.
  Steps increase from one checkpoint to the next; a row that breaks this (a
  ``step`` write that failed) ends the complete checkpoints.

``moments`` is not stored: it is recomputed from the vertices, as the time
loop does.
"""
from __future__ import annotations

import dataclasses
import importlib
import json
from collections.abc import Mapping
from typing import Any

import h5py
import numpy as np

from ..energy_names import LEDGER
from ..geometry.polygon import BlockMoments
from ..geometry.polyhedron import PolyhedronMoments
from .integrity import Rows, ordered_prefix, read_attr, read_intact, read_text, write_text

__all__ = ["CheckpointVersionError", "append_checkpoint", "commit_checkpoint", "checkpoint_count", "increasing_prefix", "truncate_checkpoints",
           "read_checkpoint", "intact_checkpoints"]

SKIPPED = ("step", "time", "moments")


def _class_path(obj: Any) -> str:
    cls = type(obj)
    return f"{cls.__module__}:{cls.__qualname__}"


class CheckpointVersionError(ValueError):
    """The checkpoint was written by an srdda whose State or carried classes this one has not."""


def _import(path: str) -> type:
    """The class ``module:Name`` a checkpoint names; a ValueError when this srdda has none (an older file)."""
    module, _, name = path.partition(":")
    try:
        obj: Any = importlib.import_module(module)
        for part in name.split("."):
            obj = getattr(obj, part)
    except (ImportError, AttributeError):
        raise CheckpointVersionError(f"the checkpoint holds a {path} that this srdda does not have (written by an older "
                         "version: its contacts were stored in another form); run the model again") from None
    return obj


def _append(group: h5py.Group, name: str, rows: np.ndarray) -> None:
    if name not in group:
        row = rows.shape[1:]
        row_bytes = max(1, int(np.prod(row, dtype=np.int64)) * rows.dtype.itemsize)
        chunk = int(max(1, min(max(len(rows), 16), (1 << 20) // row_bytes)))
        group.create_dataset(name, shape=(0, *row), maxshape=(None, *(d if d else None for d in row)),
                             dtype=rows.dtype, chunks=(chunk, *(max(d, 1) for d in row)), fletcher32=True)
    ds = group[name]
    n = ds.shape[0]
    ds.resize(n + len(rows), axis=0)
    ds[n:] = rows


def _append_value(group: h5py.Group, name: str, value: Any) -> None:
    arr = np.asarray(value)
    scalar = arr.ndim == 0
    _append(group, name, arr.reshape(1) if scalar else arr)
    group[name].attrs["scalar"] = scalar
    _append(group, f"{name}__count", np.array([1 if scalar else len(arr)], dtype=np.int64))


def append_checkpoint(group: h5py.Group, state: Any, commit: bool = True) -> None:
    """Append ``state`` (a State dataclass) as the next checkpoint of ``group``.

    ``commit=False`` leaves out its ``step`` row (:func:`commit_checkpoint`): until then it does not count.
    """
    write_text(group, "state_class", _class_path(state))
    done = group["time"].shape[0] if "time" in group else 0  # checkpoints before this one
    for f in dataclasses.fields(state):
        if f.name in SKIPPED:
            continue
        value = getattr(state, f.name)
        if isinstance(value, Mapping):
            for key in sorted({*value, *_mapping_keys(group, f.name)}):
                _append_optional(group, f"{f.name}.{key}", value.get(key), done)
        elif dataclasses.is_dataclass(value) or value is None:
            _append_optional(group, f.name, value, done)
        else:
            _append_value(group, f.name, value)
    _append(group, "time", np.array([state.time], dtype=float))
    write_text(group, "datasets", json.dumps(sorted(group)))  # what a damaged file would lack
    if commit:
        commit_checkpoint(group, state)


def _append_optional(group: h5py.Group, name: str, value: Any, done: int) -> None:
    """Append a dataclass or None as ``name`` (its ``__present`` flag, and its fields when present); a name
    new at checkpoint ``done`` is marked absent at the ones before."""
    present = f"{name}__present"
    if present not in group and done:
        _append(group, present, np.zeros(done, dtype=bool))
    _append(group, present, np.array([value is not None]))
    if value is not None:
        write_text(group[present], "class", _class_path(value))
        for g in dataclasses.fields(value):
            _append_value(group, f"{name}.{g.name}", getattr(value, g.name))


def _mapping_keys(group: h5py.Group, name: str) -> list[str]:
    """The entries of mapping field ``name`` stored so far (their ``name.<key>__present`` flags)."""
    prefix, suffix = f"{name}.", "__present"
    return [k[len(prefix):-len(suffix)] for k in group
            if k.startswith(prefix) and k.endswith(suffix) and "." not in k[len(prefix):]]


def commit_checkpoint(group: h5py.Group, state: Any) -> None:
    """Append the ``step`` row that makes the checkpoint of ``state`` count."""
    _append(group, "step", np.array([state.step], dtype=np.int64))


def _per_checkpoint(group: h5py.Group) -> list[str]:
    """Datasets with one row per checkpoint (nested fields' counts have one per present value)."""
    return [k for k in group if k in ("step", "time") or k.endswith("__present")
            or (k.endswith("__count") and "." not in k)]


def checkpoint_count(group: h5py.Group) -> int:
    """Complete checkpoints in ``group``."""
    if "step" not in group:
        return 0
    n = min(group[k].shape[0] for k in _per_checkpoint(group))
    return increasing_prefix(group["step"][:n])


def increasing_prefix(steps: np.ndarray) -> int:
    """Length of the leading run of strictly increasing ``steps`` (rows after a failed write are cut off)."""
    broken = np.flatnonzero(np.diff(steps) <= 0)
    return int(broken[0] + 1) if len(broken) else len(steps)


def truncate_checkpoints(group: h5py.Group, n: int) -> None:
    """Keep the first ``n`` checkpoints (drop one a kill cut short, or later ones)."""
    for k in _per_checkpoint(group):
        group[k].resize(n, axis=0)
    for k in [k for k in group if k.endswith("__present")]:
        kept = int(np.sum(group[k][()]))
        prefix = k[: -len("__present")] + "."
        for c in [c for c in group if c.startswith(prefix) and c.endswith("__count")]:
            group[c].resize(kept, axis=0)
    for k in [k for k in group if k.endswith("__count")]:
        group[k[: -len("__count")]].resize(int(np.sum(group[k][()])), axis=0)


def intact_checkpoints(group: h5py.Group) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The steps of the complete checkpoints, which of them read back whole, and what is damaged.

    A checkpoint reads back whole when every row it needs (its own rows and the
    counts that locate them) lies outside the chunks that fail, and every
    dataset the group's list (attribute ``datasets``) names is there.
    """
    missing = []
    if "datasets" in group.attrs:  # a missing dataset: no checkpoint can be restored whole
        missing = [f"{group.name}/{name} is missing" for name in json.loads(read_text(group, "datasets"))
                   if name not in group]
    problems = list(missing)
    if "step" not in group:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=bool), problems
    rows: dict[str, Rows] = {}
    for name in group:  # the arrays' rows are checked, not kept; the per-checkpoint rows are needed
        small = name in ("step", "time") or name.endswith(("__count", "__present"))
        rows[name] = read_intact(group, name, keep=small)
    per = _per_checkpoint(group)
    n = min(rows[k].good for k in per)  # the counts and steps are read up to their first damage
    n, damaged = ordered_prefix(rows["step"].data[:n])
    if damaged:
        problems.append(f"{group.name}/step out of order at row {n}")
    intact = np.full(n, not missing)
    lost: set[str] = set()  # datasets whose damage costs a complete checkpoint
    for name in [k for k in group if k.endswith("__count") and "." not in k]:
        field = name[: -len("__count")]
        whole = _readable(rows[field], np.cumsum(rows[name].data[:n]))
        lost |= {field} if not whole.all() else set()
        intact &= whole
    for present in [k for k in group if k.endswith("__present")]:
        shown = rows[present].data[:n].astype(bool)
        index = np.cumsum(shown) - 1  # the row of each checkpoint's value among the present ones
        prefix = present[: -len("__present")] + "."
        for count in [k for k in group if k.startswith(prefix) and k.endswith("__count")]:
            field = count[: -len("__count")]
            whole = _readable(rows[field], np.cumsum(rows[count].data[:rows[count].good]))
            readable = np.zeros(n, dtype=bool)
            within = shown & (index < len(whole))
            readable[within] = whole[index[within]]
            lost |= {field} if np.any(shown & ~readable) else set()
            intact &= ~shown | readable
    complete = min(group[k].shape[0] for k in per)
    problems += [r.problem for k, r in rows.items() if r.problem is not None and (
        k in lost or (k in per and r.good < complete) or "cannot be read" in r.problem)]
    return rows["step"].data[:n], intact, problems


def _readable(rows: Rows, ends: np.ndarray) -> np.ndarray:
    """Which of the values ending at ``ends`` (cumulated counts) in ``rows`` read back whole."""
    starts = np.concatenate([[0], ends[:-1]]) if len(ends) else ends
    return np.array([rows.intact(int(a), int(b)) for a, b in zip(starts, ends)], dtype=bool)


def _read_value(group: h5py.Group, name: str, index: int) -> Any:
    counts = group[f"{name}__count"][: index + 1]
    start = int(np.sum(counts[:-1]))
    value = group[name][start:start + int(counts[-1])]
    return value[0] if read_attr(group[name], "scalar", False) else value


def _read_optional(group: h5py.Group, name: str, index: int) -> Any:
    """The dataclass (or None) stored as ``name`` at checkpoint ``index``."""
    present = f"{name}__present"
    if not group[present][index]:
        return None
    sub = _import(read_text(group[present], "class"))
    j = int(np.sum(group[present][:index]))  # its rows are those of the present values only
    missing = [g.name for g in dataclasses.fields(sub) if f"{name}.{g.name}__count" not in group]
    if missing:
        raise CheckpointVersionError(f"the checkpoint's {name} lacks {', '.join(missing)} (written by another srdda "
                         "version); run the model again")
    return sub(**{g.name: _read_value(group, f"{name}.{g.name}", j) for g in dataclasses.fields(sub)})


def read_checkpoint(group: h5py.Group, index: int, moments: Any) -> Any:
    """The State of checkpoint ``index``; ``moments(vertices) -> BlockMoments`` recomputes the integrals."""
    cls = _import(read_text(group, "state_class"))
    fields = {f.name: f for f in dataclasses.fields(cls) if f.name not in SKIPPED}
    stored = {k.split(".")[0].removesuffix("__present").removesuffix("__count") for k in group} - {*SKIPPED}
    unknown = sorted(stored - set(fields))
    if unknown:  # what a State of another srdda carried (e.g. contacts on the State itself): not to be lost
        raise CheckpointVersionError(f"the checkpoint holds {', '.join(unknown)}, which this srdda's State has not (written "
                         "by an older version); run the model again")
    kwargs: dict[str, Any] = {"step": int(group["step"][index]), "time": float(group["time"][index])}
    for name in fields:
        if f"{name}__present" in group:
            kwargs[name] = _read_optional(group, name, index)
        elif f"{name}__count" in group:
            kwargs[name] = _read_value(group, name, index)
        elif _mapping_keys(group, name):
            entries = {key: _read_optional(group, f"{name}.{key}", index) for key in _mapping_keys(group, name)}
            kwargs[name] = {key: value for key, value in entries.items() if value is not None}
        # a field the file does not have keeps its default (a file written before the field existed)
    if "ledger" in kwargs and len(kwargs["ledger"]) < len(LEDGER):  # LEDGER grows at its end: new columns from 0
        kwargs["ledger"] = np.pad(kwargs["ledger"], (0, len(LEDGER) - len(kwargs["ledger"])))
    kwargs["moments"] = moments(kwargs["vertices"])
    if not isinstance(kwargs["moments"], (BlockMoments, PolyhedronMoments)):
        raise TypeError("moments() must return BlockMoments or PolyhedronMoments")
    return cls(**kwargs)
