"""Shi's legacy DDA text input: geometry (``.geo``, DC) and analysis (``.ana``, DF) files.

Geometry: e00; joint count and boundary-line count; counts of material lines,
bolts, fixed lines, load points, measured points, hole points; then
``x1 y1 x2 y2 type`` joint lines, ``x1 y1 x2 y2 material`` material lines,
bolts (7 numbers, not supported), ``x1 y1 x2 y2`` fixed lines (a point when
both ends coincide), ``x y`` load, measured and hole points.

Analysis: static(0)/dynamic(1) flag, number of steps, number of block and
joint materials, g2 (maximum displacement ratio), maximum time step; then per
block material 13 numbers (unit mass, unit weight, E, ν, initial stresses
σx σy τxy, initial strains, initial velocities vx vy ω) and per joint
material (friction angle °, cohesion, tension). The original format has no
penalty factor: 50 as in DDA for Windows.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from .ddainput import BlockMaterialSpec, DDAInput, DDAInputError, read_input_text

__all__ = ["read_legacy"]


def _numbers(path: Path) -> np.ndarray:
    text = read_input_text(path)
    try:
        return np.array([float(t) for t in text.split()])
    except ValueError as exc:
        raise DDAInputError(f"{path}: not a legacy DDA file of numbers ({exc})") from None


class _Reader:
    def __init__(self, path: Path) -> None:
        self.path, self.values, self.pos = path, _numbers(path), 0

    def take(self, n: int, what: str) -> np.ndarray:
        if self.pos + n > len(self.values):
            raise DDAInputError(f"{self.path}: file ends while reading {what}")
        out = self.values[self.pos:self.pos + n]
        self.pos += n
        return out

    def count(self, what: str) -> int:
        v = float(self.take(1, what)[0])
        if v < 0 or v != int(v):
            raise DDAInputError(f"{self.path}: {what} must be a whole number >= 0, got {v:g}")
        return int(v)


def read_legacy(geometry: str | Path, analysis: str | Path | None = None) -> DDAInput:
    """Read a legacy ``.geo`` / ``.ana`` pair, in the files' units.

    Without ``analysis`` only the geometry is read (no materials, no run
    parameters): :meth:`DDAInput.use_default_analysis` fills them.
    """
    g = _Reader(Path(geometry))
    e00 = float(g.take(1, "edge-node distance")[0])
    n_joints = g.count("number of joints")
    g.count("number of boundary lines")
    n_mat, n_bolts, n_fixed, n_load, n_meas, n_hole = (
        g.count(w) for w in ("number of material lines", "number of bolts", "number of fixed lines",
                             "number of load points", "number of measured points", "number of hole points"))
    joints = g.take(5 * n_joints, "joint lines").reshape(-1, 5)
    mat = g.take(5 * n_mat, "material lines").reshape(-1, 5)
    if n_bolts:
        warnings.warn(f"{g.path}: {n_bolts} rock bolt(s) are not supported (ignored)", stacklevel=2)
        g.take(7 * n_bolts, "bolts")
    fixed = g.take(4 * n_fixed, "fixed lines").reshape(-1, 4)
    load = g.take(2 * n_load, "load points").reshape(-1, 2)
    meas = g.take(2 * n_meas, "measured points").reshape(-1, 2)
    hole = g.take(2 * n_hole, "hole points").reshape(-1, 2)
    if g.pos != len(g.values):
        warnings.warn(f"{g.path}: {len(g.values) - g.pos} trailing number(s) ignored", stacklevel=2)
    if n_load:
        warnings.warn(f"{g.path}: load points carry no forces in the legacy format (as in DDA for Windows); "
                      "they are ignored", stacklevel=2)
    data = DDAInput(
        source=Path(geometry).name, edge_node_ratio=e00,
        joints=joints[:, :4], joint_types=joints[:, 4].astype(np.int64),
        material_lines=mat[:, :4], material_line_types=mat[:, 4].astype(np.int64),
        fixed_lines=fixed, measured_points=meas, hole_points=hole)
    if analysis is not None:
        _read_analysis(Path(analysis), data)
        data.source = f"{Path(geometry).name}+{Path(analysis).name}"
    return data


def _read_analysis(path: Path, data: DDAInput) -> None:
    """Fill ``data``'s run parameters and materials from a legacy ``.ana`` file."""
    a = _Reader(path)
    kind = a.count("analysis type (0 static, 1 dynamic)")
    n_steps = a.count("number of time steps")
    n_bm = a.count("number of block materials")
    n_jm = a.count("number of joint materials")
    g2, dt = (float(v) for v in a.take(2, "g2 and time step"))
    tail = 13 * n_bm + 3 * n_jm
    extra = len(a.values) - a.pos - tail
    if extra < 0:
        raise DDAInputError(f"{a.path}: file ends while reading block and joint materials")
    if extra:
        warnings.warn(f"{a.path}: {extra} number(s) of time-dependent fixed/load point data are not "
                      "supported (ignored)", stacklevel=3)
        a.take(extra, "time-dependent data")
    props = a.take(13 * n_bm, "block materials").reshape(-1, 13)
    jprops = a.take(3 * n_jm, "joint materials").reshape(-1, 3)
    data.dynamic, data.n_steps, data.max_displacement_ratio, data.max_time_step = kind == 1, n_steps, g2, dt
    data.penalty_factor, data.auto_time_step, data.auto_penalty = 50.0, True, True
    data.block_materials = [BlockMaterialSpec(unit_mass=p[0], unit_weight=p[1], young=p[2], poisson=p[3],
                                              stress=tuple(p[4:7]), strain=tuple(p[7:10]),
                                              velocity=tuple(p[10:13])) for p in props]
    data.joint_materials = [(float(j[0]), float(j[1]), float(j[2])) for j in jprops]
