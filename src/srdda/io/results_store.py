"""The results file: one self-describing HDF5 file per run, written as it goes.

:class:`ResultsStore` is a :class:`~srdda.simulation.Recorder`. It buffers the
recorded steps in memory and every ``flush_every`` recorded steps appends them
to resizable, chunked datasets, writes a checkpoint of the full
:class:`~srdda.simulation.State` and flushes the file. A run killed at any
moment (even by SIGKILL) leaves a file holding every step up to the last flush,
and :func:`resume` continues it from the last checkpoint, appending to the same
file. :func:`read_results` reads a file back into a :class:`StoredResult` with
the same histories as an in-memory :class:`~srdda.simulation.Result`.

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

Every appended dataset only grows, so the extent stored at the last flush is
always consistent; readers take the shortest extent of a group as its length.
"""
from __future__ import annotations

import dataclasses
import datetime
import json
import platform
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import h5py
import numpy as np

from ..constraints.data import links_from_flat, links_to_flat
from ..geometry.polyhedron import PolyhedronMesh
from ..model import Load, Model, ModelArrays
from ..ledger import ENERGY_NAMES
from ..results import Result, measured_points
from ..settings import RunSettings
from ..simulation import run
from ..state import State
from .checkpoint import append_checkpoint, checkpoint_count, read_checkpoint, truncate_checkpoints

__all__ = ["FORMAT", "FORMAT_VERSION", "ContactProvider", "contacts_from_state", "ResultsStore", "ResultsFileError", "StoredResult",
           "read_results", "resume", "load_checkpoint", "model_arrays_from_file"]

FORMAT = "srdda-results"
FORMAT_VERSION = 1

ContactProvider = Callable[[ModelArrays, State], Mapping[str, np.ndarray] | None]
"""Hook for contact output: per-contact arrays (first axis = contact) of one state, or None.

The default, :func:`contacts_from_state`, reads the contact set on
``state.contacts``; another provider may give any arrays (e.g. ``{"point":
(nc, 2), "normal": (nc, 2), "normal_force": (nc,), "shear_force": (nc,)}``).
The store appends them at the recorded steps that are multiples of ``contact_every`` under ``/contacts``.
"""


def contacts_from_state(arrays: ModelArrays, state: State) -> dict[str, np.ndarray] | None:
    """The default contact output: the contact set a step leaves on ``state.contacts`` (None: no record).

    Gives ``point`` (the contact vertex), ``point_b`` (its foot on the
    contacted edge), ``normal`` (the edge's outward unit normal) and every
    per-contact array of the set (``state``, ``normal_force``, ``gap``, ...).
    """
    c = getattr(state, "contacts", None)
    if c is None or not hasattr(c, "vertex"):
        return None
    vertex = np.asarray(c.vertex, dtype=np.int64)
    out: dict[str, np.ndarray] = {"point": state.vertices[vertex]}
    if hasattr(c, "edge"):
        a = state.vertices[np.asarray(c.edge, dtype=np.int64)]
        b = state.vertices[arrays.next_vertex[np.asarray(c.edge, dtype=np.int64)]]
        d = b - a
        length2 = np.maximum(np.einsum("ij,ij->i", d, d), 1e-300)
        s = np.clip(np.einsum("ij,ij->i", out["point"] - a, d) / length2, 0.0, 1.0)
        out["point_b"] = a + s[:, None] * d
        out["normal"] = np.column_stack([d[:, 1], -d[:, 0]]) / np.sqrt(length2)[:, None]  # CCW: outward
    for f in dataclasses.fields(c):
        value = getattr(c, f.name)
        if isinstance(value, np.ndarray) and value.shape[:1] == vertex.shape and f.name not in out:
            out[f.name] = value
    return out


class ResultsFileError(ValueError):
    """The file is not an srdda results file or lacks what is asked of it."""


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


def _group_length(group: h5py.Group, names: Sequence[str] | None = None) -> int:
    """Rows every dataset of ``group`` holds (the shortest extent)."""
    keys = [k for k in (names or group.keys()) if k in group and isinstance(group[k], h5py.Dataset)]
    return min((group[k].shape[0] for k in keys), default=0)


def _write_model(group: h5py.Group, arrays: ModelArrays, model_text: str | None) -> None:
    """Every array field of ``arrays`` as a dataset; names, loads and the model text as attributes."""
    for f in dataclasses.fields(arrays):
        value = getattr(arrays, f.name)
        if isinstance(value, np.ndarray):
            group.create_dataset(f.name, data=value)
    if arrays.mesh is not None:  # the faces of 3D blocks
        for f in dataclasses.fields(arrays.mesh):
            group.create_dataset(f"mesh.{f.name}", data=getattr(arrays.mesh, f.name))
    links, links_meta = links_to_flat(arrays.links)  # hinges, springs, driven points (srdda.constraints)
    for name, value in links.items():
        group.create_dataset(f"links.{name}", data=value)
    group.attrs["links"] = json.dumps(links_meta)
    group.attrs["block_names"] = json.dumps(list(arrays.block_names))
    group.attrs["loads"] = json.dumps([ld.to_json() for ld in arrays.loads])
    if model_text is not None:
        group.attrs["model_text"] = model_text


