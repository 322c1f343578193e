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

from srdda.apps.bench.formulations import BLOCK_HEIGHT, DENSITY, GRAVITY, blocks_on_base, held_tresca_step, reference_run


@pytest.mark.parametrize("dim", [2, 3])
@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), n_blocks=st.integers(1, 3))
def test_newton_equals_a_conic_solver_on_the_step_problem(dim, seed, n_blocks):
    rng = np.random.default_rng(seed)
    arrays = blocks_on_base(dim, rng, n_blocks).arrays()
    # the iteration stops at force errors below 1e-9 of the blocks' weight (1e-4 in runs): its fixed point, not
    # the tolerance of runs, is compared; N* of the yield forces up to a block's weight
    weight = DENSITY * BLOCK_HEIGHT * GRAVITY
    got = held_tresca_step(arrays, reference_run(1e-9), lambda n: rng.uniform(0.0, weight, n))
    assert got is not None  # every block starts within 2e-4 m of the base, well inside d0: contacts, a step
    problem = got.problem()
    reference, _ = problem.solve_conic(tolerance=1e-10)
    newton, potential = got.increments, problem.potential
    # the Newton solution is the minimum: its Π is no higher than the conic solver's (taken back to the fixed
    # base, where the conic solver leaves 1e-12 m), to rounding
    assert potential(newton) <= potential(reference) + 1e-12 * abs(potential(reference))
    # and the two agree: Π is strongly convex (its convexity at least A's smallest eigenvalue λ, the inertia), so a
    # point within ΔΠ of the minimum lies within sqrt(2ΔΠ/λ) of it; the conic solver's ΔΠ is at most 1e-9 of Π
    bound = np.sqrt(2.0 * 1e-9 * abs(potential(reference)) / problem.convexity)
    assert np.linalg.norm(newton - reference) <= bound, (np.linalg.norm(newton - reference), bound)
