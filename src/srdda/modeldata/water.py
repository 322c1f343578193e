"""The water in the joints as data: the phreatic surface, the tension cracks and their validation.

:class:`WaterTable` is what ``Model.water`` and ``ModelArrays.water`` hold; the pressures it gives and the terms
that apply them are :mod:`srdda.constraints.water` (which re-exports these names) and
:mod:`srdda.contact.water` (docs/water.md).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

__all__ = ["UNIT_WEIGHT", "TensionCrack", "WaterTable", "water_table"]

UNIT_WEIGHT = 9810.0  # N/m³: fresh water, 1000 kg/m³ × 9.81 m/s²


def _vector(values: Sequence[float], dim: int, what: str) -> tuple[float, ...]:
    v = tuple(float(x) for x in values)
    if len(v) != dim:
        raise ValueError(f"{what}: needs {dim} components in a {dim}D model, got {len(v)}")
    if not all(np.isfinite(v)):
        raise ValueError(f"{what}: must be finite numbers, got {list(v)}")
    return v


def _unit(values: Sequence[float], dim: int, what: str) -> tuple[float, ...]:
    v = np.array(_vector(values, dim, what))
    size = float(np.linalg.norm(v))
    if size == 0.0:
        raise ValueError(f"{what}: must not be zero")
    return tuple(float(x) for x in v / size)


@dataclass(frozen=True)
class TensionCrack:
    """An open crack: the plane through ``point`` with ``normal`` (either sense), water ``depth`` m deep in it
    above its bottom."""

    point: tuple[float, ...]
    normal: tuple[float, ...]  # unit
    depth: float


@dataclass(frozen=True)
class WaterTable:
    """The phreatic surface (the plane through ``point`` with the upward unit ``normal``), the water's unit
    weight γ_w (N/m³) and the tension cracks (module doc). ``up``: the unit vector against gravity.

    Change it between runs with :meth:`at_level`, :meth:`raised` or :func:`dataclasses.replace` on the model's
    (``Model.water``) or the arrays' (``ModelArrays.water``) table.
    """

    point: tuple[float, ...]
    normal: tuple[float, ...]
    up: tuple[float, ...]
    unit_weight: float = UNIT_WEIGHT
    cracks: tuple[TensionCrack, ...] = ()

    def head(self, x: np.ndarray) -> np.ndarray:
        """h (n,): the height of the surface above points ``x`` (n, dim) (negative above it), m."""
        n = np.asarray(self.normal)
        return (np.asarray(self.point) - x) @ n / float(n @ np.asarray(self.up))

    def pressure(self, x: np.ndarray) -> np.ndarray:
        """p (n,) = γ_w·max(h, 0) at points ``x`` (n, dim), Pa."""
        return self.unit_weight * np.maximum(self.head(x), 0.0)

    def raised(self, by: float) -> WaterTable:
        """The table with its surface ``by`` m higher (negative: a drawdown); the cracks' water unchanged."""
        return replace(self, point=tuple(float(p) for p in np.asarray(self.point) + by * np.asarray(self.up)))

    def at_level(self, level: float) -> WaterTable:
        """The table with its surface moved up or down so that it stands at elevation ``level`` (m, against
        gravity) above its point (a horizontal surface: at ``level`` everywhere); the cracks' water unchanged."""
        return self.raised(level - self.level())

    def level(self) -> float:
        """The surface's elevation (along ``up``) at the point it was given by, m."""
        return float(np.asarray(self.point) @ np.asarray(self.up))

    def padded(self) -> WaterTable:
        """The table of the model extruded along a new last axis (:meth:`srdda.model.Model.extruded`)."""
        def pad(v: tuple[float, ...]) -> tuple[float, ...]:
            return (*v, 0.0)

        return WaterTable(pad(self.point), pad(self.normal), pad(self.up), self.unit_weight,
                          tuple(TensionCrack(pad(c.point), pad(c.normal), c.depth) for c in self.cracks))


def water_table(gravity: Sequence[float] | np.ndarray, level: float | None = None, point: Sequence[float] | None = None,
                normal: Sequence[float] | None = None, unit_weight: float = UNIT_WEIGHT,
                cracks: Sequence[tuple[Sequence[float], Sequence[float], float]] = ()) -> WaterTable:
    """A validated :class:`WaterTable`: a horizontal ``level`` (elevation against gravity, m) or a plane
    through ``point`` with upward ``normal``; ``cracks`` as (point, normal, depth). ValueError naming the field.
    """
    dim = len(gravity)
    g = np.asarray(gravity, dtype=float)
    if not np.all(np.isfinite(g)) or not np.any(g != 0.0):
        raise ValueError("gravity: water pressure needs gravity (the model's gravity is zero)")
    up = tuple(float(x) for x in -g / np.linalg.norm(g))
    if not 0.0 < unit_weight < np.inf:
        raise ValueError(f"unit_weight: must be finite and > 0 (N/m³), got {unit_weight}")
    if (level is None) == (point is None):
        raise ValueError("level: give 'level' (a horizontal surface) or 'point' with 'normal', exactly one")
    if level is not None:
        if normal is not None:
            raise ValueError("normal: goes with 'point', not with 'level'")
        if not np.isfinite(level):
            raise ValueError(f"level: must be a finite number, got {level}")
        at, n = tuple(float(level) * u for u in up), up
    else:
        if normal is None:
            raise ValueError("normal: give the surface's upward normal with its 'point'")
        assert point is not None
        at, n = _vector(point, dim, "point"), _unit(normal, dim, "normal")
        if float(np.dot(n, up)) <= 0.0:
            raise ValueError(f"normal: must point up (against gravity {list(g)}), got {list(n)}")
    out = []
    for i, (p, cn, depth) in enumerate(cracks):
        if not 0.0 <= depth < np.inf:
            raise ValueError(f"cracks[{i}].depth: must be finite and >= 0 (m), got {depth}")
        out.append(TensionCrack(_vector(p, dim, f"cracks[{i}].point"), _unit(cn, dim, f"cracks[{i}].normal"),
                                float(depth)))
    return WaterTable(at, n, up, float(unit_weight), tuple(out))
