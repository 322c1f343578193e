"""The solver seam: a factorisation is reused while the assembled matrix is unchanged."""
from __future__ import annotations

import numpy as np
import pytest

from srdda.assembly.system import BlockSystem
from srdda.solvers import get_solver


def _system(n_blocks: int, seed: int = 0) -> BlockSystem:
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n_blocks, 6, 6))
    diag = np.einsum("nij,nkj->nik", a, a) + 6 * np.eye(6)  # symmetric positive definite blocks
    system = BlockSystem(diag, rng.normal(size=(n_blocks, 6)))
    i = np.arange(n_blocks - 1)
    system.add_off_diagonal(i, i + 1, 0.1 * rng.normal(size=(n_blocks - 1, 6, 6)))
    return system


@pytest.mark.parametrize("name", ["superlu"])
def test_factor_reused_while_the_matrix_is_unchanged(name):
    solver = get_solver(name)
    system = _system(50)
    dense = system.to_dense()
    for k in range(3):  # same matrix, new right-hand sides: one factorisation
        rhs = np.random.default_rng(k).normal(size=system.size)
        x = solver.solve(system, rhs)
        np.testing.assert_allclose(dense @ x, rhs, atol=1e-10)  # residual of an O(1) well-conditioned system
    assert solver.factorizations == 1
    changed = _system(50)
    changed.diag[3, 2, 2] += 1.0
    x = solver.solve(changed, changed.rhs.ravel())
    np.testing.assert_allclose(changed.to_dense() @ x, changed.rhs.ravel(), atol=1e-10)
    assert solver.factorizations == 2  # a changed value is a new factorisation, never a stale one
