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
the run holding it; it never truncates an existing file (a replaced file is
unlinked first, so a reader keeps its copy); before each flush it checks that
the disk has room for it and keeps ``<file>.reserve`` (room for one flush) to
close the file cleanly when the disk is full. A failed write stops the run
with one :class:`ResultsWriteError` saying which steps the file keeps.
"""
from __future__ import annotations

import dataclasses
import datetime
import errno
import io
import json
import os
import platform
import shutil
import socket
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

import h5py
import numpy as np

from ..constraints.data import links_to_flat
from ..model import Model, ModelArrays
from ..ledger import ENERGY_NAMES
from ..results import Result, bolt_histories, measured_points
from ..settings import RunSettings
from ..simulation import run
from ..state import State, initial_state
from .checkpoint import append_checkpoint, checkpoint_count, commit_checkpoint, truncate_checkpoints
from .results_reader import (FORMAT, FORMAT_VERSION, ResultsFileError, StoredResult, contact_records,
                             group_length, load_checkpoint, model_arrays_from_file, open_results, read_results)

__all__ = ["FORMAT", "FORMAT_VERSION", "ContactProvider", "contacts_from_state", "ResultsStore", "ResultsFileError",
           "ResultsWriteError", "OutputInUseError", "OutputExistsError", "StoredResult", "read_results", "resume",
           "load_checkpoint", "model_arrays_from_file"]


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


class ResultsWriteError(OSError):
    """The results file cannot be written (folder not writable, disk full, ...); the message says what is kept.

    ``cut_short``: a flush failed half-way, so HDF5 may crash when Python exits
    (a program should end without running exit handlers: ``os._exit``).
    """

    cut_short: bool = False


class OutputInUseError(ResultsWriteError):
    """Another run is writing the results file; the message names it (pid, host, start time, command)."""


class OutputExistsError(ResultsWriteError):
    """The results file exists and the store was told not to replace it."""


try:  # an advisory lock the OS drops when its holder dies, even by SIGKILL: no stale locks
    import fcntl

    def _try_lock(fh: IO[str]) -> bool:
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False
        return True
except ImportError:  # Windows
    import msvcrt

    def _try_lock(fh: IO[str]) -> bool:
        fh.seek(0)  # every run locks the same (first) byte
        try:
            msvcrt.locking(fh.fileno(), msvcrt.LK_NBLCK, 1)
        except OSError:
            return False
        return True


def _lock_path(path: Path) -> Path:
    return path.with_name(path.name + ".lock")


def _reserve_path(path: Path) -> Path:
    return path.with_name(path.name + ".reserve")


def _take_lock(path: Path) -> IO[str]:
    """Hold ``<path>.lock`` (an OS lock) and write who holds it; raise :class:`OutputInUseError` if another run does."""
    lock = _lock_path(path)
    while True:
        try:
            fh = open(lock, "a+", encoding="utf-8")
        except OSError as exc:
            raise ResultsWriteError(f"{path}: cannot write in {path.parent} ({exc.strerror})") from None
        try:
            locked = _try_lock(fh)
        except OSError as exc:  # a file system without locks (some network mounts)
            fh.close()
            raise ResultsWriteError(f"{path}: cannot lock {lock} ({exc.strerror}); write to a local disk") from None
        if not locked:
            fh.seek(0)
            holder = fh.read().strip() or "a run that has not said who it is yet"
            fh.close()
            raise OutputInUseError(f"{path} is being written by another run ({holder}); wait for it to end or "
                                   "write to another output")
        try:  # the previous holder may have removed the lock file between our open and our lock: retry
            if os.fstat(fh.fileno()).st_ino == os.stat(lock).st_ino:
                break
        except FileNotFoundError:
            pass
        fh.close()
    started = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    fh.seek(0)
    fh.truncate()
    fh.write(f"pid {os.getpid()} on {socket.gethostname()}, started {started}, command: {' '.join(sys.argv)}\n")
    fh.flush()
    return fh


def _release_lock(path: Path, fh: IO[str]) -> None:
    """Remove ``<path>.lock`` while still holding it, then drop the lock."""
    try:
        os.remove(_lock_path(path))
    except OSError:
        pass
    fh.close()


def _make_room(path: Path, reserve: int, need: int) -> None:
    """Check that ``need`` bytes beyond the reserve are free; keep ``<path>.reserve`` at ``reserve`` bytes.

    Where the OS can allocate disk blocks (posix_fallocate) the check allocates
    them for real (so quotas count too) and gives them back for the flush;
    elsewhere it reads the free space. Raises OSError (ENOSPC) if there is no room.
    """
    reserve_file = _reserve_path(path)
    with open(reserve_file, "r+b" if reserve_file.exists() else "wb") as fh:
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


def _free_reserve(path: Path) -> None:
    try:
        os.remove(_reserve_path(path))
    except OSError:
        pass


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

    from .. import __version__

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
                                                       *(max(d, 1) for d in row)))
    ds = group[name]
    n = ds.shape[0]
    ds.resize(n + len(rows), axis=0)
    ds[n:] = rows


def _write_model(group: h5py.Group, arrays: ModelArrays, model_text: str | None) -> None:
    """Every array field of ``arrays`` as a dataset; names, loads and the model text as attributes."""
    for f in dataclasses.fields(arrays):
        value = getattr(arrays, f.name)
        if isinstance(value, np.ndarray):
            group.create_dataset(f.name, data=value)
    for part in ("mesh", "joints"):  # the faces of 3D blocks (None in 2D); the joint table
        record = getattr(arrays, part)
        if record is not None:
            for f in dataclasses.fields(record):
                group.create_dataset(f"{part}.{f.name}", data=getattr(record, f.name))
    links, links_meta = links_to_flat(arrays.links)  # hinges, springs, driven points (srdda.constraints)
    for name, value in links.items():
        group.create_dataset(f"links.{name}", data=value)
    group.attrs["links"] = json.dumps(links_meta)
    group.attrs["block_names"] = json.dumps(list(arrays.block_names))
    group.attrs["loads"] = json.dumps([ld.to_json() for ld in arrays.loads])
    if model_text is not None:
        group.attrs["model_text"] = model_text


@dataclass
class ResultsStore:
    """Recorder writing a run into an HDF5 file incrementally (see the module docstring).

    ``flush_every``: recorded steps between flushes (and checkpoints); a killed
    run loses at most that many recorded steps. ``contact_provider`` gives
    the contact output (default: the contact set on ``state.contacts``),
    written at recorded steps that are multiples of ``contact_every``.
    ``model_text``: the model file's text, stored for provenance and re-runs.
    ``overwrite``: replace an existing file (False: raise :class:`OutputExistsError`).

    The store holds ``<path>.lock`` from :meth:`acquire` (called at the first
    record if not before) to :meth:`finish`; a write that fails stops the run
    with :class:`ResultsWriteError` and leaves the file resumable.
    """

    path: str | Path
    settings: RunSettings
    flush_every: int = 100
    model_text: str | None = None
    contact_provider: ContactProvider | None = contacts_from_state
    contact_every: int = 1
    append: bool = False  # used by resume(): continue an existing file
    overwrite: bool = True
    _file: h5py.File | None = field(default=None, init=False, repr=False)
    _lock: IO[str] | None = field(default=None, init=False, repr=False)
    _reserved: int = field(default=0, init=False, repr=False)  # bytes held by <path>.reserve
    _flushed_step: int = field(default=-1, init=False, repr=False)  # step of the last complete checkpoint
    _buffer: dict[str, list[np.ndarray]] = field(default_factory=dict, init=False, repr=False)
    _contacts: dict[str, list[np.ndarray]] = field(default_factory=dict, init=False, repr=False)
    _contact_steps: list[int] = field(default_factory=list, init=False, repr=False)
    _contact_counts: list[int] = field(default_factory=list, init=False, repr=False)
    _pending: int = field(default=0, init=False, repr=False)
    _last_step: int = field(default=-1, init=False, repr=False)
    _state: State | None = field(default=None, init=False, repr=False)

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

    def finish(self, status: str, state: State) -> None:
        """Write what is buffered, a final checkpoint and the status; close the file and release it."""
        if self._file is None:
            self.release()
            return
        self._state = state if state.step >= self._last_step else self._state
        self.flush()
        self._guarded(lambda: self._set_status_and_close(status))
        self.release()

    # -- holding the output -------------------------------------------------------
    def acquire(self) -> None:
        """Take the output's lock; refuse an existing file unless ``overwrite`` or ``append``.

        Raises :class:`OutputInUseError` naming the run that holds it,
        :class:`OutputExistsError`, or :class:`ResultsWriteError` (folder not writable).
        """
        if self._lock is not None:
            return
        self._lock = _take_lock(self.path)
        if not self.append and not self.overwrite and self.path.exists():
            self.release()
            raise OutputExistsError(f"{self.path} exists: {_describe(self.path)}")

    def release(self) -> None:
        """Drop the output's lock (and the disk reserve); :meth:`finish` does it at the end of a run."""
        if self._lock is not None:
            _free_reserve(self.path)
            _release_lock(self.path, self._lock)
            self._lock = None
            self._reserved = 0

    def _set_status_and_close(self, status: str) -> None:
        f = self._file
        self._file = None
        f.attrs["status"] = status
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
        sys.unraisablehook = lambda unraisable: failures.append(unraisable.exc_value)
        sys.stderr = captured = io.StringIO()
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
        stderr.write(captured.getvalue())  # what else the writes printed (a warning, say)

    def _abort(self, exc: BaseException, cut_short: bool) -> None:
        """Stop writing after a failed write (``cut_short``: it failed inside a flush of the HDF5 file)."""
        _free_reserve(self.path)
        f, self._file = self._file, None
        if f is not None and not cut_short:  # the file is as the last flush left it: mark it and close it
            try:
                f.attrs["status"] = f"stopped: the results could not be written ({_reason(exc)})"
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
        advice = (f"free some space or fix the folder, then continue with: srdda run --resume {self.path}"
                  if self._flushed_step >= 0 else "free some space or fix the folder, then run again")
        error = ResultsWriteError(f"{self.path}: cannot write the results ({_reason(exc)}); the file keeps {kept}; "
                                  f"{advice}")
        error.cut_short = f is not None and cut_short
        raise error from None

    # -- writing ------------------------------------------------------------------
    def flush(self) -> None:
        """Append the buffered steps and a checkpoint of the last state; flush the file."""
        if self._file is None:
            return
        need = _flush_bytes(self._buffer, self._state)
        self._reserved = max(self._reserved, need)
        # a full disk fails here, before the file is touched; the reserve is there to close it cleanly
        self._guarded(lambda: _make_room(self.path, self._reserved, need), touches_file=False)
        self._write_buffered()
        self._pending = 0
        if self._state is not None:
            self._flushed_step = self._state.step

    def _write_buffered(self) -> None:
        """Three phases, each flushed: the data; the step rows that make them count; the checkpoint's step.

        A write that fails in a phase stops the flush there, leaving what the
        earlier phases made count: readers and resume see exactly the flushed
        steps, and a checkpoint only once every step up to it is on disk.
        """
        f = self._file
        hist, contacts, cp = f["history"], f["contacts"], f["checkpoint"]
        n_cp = checkpoint_count(cp)
        new_checkpoint = self._state is not None and (n_cp == 0 or cp["step"][n_cp - 1] != self._state.step)

        def data() -> None:
            for name, rows in self._buffer.items():
                if rows and name != "step":
                    _append(hist, name, np.stack(rows), self.flush_every)
            hist["energy"].attrs["names"] = json.dumps(ENERGY_NAMES)
            if self._contact_steps:
                if "offsets" not in contacts:
                    _append(contacts, "offsets", np.zeros(1, dtype=np.int64), 1024)
                for name, rows in self._contacts.items():
                    if rows:
                        _append(contacts, name, np.concatenate(rows), 4096)
            if new_checkpoint:
                append_checkpoint(cp, self._state, commit=False)
            f.flush()

        def steps() -> None:
            if self._buffer.get("step"):
                _append(hist, "step", np.stack(self._buffer["step"]), self.flush_every)
            if self._contact_steps:
                start = int(contacts["offsets"][-1])
                _append(contacts, "step", np.array(self._contact_steps, dtype=np.int64), 1024)
                _append(contacts, "offsets", start + np.cumsum(self._contact_counts, dtype=np.int64), 1024)
            f.flush()

        def checkpoint() -> None:
            if new_checkpoint:
                commit_checkpoint(cp, self._state)
                f.flush()

        self._guarded(data, steps, checkpoint)
        self._buffer = {}
        self._contacts, self._contact_steps, self._contact_counts = {}, [], []

    def _record_contacts(self, arrays: ModelArrays, state: State) -> None:
        given = self.contact_provider(arrays, state)  # type: ignore[misc]
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
        self.acquire()
        self._reserved = _flush_bytes({}, state)
        self._guarded(lambda: _make_room(self.path, self._reserved, self._reserved), touches_file=False)
        self._guarded(lambda: self._open_file(arrays, state))

    def _open_file(self, arrays: ModelArrays, state: State) -> None:
        if self.append:
            self._file = h5py.File(self.path, "a")
            self._last_step = _truncate_to_checkpoint(self._file)
            self._flushed_step = self._last_step
            self._file.attrs["status"] = "running"
            return
        if self.path.exists():  # unlink, never truncate: a reader of the old file keeps its copy
            self.path.unlink()
        f = self._file = h5py.File(self.path, "w-")
        f.attrs.update({"format": FORMAT, "format_version": FORMAT_VERSION, "method": self.settings.method,
                        "status": "running",  # last_step -1: the run goes to its end_time, not a step count
                        "last_step": -1 if self.settings.n_steps is None else state.step + self.settings.n_steps,
                        "flush_every": self.flush_every, "contact_every": self.contact_every,
                        "created": datetime.datetime.now(datetime.timezone.utc).isoformat()})
        from .. import __version__

        f.attrs["srdda_version"] = __version__
        f.create_group("versions").attrs.update(_versions())
        f.create_group("settings").attrs["json"] = json.dumps(dataclasses.asdict(self.settings))
        _write_model(f.create_group("model"), arrays, self.model_text)
        f.create_group("history")
        f.create_group("checkpoint")
        f.create_group("contacts")
        f.flush()


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
            return (f"the results of a run (status {str(f.attrs.get('status', '?'))!r}, created "
                    f"{str(f.attrs.get('created', '?'))})")
    except OSError:
        return "a file that is not an srdda results file"


