"""Runs under ``contact_solver = "newton"`` against closed forms (the step problem itself is checked against a
conic solver in tests/test_contact_solve_reference.py)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from srdda import RunSettings, run
from srdda.apps.bench.models import jointed_slope
from srdda.apps.verify.cases2d import INCLINE_ACCELERATION, INCLINE_G, INCLINE_PENALTY, INCLINE_PSI, incline_model_2d

STEPS = 300  # of 1 ms: the block slides 0.22 m, far beyond its ~1e-6 m settling into the springs


@pytest.mark.parametrize("method", ["dda0", "srdda"])
@pytest.mark.parametrize("phi", [0.0, 20.0])
def test_sliding_on_an_incline_has_the_closed_form_acceleration(method: str, phi: float) -> None:
    # g(sin ψ − cos ψ tan φ): frictionless too, where the contacts new in the first step once stuck at an
    # unbounded yield force that no normal force ever replaced (4.995 instead of 5 m/s² under dda0)
    res = run(incline_model_2d(phi), RunSettings(dt=1e-3, n_steps=STEPS, method=method, penalty=INCLINE_PENALTY,
                                                 contact_solver="newton"), keep_history=False)
    assert res.completed, res.status
    c = res.array("centroid")[:, 1]
    t = float(res.time[-1])
    exact = INCLINE_G * (np.sin(INCLINE_PSI) - np.cos(INCLINE_PSI) * np.tan(np.radians(phi)))
    # the tolerance of srdda verify's incline-2d: the settling into the springs, 1e-6 m against 0.2 m of travel
    assert 2.0 * float(np.linalg.norm(c[-1] - c[0])) / t**2 == pytest.approx(exact, rel=INCLINE_ACCELERATION)


def test_a_step_that_once_cycled_converges_without_a_cut() -> None:
    # slope_b's sixth step: a damped step's model held the springs of its full step, not the iterate's; the
    # next direction climbed Π, was taken whole, and the iterates repeated with period 3 up to the cap (a cut).
    # Never climbing, it converges in 35 solves (docs/dev/contact-solve.md)
    model, settings = jointed_slope("b")
    res = run(model, replace(settings, n_steps=6, contact_solver="newton", newton_max_iterations=60),
              keep_history=False)
    assert res.completed, res.status
    assert int(res.final_state.cuts.sum()) == 0
