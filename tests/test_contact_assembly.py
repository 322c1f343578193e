"""The contact springs of a solve summed by changes (large systems) against a fresh sum.

On systems of more than ``INCREMENTAL_BLOCKS`` blocks the contact term sums its
springs at the first solve of a step and then adds or removes only the springs
of contacts whose state changed (docs/performance.md, "Only the contacts that
changed"). The step's matrix and right-hand side must be those of a fresh sum,
up to the order of the additions.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import srdda

from srdda.apps.bench.models import brick_wall, english_bond_wall
from srdda.contact.openclose import LOCKED, OPEN, SLIDING
from srdda.contact.penalty import directional_rows
from srdda.contact.pipeline import ContactTerm
from srdda.solvers import get_solver
from srdda.state import initial_state
from srdda.step import Stepper


def _assembled(stepper: Stepper, ctx, terms, base, monkeypatch, by_changes: bool) -> tuple[np.ndarray, np.ndarray]:
    monkeypatch.setattr("srdda.contact.penalty.INCREMENTAL_BLOCKS", 0 if by_changes else 10**9)
    system = stepper.assemble(ctx, terms, base)
    return system.to_dense(), system.rhs.ravel().copy()


def _first_step(build):
    """A model's stepper at its first step: (arrays, stepper, ctx, terms, base system, contact step)."""
    model, settings = build()
    arrays = model.arrays()
    stepper = Stepper(arrays, replace(settings, n_steps=1), get_solver("dense"))
    ctx, terms = stepper.begin(initial_state(arrays, stepper.method), settings.dt)
    base = stepper.base_system(ctx, terms)
    return arrays, stepper, ctx, terms, base, next(t for t in terms if isinstance(t, ContactTerm)).step


@pytest.mark.parametrize("build", [lambda: brick_wall(6, 6), lambda: english_bond_wall(3, 3)], ids=["2d", "3d"])
def test_springs_summed_by_changes_equal_a_fresh_sum(build, monkeypatch):
    _, stepper, ctx, terms, base, contacts = _first_step(build)
    assert contacts is not None and len(contacts) > 50
    rng = np.random.default_rng(3)
    states = np.array([OPEN, SLIDING, LOCKED], dtype=np.int8)
    if hasattr(contacts, "sign"):  # 2D: the slip direction along the edge of a sliding contact
        contacts.sign = rng.choice(np.array([-1, 1], dtype=np.int8), len(contacts))
    for trial in range(12):
        # from all closed, through every kind of change: a few contacts, then many, then back
        changed = rng.random(len(contacts)) < (0.05, 0.5)[trial % 2]
        contacts.state = np.where(changed, rng.choice(states, len(contacts)), contacts.state).astype(np.int8)
        contacts.friction_normal = rng.uniform(0.0, 1e4, len(contacts))
        matrix, rhs = _assembled(stepper, ctx, terms, base, monkeypatch, by_changes=True)
        fresh_matrix, fresh_rhs = _assembled(stepper, ctx, terms, base, monkeypatch, by_changes=False)
        # the same terms summed in another order: each spring added and removed at most 12 times, so a few
        # rounding errors of the largest entry (k_n |n·T|², 5e10 N/m here), not a spring of k_s = 2e10
        assert np.abs(matrix - fresh_matrix).max() <= 1e-12 * np.abs(fresh_matrix).max(), trial
        assert np.abs(rhs - fresh_rhs).max() <= 1e-12 * np.abs(fresh_rhs).max(), trial
    assert contacts._springs._sums is not None  # the changes path was taken


def test_a_wall_settles_alike_with_sums_by_changes(monkeypatch):
    # the whole step on either path: a 6 x 6 wall, 5 steps; the paths differ by the round-off of the sums only
    model, settings = brick_wall(6, 6)
    ends = []
    for threshold in (0, 10**9):
        monkeypatch.setattr("srdda.contact.penalty.INCREMENTAL_BLOCKS", threshold)
        result = srdda.run(model, replace(settings, n_steps=5, solver="dense"))
        assert result.completed, result.status
        ends.append(result.final_state.vertices)
    # measured 4.5e-20 m apart after moving 3.7e-5 m: round-off; 1e-12 m leaves room for another path of the
    # iteration and still catches a spring missing for one solve (~1e-6 m)
    assert np.abs(ends[0] - ends[1]).max() <= 1e-12