def _truncate_to_checkpoint(f: h5py.File) -> int:
    """Cut every appended dataset back to the last complete checkpoint; return its step.

    Without a complete checkpoint (a run stopped before its first flush) every
    dataset is emptied and -1 returned: the run restarts from its initial state.
    """
    cp = f["checkpoint"]
    n_cp = checkpoint_count(cp)
    truncate_checkpoints(cp, n_cp)
    if n_cp == 0:
        for group in (f["history"], f["contacts"]):
            for name in list(group):
                del group[name]
        return -1
    step = int(cp["step"][n_cp - 1])
    hist = f["history"]
    n = group_length(hist)
    keep = int(np.searchsorted(hist["step"][:n], step, side="right"))
    for ds in hist.values():
        ds.resize(keep, axis=0)
    c = f["contacts"]
    if "step" in c:
        k = int(np.searchsorted(c["step"][:contact_records(c)], step, side="right"))
        rows = int(c["offsets"][k])
        for name, ds in c.items():
            ds.resize({"step": k, "offsets": k + 1}.get(name, rows), axis=0)
    return step


def _resume_arrays(path: str | Path) -> ModelArrays:
    """The stored model arrays; for Python-function loads, the model rebuilt from the stored model file text."""
    try:
        return model_arrays_from_file(path)
    except ResultsFileError:
        text = read_results(path).model_text
        if text is None:
            raise
    import tomllib

    from .modelfile import model_from_dict

    return model_from_dict(tomllib.loads(text), source=f"model text stored in {path}")[0].arrays()


