"""The conjugate gradient backends against the direct solve, on the systems of real steps (issue 14).

The systems are those a brick wall's steps solve: SPD block systems whose
off-diagonal blocks are stiff contact penalties (k_n = 5e10 N/m, 20 times the
inertia term 2m/Δt² = 2.5e9 N/m of a brick, and 50 times stiffer: 1000 times
the inertia term, the issue's hard case), with every solve of the open-close
iteration (contacts opening and closing between solves).
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from srdda.assembly.system import BlockSystem
from srdda.apps.bench.models import brick_wall
from srdda.solvers import (ITERATIVE_LIMIT, AutoSolver, ConjugateGradientSolver, SolverError, SuperLUSolver,
                           get_solver, solves_inexactly)
from srdda.state import initial_state
from srdda.step import Stepper


class _Compared:
    """A solver that solves every system twice, with ``inner`` and with SuperLU, and keeps the worst gap."""

    name = "compared"

    def __init__(self, inner) -> None:
        self.inner = inner
        self.direct = SuperLUSolver()
        self.gaps: list[float] = []

    def solve(self, system: BlockSystem, rhs: np.ndarray) -> np.ndarray:
        x = self.inner.solve(system, rhs)
        exact = self.direct.solve(system, rhs)
        self.gaps.append(float(np.max(np.abs(x - exact))))
        return exact  # the run follows the direct path, so every solve is compared on the same system


def _wall_solves(solver, stiffness_factor: float = 1.0, steps: int = 3, nx: int = 8, ny: int = 6):
    """Run a small wall (steps of 1 ms, dda0) with ``solver`` and return it."""
    model, settings = brick_wall(nx, ny)
    k = settings.contact_penalty * stiffness_factor
    settings = dataclasses.replace(settings, contact_penalty=k, penalty=k)
    arrays = model.arrays()
    stepper = Stepper(arrays, settings, solver)
    state = initial_state(arrays, stepper.method)
    dt = settings.dt
    for _ in range(steps):
        outcome = stepper.step(state, dt)
        assert outcome.status != "diverged", outcome.reason
        if outcome.status == "accepted":
            state = outcome.state
        dt = outcome.dt_next
    return solver


@pytest.mark.parametrize("preconditioner", ["amg", "jacobi"])
@pytest.mark.parametrize("stiffness_factor", [1.0, 50.0])
@pytest.mark.parametrize("tolerance", [1e-9, 1e-11])
def test_cg_matches_the_direct_solve_within_the_displacement_tolerance(preconditioner, stiffness_factor, tolerance):
    compared = _wall_solves(_Compared(ConjugateGradientSolver(preconditioner, tolerance)), stiffness_factor)
    assert len(compared.gaps) >= 3  # several solves, warm-started from one another
    # the stopping rule's promise: every unknown of every solve within the tolerance of the direct solve
    assert max(compared.gaps) <= tolerance
    # and it does not over-solve wildly: the largest gap is not below 1e-4 of the tolerance (a rule that
    # always ran to round-off would pass the line above and cost several times the iterations)
    assert max(compared.gaps) >= 1e-4 * tolerance


def _wall_system(nx: int = 8, ny: int = 6, stiffness_factor: float = 1.0) -> BlockSystem:
    model, settings = brick_wall(nx, ny)
    k = settings.contact_penalty * stiffness_factor
    settings = dataclasses.replace(settings, contact_penalty=k, penalty=k)
    arrays = model.arrays()
    stepper = Stepper(arrays, settings, get_solver("superlu"))
    ctx, terms = stepper.begin(initial_state(arrays, stepper.method), settings.dt)
    return stepper.assemble(ctx, terms)


@pytest.mark.parametrize("preconditioner", ["amg", "jacobi"])
def test_warm_start_takes_fewer_iterations(preconditioner):
    system = _wall_system()
    rhs = system.full_rhs()
    changed = 1.001 * rhs  # the next solve of an iteration: a right-hand side close to the last one
    warm = ConjugateGradientSolver(preconditioner, 1e-10)
    warm.solve(system, rhs)
    warm.solve(system, changed)
    cold = ConjugateGradientSolver(preconditioner, 1e-10)
    cold.solve(system, changed)
    assert warm.iterations[1] < cold.iterations[0]
    # from the solution of a right-hand side 0.1% away the error starts 1000 times smaller: CG's
    # error falls geometrically, so the warm solve needs clearly fewer iterations (at least a third fewer)
    assert warm.iterations[1] <= 2 * cold.iterations[0] // 3


@pytest.mark.parametrize("preconditioner", ["amg", "jacobi"])
def test_a_looser_tolerance_for_one_solve_stops_earlier_within_it(preconditioner):
    # an inexact Newton step asks one solve for a looser tolerance (docs/contacts/solve.md): the solve stops
    # within that tolerance of the direct solve, in fewer iterations than at the backend's own
    system = _wall_system()
    rhs = system.full_rhs()
    exact = SuperLUSolver().solve(system, rhs)
    tight, loose = ConjugateGradientSolver(preconditioner, 1e-11), ConjugateGradientSolver(preconditioner, 1e-11)
    tight.solve(system, rhs)
    x = loose.solve(system, rhs, 1e-7)
    assert np.abs(x - exact).max() <= 1e-7
    assert loose.iterations[0] < tight.iterations[0]


def test_only_iterative_backends_solve_inexactly():
    small, large = _chain(20), _chain(ITERATIVE_LIMIT + 1)
    auto = AutoSolver()
    assert not auto.inexact(small) and auto.inexact(large)
    assert ConjugateGradientSolver("jacobi").inexact(small)
    assert not solves_inexactly(SuperLUSolver(), large) and not solves_inexactly(get_solver("dense"), small)
    assert not solves_inexactly(_Compared(SuperLUSolver()), large)  # a backend without `inexact` is exact


def test_the_same_system_again_needs_no_iteration():
    solver = ConjugateGradientSolver("amg", 1e-9)
    system = _wall_system()
    x = solver.solve(system, system.full_rhs())
    again = solver.solve(system, system.full_rhs())
    assert solver.iterations[1] == 0 and np.array_equal(x, again)


def _chain(n_blocks: int, coupling: float = 0.1, seed: int = 0) -> BlockSystem:
    """An SPD block chain: random SPD diagonal blocks, weak random couplings (diagonally dominant)."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n_blocks, 6, 6))
    system = BlockSystem(np.einsum("nij,nkj->nik", a, a) + 6 * np.eye(6), rng.normal(size=(n_blocks, 6)))
    i = np.arange(n_blocks - 1)
    system.add_off_diagonal(i, i + 1, coupling * rng.normal(size=(n_blocks - 1, 6, 6)))
    return system