def model_arrays_from_file(path: str | Path) -> ModelArrays:
    """The :class:`ModelArrays` stored in a results file (callable loads cannot be stored)."""
    with _open_read(path) as f:
        g = f["model"]
        loads_json = json.loads(g.attrs["loads"])
        if any(ld is None for ld in loads_json):
            raise ResultsFileError(f"{path}: the model has a point load given as a Python function, which a file "
                                   "cannot hold; pass the model to resume(..., model=...)")
        kwargs: dict[str, object] = {}
        for f_ in dataclasses.fields(ModelArrays):
            if f_.name == "block_names":
                kwargs[f_.name] = tuple(json.loads(g.attrs["block_names"]))
            elif f_.name == "loads":
                kwargs[f_.name] = tuple(Load.from_json(ld) for ld in loads_json)
            elif f_.name == "links" and "links" in g.attrs:
                try:
                    kwargs["links"] = links_from_flat({k[6:]: g[k][()] for k in g if k.startswith("links.")},
                                                      json.loads(g.attrs["links"]))
                except ValueError as exc:
                    raise ResultsFileError(f"{path}: {exc}; pass the model to resume(..., model=...)") from None
            elif f_.name == "mesh":
                fields = {k[5:]: g[k][()] for k in g if k.startswith("mesh.")}
                kwargs["mesh"] = PolyhedronMesh(**fields) if fields else None
            elif f_.name in g:
                kwargs[f_.name] = g[f_.name][()]
            else:
                raise ResultsFileError(f"{path}: the stored model lacks field {f_.name!r} (written by another "
                                       "srdda version?); pass the model to resume(..., model=...)")
        return ModelArrays(**kwargs)


def _open_read(path: str | Path) -> h5py.File:
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise ResultsFileError(f"{path}: cannot open as an HDF5 results file ({exc})") from exc
    if f.attrs.get("format") != FORMAT:
        f.close()
        raise ResultsFileError(f"{path}: not an srdda results file (no format={FORMAT!r} attribute)")
    return f


