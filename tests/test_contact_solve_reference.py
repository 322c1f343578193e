"""The Newton contact solve against a general convex solver (issue 29 item 2).

On small random models (2D polygons and 3D boxes near a fixed base, with random gaps, penetrations, speeds,
friction, cohesion and tension) one step's contact problem, the Tresca problem with the yield forces' N* held
at given values, is solved twice: by srdda's Newton iteration (:mod:`srdda.contact.newton`) and as the convex
program it is (:mod:`srdda.contact.conic`: the springs' potentials as Moreau envelopes, a quadratic program in
2D and a second-order cone program in 3D), written out in cvxpy and solved by clarabel (an interior-point conic
solver). The Newton iteration (stopped at force errors below 1e-9 of the blocks' weight) must reach a Π no
higher than clarabel's (asked for 1e-10 of Π), and the increments must agree to what that accuracy allows.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import srdda
from srdda.contact.conic import step_problem
from srdda.contact.newton import NewtonContactModel
from srdda.contact.pipeline import ContactTerm
from srdda.geometry.polyhedron import box
from srdda.solvers import get_solver
from srdda.state import initial_state
from srdda.step import Stepper, contact_parameters, default_terms, model_half_height

G = 9.81


class HeldTresca(NewtonContactModel):
    """The Newton contacts with N* held at given values (the Tresca problem alone)."""

    def __init__(self, arrays, params, normal_star):
        super().__init__(arrays, params)
        self.normal_star = normal_star

    def start(self, *args):
        step = super().start(*args)
        step.follow_normal_force = False
        step.known[:] = True
        step.normal_star = self.normal_star(len(step))
        return step


def _model(dim, rng, n_blocks):
    m = srdda.Model(gravity=(0.0, -G) if dim == 2 else (0.0, 0.0, -G))
    m.add_material("rock", srdda.Material(2500.0, 1e10, 0.25))
    m.add_joint_material("j", srdda.JointMaterial(friction_angle=float(rng.uniform(0, 40)),
                                                  cohesion=float(rng.choice([0.0, rng.uniform(0, 2e4)])),
                                                  tensile_strength=float(rng.choice([0.0, rng.uniform(0, 2e4)]))),
                         between=[("rock", "rock")])
    m.allow_overlap = True  # a block may start a little into the base: a penetrating contact
    if dim == 2:
        m.add_block([[-3, -1], [3, -1], [3, 0], [-3, 0]], "rock", fixed=True)
    else:
        m.add_box([-3, -3, -1], [3, 3, 0], "rock", fixed=True)
    for k in range(n_blocks):
        lift = float(rng.uniform(-2e-4, 2e-4))  # into the base, touching, or a little above it
        v = rng.uniform(-0.5, 0.5, dim)
        if dim == 2:
            x0 = 1.2 * k - 1.5
            m.add_block(np.array([[x0, lift], [x0 + 1, lift], [x0 + 1, lift + 0.5], [x0, lift + 0.5]]), "rock",
                        velocity=tuple(v), angular_velocity=float(rng.uniform(-0.5, 0.5)))
        else:
            x0 = 1.2 * k - 1.5
            m.add_box([x0, -0.5, lift], [x0 + 1, 0.5, lift + 0.5], "rock", velocity=tuple(v),
                      angular_velocity=tuple(rng.uniform(-0.5, 0.5, 3)))
    return m


def _newton_and_reference(dim, seed, n_blocks):
    rng = np.random.default_rng(seed)
    model = _model(dim, rng, n_blocks)
    arrays = model.arrays()
    # the iteration stops at force errors below 1e-9 of the blocks' weight (1e-4 in runs): its fixed point, not
    # the tolerance of runs, is compared
    run = srdda.RunSettings(dt=1e-3, n_steps=1, method="dda1", penalty=1e10, contact_solver="newton",
                            open_close_force_tolerance=1e-9)
    terms = default_terms(arrays, run)
    contact = next(t for t in terms if isinstance(t, ContactTerm))
    params = contact_parameters(arrays, run, model_half_height(arrays.vertices))
    weight = 2500.0 * (0.5 if dim == 2 else 0.5) * G
    contact.model = HeldTresca(arrays, params, lambda n: rng.uniform(0.0, weight, n))
    stepper = Stepper(arrays, run, get_solver("dense"), terms)
    state = initial_state(arrays, stepper.method)
    captured = {}
    original = type(contact).converged

    def capture(self, dd, ctx):
        captured["dd"], captured["ctx"] = dd.copy(), ctx
        return original(self, dd, ctx)

    type(contact).converged = capture
    try:
        outcome = stepper.step(state, run.dt)
    finally:
        type(contact).converged = original
    if contact.step is None or outcome.status != "accepted":
        return None
    step, ctx = contact.step, captured["ctx"]
    system = stepper.assemble(ctx, [t for t in terms if t is not contact])
    problem = step_problem(step, system, ctx.coeffs.c_p, step.yield_force(), arrays.block_fixed)
    reference, _ = problem.solve_conic(tolerance=1e-10)
    return captured["dd"].ravel(), reference, problem


@pytest.mark.parametrize("dim", [2, 3])
@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), n_blocks=st.integers(1, 3))
def test_newton_equals_a_conic_solver_on_the_step_problem(dim, seed, n_blocks):
    got = _newton_and_reference(dim, seed, n_blocks)
    assert got is not None  # every block starts within 2e-4 m of the base, well inside d0: contacts, a step
    newton, reference, problem = got
    potential = problem.potential
    # the Newton solution is the minimum: its Π is no higher than the conic solver's (taken back to the fixed
    # base, where the conic solver leaves 1e-12 m), to rounding
    assert potential(newton) <= potential(reference) + 1e-12 * abs(potential(reference))
    # and the two agree: Π is strongly convex (its convexity at least A's smallest eigenvalue λ, the inertia), so a
    # point within ΔΠ of the minimum lies within sqrt(2ΔΠ/λ) of it; the conic solver's ΔΠ is at most 1e-9 of Π
    bound = np.sqrt(2.0 * 1e-9 * abs(potential(reference)) / problem.convexity)
    assert np.linalg.norm(newton - reference) <= bound, (np.linalg.norm(newton - reference), bound)
