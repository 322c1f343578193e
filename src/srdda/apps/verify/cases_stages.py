"""Verification cases of staged analysis (docs/stages.md, docs/verification.md).

``stage-column-2d`` / ``-3d``: an equilibrium stage of a column of ten 1 m blocks on a fixed base reaches
the unbalanced-force ratio 1e-5, and the vertical stress at every block's centroid is the overburden ρ·g·h
(h: the depth of the centroid below the top). ``stage-excavation-2d`` / ``-3d``: after an equilibrium
stage, a stage that removes the block under another makes it fall at g from the stage's start.
``stage-wedge-cut-3d``: the wedge above a cut slope of examples/stages/wedge-cut.toml
(:func:`srdda.apps.verify.cases.slope3d.wedge_cut_model`): after the toe is cut it stays at FS 1.2 and, its joints
weakened, slides at Hoek & Bray's a = g sin ψ_i (1 − FS) at FS 0.8.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .cases.slope3d import WEDGE_PLANES, wedge_cut_model, wedge_solution
from ...integrators.methods import MethodName
from ...model import JointMaterial, Material, Model
from ...results import Result
from ...settings import RunSettings
from ...simulation import run
from ...stages import Stage
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


def _settings(method: MethodName, steps: int = FALL_STEPS) -> RunSettings:
    return RunSettings(dt=STAGE_DT, n_steps=steps, method=method, penalty=STAGE_PENALTY)


def _completed(result: Result, what: str) -> Result:
    if not result.completed:
        raise RuntimeError(f"{what}: the run did not complete ({result.status})")
    return result


def _column(name: str, dim: int, methods: tuple[MethodName, ...]) -> list[Row]:
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


def _excavation(name: str, dim: int, methods: tuple[MethodName, ...]) -> list[Row]:
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
_DIM_METHODS: tuple[tuple[int, tuple[MethodName, ...]], ...] = ((2, ("dda0", "dda1", "srdda")), (3, ("srdda",)))
for _dim, _methods in _DIM_METHODS:
    def _column_run(methods: tuple[MethodName, ...], quick: bool, dim: int = _dim) -> list[Row]:
        return _column(f"stage-column-{dim}d", dim, methods)

    def _excavation_run(methods: tuple[MethodName, ...], quick: bool, dim: int = _dim) -> list[Row]:
        return _excavation(f"stage-excavation-{dim}d", dim, methods)

    case(f"stage-column-{_dim}d", dim=_dim, methods=_methods, description=COLUMN)(_column_run)
    case(f"stage-excavation-{_dim}d", dim=_dim, methods=_methods, description=EXCAVATION)(_excavation_run)


# stage-wedge-cut-3d: Δt = 1 ms, k_n = 1e11 N/m as wedge-3d, contacts by Newton (docs/examples-staged.md); the cut
# stage 200 steps, the residual stage 250 (the example runs 500 each)
WEDGE_CUT_STEPS = (200, 250)
# after the cut, FS 1.2: wedge-rest-3d's bound on the travel, 1e-5 m; measured 7.2e-7 m (the springs' take-up
# of the toe's removal)
WEDGE_CUT_REST = 1e-5
# residual, FS 0.8: wedge-3d's bound of 2 % on the acceleration along the line of intersection, from the
# velocity along it from 0.05 s after the stage's start to its end; measured 1.6e-6
WEDGE_CUT_ACCELERATION = 2e-2


@case("stage-wedge-cut-3d", dim=3, methods=("srdda",),
      description="a wedge above a cut slope: stays after the toe is cut at FS 1.2, slides at FS 0.8 (Hoek & Bray)")
def wedge_cut(methods: tuple[MethodName, ...], quick: bool) -> list[Row]:
    rows: list[Row] = []
    for method in methods:
        m = wedge_cut_model()
        m.stages[1:] = [replace(s, run={"n_steps": n}) for s, n in zip(m.stages[1:], WEDGE_CUT_STEPS)]
        settings = RunSettings(dt=1e-3, n_steps=1, method=method, penalty=1e11, contact_solver="newton")
        res = _completed(run(m, settings), f"stage-wedge-cut-3d {method}")
        _, cut, residual = res.stages
        step, time = res.array("step"), np.asarray(res.time)
        centroid, velocity = res.array("centroid")[:, 0], res.array("velocity")[:, 0, :3]
        during = np.flatnonzero((step >= cut["first_step"]) & (step <= cut["last_step"]))
        travel = float(np.linalg.norm(centroid[during] - centroid[during[0]], axis=1).max())
        rows.append(row("stage-wedge-cut-3d", f"travel after the toe is cut, {WEDGE_CUT_STEPS[0]} steps (m), FS 1.2",
                        method, travel, 0.0, WEDGE_CUT_REST))
        solution = wedge_solution(*WEDGE_PLANES, m.stages[2].joint_materials["joint"].friction_angle)
        i = int(np.searchsorted(time, residual["start_time"] + 0.05 - 5e-4))
        along = velocity @ solution.line
        rows.append(row("stage-wedge-cut-3d", "acceleration along the line of intersection (m/s²), residual, FS 0.8",
                        method, (along[-1] - along[i]) / (time[-1] - time[i]), solution.acceleration,
                        WEDGE_CUT_ACCELERATION))
    return rows
