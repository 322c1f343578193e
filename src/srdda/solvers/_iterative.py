"""Preconditioned conjugate gradient for the block system of a step (issue 14, docs/performance.md).

The step's matrix without constraint rows is symmetric positive definite (a
block-diagonal inertia term plus positive semi-definite stiffness and
penalty terms), so the conjugate gradient applies. Everything here works on
whole arrays through three callables, ``matvec``, ``precondition`` and the
array methods ``@``, ``abs``, ``max``, ``copy``: a GPU backend passes CuPy
arrays and a CuPy sparse matrix and reuses :func:`pcg` as it is. On numpy
arrays :func:`block_jacobi_pcg` runs the same iteration with block-Jacobi as
one compiled loop on all cores; the arithmetic is the same, summed in
another order.

**Stopping rule** (the displacement tolerance δ, m). With the residual
r = b - A·x and the preconditioned residual z = M⁻¹·r, the error e = x* - x
solves (M⁻¹A)·e = z. In the norm of M the operator M⁻¹A is self-adjoint with
eigenvalues in [λ_min, λ_max], so ‖e‖_M ≤ ‖z‖_M / λ_min: z is the error as the
preconditioner sees it, and 1/λ_min is how much the slowest mode of the whole
system amplifies it. The iteration stops when

    max_i |z_i| / θ ≤ δ,

where θ is the smallest Ritz value of the Lanczos matrix that the conjugate
gradient's own coefficients build (Saad, *Iterative Methods for Sparse Linear
Systems*, 2nd ed., §6.7.3): θ ≥ λ_min and decreases towards it as the
iteration goes on, and no larger than the estimate given by the caller (from
earlier solves, or from :func:`smallest_eigenvalue_estimate` when a
preconditioner is built), so that a short warm-started solve, whose Krylov
space has not met the slowest modes, does not trust its own θ. The rule
applies the M-norm bound to the largest unknown (the norm that a user reads,
in metres): it is an estimate, not a bound, so tests/test_solvers_iterative.py
checks it against the direct solve on every solve of brick-wall steps with
contacts 20 and 1,000 times stiffer than the inertia term.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numba import njit, prange

from ._registry import DEFAULT_TOLERANCE, SolverError, best_direct, check_finite, register_solver

if TYPE_CHECKING:
    from ..assembly.system import BlockSystem

__all__ = ["ConjugateGradientSolver", "PCGResult", "IterativeSolverError", "pcg", "block_jacobi_pcg",
           "smallest_eigenvalue_estimate", "BlockJacobi", "SmoothedAggregation", "block_modes"]

Array = Any  # numpy.ndarray, or cupy.ndarray for a GPU backend


class IterativeSolverError(RuntimeError):
    """The conjugate gradient cannot solve this system (not positive definite, or no convergence)."""


@dataclass(frozen=True)
class PCGResult:
    """The solution, the iterations it took, max|z| of the solution and θ (≥ λ_min(M⁻¹A)).

    The error estimate of the solution is ``final_residual / smallest_ritz`` (m).
    """

    x: Array
    iterations: int
    final_residual: float  # max|z| of the solution
    smallest_ritz: float
    converged: bool = True  # False: ``max_iterations`` reached first


def _smallest_ritz(alphas: list[float] | np.ndarray, betas: list[float] | np.ndarray) -> float:
    """The smallest eigenvalue of the Lanczos matrix of a PCG run (Saad §6.7.3).

    ``alphas[j]`` are the step lengths, ``betas[j]`` (j ≥ 1) the ratios
    (r_j·z_j)/(r_{j-1}·z_{j-1}) of the same run.
    """
    a = np.asarray(alphas)
    b = np.asarray(betas[1: len(alphas)])
    diag = 1.0 / a
    diag[1:] += b / a[:-1]
    off = np.sqrt(b) / a[:-1]
    if len(a) == 1:
        return float(diag[0])
    return float(sla.eigvalsh_tridiagonal(diag, off, select="i", select_range=(0, 0))[0])


def _converged(rz: float, error: float, tolerance: float, theta: float, k: int,
               ritz: Callable[[], float]) -> tuple[bool, float]:
    """The test at the top of CG iteration k: (converged, θ); raises on a non-finite or negative r·z.

    ``error`` is max|z|; ``ritz()`` the smallest Ritz value of the run so far,
    computed only when the cheap bound with the current θ is met (θ only
    decreases).
    """
    if not np.isfinite(rz):
        raise IterativeSolverError(f"the conjugate gradient produced non-finite values at iteration {k}")
    if rz < 0.0:
        raise IterativeSolverError("the preconditioner is not positive definite (r·M⁻¹r < 0)")
    if error == 0.0:
        return True, theta
    if k and error <= tolerance * theta:
        theta = min(theta, ritz())
    return bool(np.isfinite(theta) and error <= tolerance * theta), theta


def pcg(matvec: Callable[[Array], Array], precondition: Callable[[Array], Array], b: Array, x0: Array,
        tolerance: float, max_iterations: int, ritz_bound: float = np.inf) -> PCGResult:
    """Solve A·x = b by the preconditioned conjugate gradient from ``x0``, to the displacement ``tolerance``.

    ``ritz_bound``: an estimate of λ_min(M⁻¹A) known before this solve
    (module doc); ``inf`` when none. Raises :class:`IterativeSolverError`
    when p·A·p ≤ 0 (the matrix or the preconditioner is not positive
    definite); returns ``converged=False`` after ``max_iterations``.
    """
    x = x0.copy()
    r = b - matvec(x)
    z = precondition(r)
    rz = float(r @ z)
    error = float(abs(z).max())
    alphas: list[float] = []
    betas: list[float] = [0.0]
    theta = ritz_bound
    p = z.copy()
    for k in range(max_iterations + 1):
        done, theta = _converged(rz, error, tolerance, theta, k, lambda: _smallest_ritz(alphas, betas))
        if done:
            return PCGResult(x, k, error, theta)
        if k == max_iterations:
            break
        q = matvec(p)
        pq = float(p @ q)
        if not pq > 0.0:
            raise IterativeSolverError(f"the matrix is not positive definite (p·A·p = {pq:.3g} at iteration {k}): "
                                       "the conjugate gradient needs a symmetric positive definite system")
        alpha = rz / pq
        x += alpha * p
        r -= alpha * q
        z = precondition(r)
        rz_next = float(r @ z)
        error = float(abs(z).max())
        beta = rz_next / rz
        alphas.append(alpha)
        betas.append(beta)
        rz = rz_next
        p *= beta
        p += z
    return PCGResult(x, max_iterations, error, min(theta, _smallest_ritz(alphas, betas)) if alphas else theta,
                     converged=False)


def smallest_eigenvalue_estimate(matvec: Callable[[Array], Array], precondition: Callable[[Array], Array],
                                 start: Array, iterations: int) -> float:
    """λ_min(M⁻¹A) estimated by ``iterations`` Lanczos steps (through PCG) from the vector ``start``.

    A random start holds every eigenvector, so the smallest Ritz value
    approaches λ_min from above within a few tens of steps when M is a good
    preconditioner (measured in docs/performance.md).
    """
    return pcg(matvec, precondition, matvec(start), 0.0 * start, 0.0, iterations).smallest_ritz


@njit(cache=True)
def _block_products(inverse: np.ndarray, r: np.ndarray) -> np.ndarray:
    """``(inverse @ r.reshape(-1, ndof, 1)).reshape(-1)`` in one compiled pass (no batched-matmul set-up)."""
    n, ndof, _ = inverse.shape
    out = np.empty(n * ndof)
    for i in range(n):
        for a in range(ndof):
            acc = 0.0
            for b in range(ndof):
                acc += inverse[i, a, b] * r[i * ndof + b]
            out[i * ndof + a] = acc
    return out


@njit(parallel=True, cache=True)
def _bsr_product(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, x: np.ndarray, y: np.ndarray,
                 width: tuple[float, ...]) -> None:
    """y = A·x for a BSR matrix of square blocks of ``len(width)`` rows, a block row per thread.

    The block size is the length of the tuple ``width`` so that it is known when compiling: the
    loops over a block unroll and the row sums stay in registers (2.6 times scipy's BSR product on
    two threads, 1.3 times on one, docs/performance.md). No two threads write the same entry.
    """
    size = len(width)
    for i in prange(len(indptr) - 1):
        acc = np.zeros(size)
        for k in range(indptr[i], indptr[i + 1]):
            j = indices[k] * size
            for a in range(size):
                s = 0.0
                for c in range(size):
                    s += data[k, a, c] * x[j + c]
                acc[a] += s
        for a in range(size):
            y[i * size + a] = acc[a]


@njit(parallel=True, cache=True)
def _pcg_iterations(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, inverse: np.ndarray, x: np.ndarray,
                    r: np.ndarray, z: np.ndarray, p: np.ndarray, q: np.ndarray, k: int, rz: float, error: float,
                    threshold: float, max_iterations: int, alphas: np.ndarray, betas: np.ndarray,
                    width: tuple[float, ...]) -> tuple[int, float, float, float]:
    """Block-Jacobi CG iterations from iteration ``k`` until max|z| ≤ ``threshold``, ``max_iterations`` or a failure.

    The same arithmetic as :func:`pcg` (q = A·p, α = r·z / p·q, x += αp,
    r -= αq, z = M⁻¹r, β, p = z + βp), each pass parallel over block rows;
    records α and β for the Ritz value. Returns (k, r·z, max|z|, p·q): p·q ≤ 0
    or a non-finite or negative r·z stops it for the caller to report.
    """
    size = len(width)
    n = len(indptr) - 1
    pq = 1.0
    while k < max_iterations:
        _bsr_product(indptr, indices, data, p, q, width)
        pq = 0.0
        for i in prange(len(p)):
            pq += p[i] * q[i]
        if not pq > 0.0:
            break
        alpha = rz / pq
        rz_next = 0.0
        largest = 0.0
        for i in prange(n):
            base = i * size
            for a in range(size):
                x[base + a] += alpha * p[base + a]
                r[base + a] -= alpha * q[base + a]
            for a in range(size):
                s = 0.0
                for c in range(size):
                    s += inverse[i, a, c] * r[base + c]
                z[base + a] = s
                rz_next += r[base + a] * s
                largest = max(largest, abs(s))
        beta = rz_next / rz
        alphas[k] = alpha
        betas[k + 1] = beta
        k += 1
        rz = rz_next
        error = largest
        for i in prange(len(p)):
            p[i] = z[i] + beta * p[i]
        if not (np.isfinite(rz) and rz >= 0.0) or error <= threshold:
            break
    return k, rz, error, pq


def block_jacobi_pcg(matrix: sp.bsr_matrix, preconditioner: BlockJacobi, b: np.ndarray, x0: np.ndarray,
                     tolerance: float, max_iterations: int, ritz_bound: float = np.inf) -> PCGResult:
    """:func:`pcg` with block-Jacobi on a numpy BSR matrix, its iterations one compiled parallel loop.

    The same iteration, stopping rule and errors as :func:`pcg` (the sums
    are in another order, so the iterates agree to round-off, not bit for
    bit); Python only computes the Ritz value when the cheap bound is met.
    """
    width = (0.0,) * matrix.blocksize[0]
    indptr, indices, data = matrix.indptr, matrix.indices, matrix.data
    x = np.array(x0, dtype=float)
    r = np.empty_like(x)
    _bsr_product(indptr, indices, data, x, r, width)
    r = b - r
    z = preconditioner(r)
    rz = float(r @ z)
    error = float(np.abs(z).max()) if len(z) else 0.0
    p, q = z.copy(), np.empty_like(x)
    alphas, betas = np.empty(max_iterations), np.zeros(max_iterations + 1)
    theta, k = ritz_bound, 0
    while True:
        done, theta = _converged(rz, error, tolerance, theta, k, lambda: _smallest_ritz(alphas[:k], betas))
        if done:
            return PCGResult(x, k, error, theta)
        if k == max_iterations:
            break
        k, rz, error, pq = _pcg_iterations(indptr, indices, data, preconditioner.inverse, x, r, z, p, q, k, rz,
                                           error, tolerance * theta, max_iterations, alphas, betas, width)
        if not pq > 0.0:
            raise IterativeSolverError(f"the matrix is not positive definite (p·A·p = {pq:.3g} at iteration {k}): "
                                       "the conjugate gradient needs a symmetric positive definite system")
    return PCGResult(x, max_iterations, error, min(theta, _smallest_ritz(alphas[:k], betas)) if k else theta,
                     converged=False)


@njit(parallel=True, cache=True)
def _spd_inverses(diag: np.ndarray, out: np.ndarray, width: tuple[float, ...]) -> int:
    """``out[b]`` = diag[b]⁻¹ by Cholesky: diag[b] = L·Lᵀ, inverse L⁻ᵀ·L⁻¹ (exactly symmetric).

    A block per thread.

    Reads the lower triangles. Returns the first block that is not positive
    definite (a pivot ≤ 0 or not a number, as LAPACK's potrf), or the number
    of blocks when all are. 24 times numpy's cholesky and inv on 10,000 6×6
    blocks (docs/performance.md).
    """
    size = len(width)
    failed = diag.shape[0]
    for b in prange(diag.shape[0]):
        low = np.zeros((size, size))
        inv = np.zeros((size, size))
        ok = True
        for j in range(size):
            s = diag[b, j, j]
            for k in range(j):
                s -= low[j, k] * low[j, k]
            if not s > 0.0:
                ok = False
                break
            low[j, j] = np.sqrt(s)
            for i in range(j + 1, size):
                t = diag[b, i, j]
                for k in range(j):
                    t -= low[i, k] * low[j, k]
                low[i, j] = t / low[j, j]
        if not ok:
            failed = min(failed, b)
            continue
        for j in range(size):  # L⁻¹, column by column
            inv[j, j] = 1.0 / low[j, j]
            for i in range(j + 1, size):
                t = 0.0
                for k in range(j, i):
                    t -= low[i, k] * inv[k, j]
                inv[i, j] = t / low[i, i]
        for a in range(size):
            for c in range(a + 1):
                t = 0.0
                for k in range(a, size):
                    t += inv[k, a] * inv[k, c]
                out[b, a, c] = t
                out[b, c, a] = t
    return failed


def not_positive_definite_block(block: int) -> IterativeSolverError:
    """The error of block-Jacobi (on the CPU or a device) whose diagonal block ``block`` is not positive definite."""
    return IterativeSolverError(f"diagonal block {block} of the matrix is not positive definite: "
                                "the conjugate gradient needs a symmetric positive definite system")


class BlockJacobi:
    """M = the block diagonal of A (ndof×ndof blocks): its inverse applied to all blocks at once.

    On numpy arrays the product is one compiled loop (a third of the batched
    matmul's time on 10,000 blocks, measured in docs/performance.md); other
    arrays (CuPy) take the batched product.
    """

    def __init__(self, diag: np.ndarray) -> None:
        self.ndof = diag.shape[1]
        self.inverse = np.empty_like(diag, dtype=np.float64)
        # a principal sub-matrix of an SPD matrix is SPD: a block that is not shows the matrix is not
        failed = _spd_inverses(np.ascontiguousarray(diag, dtype=np.float64), self.inverse, (0.0,) * self.ndof)
        if failed < len(diag):
            raise not_positive_definite_block(failed)

    def __call__(self, r: Array) -> Array:
        if isinstance(r, np.ndarray):
            return _block_products(self.inverse, r)
        return (self.inverse @ r.reshape(-1, self.ndof, 1)).reshape(-1)


def block_modes(n_blocks: int, ndof: int) -> np.ndarray:
    """The near-null space given to the aggregation: one column per unknown of a block, constant over blocks.

    A smooth error is nearly the same motion (translation, rotation, strain)
    of neighbouring blocks; each aggregate of blocks gets these ndof coarse
    unknowns, so the coarse levels keep the block structure.
    """
    return np.tile(np.eye(ndof), (n_blocks, 1))


class SmoothedAggregation:
    """M⁻¹ = one V-cycle of pyamg's smoothed-aggregation multigrid on the block-sparse matrix.

    Symmetric block Gauss-Seidel sweeps before and after the coarse correction
    keep the cycle symmetric positive definite, as the conjugate gradient needs.
    """

    def __init__(self, matrix: sp.bsr_matrix) -> None:
        import pyamg

        ndof = matrix.blocksize[0]
        self.hierarchy = pyamg.smoothed_aggregation_solver(matrix, B=block_modes(matrix.shape[0] // ndof, ndof),
                                                           symmetry="hermitian")
        self._cycle = self.hierarchy.aspreconditioner(cycle="V")

    def __call__(self, r: Array) -> Array:
        return self._cycle.matvec(r)


class ConjugateGradientSolver:
    """Preconditioned conjugate gradient to a displacement tolerance (module doc).

    ``preconditioner`` is ``"amg"`` (pyamg's smoothed aggregation) or
    ``"jacobi"`` (the inverse block diagonal, rebuilt for every matrix: one
    batched ndof×ndof inverse). Each solve starts from the previous solution
    (the open-close iteration changes a few contacts; successive steps move
    alike).

    A multigrid hierarchy is built from one matrix and kept while it serves:
    a solve that has not converged after ``REBUILD_ITERATIONS`` builds a new
    one from its own matrix and goes on from where it stopped (contacts that
    open or close can leave a block held by inertia alone, which the old
    aggregates do not represent; a fresh hierarchy solves these systems from
    zero in 10-25 iterations). The stopping rule's estimate of λ_min(M⁻¹A):
    for a new hierarchy, ``PROBE_ITERATIONS`` Lanczos steps from a random
    vector, halved (they overestimate it by up to 20 % on the walls and slopes
    measured), then the smallest Ritz value of the solves made with it; for
    block-Jacobi, the smallest of all solves (the first one starts from zero).
    Systems with constraint rows (saddle points, not definite) go to the best
    installed direct backend.
    """

    MAX_ITERATIONS = 5000
    REBUILD_ITERATIONS = 40
    PROBE_ITERATIONS = 20

    def __init__(self, preconditioner: str, tolerance: float = DEFAULT_TOLERANCE) -> None:
        if preconditioner not in ("amg", "jacobi"):
            raise ValueError(f"unknown preconditioner {preconditioner!r}; choose 'amg' or 'jacobi'")
        if not tolerance > 0:
            raise ValueError(f"the displacement tolerance must be positive, got {tolerance}")
        self.name = f"cg-{preconditioner}"
        self.preconditioner = preconditioner
        self.tolerance = tolerance
        self.direct = best_direct()
        self.iterations: list[int] = []  # per solve (benchmarks and tests read them)
        self.setups = 0  # preconditioners built
        self._x: np.ndarray | None = None
        self._amg: SmoothedAggregation | None = None
        self._ritz = np.inf

    def _build_hierarchy(self, matrix: sp.bsr_matrix) -> SmoothedAggregation:
        self._amg = SmoothedAggregation(matrix)
        self.setups += 1
        start = np.random.default_rng(0).standard_normal(matrix.shape[0])  # seeded: runs stay reproducible
        self._ritz = 0.5 * smallest_eigenvalue_estimate(matrix.__matmul__, self._amg, start, self.PROBE_ITERATIONS)
        return self._amg

    def _pcg(self, system: BlockSystem, matrix: sp.bsr_matrix, rhs: np.ndarray, x0: np.ndarray,
             tolerance: float) -> PCGResult:
        if self.preconditioner == "jacobi":
            self.setups += 1
            return block_jacobi_pcg(matrix, BlockJacobi(system.diag), rhs, x0, tolerance, self.MAX_ITERATIONS,
                                    self._ritz)
        if self._amg is not None and self._amg.hierarchy.levels[0].A.shape == matrix.shape:
            first = pcg(matrix.__matmul__, self._amg, rhs, x0, tolerance, self.REBUILD_ITERATIONS, self._ritz)
            if first.converged:
                return first
            x0 = first.x
        else:
            first = None
        hierarchy = self._build_hierarchy(matrix)  # sets the estimate self._ritz
        second = pcg(matrix.__matmul__, hierarchy, rhs, x0, tolerance, self.MAX_ITERATIONS, self._ritz)
        return second if first is None else replace(second, iterations=first.iterations + second.iterations)

    def inexact(self, system: BlockSystem) -> bool:
        return not system.n_constraints  # constrained systems go to the direct backend

    def _matrix(self, system: BlockSystem) -> sp.bsr_matrix:
        """The matrix that :meth:`_pcg` is given: the whole assembled one."""
        return system.to_bsr()

    def solve(self, system: BlockSystem, rhs: np.ndarray, tolerance: float | None = None) -> np.ndarray:
        if system.n_constraints:
            return self.direct.solve(system, rhs)
        tolerance = self.tolerance if tolerance is None else tolerance
        matrix = self._matrix(system)
        if self._x is None or len(self._x) != len(rhs):
            if self._x is not None or self.preconditioner == "jacobi":  # another model: forget its estimate
                self._ritz = np.inf
            self._x = np.zeros_like(rhs)
        try:
            result = self._pcg(system, matrix, rhs, self._x, tolerance)
        except IterativeSolverError as exc:
            self._x = None
            raise SolverError(f"{self.name}: {exc}") from exc
        if not result.converged:
            self._x = None
            raise SolverError(f"{self.name}: the conjugate gradient did not reach the displacement tolerance "
                              f"{tolerance:.3g} m in {result.iterations} iterations (estimated error "
                              f"{result.final_residual / result.smallest_ritz:.3g} m)")
        self._ritz = result.smallest_ritz
        self.iterations.append(result.iterations)
        self._x = result.x.copy()
        return check_finite(result.x)


register_solver("cg-amg", lambda tolerance: ConjugateGradientSolver("amg", tolerance))
register_solver("cg-jacobi", lambda tolerance: ConjugateGradientSolver("jacobi", tolerance))
