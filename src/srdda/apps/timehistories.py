"""Time histories of blocks and measured points as a table, one column per component (``srdda history``).

As UDEC's HISTORY: every recorded step of a run (an in-memory
:class:`~srdda.results.Result` or a results file's
:class:`~srdda.io.results_reader.StoredResult`) is a row; the columns are the
time, the step, then each chosen block's and measured point's quantities, in
SI units named in the header. The components and units are those of the
figures (:func:`srdda.apps.plotting.components`, :func:`srdda.apps.plotting.quantity_unit`).
"""
from __future__ import annotations

import csv
from collections.abc import Sequence
from typing import IO, Any

import numpy as np

from .plotting import components, quantity_unit

__all__ = ["BLOCK_QUANTITIES", "POINT_QUANTITIES", "history_table", "write_history_csv"]

Results = Any  # Result or StoredResult: both have .array(name), .block_names

# what each quantity of a block or a measured point is made of: (recorded history, from its start?)
BLOCK_QUANTITIES = {"centroid": ("centroid", False), "displacement": ("centroid", True),
                    "rotation": ("rotation", False), "velocity": ("velocity", False), "stress": ("stress", False),
                    "area": ("area", False)}
POINT_QUANTITIES = {"position": ("measured_position", False), "displacement": ("measured_position", True),
                    "velocity": ("measured_velocity", False)}


def _columns(res: Results, name: str, history: str, relative: bool) -> tuple[np.ndarray, list[str], list[str]]:
    """A quantity of every block or point as (recorded steps, blocks or points, components), its component
    names and their units."""
    values = np.asarray(res.array(history), dtype=float)
    if relative:
        values = values - values[0]
    per_item = values.reshape(len(values), values.shape[1], -1)
    if values.ndim == 2:  # one number per block: area, a 2D rotation
        return per_item, [name], [quantity_unit(res, history)]
    comps = components(res).get(history)
    if comps is None:  # a 3D rotation: the entries of the matrix R, row by row
        n = values.shape[-1]
        return per_item, [f"{name}.R{i + 1}{j + 1}" for i in range(n) for j in range(n)], ["1"] * n * n
    if history == "measured_velocity":  # named as a block's velocity of translation: velocity.vx fits both
        comps = tuple(f"v{c}" for c in comps)
    units = [quantity_unit(res, history if history.startswith("measured") else f"{history}.{c}") for c in comps]
    return per_item, [f"{name}.{c}" for c in comps], units


def _chosen(res: Results, asked: Sequence[str], table: dict[str, tuple[str, bool]], what: str,
            ) -> list[tuple[np.ndarray, list[str], list[str]]]:
    """The columns of the quantities ``asked`` (all when none) of ``what`` ("blocks", "measured points"):
    a name of ``table`` (all its components) or NAME.COMPONENT; ValueError naming one that is not there."""
    out = []
    for q in asked or list(table):
        name, _, part = q.partition(".")
        if name not in table:
            raise ValueError(f"no quantity {q!r} for {what}; they have {', '.join(table)}")
        values, names, units = _columns(res, name, *table[name])
        if part:
            if q not in names:
                raise ValueError(f"no quantity {q!r}; the components of {name} are {', '.join(names)}")
            k = names.index(q)
            values, names, units = values[..., k:k + 1], [q], [units[k]]
        out.append((values, names, units))
    return out


def history_table(res: Results, blocks: Sequence[int] = (), points: Sequence[int] = (),
                  quantities: Sequence[str] = ()) -> tuple[list[str], np.ndarray]:
    """The header and the table (recorded steps × columns) of the histories of ``blocks`` and measured
    ``points`` (indices): ``time (s)``, ``step``, then per block and per point each of ``quantities``
    (all of :data:`BLOCK_QUANTITIES` / :data:`POINT_QUANTITIES` when empty; ``velocity.vx``: one component).

    A quantity that blocks or points (whichever are asked for) do not record is a ValueError naming it.
    """
    header, parts = ["time (s)", "step"], [res.array("time")[:, None], res.array("step")[:, None]]
    for items, table, what, labels in ((blocks, BLOCK_QUANTITIES, "blocks", [res.block_names[b] for b in blocks]),
                                       (points, POINT_QUANTITIES, "measured points", [f"point {p}" for p in points])):
        if not len(items):
            continue
        chosen = _chosen(res, quantities, table, what)
        values = np.concatenate([v[:, list(items)] for v, _, _ in chosen], axis=2)  # (steps, items, columns)
        names = [f"{n} ({u})" for _, ns, us in chosen for n, u in zip(ns, us)]
        header += [f"{label}: {n}" for label in labels for n in names]
        parts.append(values.reshape(len(values), -1))
    return header, np.concatenate(parts, axis=1)


def write_history_csv(header: list[str], table: np.ndarray, out: IO[str]) -> None:
    """The table as CSV: the header row, then one row per recorded step (every digit of each number)."""
    csv.writer(out, lineterminator="\n").writerow(header)
    np.savetxt(out, table, delimiter=",", fmt="%.17g")
