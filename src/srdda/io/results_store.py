"""The results file: one self-describing HDF5 file per run, written as it goes.

:class:`ResultsStore` is a :class:`~srdda.simulation.Recorder`. It buffers the
recorded steps in memory and every ``flush_every`` recorded steps appends them
to resizable, chunked datasets, writes a checkpoint of the full
:class:`~srdda.simulation.State` and flushes the file. A run killed at any
moment (even by SIGKILL) leaves a file holding every step up to the last flush,
and :func:`resume` continues it from the last checkpoint, appending to the same
file. :func:`read_results` (:mod:`srdda.io.results_reader`, re-exported here)
reads a file back into a :class:`StoredResult` with the same histories as an
in-memory :class:`~srdda.simulation.Result`.

Layout (see docs/results.md)::

    /                 attrs: format, format_version, srdda_version, method, status,
                      last_step, flush_every, contact_every, created
    /versions         attrs: python, numpy, scipy, h5py, hdf5, ...
    /settings         attrs: json (the RunSettings)
    /model            one dataset per array field of ModelArrays; attrs: block_names,
                      model_text (when the model came from a file), loads (json)
    /history/<name>   first axis = recorded step: step, time, centroid, area,
                      rotation, velocity, stress, vertices, measured_position,
                      measured_velocity, energy (attr names), iterations
    /checkpoint/<f>   one checkpoint per flush: step, time and every State field
                      (see :mod:`srdda.io.checkpoint`)
    /contacts/<name>  rows of all recorded contacts, ``offsets`` (k+1) and ``step`` (k)

Every appended dataset only grows. A flush writes in three phases, each
flushed to the file: the data rows (histories, contact rows, checkpoint
fields), then the ``step`` rows that make them count (history, contacts), then
the checkpoint's ``step``. Readers take the shortest extent of a group, cut
where ``step`` stops increasing, as its length; so a flush cut short anywhere
leaves exactly the earlier flushes visible, and a checkpoint only counts once
every step up to it is on disk.

Output safety (docs/reliability.md): a store holds its file from the first
write (or :meth:`ResultsStore.acquire`) to :meth:`ResultsStore.finish` by an
OS lock on ``<file>.lock`` taken before the HDF5 file is opened, which names
the run holding it (:mod:`srdda.io.outputlock`); it never truncates an existing
file (a replaced file is unlinked first, so a reader keeps its copy); before
each flush it checks that the disk has room for it and keeps a reserve (room
for one flush, in a file without a name: nothing is left behind, whatever
stops the run) to close the file cleanly when the disk is full. A failed write
stops the run with one :class:`ResultsWriteError` saying which steps the file
keeps. Every dataset and text attribute carries a checksum
(:mod:`srdda.io.integrity`): a damaged file is found when it is read, and
:func:`resume` continues it from its last intact checkpoint.
"""
from __future__ import annotations

import dataclasses
import datetime
import errno
import json
import io
import os
import platform
import shutil
import sys
import tempfile
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from operator import attrgetter
from pathlib import Path
from typing import IO

import h5py
import numpy as np

from .._version import __version__
from ..constraints.data import links_to_flat
from ..model import Model, ModelArrays
from ..ledger import ENERGY_NAMES
from ..results import Result, bolt_histories, measured_points, with_stage_row
from ..settings import RunSettings
from ..simulation import run
from ..state import State, initial_state
from .checkpoint import append_checkpoint, checkpoint_count, commit_checkpoint, truncate_checkpoints
from .integrity import LIBVER, DamagedError, checksummed, read_text, write_text
from .outputlock import OutputInUseError, ResultsWriteError, release_lock, take_lock
from .results_reader import (FORMAT, FORMAT_VERSION, MODEL_DATASETS, Intact, ResultsDamageWarning, ResultsFileError,
                             ResultsInUseError, StoredResult, checkpoint_state, inspect_results, load_checkpoint,
                             model_arrays_from_file, open_results, read_header, read_results, stage_table)

__all__ = ["FORMAT", "FORMAT_VERSION", "ContactProvider", "contacts_from_state", "ResultsStore", "ResultsFileError",
           "ResultsWriteError", "ResultsDamageWarning", "ResultsInUseError", "OutputInUseError", "OutputExistsError",
           "StoredResult", "read_results", "resume", "prepare_resume", "Resumption", "ResumePoint", "load_checkpoint",
           "model_arrays_from_file"]