@dataclass
class ResultsStore:
    """Recorder writing a run into an HDF5 file incrementally (see the module docstring).

    ``flush_every``: recorded steps between flushes (and checkpoints); a killed
    run loses at most that many recorded steps. ``contact_provider`` gives
    the contact output (default: the contact set on ``state.contacts``),
    written at recorded steps that are multiples of ``contact_every``.
    ``model_text``: the model file's text, stored for provenance and re-runs.
    """

    path: str | Path
    settings: RunSettings
    flush_every: int = 100
    model_text: str | None = None
    contact_provider: ContactProvider | None = contacts_from_state
    contact_every: int = 1
    append: bool = False  # used by resume(): continue an existing file
    _file: h5py.File | None = field(default=None, init=False, repr=False)
    _buffer: dict[str, list[np.ndarray]] = field(default_factory=dict, init=False, repr=False)
    _contacts: dict[str, list[np.ndarray]] = field(default_factory=dict, init=False, repr=False)
    _contact_steps: list[int] = field(default_factory=list, init=False, repr=False)
    _contact_counts: list[int] = field(default_factory=list, init=False, repr=False)
    _pending: int = field(default=0, init=False, repr=False)
    _last_step: int = field(default=-1, init=False, repr=False)
    _state: State | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
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
        """Write what is buffered, a final checkpoint and the status; close the file."""
        if self._file is None:
            return
        self._state = state if state.step >= self._last_step else self._state
        self.flush()
        self._file.attrs["status"] = status
        self._file.close()
        self._file = None

    # -- writing ------------------------------------------------------------------
    def flush(self) -> None:
        """Append the buffered steps and a checkpoint of the last state; flush the file."""
        f = self._file
        if f is None:
            return
        hist = f["history"]
        for name, rows in self._buffer.items():
            if rows:
                _append(hist, name, np.stack(rows), self.flush_every)
        self._buffer = {}
        hist["energy"].attrs["names"] = json.dumps(ENERGY_NAMES)
        if self._contact_steps:
            g = f["contacts"]
            counts = self._contact_counts
            start = int(g["offsets"][-1]) if "offsets" in g and len(g["offsets"]) else 0
            if "offsets" not in g:
                _append(g, "offsets", np.zeros(1, dtype=np.int64), 1024)
            for name, rows in self._contacts.items():
                if rows:
                    _append(g, name, np.concatenate(rows), 4096)
            _append(g, "step", np.array(self._contact_steps, dtype=np.int64), 1024)
            _append(g, "offsets", start + np.cumsum(counts, dtype=np.int64), 1024)
            self._contacts, self._contact_steps, self._contact_counts = {}, [], []
        if self._state is not None:
            cp = f["checkpoint"]
            n = checkpoint_count(cp)
            if n == 0 or cp["step"][n - 1] != self._state.step:
                append_checkpoint(cp, self._state)
        self._pending = 0
        f.flush()

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
        if self.append:
            self._file = h5py.File(self.path, "a")
            self._last_step = _truncate_to_checkpoint(self._file)
            self._file.attrs["status"] = "running"
            return
        f = h5py.File(self.path, "w")
        f.attrs.update({"format": FORMAT, "format_version": FORMAT_VERSION, "method": self.settings.method,
                        "status": "running", "last_step": state.step + self.settings.n_steps,
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
        self._file = f


def _truncate_to_checkpoint(f: h5py.File) -> int:
    """Cut every appended dataset back to the last complete checkpoint; return its step."""
    cp = f["checkpoint"]
    n_cp = checkpoint_count(cp)
    if n_cp == 0:
        raise ResultsFileError(f"{f.filename}: no checkpoint was flushed; nothing to resume from")
    truncate_checkpoints(cp, n_cp)
    step = int(cp["step"][n_cp - 1])
    hist = f["history"]
    n = _group_length(hist)
    keep = int(np.searchsorted(hist["step"][:n], step, side="right"))
    for ds in hist.values():
        ds.resize(keep, axis=0)
    c = f["contacts"]
    if "step" in c:
        k = min(len(c["step"]), len(c["offsets"]) - 1)
        k = int(np.searchsorted(c["step"][:k], step, side="right"))
        rows = int(c["offsets"][k])
        for name, ds in c.items():
            ds.resize({"step": k, "offsets": k + 1}.get(name, rows), axis=0)
    return step


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

    @property
    def mesh(self) -> PolyhedronMesh | None:
        """The faces of 3D blocks, read from the file (None for a 2D run)."""
        with _open_read(self.path) as f:
            fields = {k[5:]: f["model"][k][()] for k in f["model"] if k.startswith("mesh.")}
        return PolyhedronMesh(**fields) if fields else None

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


def read_results(path: str | Path) -> StoredResult:
    """Read every flushed step of a results file (also of a run that was killed)."""
    with _open_read(path) as f:
        hist = f["history"]
        n = _group_length(hist)
        histories = {k: ds[:n] for k, ds in hist.items()}
        g = f["model"]
        c = f["contacts"]
        contacts: dict[str, np.ndarray] = {}
        if "step" in c:
            k = min(len(c["step"]), len(c["offsets"]) - 1)
            rows = int(c["offsets"][k])
            contacts = {name: ds[:k] if name == "step" else ds[:k + 1] if name == "offsets" else ds[:rows]
                        for name, ds in c.items()}
        energy_names = tuple(json.loads(hist["energy"].attrs["names"])) if "energy" in hist else ENERGY_NAMES
        return StoredResult(
            path=str(path), block_names=tuple(json.loads(g.attrs["block_names"])), method=str(f.attrs["method"]),
            status=str(f.attrs["status"]), settings=RunSettings(**json.loads(f["settings"].attrs["json"])),
            histories=histories, energy_names=energy_names, block_ptr=g["block_ptr"][()],
            block_material=g["block_material"][()], block_fixed=g["block_fixed"][()],
            initial_vertices=g["vertices"][()], contacts=contacts,
            model_text=str(g.attrs["model_text"]) if "model_text" in g.attrs else None,
            versions={k: str(v) for k, v in f["versions"].attrs.items()})


def load_checkpoint(path: str | Path, arrays: ModelArrays) -> State:
    """The :class:`State` of the last complete checkpoint of a results file."""
    def moments(vertices: np.ndarray):
        if vertices.shape != arrays.vertices.shape:
            raise ResultsFileError(f"{path}: the checkpoint has {len(vertices)} vertices, the model "
                                   f"{len(arrays.vertices)}")
        return arrays.moments(vertices)

    with _open_read(path) as f:
        cp = f["checkpoint"]
        n = checkpoint_count(cp)
        if n == 0:
            raise ResultsFileError(f"{path}: no checkpoint was flushed; nothing to resume from")
        return read_checkpoint(cp, n - 1, moments)


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

    The model comes from the file unless given: its stored arrays, or, when it
    has loads given as Python functions, the stored model file text (a model
    built in Python with such loads must be given). Returns the :class:`Result` of the continued
    part, holding its first and last recorded steps (the file holds the whole run).
    """
    arrays = _resume_arrays(path) if model is None else (model.arrays() if isinstance(model, Model) else model)
    with _open_read(path) as f:
        settings = RunSettings(**json.loads(f["settings"].attrs["json"]))
        last_step = int(f.attrs["last_step"])
        stored_flush = int(f.attrs["flush_every"])
        contact_every = int(f.attrs["contact_every"])
    state = load_checkpoint(path, arrays)
    remaining = dataclasses.replace(settings, n_steps=max(0, last_step - state.step))
    store = ResultsStore(path, remaining, flush_every=flush_every or stored_flush, append=True,
                         contact_provider=contact_provider, contact_every=contact_every)
    return run(arrays, remaining, progress=progress, state=state, recorders=[store], keep_history=False)
