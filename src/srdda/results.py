"""Where a run's recorded steps go: the :class:`Recorder` interface and the in-memory :class:`Result`.

The run computes each recorded step's energies once (:func:`srdda.ledger.energies`)
and hands them, with the state, to every recorder: :class:`Result` keeps the
histories in memory (small runs, the API's return value),
:class:`srdda.io.results_store.ResultsStore` streams them to an HDF5 file.
With ``srdda.run(..., keep_history=False)`` the Result keeps only the first and
the last recorded step, so a long run streamed to a file does not grow in memory.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from .constraints.bolts import bolt_forces, bolt_state
from .energy_names import CUT_CAUSES
from .modeldata.arrays import ModelArrays
from .state import State

__all__ = ["Recorder", "Result", "measured_points", "bolt_histories"]


class Recorder(Protocol):
    """Receives the recorded steps of a run (in memory, to a file, ...).

    A recorder that holds something (a file, a lock) may also have
    ``abandon(reason: str)``: the run calls it instead of ``finish`` when it
    stops by an exception (Ctrl-C, an error), then lets the exception go on.
    """

    def record(self, arrays: ModelArrays, state: State, solves: int, energy: Mapping[str, float]) -> None: ...

    def finish(self, status: str, state: State) -> None: ...


def with_stage_row(rows: list[dict], index: int, entry: Mapping[str, object]) -> list[dict]:
    """The stage table ``rows`` with the row of stage ``index`` (a stage began or ended): the rows of the stages
    before it, then its own (a resumed run writes the rows of its stage and those after it again)."""
    return [row for row in rows if row["index"] < index] + [{"index": index, **entry}]


def reference_rows(steps: np.ndarray, stages: Sequence[Mapping[str, Any]]) -> np.ndarray:
    """For every recorded row (its ``steps``), the row its displacements are measured from: the first row, or
    the first row of the last stage begun by then that resets displacements (a staged run's ``stages`` table)."""
    steps = np.asarray(steps)
    out = np.zeros(len(steps), dtype=np.int64)
    for row in stages:
        at = np.flatnonzero(steps == row["first_step"])
        if row["reset_displacements"] and len(at):
            out[steps >= row["first_step"]] = at[0]
    return out


def removed_blocks(step: int, stages: Sequence[Mapping[str, Any]], n_blocks: int) -> np.ndarray:
    """The blocks (bool, n_blocks) the stages begun by ``step`` removed (a staged run's ``stages`` table)."""
    removed = np.zeros(n_blocks, dtype=bool)
    for row in stages:
        if row["first_step"] <= step:
            removed[row["removed_blocks"]] = True
    return removed


def measured_points(arrays: ModelArrays, state: State) -> tuple[np.ndarray, np.ndarray]:
    """Positions and velocities (n, dim) of the measured points."""
    mr = arrays.attached.measured_rows
    blocks = arrays.attached.point_block[mr]
    lever = state.points[mr] - state.moments.centroid[blocks]
    T = arrays.block_type.shape(lever)
    return state.points[mr].copy(), np.einsum("nij,nj->ni", T, state.velocity[blocks])


def bolt_histories(arrays: ModelArrays, state: State) -> dict[str, np.ndarray]:
    """The recorded bolt quantities of one state: axial and shear force (N; 0 once broken), broken flag,
    break time (s, nan while intact) and the two ends (n_bolts, 2, dim) of every bolt."""
    links = arrays.links
    if not links.n_bolts:  # every model records them: keep the common case cheap
        empty, no_end = np.zeros(0), np.zeros((0, arrays.block_type.dim))
        return {"bolt_force": empty, "bolt_shear_force": empty, "bolt_broken": np.zeros(0, dtype=bool),
                "bolt_break_time": empty, "bolt_ends": np.stack([no_end, no_end], axis=1)}
    bolts = bolt_forces(links, state)
    return {"bolt_force": bolts.axial, "bolt_shear_force": bolts.shear, "bolt_broken": ~bolts.intact,
            "bolt_break_time": np.array(bolt_state(links, state).break_time, dtype=float),
            "bolt_ends": np.stack([bolts.end_a, bolts.end_b], axis=1)}


BOLT_HISTORIES = ("bolt_force", "bolt_shear_force", "bolt_broken", "bolt_break_time", "bolt_ends")
_HISTORIES = ("step", "time", "centroid", "area", "rotation", "velocity", "stress", "measured_position",
              "measured_velocity", "energy", "iterations", "multipliers", "closed_contacts", "max_penetration",
              *BOLT_HISTORIES, "vertices")


@dataclass
class Result:
    """Recorded histories of a run (rows = recorded steps) and how it ended; the in-memory recorder.

    ``array(name)`` gives a history as one array: ``centroid`` (n, nb, dim),
    ``vertices`` (n, nv, dim), ``measured_position`` and ``measured_velocity``
    (n, nm, dim: the measured points in the order they were added; also
    :meth:`measured`), ``velocity``, ``stress``, ``energy`` (columns
    :attr:`energy_names`; also :meth:`energies`), ... ``keep_history=False``
    keeps the first and the latest recorded step only.
    """

    block_names: tuple[str, ...]
    method: str
    keep_history: bool = True
    step: list[int] = field(default_factory=list)
    time: list[float] = field(default_factory=list)
    centroid: list[np.ndarray] = field(default_factory=list)
    area: list[np.ndarray] = field(default_factory=list)  # block volume per metre of thickness in 2D
    rotation: list[np.ndarray] = field(default_factory=list)
    velocity: list[np.ndarray] = field(default_factory=list)
    stress: list[np.ndarray] = field(default_factory=list)
    measured_position: list[np.ndarray] = field(default_factory=list)
    measured_velocity: list[np.ndarray] = field(default_factory=list)
    energy: list[dict[str, float]] = field(default_factory=list)
    iterations: list[int] = field(default_factory=list)
    multipliers: list[np.ndarray] = field(default_factory=list)  # μ per step; force on point a = -μ (N/m)
    closed_contacts: list[int] = field(default_factory=list)  # closed (sliding or locked) contacts
    max_penetration: list[float] = field(default_factory=list)  # deepest closed contact (m)
    bolt_force: list[np.ndarray] = field(default_factory=list)  # axial force per bolt (N/m in 2D), 0 once broken
    bolt_shear_force: list[np.ndarray] = field(default_factory=list)  # |dowel force| per bolt
    bolt_broken: list[np.ndarray] = field(default_factory=list)  # bool per bolt
    bolt_break_time: list[np.ndarray] = field(default_factory=list)  # s, nan while intact
    bolt_ends: list[np.ndarray] = field(default_factory=list)  # (n_bolts, 2, dim) m
    vertices: list[np.ndarray] = field(default_factory=list)  # (nv, dim) m: every block's vertices
    bolt_names: tuple[str, ...] = ()
    keep_vertices: bool = True  # False: no vertices history (a large model's memory)
    status: str = "running"
    final_state: State | None = None
    stages: list[dict] = field(default_factory=list)  # a staged run's stage table (srdda.staging): one row a stage

    def stage(self, index: int, entry: Mapping[str, object]) -> None:
        """A stage of a staged run began or ended: its row of :attr:`stages`."""
        self.stages = with_stage_row(self.stages, index, entry)

    def array(self, name: str) -> np.ndarray:
        """A history as one array (first axis = recorded step); ``energy`` has the columns :attr:`energy_names`."""
        if name == "energy":
            return np.array([[e[k] for k in self.energy_names] for e in self.energy])
        return np.asarray(getattr(self, name))

    @property
    def energy_names(self) -> tuple[str, ...]:
        """The columns of ``array("energy")``: the ledger's entries (srdda.ledger.ENERGY_NAMES)."""
        return tuple(self.energy[0]) if self.energy else ()

    def energies(self) -> dict[str, np.ndarray]:
        """Every energy of the ledger as a series (J, J/m in 2D) by name: ``energies()["kinetic"]``."""
        table = self.array("energy")
        return {name: table[:, k] for k, name in enumerate(self.energy_names)}

    def measured(self, point: int) -> tuple[np.ndarray, np.ndarray]:
        """Position and velocity histories (n, dim) of measured point ``point`` (0: the first one added)."""
        return self.array("measured_position")[:, point], self.array("measured_velocity")[:, point]

    @property
    def completed(self) -> bool:
        return self.status == "completed"

    @property
    def cuts(self) -> dict[str, int]:
        """Step attempts cut in the run, by cause (:data:`srdda.term.CUT_CAUSES`), counted from its first step
        (``State.cuts``: a run continued from a state or a checkpoint goes on counting)."""
        return self.final_state.cuts_by_cause if self.final_state is not None else dict.fromkeys(CUT_CAUSES, 0)

    def record(self, arrays: ModelArrays, state: State, solves: int, energy: Mapping[str, float]) -> None:
        """Append one step's histories (replacing the latest one when the history is not kept)."""
        if not self.keep_history and len(self.step) == 2:
            for name in _HISTORIES:
                getattr(self, name).pop()
        mom = state.moments
        contacts = state.contacts
        pos, vel = measured_points(arrays, state)
        row = (state.step, state.time, mom.centroid, mom.volume, state.rotation.copy(), state.velocity.copy(),
               state.stress.copy(), pos, vel, dict(energy), solves, state.multipliers.copy(),
               0 if contacts is None else int(np.count_nonzero(contacts.closed)),
               0.0 if contacts is None else contacts.max_penetration,
               *bolt_histories(arrays, state).values(),
               state.vertices.copy() if self.keep_vertices else np.zeros((0, arrays.block_type.dim)))
        self.bolt_names = arrays.links.bolt_names
        for name, value in zip(_HISTORIES, row):
            getattr(self, name).append(value)

    def finish(self, status: str, state: State) -> None:
        self.status = status
        self.final_state = state
