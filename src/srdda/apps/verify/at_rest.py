"""At rest stays at rest (issue 29, item 5): models whose contacts hold them, brought to equilibrium by an
equilibrium stage (docs/stages.md) and then run dynamically from there, move no further than the contact
springs' rounding.

Each model is run as two stages: ``equilibrium`` (damped steps until the unbalanced-force ratio is below
1e-5: srdda.settle) and a dynamic stage with ``reset_displacements``, whose travel (or, for the wall, speed)
is measured from its start. Rows under ``contact_solver = "newton"`` are checked; the same runs under the
default open-close are information rows (docs/contacts/solve.md, *At rest from the start*).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..bench.models import brick_wall
from .cases.slope3d import wedge_friction_for, wedge_model
from ...integrators.methods import MethodName
from ...model import Model
from ...settings import RunSettings
from ...simulation import run
from ...stages import Stage
from .cases2d import INCLINE_PENALTY, STICKING_ANGLE, _completed, incline_model_2d
from .registry import Row, case, row

__all__ = ["rest_travel"]

# The bounds: the block on the 30° incline with φ = 35° moves less than 1e-6 m from the start of the dynamic stage, a wedge at FS 1.2 or 1.05 less than 1e-5 m
# (measured under Newton: 4e-11 m, 6e-12 m, 1e-10 m and 6e-11 m), the 30 x 30 brick wall's largest speed after
# 0.1 s is below 1e-4 m/s (measured 4.0e-7 m/s).
INCLINE_AT_REST, WEDGE_AT_REST, WALL_AT_REST = 1e-6, 1e-5, 1e-4
INCLINE_STEPS, WEDGE_STEPS, WALL_TIME = 1000, 600, 0.1  # the dynamic stage: 1 s, 0.6 s, 0.1 s of 1 ms steps
WEDGE_FACTORS = (1.2, 1.05)
WALL_SIZE = 30  # bricks along and up


def rest_travel(model: Model, settings: RunSettings, dynamic: dict[str, float]) -> tuple[float, np.ndarray]:
    """(the largest travel of a moving block over the dynamic stage (m), the blocks' final speeds (nb,)
    (m/s)): ``model`` gets an equilibrium stage and a dynamic stage
    with the run settings ``dynamic`` that starts from it at rest (the model is changed)."""
    model.add_stage(Stage("equilibrium", kind="equilibrium"))
    model.add_stage(Stage("at rest", reset_displacements=True, run=dynamic))
    res = _completed(run(model, settings), "at rest")
    start = res.stages[1]["first_step"]
    centroids = res.array("centroid")[res.array("step") >= start]
    moving = ~model.arrays().block_fixed
    travel = float(np.max(np.linalg.norm(centroids[:, moving] - centroids[0, moving], axis=2)))
    assert res.final_state is not None
    speed = np.linalg.norm(res.final_state.velocity[:, :centroids.shape[2]], axis=1)
    return travel, speed


def _incline(dim: int) -> Model:
    m = incline_model_2d(STICKING_ANGLE)
    return m if dim == 2 else m.extruded(1.0)


def _rows(name: str, dim: int, methods: tuple[MethodName, ...]) -> list[Row]:
    rows: list[Row] = []
    for solver in ("newton", "open-close"):
        for method in methods if solver == "newton" else ("srdda",):
            settings = RunSettings(dt=1e-3, n_steps=1, method=method, penalty=INCLINE_PENALTY, contact_solver=solver)
            travel, _ = rest_travel(_incline(dim), settings, {"n_steps": INCLINE_STEPS})
            rows.append(row(name, f"incline φ = {STICKING_ANGLE:g}°: travel in 1 s after equilibrium (m), {solver}",
                            method, travel, 0.0, INCLINE_AT_REST if solver == "newton" else None))
            if dim == 3:
                for fs in WEDGE_FACTORS:
                    settings = RunSettings(dt=1e-3, n_steps=1, method=method, penalty=1e11, contact_solver=solver)
                    travel, _ = rest_travel(wedge_model(wedge_friction_for(fs)), settings,
                                               {"n_steps": WEDGE_STEPS})
                    rows.append(row(name, f"wedge FS {fs:g}: travel in 0.6 s after equilibrium (m), {solver}",
                                    method, travel, 0.0, WEDGE_AT_REST if solver == "newton" else None))
            elif method == "srdda":
                wall, settings = brick_wall(WALL_SIZE, WALL_SIZE)
                settings = replace(settings, method=method, contact_solver=solver, n_steps=None, end_time=WALL_TIME)
                _, speed = rest_travel(wall, settings, {"end_time": WALL_TIME})
                rows.append(row(name, f"{WALL_SIZE} x {WALL_SIZE} wall: largest speed 0.1 s after equilibrium (m/s), "
                                f"{solver}", method, float(speed.max()), 0.0,
                                WALL_AT_REST if solver == "newton" else None))
    return rows


@case("at-rest-2d", dim=2, methods=("srdda", "dda1", "dda0"),
      description="after an equilibrium stage, the incline at φ = 35° and a 30 x 30 brick wall stay at rest")
def at_rest_2d(methods: tuple[MethodName, ...], quick: bool) -> list[Row]:
    return _rows("at-rest-2d", 2, methods)


@case("at-rest-3d", dim=3, methods=("srdda", "dda1", "dda0"),
      description="after an equilibrium stage, the extruded incline at φ = 35° and the wedge at FS 1.2, 1.05 stay")
def at_rest_3d(methods: tuple[MethodName, ...], quick: bool) -> list[Row]:
    return _rows("at-rest-3d", 3, methods)