@pytest.mark.parametrize("build", [lambda: brick_wall(6, 6), lambda: english_bond_wall(3, 3)], ids=["2d", "3d"])
def test_gaps_and_shears_from_the_rows_equal_the_shape_products(build, monkeypatch):
    # large systems move the gaps and shears by the springs' rows n·T, e·T times Δd in one compiled pass
    # (ContactSprings.increments); small ones by the einsums of T·Δd. The same quantities in another order.
    arrays, stepper, ctx, terms, base, contacts = _first_step(build)
    stepper.assemble(ctx, terms, base)  # the shapes and rows of the step
    rng = np.random.default_rng(5)
    start = (contacts.state.copy(), contacts.flips.copy(), contacts.closed_this_step.copy())
    for trial in range(5):
        dd = rng.normal(scale=1e-4, size=(arrays.n_blocks, base.ndof))
        found = []
        for threshold in (0, 10**9):
            monkeypatch.setattr("srdda.contact.penalty.INCREMENTAL_BLOCKS", threshold)
            contacts.state, contacts.flips, contacts.closed_this_step = (a.copy() for a in start)
            contacts.iterations, contacts._secant = 0, None
            contacts.converged(dd, ctx)
            found.append((contacts.gap.copy(), contacts.shear.copy(), contacts.state.copy()))
        (gap, shear, state), (gap_ref, shear_ref, state_ref) = found
        # 12-24 products of 1e-4 m displacements by shape entries of order 1: a few ulp of the largest term
        scale = np.abs(gap_ref).max() + np.abs(shear_ref).max()
        assert np.abs(gap - gap_ref).max() <= 1e-13 * scale, trial
        assert np.abs(shear - shear_ref).max() <= 1e-13 * scale, trial
        assert np.array_equal(state, state_ref), trial  # and so the open-close rules decide alike


@pytest.mark.parametrize("spec, directions, shapes", [
    ("nk,nki->ni", (2,), (2, 6)),  # 2D: n·T, t·T
    ("nk,nki->ni", (3,), (3, 12)),  # 3D: n·T
    ("nmk,nki->nmi", (2, 3), (3, 12)),  # 3D: the frame's two shear directions e·T
], ids=["2d", "3d-normal", "3d-frame"])
def test_directional_rows_are_the_einsum_bit_for_bit(spec, directions, shapes):
    # the contact springs' rows: the compiled pass replaced these einsums at every size, so the paper's rows
    # keep their bits; zeros and signed zeros included (shape entries vanish, directions are axis-aligned)
    rng = np.random.default_rng(21)
    n = 50_000
    d, t = rng.normal(size=(n, *directions)), rng.normal(size=(n, *shapes))
    d[rng.random(d.shape) < 0.1] = -0.0
    t[rng.random(t.shape) < 0.2] = 0.0
    assert np.array_equal(directional_rows(d, t).view(np.int64), np.einsum(spec, d, t).view(np.int64))


def test_row_increments_on_one_thread_and_on_all_are_the_same_bits():
    # small models move the gaps and shears on one thread (starting the threads took 0.14 s of slope_a's 3.0 s
    # under Newton, 100 steps), large ones on all cores: each contact's sums are the same in both, so the same bits
    from srdda.contact.penalty import _row_increments, _row_increments_parallel
    rng = np.random.default_rng(11)
    for nb, ndof, k in ((7, 6, 1), (9, 12, 2)):
        n = 3000
        args = (rng.integers(0, nb, n), rng.integers(0, nb, n), rng.normal(size=(n, ndof)), rng.normal(size=(n, ndof)),
                rng.normal(size=(n, k, ndof)), rng.normal(size=(n, k, ndof)), rng.normal(size=(nb, ndof)))
        out = [(np.empty(n), np.empty((n, k))) for _ in range(2)]
        _row_increments(*args, *out[0])
        _row_increments_parallel(*args, *out[1])
        assert np.array_equal(out[0][0], out[1][0]) and np.array_equal(out[0][1], out[1][1])
        # and they are the rows times the blocks' increments
        dn = np.einsum("ni,ni->n", args[2], args[6][args[0]]) - np.einsum("ni,ni->n", args[3], args[6][args[1]])
        assert np.allclose(out[0][0], dn, rtol=0, atol=1e-12)