def test_auto_chooses_by_size():
    auto = AutoSolver()
    assert auto.choose(_chain(20)) is auto.dense  # 120 unknowns
    assert auto.choose(_chain(21)) is auto.direct
    assert auto.choose(_chain(ITERATIVE_LIMIT)) is auto.direct
    large = _chain(ITERATIVE_LIMIT + 1)
    assert auto.choose(large) is auto.iterative
    x = auto.solve(large, large.full_rhs())
    # 1e-9 m (the default tolerance) on an O(1) system whose solution is O(0.1)
    np.testing.assert_allclose(x, SuperLUSolver().solve(large, large.full_rhs()), atol=1e-9)
    assert auto.fallbacks == 0 and len(auto.iterative.iterations) == 1


def test_constrained_systems_keep_the_direct_path():
    system = _chain(30)
    rng = np.random.default_rng(1)
    system.add_point_constraints(np.array([3]), rng.normal(size=(1, 2, 6)), np.array([7]),
                                 rng.normal(size=(1, 2, 6)), np.zeros((1, 2)))
    solver = ConjugateGradientSolver("amg")
    x = solver.solve(system, system.full_rhs())
    np.testing.assert_allclose(system.saddle_dense() @ x, system.full_rhs(), atol=1e-10)  # LU round-off
    assert solver.iterations == []