ContactProvider = Callable[[ModelArrays, State], Mapping[str, np.ndarray] | None]
"""Hook for contact output: per-contact arrays (first axis = contact) of one state, or None.

The default, :func:`contacts_from_state`, reads the contact set on
``state.contacts``; another provider may give any arrays (e.g. ``{"point":
(nc, 2), "normal": (nc, 2), "normal_force": (nc,), "shear_force": (nc,)}``).
The store appends them at the recorded steps that are multiples of ``contact_every`` under ``/contacts``.
"""


def contacts_from_state(arrays: ModelArrays, state: State) -> dict[str, np.ndarray] | None:
    """The default contact output: the contact set a step leaves on ``state.contacts`` (None: no record).

    Every per-contact array of the set, in 2D and 3D alike: ``point`` (the
    contact point x_a at the start of the step), ``point_b`` (its foot on the
    other block), ``normal``, ``state``, ``normal_force``, ``gap``, ``shear``,
    ``direction``, ``block_a``, ``block_b``, ... (:class:`srdda.contact.ContactSet`).
    """
    c = getattr(state, "contacts", None)
    if c is None:
        return None
    n = len(c.key)
    return {f.name: getattr(c, f.name) for f in dataclasses.fields(c)
            if isinstance(getattr(c, f.name), np.ndarray) and len(getattr(c, f.name)) == n}


class OutputExistsError(ResultsWriteError):
    """The results file exists and the store was told not to replace it."""


def _lock_path(path: Path) -> Path:
    return path.with_name(path.name + ".lock")


def _reserve_file(path: Path) -> IO[bytes]:
    """A file without a name in ``path``'s folder to hold the disk reserve: the OS frees it with its holder."""
    return tempfile.TemporaryFile(dir=path.parent, prefix=f".{path.name}.reserve-")


def _make_room(reserve_file: IO[bytes], path: Path, reserve: int, need: int) -> None:
    """Check that ``need`` bytes beyond the reserve are free; keep ``reserve`` bytes in ``reserve_file``.

    Where the OS can allocate disk blocks (posix_fallocate) the check allocates
    them for real (so quotas count too) and gives them back for the flush;
    elsewhere it reads the free space of ``path``'s folder. Raises OSError (ENOSPC) if there is no room.
    """
    fh = reserve_file
    if hasattr(os, "posix_fallocate"):
        os.posix_fallocate(fh.fileno(), 0, reserve + need)
        fh.truncate(reserve)
        return
    fh.seek(0, os.SEEK_END)
    block = bytes(1 << 20)
    while fh.tell() < reserve:
        fh.write(block[: reserve - fh.tell()])
    fh.flush()
    os.fsync(fh.fileno())
    if shutil.disk_usage(path.parent).free < need:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def _flush_bytes(rows: Mapping[str, list[np.ndarray]], state: State | None) -> int:
    """An upper bound of the disk space one flush takes (see docs/reliability.md).

    Each appended dataset may allocate a new chunk besides its rows (chunks hold
    at most one flush of rows, or one checkpoint), hence the factor 2; contact
    chunks (at most ~64 KiB each) and HDF5 metadata fit in the 2 MiB added.
    """
    history = sum(a.nbytes for arrays in rows.values() for a in arrays)
    checkpoint = 0
    if state is not None:
        for f in dataclasses.fields(state):
            value = getattr(state, f.name)
            if isinstance(value, np.ndarray):
                checkpoint += value.nbytes
            elif dataclasses.is_dataclass(value):
                checkpoint += sum(np.asarray(getattr(value, g.name)).nbytes for g in dataclasses.fields(value))
    return 2 * (history + checkpoint) + (2 << 20)


def _versions() -> dict[str, str]:
    import scipy

    return {"srdda": __version__, "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__, "h5py": h5py.__version__, "hdf5": h5py.version.hdf5_version,
            "platform": platform.platform()}