def resume(path: str | Path, model: Model | ModelArrays | None = None, flush_every: int | None = None,
           progress: Callable[[int], None] | None = None,
           contact_provider: ContactProvider | None = contacts_from_state,
           ) -> Result:
    """Continue the run of a results file from its last checkpoint up to its last step, appending to it.

    A file without a checkpoint (a run stopped before its first flush) restarts from the initial state.

    The model comes from the file unless given: its stored arrays, or, when it
    has loads given as Python functions, the stored model file text (a model
    built in Python with such loads must be given). Returns the :class:`Result` of the continued
    part, holding its first and last recorded steps (the file holds the whole run).
    """
    arrays = _resume_arrays(path) if model is None else (model.arrays() if isinstance(model, Model) else model)
    with open_results(path) as f:
        settings = RunSettings(**json.loads(f["settings"].attrs["json"]))
        last_step = int(f.attrs["last_step"])
        stored_flush = int(f.attrs["flush_every"])
        contact_every = int(f.attrs["contact_every"])
        flushed = checkpoint_count(f["checkpoint"]) > 0
    # a run stopped before its first flush restarts from its initial state
    state = load_checkpoint(path, arrays) if flushed else initial_state(arrays, settings.resolved_method())
    remaining = settings if last_step < 0 else dataclasses.replace(settings, n_steps=max(0, last_step - state.step))
    store = ResultsStore(path, remaining, flush_every=flush_every or stored_flush, append=True,
                         contact_provider=contact_provider, contact_every=contact_every)
    return run(arrays, remaining, progress=progress, state=state, recorders=[store], keep_history=False)
