"""The 2D open-close rules and the friction's secant step, compiled contact by contact, against their
whole-array form (the code before they were compiled), bit for bit: the paper's rows depend on every bit."""
from __future__ import annotations

import numpy as np

from srdda.contact.openclose import LOCKED, OPEN, SLIDING, next_states
from srdda.contact.term import _secant_normal


def _array_rules(state, sign, gap, shear, kn, ks, tan_phi, cohesion_force, tension_force, closed_this_step,
                 friction_normal, friction_tolerance, tolerance, settled_force):
    normal = -kn * gap
    closed = normal >= -tension_force - np.where(state != OPEN, kn * tolerance, 0.0)
    strength = np.maximum(normal, 0.0) * tan_phi + cohesion_force
    slip = np.sign(shear).astype(np.int8)
    holds = ks * np.abs(shear) <= strength
    reversed_slip = (state == SLIDING) & (sign * shear < -tolerance) & (strength > 0)
    holds = holds & (state != SLIDING)
    glancing = (state == LOCKED) & ~closed & closed_this_step
    new_state = np.where(closed, np.where(holds | reversed_slip | (state == OPEN), LOCKED, SLIDING), OPEN)
    new_state = np.where(glancing, SLIDING, new_state).astype(np.int8)
    new_sign = np.where(new_state == SLIDING, np.where(state == SLIDING, sign, slip), 0).astype(np.int8)
    friction = tan_phi > 0
    changed = (new_state != state) | ((new_state == SLIDING) & (new_sign != sign) & friction)
    off = np.abs(np.maximum(normal, 0.0) - friction_normal)
    unsettled = (new_state == SLIDING) & (state == SLIDING) & friction & (
        off > friction_tolerance * np.maximum(normal, 0.0)) & (off * tan_phi > settled_force)
    return new_state, new_sign, changed, unsettled


def _pick(rng, n, *values):
    return np.asarray(values)[rng.integers(0, len(values), n)]


def test_compiled_open_close_rules_equal_the_array_rules_bit_for_bit():
    rng = np.random.default_rng(11)
    n, kn, ks = 20_000, 5e10, 2e10
    for tolerance in (0.0, 2e-7 * 25.0):
        state = _pick(rng, n, OPEN, SLIDING, LOCKED).astype(np.int8)
        sign = _pick(rng, n, -1, 0, 1).astype(np.int8)
        # gaps and shears around every threshold, with exact zeros and the band's edges
        gap = np.where(rng.random(n) < 0.1, _pick(rng, n, 0.0, -0.0, tolerance, -tolerance),
                       rng.normal(scale=1e-6, size=n))
        shear = np.where(rng.random(n) < 0.1, _pick(rng, n, 0.0, tolerance, -tolerance),
                         rng.normal(scale=1e-6, size=n))
        tan_phi = _pick(rng, n, 0.0, np.tan(np.radians(30.0)))
        cohesion = np.where(rng.random(n) < 0.2, rng.uniform(0, 1e4, n), 0.0)
        tension = np.where(rng.random(n) < 0.2, rng.uniform(0, 1e4, n), 0.0)
        closed_this_step = rng.random(n) < 0.3
        friction_normal = np.maximum(-kn * gap, 0.0) * (1.0 + _pick(rng, n, 0.0, 1e-4, 1e-2))
        for settled in (0.0, rng.uniform(0.0, 10.0, n)):
            args = (state, sign, gap, shear, kn, ks, tan_phi, cohesion, tension, closed_this_step,
                    friction_normal, 1e-3, tolerance, settled)
            for got, want in zip(next_states(*args), _array_rules(*args)):
                assert got.dtype == want.dtype and np.array_equal(got, want)


def test_compiled_secant_step_equals_the_array_step_bit_for_bit():
    rng = np.random.default_rng(12)
    n = 20_000
    used, prev_used = rng.uniform(0, 1e4, n), rng.uniform(0, 1e4, n)
    prev_used[:100] = used[:100]  # no secant without a previous distinct N
    solved = np.where(rng.random(n) < 0.1, 0.0, rng.uniform(0, 1e4, n))
    residual, prev_residual = solved - used, rng.normal(scale=1e3, size=n)
    prev_residual[100:200] = residual[100:200]  # a flat residual: no slope
    sliding = rng.random(n) < 0.7
    got = solved.copy()
    _secant_normal(used, solved, residual, prev_used, prev_residual, sliding, got)
    slope = residual - prev_residual
    ok = sliding & (np.abs(slope) > 1e-12 * np.maximum(np.abs(residual), 1e-300)) & (used != prev_used)
    secant = used - np.where(ok, residual * (used - prev_used) / np.where(ok, slope, 1.0), 0.0)
    inside = (secant >= np.minimum(used, solved)) & (secant <= np.maximum(used, solved))
    want = np.where(ok & inside & (solved > 0), secant, solved)
    assert np.array_equal(got, want)
    assert 0 < np.count_nonzero(got != solved) < n  # both branches taken