def _indefinite(n_blocks: int) -> BlockSystem:
    system = _chain(n_blocks)
    system.diag[5] = -system.diag[5]  # one block with negative stiffness: symmetric, not definite
    return system


@pytest.mark.parametrize("preconditioner", ["amg", "jacobi"])
def test_a_matrix_that_is_not_positive_definite_is_a_clear_error(preconditioner):
    system = _indefinite(50)
    with pytest.raises(SolverError, match="not positive definite"):
        ConjugateGradientSolver(preconditioner).solve(system, system.full_rhs())


def test_a_diverging_cg_is_a_clear_error_and_auto_falls_back_to_the_direct_solve(monkeypatch):
    monkeypatch.setattr(ConjugateGradientSolver, "MAX_ITERATIONS", 1)
    system = _chain(ITERATIVE_LIMIT + 1, coupling=1.0)
    with pytest.raises(SolverError, match="did not reach the displacement tolerance"):
        ConjugateGradientSolver("jacobi").solve(system, system.full_rhs())
    auto = AutoSolver()
    auto.direct = SuperLUSolver()  # the fallback of every installation (pardiso, cholmod when installed)
    x = auto.solve(system, system.full_rhs())
    assert auto.fallbacks == 1
    np.testing.assert_array_equal(x, SuperLUSolver().solve(system, system.full_rhs()))


def test_a_hierarchy_that_no_longer_serves_is_rebuilt_within_the_solve():
    solver = ConjugateGradientSolver("amg", 1e-10)
    system = _wall_system()
    solver.solve(system, system.full_rhs())
    solver.solve(system, 1.5 * system.full_rhs())
    assert solver.setups == 1  # the same matrix: the hierarchy serves (converged within REBUILD_ITERATIONS)
    # contacts 50 times stiffer: the old hierarchy takes more than REBUILD_ITERATIONS = 40 (62 measured),
    # so a new one is built from this matrix within the solve, which goes on from where it stopped
    stiffer = _wall_system(stiffness_factor=50.0)
    x = solver.solve(stiffer, stiffer.full_rhs())
    assert solver.setups == 2 and solver.iterations[-1] > ConjugateGradientSolver.REBUILD_ITERATIONS
    exact = SuperLUSolver().solve(stiffer, stiffer.full_rhs())
    assert np.max(np.abs(x - exact)) <= 1e-10


def test_the_tolerance_setting_is_checked_and_takes_units():
    from pydantic import ValidationError

    from srdda import RunSettings

    assert RunSettings(dt=1e-3, n_steps=1, solver_tolerance="2 mm").solver_tolerance == pytest.approx(2e-3)
    with pytest.raises(ValidationError, match="solver_tolerance"):
        RunSettings(dt=1e-3, n_steps=1, solver_tolerance=0.0)
    with pytest.raises(ValueError, match="tolerance must be positive"):
        get_solver("cg-amg", -1.0)


@pytest.mark.parametrize("preconditioner", ["amg", "jacobi"])
def test_3d_blocks_of_twelve_unknowns(preconditioner):
    rng = np.random.default_rng(3)
    n_blocks = 200
    a = rng.normal(size=(n_blocks, 12, 12))
    system = BlockSystem(np.einsum("nij,nkj->nik", a, a) + 12 * np.eye(12), rng.normal(size=(n_blocks, 12)))
    i = np.arange(n_blocks - 1)
    system.add_off_diagonal(i, i + 1, 0.5 * rng.normal(size=(n_blocks - 1, 12, 12)))
    x = ConjugateGradientSolver(preconditioner, 1e-10).solve(system, system.full_rhs())
    exact = SuperLUSolver().solve(system, system.full_rhs())
    assert np.max(np.abs(x - exact)) <= 1e-10  # the tolerance asked for


