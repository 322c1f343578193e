"""Runs under ``contact_solver = "newton"`` against closed forms (the step problem itself is checked against a
conic solver in tests/test_contact_solve_reference.py)."""
from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import srdda
from srdda import RunSettings, run
from srdda.apps.bench.models import brick_wall, jointed_slope
from srdda.contact import newton
from srdda.contact.newton import NEARLY_SETTLED
from srdda.geometry.polyhedron import box
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


def test_a_box_whose_slip_stops_within_a_step_sticks_at_the_next_solve() -> None:
    # a box sliding at 1.08 cm/s over a base (φ = 30°) stops in its third step of 1 ms. A slipping contact's model
    # is its constant yield force: the solve's full step carried the corners' slip back through the shear
    # springs' elastic range, and a model slipping the other way would overshoot back (damped steps of α ≈ 0.1).
    # Modelled sticking where the shear passes through the elastic range, the step takes 3 solves (was 6)
    m = srdda.Model(gravity=(0.0, 0.0, -9.81))
    m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
    m.add_joint_material("j", srdda.JointMaterial(friction_angle=30.0), between=[("rock", "rock")])
    m.add_polyhedron(*box((-3, -3, -1), (3, 3, 0)), "rock", fixed=True)
    m.add_polyhedron(*box((0, 0, 0), (1, 1, 0.5)), "rock", velocity=(0.01, 0.004, 0.0))
    res = run(m, RunSettings(dt=1e-3, n_steps=4, penalty=1e10, contact_solver="newton"))
    assert res.completed, res.status
    assert int(res.iterations[3]) <= 3  # the step it stops in (measured 7, 5, 3, 2 solves in its four steps)
    # stopped: what is left is the springs' ringing, 1e-4 m/s against 1.08e-2 m/s at the start
    assert float(np.abs(res.array("velocity")[-1][1, :3]).max()) < 1e-3


def test_the_tangent_across_a_slip_is_never_stiffer_than_the_shear_spring(monkeypatch) -> None:
    # a box sliding at 0.22 m/s over a base (φ = 30°), 30 steps of 1 ms, N* following the normal forces once a
    # step (at 1 % of the contacts still changing state: the rule that made the case). A contact modelled
    # slipping whose yield force rose with N* after its state was set has |s| < τ/k_s: its tangent τ/|s| across
    # the slip reached 6.8e8 k_s here (1e21 N/m on slope3d_1k), and the dense solve warned of a matrix with
    # rcond 9e-20. The tangent is τ/|s| where the shear is beyond the elastic range, k_s within it (where the
    # two meet)
    from srdda.contact.newton import NewtonContactStep
    from srdda.contact.openclose import magnitudes
    ratios = []  # (the tangent used, τ/|s|) over k_s, the largest of every call
    tangent = NewtonContactStep._tangent_stiffness

    def recorded(self, tau):
        out = tangent(self, tau)
        turning = out > 0.0
        if np.any(turning):
            ks = self.response.shear_stiffness[turning]
            exact = tau[turning] / magnitudes(self.slip_shear)[turning]
            beyond = exact <= ks  # the shear beyond its elastic range: the consistent tangent itself
            np.testing.assert_array_equal(out[turning][beyond], exact[beyond])
            ratios.append((float(np.max(out[turning] / ks)), float(np.max(exact / ks))))
        return out

    monkeypatch.setattr(NewtonContactStep, "_tangent_stiffness", recorded)
    monkeypatch.setattr(newton, "NORMAL_UPDATES", 1)
    monkeypatch.setattr(newton, "NEARLY_SETTLED", 0.01)
    m = srdda.Model(gravity=(0.0, 0.0, -9.81))
    m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
    m.add_joint_material("j", srdda.JointMaterial(friction_angle=30.0), between=[("rock", "rock")])
    m.add_polyhedron(*box((-3, -3, -1), (3, 3, 0)), "rock", fixed=True)
    m.add_polyhedron(*box((0, 0, 0), (1, 1, 0.5)), "rock", velocity=(0.2, -0.1, 0.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the ill-conditioned solve's LinAlgWarning
        res = run(m, RunSettings(dt=1e-3, n_steps=30, penalty=1e10, contact_solver="newton"))
    assert res.completed, res.status
    used, exact = np.max(ratios, axis=0)
    assert exact > 1e3  # the case arises (measured 6.8e8)
    assert used <= 1.0


def test_normal_forces_follow_once_the_active_set_has_nearly_settled() -> None:
    # the Tresca fixed point's N* updates wait for at most 5 % of the contacts to still change state, not for
    # none: the settling after an update no longer follows the last few changes. A 10 × 10 brick wall (570
    # contacts), 20 steps of 1 ms, N* followed until it settles (no cap on the updates, friction tolerance
    # 1e-5): 180 → 163 solves, the same motion to 2.4e-6 of its largest displacement
    model, settings = brick_wall(10, 10)
    runs = {}
    for fraction in (0.0, NEARLY_SETTLED):
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(newton, "NEARLY_SETTLED", fraction)
            patch.setattr(newton, "NORMAL_UPDATES", 20)
            runs[fraction] = run(model, replace(settings, n_steps=20, contact_solver="newton",
                                                friction_tolerance=1e-5))
    waited, early = runs[0.0], runs[NEARLY_SETTLED]
    assert early.completed and waited.completed
    assert sum(early.iterations) < sum(waited.iterations)  # measured 163 against 180
    moved = np.abs(waited.array("centroid")[-1] - waited.array("centroid")[0]).max()
    # the two solve the same Coulomb problem, N* settled to 1e-5: 1e-4 of the displacement bounds what the
    # order of the updates changes (measured 2.4e-6)
    assert np.abs(early.array("centroid")[-1] - waited.array("centroid")[-1]).max() <= 1e-4 * moved


def test_inexact_solves_while_contacts_change_state_reach_the_same_step(monkeypatch) -> None:
    # while more than 1 % of the contacts changed state at the last iterate, the conjugate gradient solves to
    # 0.3 × the iterate's largest change instead of 1e-9 m; the step still ends with a solve at 1e-9 m. slope_a's
    # first step under cg-jacobi: 315 → 208 CG iterations (measured); the converged increments agree within
    # 10 × the tolerance (both end at 1e-9 m from the same convex problem; measured 3.4e-10 m)
    import srdda.solvers._iterative as iterative

    model, settings = jointed_slope("a")
    settings = replace(settings, n_steps=1, contact_solver="newton", solver="cg-jacobi")
    counted = iterative.ConjugateGradientSolver.solve
    results, work = {}, {}
    for forcing in (0.0, newton.INEXACT_FORCING):
        spent = [0]

        def solve(self, system, rhs, tolerance=None, spent=spent):
            x = counted(self, system, rhs, tolerance)
            spent[0] += self.iterations[-1]
            return x

        monkeypatch.setattr(iterative.ConjugateGradientSolver, "solve", solve)
        monkeypatch.setattr(newton, "INEXACT_FORCING", forcing)
        results[forcing], work[forcing] = run(model, settings), spent[0]
    tight, inexact = results[0.0], results[newton.INEXACT_FORCING]
    assert tight.completed and inexact.completed
    assert work[newton.INEXACT_FORCING] < work[0.0]
    assert np.abs(tight.array("centroid")[-1] - inexact.array("centroid")[-1]).max() <= 10 * settings.solver_tolerance
