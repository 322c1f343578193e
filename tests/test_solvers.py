"""The solver seam: a factorisation is reused while the matrix is unchanged, an analysis while its pattern is."""
from __future__ import annotations

import numpy as np
import pytest

import scipy.sparse.linalg as spla

from srdda.assembly.system import BlockSystem
from srdda.solvers import available_solvers, get_solver
from srdda.solvers._direct import _Analysing, _BlockPattern


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


class _CountingAnalysis(_Analysing):
    """An analysing backend on SuperLU (always installed) that counts its analyses and factorisations."""

    name = "counting"

    def analyse(self, matrix):
        self.analysed_nnz = matrix.nnz

    def factorize(self, matrix):
        return spla.splu(matrix.tocsc()).solve


def _with_couplings(pairs: list[tuple[int, int]], n_blocks: int = 12, seed: int = 0) -> BlockSystem:
    """An SPD block system whose off-diagonal blocks couple ``pairs`` (as contacts do)."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n_blocks, 6, 6))
    system = BlockSystem(np.einsum("nij,nkj->nik", a, a) + 6 * np.eye(6), rng.normal(size=(n_blocks, 6)))
    i, j = np.array(pairs).T
    system.add_off_diagonal(i, j, 0.1 * rng.normal(size=(len(pairs), 6, 6)))
    return system


def _backends_with_analysis():
    return [_CountingAnalysis(), *(get_solver(n) for n in ("cholmod", "pardiso") if n in available_solvers())]


@pytest.mark.parametrize("solver", _backends_with_analysis(), ids=lambda s: s.name)
def test_the_analysis_is_reused_while_the_pattern_stays_inside(solver):
    chain = [(k, k + 1) for k in range(11)]
    steps = [
        (_with_couplings(chain), 1),  # first matrix: analysed
        (_with_couplings(chain[:5] + chain[6:], seed=1), 1),  # a contact opened: inside the pattern
        (_with_couplings(chain, seed=2), 1),  # it closed again
        (_with_couplings(chain + [(0, 5)], seed=3), 2),  # a new coupling: analysed on the union
        (_with_couplings(chain, seed=4), 2),  # inside the union
        (_with_couplings([(0, 11), (3, 9)], seed=5), 3),  # a different pattern: analysed again
    ]
    for system, analyses in steps:
        x = solver.solve(system, system.rhs.ravel())
        # residual of an O(1), diagonally dominant system: round-off
        np.testing.assert_allclose(system.to_dense() @ x, system.rhs.ravel(), atol=1e-10)
        assert solver.analyses == analyses
    assert solver.factorizations == len(steps)
    solver.solve(system, 2.0 * system.rhs.ravel())
    assert solver.factorizations == len(steps)  # the same matrix again: the factor is reused


def test_the_block_pattern_writes_a_matrix_with_explicit_zeros():
    system = _with_couplings([(0, 1), (2, 5)])
    bsr = system.to_bsr()
    keys = _BlockPattern.keys_of(bsr)
    wider = np.union1d(keys, [3 * 12 + 4, 4 * 12 + 3])
    for upper in (False, True):
        pattern = _BlockPattern(wider, 12, 6, upper)
        matrix = pattern.csr(bsr, pattern.positions(keys))
        expected = np.triu(system.to_dense()) if upper else system.to_dense()
        np.testing.assert_array_equal(matrix.toarray(), expected)
        assert matrix.nnz == (len(wider) * 36 + 12 * 6) // 2 if upper else len(wider) * 36
        assert matrix.has_sorted_indices
    assert _BlockPattern(keys, 12, 6, False).positions(wider) is None


class _GaussSeidel:
    """A toy backend from outside srdda: Gauss-Seidel sweeps on the dense matrix until the increment stops moving."""

    name = "toy-gauss-seidel"

    def __init__(self, tolerance: float) -> None:
        self.tolerance = tolerance
        self.sweeps = 0

    def solve(self, system: BlockSystem, rhs: np.ndarray) -> np.ndarray:
        a = system.to_dense()
        lower, upper = np.tril(a), np.triu(a, 1)
        x = np.zeros_like(rhs)
        for _ in range(10_000):
            new = np.linalg.solve(lower, rhs - upper @ x)  # one sweep: a triangular solve
            self.sweeps += 1
            if np.max(np.abs(new - x)) < 1e-3 * self.tolerance:
                return new
            x = new
        raise AssertionError("Gauss-Seidel did not converge")


def test_a_registered_solver_runs_a_model_as_the_direct_one_does(monkeypatch):
    # register_solver plugs a backend in without editing srdda: RunSettings accepts its name, run() uses it.
    # A block sliding on a fixed block for 50 steps (contacts: the open-close iteration solves several times a
    # step). Gauss-Seidel converges on the SPD step matrix; stopped when a sweep changes no unknown by more than
    # 1e-3 of the displacement tolerance (1e-12 m), its leftover error is a few 1e-12 m per solve: the runs'
    # centroids agree within 1e-10 m (4e-12 m measured) while the block slides 3.7e-3 m.
    import srdda
    from srdda.solvers import _registry

    monkeypatch.setattr(_registry, "_TABLE", dict(_registry._TABLE))  # the registration ends with the test
    made: list[_GaussSeidel] = []

    def factory(tolerance: float) -> _GaussSeidel:
        made.append(_GaussSeidel(tolerance))
        return made[-1]

    srdda.solvers.register_solver("toy-gauss-seidel", factory)
    assert "toy-gauss-seidel" in available_solvers()
    with pytest.raises(ValueError, match="already registered"):
        srdda.solvers.register_solver("toy-gauss-seidel", _GaussSeidel)

    def slide(solver: str) -> np.ndarray:
        m = srdda.Model(gravity=(0.0, -9.81))
        m.add_material("rock", srdda.Material(density=2500.0, young=1e9, poisson=0.25))
        m.add_joint_material("joint", srdda.JointMaterial(friction_angle=10.0), between=[("rock", "rock")])
        m.add_block([[-1, -1], [3, -1], [3, 0], [-1, 0]], "rock", fixed=True)
        m.add_block([[0, 0], [1, 0], [1, 0.5], [0, 0.5]], "rock")
        m.rotate(30.0)
        result = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=50, solver=solver))
        assert result.completed
        return np.asarray(result.array("centroid"))

    ours, direct = slide("toy-gauss-seidel"), slide("superlu")
    assert made and made[0].sweeps > 50  # the run solved with the toy backend
    assert np.max(np.abs(ours - direct)) < 1e-10
    assert np.max(np.abs(direct[-1] - direct[0])) > 1e-3  # the block slid: the comparison means something