@pytest.mark.parametrize("ndof", [6, 12])
def test_compiled_block_jacobi_cg_is_the_array_cg(ndof):
    # block_jacobi_pcg runs pcg's iteration as one compiled parallel loop: the same iterations, stopping
    # rule and Ritz value; its sums run in another order, so the iterates agree to round-off (1e-12 of
    # the solution here, measured 1e-16), not bit for bit
    from srdda.solvers import BlockJacobi, block_jacobi_pcg, pcg
    from srdda.solvers._iterative import _bsr_product
    system = _chain(300, coupling=0.4, seed=ndof) if ndof == 6 else _chain12(300)
    matrix, rhs = system.to_bsr(), system.full_rhs()
    product = np.empty_like(rhs)
    _bsr_product(matrix.indptr, matrix.indices, matrix.data, rhs, product, (0.0,) * ndof)
    np.testing.assert_allclose(product, matrix @ rhs, rtol=0, atol=1e-13 * np.abs(matrix @ rhs).max())
    jacobi = BlockJacobi(system.diag)
    for x0, ritz in ((np.zeros_like(rhs), np.inf), (0.9 * SuperLUSolver().solve(system, rhs), 0.05)):
        array = pcg(matrix.__matmul__, jacobi, rhs, x0, 1e-10, 500, ritz)
        compiled = block_jacobi_pcg(matrix, jacobi, rhs, x0, 1e-10, 500, ritz)
        assert compiled.iterations == array.iterations > 3
        assert compiled.smallest_ritz == pytest.approx(array.smallest_ritz, rel=1e-10)
        assert np.max(np.abs(compiled.x - array.x)) <= 1e-12 * np.max(np.abs(array.x))
    # and stops where pcg stops when the iterations run out
    short = block_jacobi_pcg(matrix, jacobi, rhs, np.zeros_like(rhs), 1e-10, 2)
    assert not short.converged and short.iterations == 2


def _chain12(n_blocks: int) -> BlockSystem:
    rng = np.random.default_rng(5)
    a = rng.normal(size=(n_blocks, 12, 12))
    system = BlockSystem(np.einsum("nij,nkj->nik", a, a) + 12 * np.eye(12), rng.normal(size=(n_blocks, 12)))
    i = np.arange(n_blocks - 1)
    system.add_off_diagonal(i, i + 1, 0.5 * rng.normal(size=(n_blocks - 1, 12, 12)))
    return system


def test_a_run_holds_blas_to_one_thread_while_it_steps():
    # the compiled CG's threads need the cores: BLAS's idle threads spin after each stacked product
    from threadpoolctl import threadpool_info

    from srdda.simulation import run

    def blas_threads() -> list[int]:
        return [info["num_threads"] for info in threadpool_info() if info["user_api"] == "blas"]

    seen: list[list[int]] = []

    class _Threads:
        def record(self, arrays, state, solves, energy) -> None:
            seen.append(blas_threads())

        def finish(self, status, state) -> None:
            pass

    outside = blas_threads()
    assert outside  # numpy's BLAS is found (else the limit below would do nothing unseen)
    model, settings = brick_wall(3, 2)
    run(model, dataclasses.replace(settings, n_steps=2), recorders=[_Threads()])
    assert seen[1:] == [[1] * len(outside)] * 2  # both steps (the initial record is made before stepping)
    assert blas_threads() == outside  # and given back after the run


@pytest.mark.parametrize("ndof", [6, 12])
def test_block_jacobi_inverts_each_block_by_cholesky(ndof):
    from srdda.solvers import BlockJacobi, IterativeSolverError
    rng = np.random.default_rng(ndof)
    a = rng.normal(size=(400, ndof, ndof))
    diag = a @ np.swapaxes(a, 1, 2) + 0.1 * np.eye(ndof)  # condition numbers up to about 1e4
    inverse = BlockJacobi(diag).inverse
    assert np.array_equal(inverse, np.swapaxes(inverse, 1, 2))  # L⁻ᵀL⁻¹ summed the same way both sides
    # LAPACK's inverse by another route: equal to round-off times the condition number (measured 8e-15)
    np.testing.assert_allclose(inverse, np.linalg.inv(diag), rtol=0, atol=1e-11 * np.abs(inverse).max())
    diag[[250, 31]] *= -1.0  # the first block that is not positive definite is named
    with pytest.raises(IterativeSolverError, match="diagonal block 31 "):
        BlockJacobi(diag)
