"""The solver seam: a factorisation is reused while the matrix is unchanged, an analysis while its pattern is."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import scipy.sparse.linalg as spla

from srdda.assembly.system import BlockSystem
from srdda.solvers import available_solvers, get_solver
from srdda.solvers import SolverError
from srdda.solvers._blockcholesky import BlockFactorPattern, factorize_blocks
from srdda.solvers._direct import _Analysing, _BlockPattern


def _system(n_blocks: int, seed: int = 0) -> BlockSystem:
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n_blocks, 6, 6))
    diag = np.einsum("nij,nkj->nik", a, a) + 6 * np.eye(6)  # symmetric positive definite blocks
    system = BlockSystem(diag, rng.normal(size=(n_blocks, 6)))
    i = np.arange(n_blocks - 1)
    system.add_off_diagonal(i, i + 1, 0.1 * rng.normal(size=(n_blocks - 1, 6, 6)))
    return system


@pytest.mark.parametrize("name", ["superlu", "block-cholesky"])
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


def _random_block_system(n_blocks: int, ndof: int, n_pairs: int, seed: int) -> BlockSystem:
    """An SPD block system with random couplings (repeats and both orders, as contacts give), its diagonal
    blocks dominant so that it is well conditioned (condition number below about 10)."""
    rng = np.random.default_rng(seed)
    i = rng.integers(0, n_blocks, n_pairs)
    j = rng.integers(0, n_blocks, n_pairs)
    keep = i != j
    i, j = i[keep], j[keep]
    couplings = rng.uniform(-1.0, 1.0, size=(len(i), ndof, ndof)) / ndof
    diag = np.zeros((n_blocks, ndof, ndof))
    weight = np.bincount(np.concatenate([i, j]), minlength=n_blocks) + 1.0  # Gershgorin: row sums below this
    a = rng.normal(size=(n_blocks, ndof, ndof)) / ndof
    diag += np.einsum("nij,nkj->nik", a, a) + 2.0 * weight[:, None, None] * np.eye(ndof)
    system = BlockSystem(diag, rng.normal(size=(n_blocks, ndof)))
    system.add_off_diagonal(i, j, couplings)
    return system


# no deadline: the first example of each block size compiles its kernels (seconds on a fresh clone), which is
# not what these tests measure
@settings(deadline=None)
@given(n_blocks=st.integers(1, 40), ndof=st.sampled_from([6, 12]), density=st.floats(0.0, 3.0),
       seed=st.integers(0, 2**32 - 1))
def test_block_cholesky_solves_random_block_systems(n_blocks, ndof, density, seed):
    # against LAPACK on the dense matrix: both backward stable on a matrix of condition number ~10, so the
    # solutions agree to a few hundred ulps of the solution's size (bound 1e-12 relative)
    system = _random_block_system(n_blocks, ndof, int(density * n_blocks), seed)
    x = get_solver("block-cholesky").solve(system, system.rhs.ravel())
    expected = np.linalg.solve(system.to_dense(), system.rhs.ravel())
    assert np.max(np.abs(x - expected)) <= 1e-12 * np.max(np.abs(expected))


@settings(deadline=None)  # as above
@given(n_blocks=st.integers(2, 30), density=st.floats(0.5, 3.0), seed=st.integers(0, 2**32 - 1))
def test_block_cholesky_pattern_holds_every_entry_of_the_factor(n_blocks, density, seed):
    # the symbolic factorisation (elimination tree, fill-in) against the dense Cholesky of the matrix in the
    # same order: every block of L that is not exactly zero lies in the factor's pattern, and the compiled
    # factorisation equals it to rounding
    ndof = 6
    system = _random_block_system(n_blocks, ndof, int(density * n_blocks), seed)
    bsr = system.to_bsr()
    keys = _BlockPattern.keys_of(bsr)
    symbolic = BlockFactorPattern(keys, n_blocks)
    dense = system.to_dense().reshape(n_blocks, ndof, n_blocks, ndof)[symbolic.order][:, :, symbolic.order]
    lower = np.linalg.cholesky(dense.reshape(n_blocks * ndof, -1)).reshape(n_blocks, ndof, n_blocks, ndof)
    in_pattern = np.zeros((n_blocks, n_blocks), dtype=bool)
    columns = np.repeat(np.arange(n_blocks), np.diff(symbolic.pointers))
    in_pattern[symbolic.rows, columns] = True
    assert not np.any(np.any(lower != 0.0, axis=(1, 3)) & ~in_pattern)
    factor = symbolic.placed(bsr.data)
    assert factorize_blocks(symbolic.pointers, symbolic.rows, factor) == -1
    expected = lower[symbolic.rows, :, columns, :]
    assert np.max(np.abs(factor - expected)) <= 1e-12 * np.max(np.abs(lower))


def test_block_cholesky_results_do_not_depend_on_the_matrices_solved_before():
    # each pattern is analysed on its own (kept for when it recurs), never on a union grown from earlier
    # matrices: a fresh solver (a run resumed from a saved state) gives the same bits as one that solved others
    chain = [(k, k + 1) for k in range(11)]
    sequence = [_with_couplings(chain), _with_couplings(chain[:5] + chain[6:], seed=1),
                _with_couplings(chain + [(0, 5)], seed=2), _with_couplings(chain, seed=3)]
    used = get_solver("block-cholesky")
    for system in sequence:
        x = used.solve(system, system.rhs.ravel())
        fresh = get_solver("block-cholesky").solve(system, system.rhs.ravel())
        assert np.array_equal(x, fresh)
        np.testing.assert_allclose(system.to_dense() @ x, system.rhs.ravel(), atol=1e-10)  # round-off, O(1)
    assert used.analyses == 3  # the chain's pattern recurred: its analysis was kept
    assert used.factorizations == 4
    used.solve(sequence[-1], 2.0 * sequence[-1].rhs.ravel())
    assert used.factorizations == 4  # the same matrix again: the factor is reused


def test_block_cholesky_names_a_matrix_that_is_not_positive_definite():
    system = _random_block_system(10, 6, 15, 0)
    system.diag[4] = -system.diag[4]
    with pytest.raises(SolverError, match="not positive definite"):
        get_solver("block-cholesky").solve(system, system.rhs.ravel())


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


def test_a_run_under_the_block_cholesky_resumes_bit_for_bit():
    # slope_a (74 blocks: the direct tier of ``auto``), 12 steps straight through against 6 steps, then a new
    # stepper and solver from the state reached (what `srdda run --resume` builds): the open-close iteration
    # changes the matrix's pattern from solve to solve, and every state array must agree to the bit
    from srdda.apps.bench.models import jointed_slope
    from srdda.state import initial_state
    from srdda.step import Stepper, default_terms

    model, settings = jointed_slope("a")
    settings = replace(settings, solver="block-cholesky")
    arrays = model.arrays()

    def steps(state, n):
        solver = get_solver("block-cholesky")
        stepper = Stepper(arrays, settings, solver, default_terms(arrays, settings))
        state = initial_state(arrays, stepper.method) if state is None else state
        for _ in range(n):
            outcome = stepper.step(state, settings.dt)
            assert outcome.status == "accepted"
            state = outcome.state
        return state, solver

    straight, solver = steps(None, 12)
    assert solver.analyses > 1  # the pattern changed within the run: a history-dependent analysis would show
    resumed, _ = steps(steps(None, 6)[0], 6)
    for name in ("vertices", "velocity", "acceleration", "stress"):
        np.testing.assert_array_equal(getattr(resumed, name), getattr(straight, name), err_msg=name)
