"""Verification cases of staged analysis (docs/stages.md, docs/verification.md).

``stage-column-2d`` / ``-3d``: an equilibrium stage of a column of ten 1 m blocks on a fixed base reaches
the unbalanced-force ratio 1e-5, and the vertical stress at every block's centroid is the overburden ρ·g·h
(h: the depth of the centroid below the top). ``stage-excavation-2d`` / ``-3d``: after an equilibrium
stage, a stage that removes the block under another makes it fall at g from the stage's start.
"""
from __future__ import annotations

import numpy as np

from ..model import JointMaterial, Material, Model
from ..results import Result
from ..settings import RunSettings
from ..simulation import run
from ..stages import Stage
from .registry import Row, case, row

__all__ = ["stacked_column"]

STAGE_G, STAGE_RHO = 9.81, 2500.0
COLUMN_BLOCKS = 10
# Δt = 10 ms (a column of ten 1 m blocks of E = 1 GPa under a contact penalty of 1e10 N/m: Δt is well
# inside the step control's bound); the equilibrium stage settles in 35 steps in 2D, 42 in 3D (measured)
STAGE_DT, STAGE_PENALTY = 1e-2, 1e10
# The ratio to reach: 3DEC's default for `model solve`
RATIO_TOLERANCE = 1e-5
# The overburden stress at each centroid: within 1 % (the acceptance). Measured: 3.6e-5 (2D),
# 1.2e-4 (3D): the residual of a ratio of 1e-5 spread over the column's contacts
STRESS_TOLERANCE = 1e-2
# The fall of the freed block from the stage's start against g·t²/2: Shi's step integrates a constant force
# exactly and the block's elastic rebound (its settled stress released) leaves its centroid where it is;
# measured 1e-14 (round-off); 1e-6 is the acceptance
FALL_TOLERANCE = 1e-6
FALL_STEPS = 20


def stacked_column(n: int, dim: int) -> Model:
    """``n`` stacked unit blocks ``b0`` (bottom) .. on a fixed ``base``, friction 30°; 2D squares or 3D cubes."""
    m = Model(gravity=(0.0, -STAGE_G) if dim == 2 else (0.0, 0.0, -STAGE_G))
    m.add_material("rock", Material(STAGE_RHO, 1e9, 0.25))
    m.add_joint_material("joint", JointMaterial(friction_angle=30.0), between=[("rock", "rock")])
    if dim == 2:
        m.add_block([[-1, -1], [2, -1], [2, 0], [-1, 0]], "rock", fixed=True, name="base")
        for i in range(n):
            m.add_block([[0, i], [1, i], [1, i + 1], [0, i + 1]], "rock", name=f"b{i}")
    else:
        m.add_box((-1, -1, -1), (2, 2, 0), "rock", fixed=True, name="base")
        for i in range(n):
            m.add_box((0, 0, i), (1, 1, i + 1), "rock", name=f"b{i}")
    return m


def _settings(method: str, steps: int = FALL_STEPS) -> RunSettings:
    return RunSettings(dt=STAGE_DT, n_steps=steps, method=method, penalty=STAGE_PENALTY)


def _completed(result: Result, what: str) -> Result:
    if not result.completed:
        raise RuntimeError(f"{what}: the run did not complete ({result.status})")
    return result


def _column(name: str, dim: int, methods: tuple[str, ...]) -> list[Row]:
    rows: list[Row] = []
    for method in methods:
        m = stacked_column(COLUMN_BLOCKS, dim)
        m.add_stage(Stage("gravity", kind="equilibrium", tolerance=RATIO_TOLERANCE))
        res = _completed(run(m, _settings(method)), f"{name} {method}")
        end = res.stages[-1]
        rows.append(row(name, f"unbalanced-force ratio reached ({end['steps']} steps)", method, end["ratio"], 0.0,
                        RATIO_TOLERANCE))
        assert res.final_state is not None
        vertical = res.final_state.stress[1:, 1 if dim == 2 else 2]  # σy (2D), σz (3D); compression < 0
        depth = COLUMN_BLOCKS - np.arange(COLUMN_BLOCKS) - 0.5
        reference = -STAGE_RHO * STAGE_G * depth
        worst = int(np.argmax(np.abs(vertical / reference - 1.0)))
        rows.append(row(name, f"vertical stress at the centroid, worst of {COLUMN_BLOCKS} (b{worst}), Pa", method,
                        vertical[worst], reference[worst], STRESS_TOLERANCE))
    return rows


def _excavation(name: str, dim: int, methods: tuple[str, ...]) -> list[Row]:
    rows: list[Row] = []
    for method in methods:
        m = stacked_column(2, dim)
        m.add_stage(Stage("gravity", kind="equilibrium", tolerance=RATIO_TOLERANCE))
        m.add_stage(Stage("excavate", remove_blocks=["b0"], reset_displacements=True))
        res = _completed(run(m, _settings(method)), f"{name} {method}")
        start = res.stages[-1]["first_step"]
        steps, time = res.array("step"), res.array("time")
        height = res.array("centroid")[:, 2, dim - 1]  # b1
        k0, k1 = int(np.flatnonzero(steps == start)[0]), len(steps) - 1
        t = time[k1] - time[k0]
        rows.append(row(name, f"fall of the freed block in {t:.3g} s from the stage's start, m", method,
                        height[k0] - height[k1], 0.5 * STAGE_G * t * t, FALL_TOLERANCE))
    return rows


COLUMN = "an equilibrium stage of a 10-block column: ratio < 1e-5, σv = ρ g h at every centroid"
EXCAVATION = "equilibrium, then the block under another removed: it falls at g from the stage's start"
for _dim, _methods in ((2, ("dda0", "dda1", "srdda")), (3, ("srdda",))):
    case(f"stage-column-{_dim}d", dim=_dim, methods=_methods, description=COLUMN)(
        lambda methods, quick, dim=_dim: _column(f"stage-column-{dim}d", dim, methods))
    case(f"stage-excavation-{_dim}d", dim=_dim, methods=_methods, description=EXCAVATION)(
        lambda methods, quick, dim=_dim: _excavation(f"stage-excavation-{dim}d", dim, methods))