def _chunk_rows(row_shape: tuple[int, ...], itemsize: int, rows: int) -> int:
    """Rows per chunk: one flush worth of rows, capped near 1 MiB per chunk."""
    row_bytes = max(1, int(np.prod(row_shape, dtype=np.int64)) * itemsize)
    return int(max(1, min(rows, (1 << 20) // row_bytes)))


def _append(group: h5py.Group, name: str, rows: np.ndarray, chunk_rows: int) -> None:
    """Append ``rows`` (first axis = new rows) to a resizable dataset, creating it if needed."""
    rows = np.asarray(rows)
    if name not in group:
        row = rows.shape[1:]  # an empty axis (no measured points, say) cannot be chunked: leave it growable
        group.create_dataset(name, shape=(0, *row), maxshape=(None, *(d if d else None for d in row)),
                             dtype=rows.dtype, chunks=(_chunk_rows(row, rows.dtype.itemsize, chunk_rows),
                                                       *(max(d, 1) for d in row)), fletcher32=True)
    ds = group[name]
    n = ds.shape[0]
    ds.resize(n + len(rows), axis=0)
    ds[n:] = rows


def _write_model(group: h5py.Group, arrays: ModelArrays, model_text: str | None) -> None:
    """Every array of ``arrays`` as a dataset (named as :data:`MODEL_DATASETS` says); names, loads, stages and
    the model text as attributes (checksummed). A stage's arrays store the model as built (``arrays.base``)."""
    arrays = arrays.base if arrays.base is not None else arrays

    def dataset(name: str, value: np.ndarray) -> None:
        value = np.asarray(value)
        group.create_dataset(name, data=value, **checksummed(value))

    for name, field_ in MODEL_DATASETS.items():
        value = attrgetter(field_)(arrays)
        if value is not None:  # an optional array (face_joint in 2D, block_removed without stages)
            dataset(name, value)
    for part in ("mesh", "joints"):  # the faces of 3D blocks (None in 2D); the joint table
        record = getattr(arrays, part)
        if record is not None:
            for f in dataclasses.fields(record):
                dataset(f"{part}.{f.name}", getattr(record, f.name))
    links, links_meta = links_to_flat(arrays.links)  # hinges, springs, driven points (srdda.constraints)
    for name, value in links.items():
        dataset(f"links.{name}", value)
    write_text(group, "links", json.dumps(links_meta))
    write_text(group, "block_names", json.dumps(list(arrays.block_names)))
    write_text(group, "loads", json.dumps([ld.to_json() for ld in arrays.attached.load_force]))
    if model_text is not None:
        write_text(group, "model_text", model_text)
    if arrays.stages:
        write_text(group, "stages", json.dumps([plan.to_json() for plan in arrays.stages]))


@dataclass(frozen=True)
class ResumePoint:
    """Where :func:`resume` continues a file: the checkpoint, and the rows the file keeps before it.

    ``step`` -1: no usable checkpoint, the run restarts from its initial state.
    ``copy`` (a damaged file): the intact rows to keep, written into a new file
    that replaces the damaged one; None: the file is cut back in place.
    """

    step: int
    checkpoint: int
    history_rows: int
    contact_records: int
    last_step: int  # where the run ends (-1: at its end time)
    copy: Intact | None = None


@dataclass
class ResultsStore:
    """Recorder writing a run into an HDF5 file incrementally (see the module docstring).

    ``flush_every``: recorded steps between flushes (and checkpoints); a killed
    run loses at most that many recorded steps. ``contact_provider`` gives
    the contact output (default: the contact set on ``state.contacts``),
    written at recorded steps that are multiples of ``contact_every``.
    ``model_text``: the model file's text, stored for provenance and re-runs.
    ``overwrite``: replace an existing file (False: raise :class:`OutputExistsError`).
    ``resume_from``: continue an existing file from that point (:func:`resume` sets it).

    The store holds ``<path>.lock`` from :meth:`acquire` (called at the first
    record if not before) to :meth:`finish` (or :meth:`abandon`, when the run
    stops by an exception); a write that fails stops the run with
    :class:`ResultsWriteError` and leaves the file resumable.
    """

    path: Path  # a str is taken too: __post_init__ makes it a Path
    settings: RunSettings
    flush_every: int = 100
    model_text: str | None = None
    contact_provider: ContactProvider | None = contacts_from_state
    contact_every: int = 1
    resume_from: ResumePoint | None = None
    overwrite: bool = True
    _file: h5py.File | None = field(default=None, init=False, repr=False)
    _lock: IO[str] | None = field(default=None, init=False, repr=False)
    _reserve: IO[bytes] | None = field(default=None, init=False, repr=False)  # the disk reserve's file
    _reserved: int = field(default=0, init=False, repr=False)  # bytes it holds
    _flushed_step: int = field(default=-1, init=False, repr=False)  # step of the last complete checkpoint
    _writing: bool = field(default=False, init=False, repr=False)  # inside a write to the file
    _buffer: dict[str, list[np.ndarray]] = field(default_factory=dict, init=False, repr=False)
    _contacts: dict[str, list[np.ndarray]] = field(default_factory=dict, init=False, repr=False)
    _contact_steps: list[int] = field(default_factory=list, init=False, repr=False)
    _contact_counts: list[int] = field(default_factory=list, init=False, repr=False)
    _pending: int = field(default=0, init=False, repr=False)
    _last_step: int = field(default=-1, init=False, repr=False)
    _state: State | None = field(default=None, init=False, repr=False)
    stage_table: list[dict] = field(default_factory=list, init=False, repr=False)  # rows of the stages begun

    def __post_init__(self) -> None:
        self.path = Path(self.path)
        if self.flush_every < 1:
            raise ValueError(f"flush_every must be >= 1, got {self.flush_every}")
        if self.contact_every < 1:
            raise ValueError(f"contact_every must be >= 1, got {self.contact_every}")

    # -- Recorder protocol ----------------------------------------------------
    def record(self, arrays: ModelArrays, state: State, solves: int, energy: Mapping[str, float]) -> None:
        """Buffer one recorded step; flush every ``flush_every`` of them."""
        if self._file is None:
            self._open(arrays, state)
        if state.step <= self._last_step:  # a resumed run re-records its starting state
            return
        mom = state.moments
        pos, vel = measured_points(arrays, state)
        row = {"step": np.int64(state.step), "time": np.float64(state.time), "centroid": mom.centroid,
               "area": mom.volume, "rotation": state.rotation, "velocity": state.velocity, "stress": state.stress,
               "vertices": state.vertices, "measured_position": pos, "measured_velocity": vel,
               "energy": np.array([energy[k] for k in ENERGY_NAMES]), "iterations": np.int64(solves)}
        if arrays.links.n_multipliers:  # constraint forces, one row per step (srdda.constraints)
            row["multipliers"] = state.multipliers
        row.update(bolt_histories(arrays, state))  # rock bolts: forces, broken flags, ends
        for name, value in row.items():
            self._buffer.setdefault(name, []).append(np.array(value, copy=True))
        if self.contact_provider is not None and state.step % self.contact_every == 0:
            self._record_contacts(arrays, state)
        self._last_step = state.step
        self._state = state
        self._pending += 1
        if self._pending >= self.flush_every:
            self.flush()

    def stage(self, index: int, entry: Mapping[str, object]) -> None:
        """A stage of a staged run began or ended: its row of the stage table (written at the next flush)."""
        self.stage_table = with_stage_row(self.stage_table, index, entry)

    def finish(self, status: str, state: State) -> None:
        """Write what is buffered, a final checkpoint and the status; close the file and release it."""
        if self._file is None:
            self.release()
            return
        self._state = state if state.step >= self._last_step else self._state
        self.flush()
        self._guarded(lambda: self._set_status_and_close(status))
        self.release()

    def abandon(self, reason: str) -> None:
        """The run stopped by an exception (Ctrl-C, an error): keep what is recorded, close, release.

        Outside a write, the buffered steps are flushed with a checkpoint and the
        status says why the run stopped (``srdda run --resume`` continues it);
        inside one (the exception interrupted a flush) the file is left as its
        last complete flush made it.
        """
        if self._file is not None and self._writing:
            f, self._file = self._file, None
            _detach(f)
        elif self._file is not None:
            try:
                if self._state is not None:
                    self.finish(f"stopped: {reason}", self._state)
                else:
                    self._guarded(lambda: self._set_status_and_close(f"stopped: {reason}"))
            except ResultsWriteError:
                pass
        self.release()

    # -- holding the output -------------------------------------------------------
    def acquire(self) -> None:
        """Take the output's lock; refuse an existing file unless ``overwrite`` or resuming it.

        Raises :class:`OutputInUseError` naming the run that holds it,
        :class:`OutputExistsError`, or :class:`ResultsWriteError` (folder not writable).
        """
        if self._lock is not None:
            return
        self._lock = take_lock(_lock_path(self.path), str(self.path))
        if self.resume_from is None and not self.overwrite and self.path.exists():
            self.release()
            raise OutputExistsError(f"{self.path} exists: {_describe(self.path)}")

    def release(self) -> None:
        """Drop the output's lock and the disk reserve; :meth:`finish` does it at the end of a run."""
        if self._reserve is not None:
            self._reserve.close()
            self._reserve, self._reserved = None, 0
        if self._lock is not None:
            release_lock(_lock_path(self.path), self._lock)
            self._lock = None

    def _set_status_and_close(self, status: str) -> None:
        f = self._file
        assert f is not None  # called with the file open
        self._file = None
        write_text(f, "status", status)
        f.close()

    def _guarded(self, *writes: Callable[[], None], touches_file: bool = True) -> None:
        """Run ``writes`` in order; on a failure stop, close the file keeping what is flushed, raise ResultsWriteError.

        h5py reports a failed write as OSError or RuntimeError, or, when it
        happens as an object is released, only to ``sys.unraisablehook`` and
        stderr: those are collected here instead of printed (one traceback per
        open object otherwise), and count as failures, checked after each write.
        """
        failures: list[BaseException] = []
        hook, stderr = sys.unraisablehook, sys.stderr
        sys.unraisablehook = lambda unraisable: failures.append(unraisable.exc_value
                                                                or RuntimeError(unraisable.err_msg))
        sys.stderr = captured = io.StringIO()
        self._writing = touches_file
        try:
            for write in writes:
                write()
                if failures:
                    break
        except (OSError, RuntimeError) as exc:
            failures.insert(0, exc)
        finally:
            sys.unraisablehook, sys.stderr = hook, stderr
        if failures:
            self._abort(failures[0], touches_file)
        self._writing = False
        stderr.write(captured.getvalue())  # what else the writes printed (a warning, say)

    def _abort(self, exc: BaseException, cut_short: bool) -> None:
        """Stop writing after a failed write (``cut_short``: it failed inside a flush of the HDF5 file)."""
        self._writing = False
        if self._reserve is not None:  # its room lets the file close cleanly on a full disk
            self._reserve.close()
            self._reserve, self._reserved = None, 0
        f, self._file = self._file, None
        if f is not None and not cut_short:  # the file is as the last flush left it: mark it and close it
            try:
                write_text(f, "status", f"stopped: the results could not be written ({_reason(exc)})")
                f.close()
            except (OSError, RuntimeError):
                cut_short = True
        if f is not None and cut_short:
            _detach(f)
        self.release()
        kept = (f"every step up to step {self._flushed_step}" if self._flushed_step >= 0
                else "no step (it failed before its first flush)")
        if f is not None and cut_short:
            kept += " unless the interrupted flush damaged it"
        error = ResultsWriteError(f"{self.path}: cannot write the results ({_reason(exc)}); the file keeps {kept}; "
                                  f"{_advice(exc, self.path, self._flushed_step >= 0)}")
        error.cut_short = f is not None and cut_short
        raise error from None

    # -- writing ------------------------------------------------------------------
    def flush(self) -> None:
        """Append the buffered steps and a checkpoint of the last state; flush the file."""
        if self._file is None:
            return
        self._make_room(_flush_bytes(self._buffer, self._state))
        history = {name: np.stack(rows) for name, rows in self._buffer.items() if rows}
        contacts = {name: np.concatenate(rows) for name, rows in self._contacts.items() if rows}
        self._write(history, contacts, self._contact_steps, self._contact_counts)
        self._buffer = {}
        self._contacts, self._contact_steps, self._contact_counts = {}, [], []
        self._pending = 0
        if self._state is not None:
            self._flushed_step = self._state.step

    def _make_room(self, need: int) -> None:
        """Room on the disk for a write of ``need`` bytes and the reserve; a full disk fails here, file untouched."""
        def make_room() -> None:
            if self._reserve is None:
                self._reserve = _reserve_file(self.path)
            _make_room(self._reserve, self.path, self._reserved, need)

        self._reserved = max(self._reserved, need)
        self._guarded(make_room, touches_file=False)

    def _write(self, history: Mapping[str, np.ndarray], contacts: Mapping[str, np.ndarray],
               contact_steps: list[int], contact_counts: list[int]) -> None:
        """Three phases, each flushed: the data; the step rows that make them count; the checkpoint's step.

        ``history``: rows of each history (``step`` among them); ``contacts``:
        the rows of the contact records of ``contact_steps``, ``contact_counts``
        rows each. A write that fails in a phase stops the flush there, leaving
        what the earlier phases made count: readers and resume see exactly the
        flushed steps, and a checkpoint only once every step up to it is on disk.
        """
        f = self._file
        assert f is not None  # flush returns without a file
        hist, c, cp = f["history"], f["contacts"], f["checkpoint"]
        n_cp = checkpoint_count(cp)
        new_checkpoint = self._state is not None and (n_cp == 0 or cp["step"][n_cp - 1] != self._state.step)

        def data() -> None:
            for name, rows in history.items():
                if name != "step":
                    _append(hist, name, rows, self.flush_every)
            if "energy" in hist:
                write_text(hist["energy"], "names", json.dumps(ENERGY_NAMES))
            if contact_steps:
                if "offsets" not in c:
                    _append(c, "offsets", np.zeros(1, dtype=np.int64), 1024)
                for name, rows in contacts.items():
                    _append(c, name, rows, 4096)
            for group in (hist, c):  # what a damaged file would lack
                write_text(group, "datasets", json.dumps(sorted(group)))
            if self.stage_table:
                write_text(f, "stages", json.dumps(self.stage_table))
            if new_checkpoint:
                append_checkpoint(cp, self._state, commit=False)
            f.flush()

        def steps() -> None:
            if "step" in history:
                _append(hist, "step", history["step"], self.flush_every)
            if contact_steps:
                start = int(c["offsets"][-1])
                _append(c, "step", np.array(contact_steps, dtype=np.int64), 1024)
                _append(c, "offsets", start + np.cumsum(contact_counts, dtype=np.int64), 1024)
            f.flush()

        def checkpoint() -> None:
            if new_checkpoint:
                commit_checkpoint(cp, self._state)
                f.flush()

        self._guarded(data, steps, checkpoint)

    def _record_contacts(self, arrays: ModelArrays, state: State) -> None:
        assert self.contact_provider is not None  # record calls this only with a provider
        given = self.contact_provider(arrays, state)
        if given is None:
            return
        data = {k: np.asarray(v) for k, v in given.items()}
        sizes = {len(v) for v in data.values()}
        if len(sizes) > 1:
            raise ValueError(f"contact arrays of step {state.step} differ in length: {sizes}")
        for name, value in data.items():
            self._contacts.setdefault(name, []).append(value)
        self._contact_counts.append(sizes.pop() if sizes else 0)
        self._contact_steps.append(state.step)

    def _open(self, arrays: ModelArrays, state: State) -> None:
        if self.resume_from is not None:  # a failure before the first flush keeps what the file kept
            self._flushed_step = self.resume_from.step
        self.acquire()
        self._make_room(_flush_bytes({}, state))
        self._guarded(lambda: self._open_file(arrays, state))

    def _open_file(self, arrays: ModelArrays, state: State) -> None:
        point = self.resume_from
        if point is not None and point.copy is None:
            self._file = h5py.File(self.path, "a")
            self._last_step = _cut_back(self._file, point)
            rows = stage_table(self._file)  # the rows of the stages before the resumed one, then the run's
            for row in self.stage_table:
                rows = with_stage_row(rows, row["index"], row)
            self.stage_table = rows
            write_text(self._file, "status", "running")
            self._file.attrs["flush_every"] = self.flush_every
            return
        if self.path.exists():  # unlink, never truncate: a reader of the old file keeps its copy
            self.path.unlink()
        f = self._file = h5py.File(self.path, "w-", libver=LIBVER)
        staged = bool((arrays.base if arrays.base is not None else arrays).stages)  # the stages say where it ends
        last_step = -1 if self.settings.n_steps is None or staged else state.step + self.settings.n_steps
        if point is not None:  # a damaged file rewritten: the run keeps its end
            last_step = point.last_step
        f.attrs.update({"format_version": FORMAT_VERSION, "last_step": last_step, "flush_every": self.flush_every,
                        "contact_every": self.contact_every})
        for name, text in (("format", FORMAT), ("method", self.settings.method), ("status", "running"),
                           ("created", datetime.datetime.now(datetime.timezone.utc).isoformat()),
                           ("srdda_version", __version__)):
            write_text(f, name, text)
        versions = f.create_group("versions")
        for name, text in _versions().items():
            write_text(versions, name, text)
        write_text(f.create_group("settings"), "json", json.dumps(dataclasses.asdict(self.settings)))
        _write_model(f.create_group("model"), arrays, self.model_text)
        f.create_group("history")
        f.create_group("checkpoint")
        f.create_group("contacts")
        f.flush()
        if point is not None and point.step >= 0:
            self._copy_intact(point, state)

    def _copy_intact(self, point: ResumePoint, state: State) -> None:
        """Write the intact rows of a damaged file (``point.copy``) and the checkpoint to continue from."""
        copy = point.copy
        assert copy is not None  # a damaged file's point (_open cuts a sound one back in place)
        history = {name: rows[:point.history_rows] for name, rows in copy.histories.items()}
        contacts, steps, counts = {}, [], []
        if point.contact_records:
            k, offsets = point.contact_records, copy.contacts["offsets"]
            contacts = {name: rows[:offsets[k]] for name, rows in copy.contacts.items()
                        if name not in ("step", "offsets")}
            steps, counts = copy.contacts["step"][:k].tolist(), np.diff(offsets[:k + 1]).tolist()
        self._state = state
        self._write(history, contacts, steps, counts)
        self._last_step = point.step


def _reason(exc: BaseException) -> str:
    """The OS's words for a failed write (h5py buries them in a long message)."""
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    text = str(exc)
    marker = "error message = '"
    if marker in text:
        return text.split(marker, 1)[1].split("'", 1)[0]
    return text.splitlines()[0] if text else type(exc).__name__


def _detach(f: h5py.File) -> None:
    """Close a file whose flush failed without writing to it again.

    HDF5 would retry the failed writes on close with metadata it could not
    keep consistent (in tests that retry damaged the flushed steps): the file's
    descriptor is pointed at the null device first, so the file keeps what the
    OS took before the failure; h5py's complaints while it closes are not
    printed. HDF5 may still hold objects of the file whose release failed and
    crash when it shuts down at exit (see docs/reliability.md).
    """
    hook, stderr = sys.unraisablehook, sys.stderr
    sys.unraisablehook, sys.stderr = (lambda _: None), io.StringIO()
    try:
        null = os.open(os.devnull, os.O_RDWR)
        os.dup2(null, f.id.get_vfd_handle())
        os.close(null)
        f.close()
    except (OSError, ValueError, RuntimeError):
        pass
    finally:
        sys.unraisablehook, sys.stderr = hook, stderr


def _describe(path: Path) -> str:
    """What a results file holds, for messages: its status and when it was created."""
    try:
        with h5py.File(path, "r") as f:
            return f"the results of a run (status {read_text(f, 'status')!r}, created {read_text(f, 'created')})"
    except (OSError, DamagedError):
        return "a file that is not an srdda results file (or a damaged one)"


def _advice(exc: BaseException, path: Path, kept: bool) -> str:
    """What to do after a failed write: free space, or make the folder writable; then resume or run again."""
    code = exc.errno if isinstance(exc, OSError) else None
    if code in (errno.EACCES, errno.EPERM, errno.EROFS) or "ermission denied" in str(exc) or "ead-only" in str(exc):
        fix = f"make {path.parent} writable"
    elif code in (errno.ENOSPC, errno.EDQUOT) or "o space left" in str(exc):
        fix = "free some space"
    else:
        fix = "free some space or fix the folder"
    return f"{fix}, then continue with: srdda run --resume {path}" if kept else f"{fix}, then run again"


def _cut_back(f: h5py.File, point: ResumePoint) -> int:
    """Cut every appended dataset back to ``point`` (an intact file); return its step (-1: emptied, a restart)."""
    cp = f["checkpoint"]
    if point.step < 0:
        for group in (f["history"], f["contacts"], cp):
            for name in list(group):
                del group[name]
            for name in [a for a in group.attrs if a.startswith("datasets")]:
                del group.attrs[name]
        return -1
    truncate_checkpoints(cp, point.checkpoint + 1)
    for ds in f["history"].values():
        ds.resize(point.history_rows, axis=0)
    c = f["contacts"]
    if "step" in c:
        k = point.contact_records
        rows = int(c["offsets"][k])
        for name, ds in c.items():
            ds.resize({"step": k, "offsets": k + 1}.get(name, rows), axis=0)
    return point.step


def _resume_arrays(path: str | Path) -> ModelArrays:
    """The stored model arrays; for Python-function loads, the model rebuilt from the stored model file text."""
    try:
        return model_arrays_from_file(path)
    except ResultsFileError:
        with warnings.catch_warnings():  # the damage, if any, is told by the resume
            warnings.simplefilter("ignore", ResultsDamageWarning)
            text = read_results(path, names=("step",)).model_text
        if text is None:
            raise
    import tomllib

    from .modelfile import model_from_dict

    return model_from_dict(tomllib.loads(text), source=f"model text stored in {path}")[0].arrays()


@dataclass
class Resumption:
    """A resume ready to run (:func:`prepare_resume`): the file is held, its state loaded; :meth:`run` continues it.

    ``start``: the step it continues from (-1: the run restarts from its
    initial state); ``settings``: the run's settings for the steps left;
    ``damage``: one line naming what of the file is damaged (None if intact).
    """

    path: Path
    arrays: ModelArrays
    settings: RunSettings
    state: State
    store: ResultsStore
    start: int
    damage: str | None

    def run(self, progress: Callable[[int], None] | None = None) -> Result:
        """Continue the run to its end, appending to the file; returns the :class:`Result` of the continued part."""
        try:
            return run(self.arrays, self.settings, progress=progress, state=self.state, recorders=[self.store],
                       keep_history=False)
        finally:
            self.store.release()


def prepare_resume(path: str | Path, model: Model | ModelArrays | None = None, flush_every: int | None = None,
                   contact_provider: ContactProvider | None = contacts_from_state) -> Resumption:
    """Hold a results file and find where its run continues: its last intact checkpoint (see :func:`resume`).

    Raises :class:`OutputInUseError` (another run holds the file),
    :class:`ResultsWriteError` (its folder cannot be written) or
    :class:`ResultsFileError` (not a results file, or damaged where it cannot be resumed).
    """
    path = Path(path)
    with open_results(path) as f:  # for the store; read again below, under the lock
        header = read_header(f, path)
    store = ResultsStore(path, header.settings, flush_every=flush_every or header.flush_every,
                         contact_provider=contact_provider, contact_every=header.contact_every,
                         resume_from=ResumePoint(-1, -1, 0, 0, header.last_step))
    try:
        store.acquire()
    except OutputInUseError:
        raise
    except ResultsWriteError as exc:
        raise ResultsWriteError(f"{exc}; the file is unchanged: make the folder writable, then resume it again"
                                ) from None
    try:
        return _prepare(path, store, model)
    except BaseException:
        store.release()
        raise


def _prepare(path: Path, store: ResultsStore, model: Model | ModelArrays | None) -> Resumption:
    arrays = _resume_arrays(path) if model is None else (model.arrays() if isinstance(model, Model) else model)
    with open_results(path) as f:
        header = read_header(f, path)
        found = inspect_results(f, path, keep=False)  # checks every row; keeps the steps only
        problems = list(found.problems)
        state, chosen = None, -1
        for index in np.flatnonzero(found.checkpoint_intact & (found.checkpoint_steps <= found.last_step))[::-1]:
            try:
                state, chosen = checkpoint_state(f["checkpoint"], int(index), arrays, path), int(index)
                break
            except ResultsFileError as exc:
                problems.append(str(exc).removeprefix(f"{path}: "))
        if problems and state is not None:  # the intact rows to copy into a new file
            found = inspect_results(f, path)
            try:
                store.stage_table = stage_table(f)
            except DamagedError:  # the resumed run writes the rows of its stages again
                store.stage_table = []
    settings = header.settings
    start = -1 if state is None else state.step
    if state is None:
        state = initial_state(arrays, settings.resolved_method())
    rows = int(np.searchsorted(found.histories["step"], start, side="right")) if "step" in found.histories else 0
    records = int(np.searchsorted(found.contacts["step"], start, side="right")) if found.contacts else 0
    damaged = dataclasses.replace(found, problems=tuple(problems))
    store.resume_from = ResumePoint(start, chosen, rows, records, header.last_step, damaged if problems else None)
    then = (f"; resuming from the checkpoint at step {start}" if start >= 0
            else "; restarting the run from its beginning")
    remaining = settings if header.last_step < 0 else dataclasses.replace(
        settings, n_steps=max(0, header.last_step - state.step))
    return Resumption(path, arrays, remaining, state, store, start, damaged.message(path, then))


def resume(path: str | Path, model: Model | ModelArrays | None = None, flush_every: int | None = None,
           progress: Callable[[int], None] | None = None,
           contact_provider: ContactProvider | None = contacts_from_state,
           ) -> Result:
    """Continue the run of a results file from its last intact checkpoint up to its last step, appending to it.

    The run keeps every setting the file stores (its flush interval too, unless
    ``flush_every`` is given). A file without an intact checkpoint (a run
    stopped before its first flush, or damaged before it) restarts from the
    initial state. A damaged file (:func:`~srdda.io.results_reader.inspect_results`)
    gives a :class:`ResultsDamageWarning` naming the damage; its intact rows up
    to the checkpoint are kept (in a new file that replaces it) and the rest
    is run again, so it ends as the uninterrupted run would have.

    The model comes from the file unless given: its stored arrays, or, when it
    has loads given as Python functions, the stored model file text (a model
    built in Python with such loads must be given). Returns the :class:`Result` of the continued
    part, holding its first and last recorded steps (the file holds the whole run).
    """
    prepared = prepare_resume(path, model, flush_every, contact_provider)
    if prepared.damage is not None:
        warnings.warn(prepared.damage, ResultsDamageWarning, stacklevel=2)
    return prepared.run(progress)
