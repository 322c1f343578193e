"""At rest from t = 0, without an equilibrium stage: how far the models of ``srdda verify``'s at-rest rows move
when released with unstressed contacts (the figures of docs/contacts/solve.md, *At rest from the start*).

The verify rows (srdda.apps.verify.at_rest) first bring each model to equilibrium; this probe runs the same
models, settings and durations from their given state instead, under both contact solvers (srdda):

* the block on the 30° incline with φ = 35° (1 s of 1 ms steps), in 2D and extruded to 3D;
* the tetrahedral wedge at FS 1.2 and 1.05 (0.6 s);
* the 30 × 30 brick wall (0.1 s): its blocks' largest speed at the end.

Travel: the largest distance of a moving block's centroid from where it started, over every step. It holds
the settling into the contact springs and the blocks' own elastic compression under their weight (the
incline's block, E = 1 GPa, ends 4.6 µm from its start under Newton, 1.25 µm with E = 1,000 GPa: the springs'
part), which is why a model that must start at rest starts with an equilibrium stage (docs/stages.md).

    python benchmarks/probe_rest_from_zero.py
"""
from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from srdda import RunSettings, run
from srdda.apps.bench.models import brick_wall
from srdda.apps.verify.at_rest import INCLINE_STEPS, WALL_SIZE, WALL_TIME, WEDGE_FACTORS, WEDGE_STEPS
from srdda.apps.verify.cases.slope3d import wedge_friction_for, wedge_model
from srdda.apps.verify.cases2d import INCLINE_PENALTY, STICKING_ANGLE, incline_model_2d
from srdda.model import Model

SOLVERS = ("open-close", "newton")


def travel(model: Model, settings: RunSettings) -> float:
    """The largest travel (m) of a moving block's centroid from its start over the run."""
    res = run(model, settings)
    centroids = res.array("centroid")
    moving = ~model.arrays().block_fixed
    return float(np.max(np.linalg.norm(centroids[:, moving] - centroids[0, moving], axis=2)))


def main() -> None:
    warnings.simplefilter("ignore")  # open-close's energy watch warns on these releases; the figures say enough
    print("model | " + " | ".join(SOLVERS))
    for dim in (2, 3):
        incline = incline_model_2d(STICKING_ANGLE)
        figures = [travel(incline if dim == 2 else incline.extruded(1.0), RunSettings(dt=1e-3, n_steps=INCLINE_STEPS, method="srdda",
                                                     penalty=INCLINE_PENALTY, contact_solver=solver))
                   for solver in SOLVERS]
        print(f"incline {dim}D, travel in 1 s (m) | " + " | ".join(f"{f:.3g}" for f in figures))
    for fs in WEDGE_FACTORS:
        figures = [travel(wedge_model(wedge_friction_for(fs)), RunSettings(dt=1e-3, n_steps=WEDGE_STEPS,
                                                                             method="srdda", penalty=1e11,
                                                                             contact_solver=solver))
                   for solver in SOLVERS]
        print(f"wedge FS {fs:g}, travel in 0.6 s (m) | " + " | ".join(f"{f:.3g}" for f in figures))
    speeds = []
    for solver in SOLVERS:
        wall, settings = brick_wall(WALL_SIZE, WALL_SIZE)
        res = run(wall, replace(settings, method="srdda", contact_solver=solver, n_steps=None, end_time=WALL_TIME))
        assert res.final_state is not None
        speeds.append(float(np.linalg.norm(res.final_state.velocity[:, :2], axis=1).max()))
    print(f"{WALL_SIZE} x {WALL_SIZE} wall, largest speed after {WALL_TIME:g} s (m/s) | "
          + " | ".join(f"{s:.3g}" for s in speeds))


if __name__ == "__main__":
    main()
