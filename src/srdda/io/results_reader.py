"""Reading a results file (:mod:`srdda.io.results_store` writes it): its histories, model and checkpoints.

:func:`read_results` reads every flushed step into a :class:`StoredResult`
(the same histories as an in-memory :class:`~srdda.results.Result`),
:func:`model_arrays_from_file` the stored model, :func:`load_checkpoint` the
state of the last complete checkpoint. A step counts once every dataset of its
group holds it (the layout and the three-phase flush are in the store's module
doc and docs/results.md).
"""
from __future__ import annotations

import dataclasses
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from ..constraints.data import links_from_flat
from ..geometry.polyhedron import PolyhedronMesh
from ..ledger import ENERGY_NAMES
from ..model import JointTable, Load, ModelArrays
from ..settings import RunSettings
from ..state import State
from .checkpoint import checkpoint_count, increasing_prefix, read_checkpoint

__all__ = ["FORMAT", "FORMAT_VERSION", "ResultsFileError", "StoredResult", "read_results", "load_checkpoint",
           "model_arrays_from_file", "open_results", "group_length", "contact_records"]

FORMAT = "srdda-results"
FORMAT_VERSION = 2  # 2: one contact set for 2D and 3D, the joint table (1: srdda 0.1.0)


class ResultsFileError(ValueError):
    """The file is not an srdda results file or lacks what is asked of it."""


def group_length(group: h5py.Group) -> int:
    """Rows every dataset of ``group`` holds: the shortest extent, cut where ``step`` stops increasing."""
    n = min((ds.shape[0] for ds in group.values() if isinstance(ds, h5py.Dataset)), default=0)
    return increasing_prefix(group["step"][:n]) if "step" in group else n


def contact_records(c: h5py.Group) -> int:
    """Complete contact records: each needs its step and its closing offset."""
    return increasing_prefix(c["step"][: min(len(c["step"]), len(c["offsets"]) - 1)])


def model_arrays_from_file(path: str | Path) -> ModelArrays:
    """The :class:`ModelArrays` stored in a results file (callable loads cannot be stored)."""
    with open_results(path) as f:
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
            elif f_.name == "joints" and "joints.friction_angle" in g:
                kwargs["joints"] = JointTable(**{k[7:]: g[k][()] for k in g if k.startswith("joints.")})
            elif f_.name == "joints" and "joint_properties" in g:  # files of srdda 0.1.0: (nj, 3) columns
                table = g["joint_properties"][()]
                nan = np.full(len(table), np.nan)
                kwargs["joints"] = JointTable(table[:, 0], table[:, 1], table[:, 2], nan, nan.copy())
            elif f_.name in g:
                kwargs[f_.name] = g[f_.name][()]
            elif f_.default is None:  # an optional array (face_joint: 3D faces naming joint materials)
                kwargs[f_.name] = None
            else:
                raise ResultsFileError(f"{path}: the stored model lacks field {f_.name!r} (written by another "
                                       "srdda version?); pass the model to resume(..., model=...)")
        return ModelArrays(**kwargs)


def open_results(path: str | Path) -> h5py.File:
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise ResultsFileError(f"{path}: cannot open as an HDF5 results file ({exc})") from exc
    if f.attrs.get("format") != FORMAT:
        f.close()
        raise ResultsFileError(f"{path}: not an srdda results file (no format={FORMAT!r} attribute)")
    missing = [g for g in ("settings", "model", "history", "checkpoint", "contacts") if g not in f]
    if missing or "last_step" not in f.attrs:
        f.close()
        raise ResultsFileError(f"{path}: an incomplete results file (no {', '.join(missing) or 'last_step'}: the "
                               "run was stopped while it created the file); run the model again")
    return f


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

    @property
    def mesh(self) -> PolyhedronMesh | None:
        """The faces of 3D blocks, read from the file (None for a 2D run)."""
        with open_results(self.path) as f:
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


def read_results(path: str | Path, names: Sequence[str] | None = None) -> StoredResult:
    """Read every flushed step of a results file (also of a run that was killed).

    ``names`` reads only those histories (e.g. leave out the vertices of a large model).
    """
    with open_results(path) as f:
        hist = f["history"]
        n = group_length(hist)
        histories = {k: ds[:n] for k, ds in hist.items() if names is None or k in names}
        g = f["model"]
        c = f["contacts"]
        contacts: dict[str, np.ndarray] = {}
        if "step" in c:
            k = contact_records(c)
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
            versions={k: str(v) for k, v in f["versions"].attrs.items()},
            bolt_names=tuple(json.loads(g.attrs["links"]).get("bolt_names", ())) if "links" in g.attrs else ())


def load_checkpoint(path: str | Path, arrays: ModelArrays) -> State:
    """The :class:`State` of the last complete checkpoint of a results file."""
    def moments(vertices: np.ndarray):
        if vertices.shape != arrays.vertices.shape:
            raise ResultsFileError(f"{path}: the checkpoint has {len(vertices)} vertices, the model "
                                   f"{len(arrays.vertices)}")
        return arrays.moments(vertices)

    with open_results(path) as f:
        cp = f["checkpoint"]
        n = checkpoint_count(cp)
        if n == 0:
            raise ResultsFileError(f"{path}: no checkpoint was flushed; nothing to resume from")
        try:
            return read_checkpoint(cp, n - 1, moments)
        except ValueError as exc:
            raise ResultsFileError(f"{path}: {exc}") from None
