"""The open-close rules and the friction's secant step, compiled contact by contact, against their whole-array
forms (the code before they were compiled, and before 2D and 3D shared them), bit for bit: the paper's rows
depend on every bit."""
from __future__ import annotations

import numpy as np

from srdda.contact.openclose import LOCKED, OPEN, SLIDING, next_states
from srdda.contact.pipeline import _secant_normal


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
            want = _array_rules(*args)
            strength = np.maximum(-kn * gap, 0.0) * tan_phi + cohesion
            got = next_states(state, sign[:, None].astype(float), gap, shear[:, None], shear[:, None] * 0.5,
                              np.full(n, kn), np.full(n, ks), strength, tan_phi, tension, closed_this_step,
                              friction_normal, np.zeros(n, dtype=bool), 1e-3, tolerance, settled)
            new_state, new_direction, _, changed, unsettled = got
            assert new_state.dtype == want[0].dtype and np.array_equal(new_state, want[0])
            assert np.array_equal(new_direction[:, 0], want[1].astype(float))
            assert np.array_equal(changed, want[2]) and np.array_equal(unsettled, want[3])


def _array_rules_3d(state, direction, gap, shear, slip, kn, ks, tan_phi, cohesion_force, tension_force,
                    closed_this_step, friction_normal, friction_tolerance):
    """The 3D rules as they were written for polyhedra alone (contacts whose sliding spring is dragged)."""
    normal = -kn * gap
    closed = normal >= -tension_force
    strength = np.maximum(normal, 0.0) * tan_phi + cohesion_force
    size = np.linalg.norm(shear, axis=1)
    holds = ks * size <= strength
    sliding = state == SLIDING
    limit = strength / ks
    trial = np.where(sliding[:, None], direction * limit[:, None] + slip, shear)
    trial_size = np.linalg.norm(trial, axis=1)
    unit = np.where(trial_size[:, None] > 0, trial / np.where(trial_size > 0, trial_size, 1.0)[:, None], 0.0)
    reversed_slip = sliding & (np.einsum("nk,nk->n", slip, direction) < 0) & (strength > 0)
    stays = ~holds & ~reversed_slip & (state != OPEN)
    glancing = (state == LOCKED) & ~closed & closed_this_step
    new_state = np.where(closed, np.where(stays, SLIDING, LOCKED), OPEN)
    new_state = np.where(glancing, SLIDING, new_state).astype(np.int8)
    now_sliding = new_state == SLIDING
    trial_direction = np.where(now_sliding[:, None], unit, 0.0)
    new_direction = np.where((now_sliding & sliding)[:, None], direction, trial_direction)
    changed = new_state != state
    force = np.maximum(normal, 0.0)
    unsettled = now_sliding & sliding & (tan_phi > 0) & (np.abs(force - friction_normal) > friction_tolerance * force)
    return new_state, new_direction, trial_direction, changed, unsettled


def test_compiled_rules_of_dragged_springs_equal_the_3d_array_rules_bit_for_bit():
    # the rules of a contact whose sliding spring is dragged at its strength (3D vertex-face), with no band
    # and no negligible force, are those the polyhedra had before 2D and 3D shared one set
    rng = np.random.default_rng(13)
    n, kn, ks = 20_000, 5e10, 2e10
    state = _pick(rng, n, OPEN, SLIDING, LOCKED).astype(np.int8)
    angle = rng.uniform(0, 2 * np.pi, n)
    direction = np.where((state == SLIDING)[:, None], np.column_stack([np.cos(angle), np.sin(angle)]), 0.0)
    gap = np.where(rng.random(n) < 0.1, _pick(rng, n, 0.0, -0.0), rng.normal(scale=1e-6, size=n))
    shear = np.where(rng.random((n, 2)) < 0.1, 0.0, rng.normal(scale=1e-6, size=(n, 2)))
    slip = np.where(rng.random((n, 2)) < 0.1, 0.0, rng.normal(scale=1e-6, size=(n, 2)))
    tan_phi = _pick(rng, n, 0.0, np.tan(np.radians(30.0)))
    cohesion = np.where(rng.random(n) < 0.2, rng.uniform(0, 1e4, n), 0.0)
    tension = np.where(rng.random(n) < 0.2, rng.uniform(0, 1e4, n), 0.0)
    closed_this_step = rng.random(n) < 0.3
    friction_normal = np.maximum(-kn * gap, 0.0) * (1.0 + _pick(rng, n, 0.0, 1e-4, 1e-2))
    want = _array_rules_3d(state, direction, gap, shear, slip, kn, ks, tan_phi, cohesion, tension, closed_this_step,
                           friction_normal, 1e-3)
    strength = np.maximum(-kn * gap, 0.0) * tan_phi + cohesion
    got = next_states(state, direction, gap, shear, slip, np.full(n, kn), np.full(n, ks), strength, tan_phi, tension,
                      closed_this_step, friction_normal, np.ones(n, dtype=bool), 1e-3, 0.0, 0.0)
    for g, w in zip(got, want):
        assert np.array_equal(g, w)
    assert 0 < np.count_nonzero(got[0] == SLIDING) < n


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
