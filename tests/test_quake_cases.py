"""The newmark and bolted-block verification cases: their references against closed forms, the engine against
them on a short pulse, and the bolted block's case itself (slow)."""
import numpy as np
import pytest

from srdda import RunSettings, run
from srdda.history import TimeHistory
from srdda.apps.verify import CASES, run_case
from srdda.apps.verify.cases_quake import (NEWMARK_PENALTY, QUAKE_G, bolt_requirement, newmark_model,
                                      newmark_sliding)

PSI, PHI = np.radians(20.0), 30.0
PULSE, WIDTH, RAMP = 0.4 * QUAKE_G, 0.25, 0.01  # ground acceleration towards +x: down-slope pseudo-force (the slope rises to +x)


def _pulse() -> TimeHistory:
    return TimeHistory(table=np.array([[0.0, PULSE, 0.0], [WIDTH, PULSE, 0.0], [WIDTH + RAMP, 0.0, 0.0]]))


def _pulse_sliding() -> float:
    """Newmark's displacement for the pulse in closed form: constant slip acceleration f1 during it, a linear
    change to f2 < 0 over RAMP, then deceleration at f2 until the block sticks."""
    tan_phi = np.tan(np.radians(PHI))
    f1 = PULSE * (np.cos(PSI) + np.sin(PSI) * tan_phi) + QUAKE_G * (np.sin(PSI) - np.cos(PSI) * tan_phi)
    f2 = QUAKE_G * (np.sin(PSI) - np.cos(PSI) * tan_phi)
    v1, s1 = f1 * WIDTH, 0.5 * f1 * WIDTH**2
    v2 = v1 + 0.5 * (f1 + f2) * RAMP
    s2 = s1 + v1 * RAMP + RAMP**2 * (f1 / 3 + f2 / 6)
    return s2 + v2**2 / (2 * -f2)


def test_newmarks_integration_matches_the_closed_form_of_a_pulse():
    # solve_ivp at rtol 1e-10 over piecewise-linear forcing, events located to its tolerance
    assert newmark_sliding(_pulse(), PSI, PHI, QUAKE_G, 1.5) == pytest.approx(_pulse_sliding(), rel=1e-8)


def test_newmarks_integration_refuses_up_slope_sliding():
    violent = TimeHistory(table=np.array([[0.0, -2.0 * QUAKE_G, 0.0], [1.0, -2.0 * QUAKE_G, 0.0]]))
    with pytest.raises(ValueError, match="up the incline"):
        newmark_sliding(violent, PSI, PHI, QUAKE_G, 1.0)


def test_the_block_on_the_incline_slides_as_newmarks_under_a_pulse():
    res = run(newmark_model(_pulse(), PSI, PHI), RunSettings(dt=1e-3, end_time=0.9, method="srdda",
                                                             penalty=NEWMARK_PENALTY), keep_history=False)
    assert res.completed
    c = res.array("centroid")[:, 1]
    down = -np.array([np.cos(PSI), np.sin(PSI)])
    # the case's tolerance (2 %); the contacts' creep while the block sticks is short here
    assert (c[-1] - c[0]) @ down == pytest.approx(_pulse_sliding(), rel=0.02)


def test_the_bolt_requirement_balances_the_forces():
    w, psi, phi, beta = 1.0e4, np.radians(40.0), 20.0, np.radians(15.0)
    t = bolt_requirement(w, psi, phi, beta)
    normal = w * np.cos(psi) + t * np.sin(beta)  # the bolt pulls into the incline
    # along the incline: bolt up-slope + full friction = the weight's down-slope share (exact identity)
    assert t * np.cos(beta) + normal * np.tan(np.radians(phi)) == pytest.approx(w * np.sin(psi), rel=1e-14)


def test_the_cases_are_registered_for_the_three_methods():
    for name in ("newmark", "bolted-block"):
        assert set(CASES[name].methods) == {"dda0", "dda1", "srdda"}


@pytest.mark.slow
def test_bolted_block_case_passes_under_srdda():
    rows = run_case("bolted-block", methods=("srdda",))
    assert len(rows) == 4 and all(r["passed"] is not False for r in rows), rows
