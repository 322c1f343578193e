"""Preconditioned conjugate gradient for the block system of a step (issue 14, docs/performance.md).

The step's matrix without constraint rows is symmetric positive definite (a
block-diagonal inertia term plus positive semi-definite stiffness and
penalty terms), so the conjugate gradient applies. Everything here works on
whole arrays through three callables, ``matvec``, ``precondition`` and the
array methods ``@``, ``abs``, ``max``, ``copy``: a GPU backend passes CuPy
arrays and a CuPy sparse matrix and reuses :func:`pcg` as it is. On numpy
arrays :class:`BlockJacobi` runs as compiled loops and fuses an iteration's
vector updates (``advance``); the arithmetic is the same.

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
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numba import njit

__all__ = ["PCGResult", "IterativeSolverError", "pcg", "smallest_eigenvalue_estimate", "BlockJacobi",
           "SmoothedAggregation", "block_modes"]

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


def _smallest_ritz(alphas: list[float], betas: list[float]) -> float:
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


def pcg(matvec: Callable[[Array], Array], precondition: Callable[[Array], Array], b: Array, x0: Array,
        tolerance: float, max_iterations: int, ritz_bound: float = np.inf) -> PCGResult:
    """Solve A·x = b by the preconditioned conjugate gradient from ``x0``, to the displacement ``tolerance``.

    ``ritz_bound``: an estimate of λ_min(M⁻¹A) known before this solve
    (module doc); ``inf`` when none. Raises :class:`IterativeSolverError`
    when p·A·p ≤ 0 (the matrix or the preconditioner is not positive
    definite); returns ``converged=False`` after ``max_iterations``. A
    preconditioner with an ``advance(x, r, z, p, q, α)`` method (numpy arrays
    only) makes the updates x += αp, r -= αq, z = M⁻¹r in one pass and returns
    (r·z, max|z|).
    """
    x = x0.copy()
    r = b - matvec(x)
    z = precondition(r)
    rz = float(r @ z)
    error = float(abs(z).max())
    # a preconditioner may fuse the vector updates of an iteration into one pass (BlockJacobi.advance)
    advance = getattr(precondition, "advance", None) if isinstance(b, np.ndarray) else None
    alphas: list[float] = []
    betas: list[float] = [0.0]
    theta = ritz_bound
    p = z.copy()
    for k in range(max_iterations + 1):
        if not np.isfinite(rz):
            raise IterativeSolverError(f"the conjugate gradient produced non-finite values at iteration {k}")
        if rz < 0.0:
            raise IterativeSolverError("the preconditioner is not positive definite (r·M⁻¹r < 0)")
        if error == 0.0:
            return PCGResult(x, k, 0.0, theta)
        if alphas and error <= tolerance * theta:  # θ only decreases: test the cheap bound first
            theta = min(theta, _smallest_ritz(alphas, betas))
        if np.isfinite(theta) and error <= tolerance * theta:
            return PCGResult(x, k, error, theta)
        if k == max_iterations:
            break
        q = matvec(p)
        pq = float(p @ q)
        if not pq > 0.0:
            raise IterativeSolverError(f"the matrix is not positive definite (p·A·p = {pq:.3g} at iteration {k}): "
                                       "the conjugate gradient needs a symmetric positive definite system")
        alpha = rz / pq
        if advance is not None:
            rz_next, error = advance(x, r, z, p, q, alpha)
        else:
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


@njit(cache=True)
def _advance(inverse: np.ndarray, x: np.ndarray, r: np.ndarray, z: np.ndarray, p: np.ndarray, q: np.ndarray,
             alpha: float) -> tuple[float, float]:
    """One CG update in one pass: x += αp, r -= αq, z = M⁻¹r (block-Jacobi); returns r·z and max|z|."""
    n, ndof, _ = inverse.shape
    rz = 0.0
    largest = 0.0
    for i in range(n):
        base = i * ndof
        for a in range(ndof):
            x[base + a] += alpha * p[base + a]
            r[base + a] -= alpha * q[base + a]
        for a in range(ndof):
            acc = 0.0
            for c in range(ndof):
                acc += inverse[i, a, c] * r[base + c]
            z[base + a] = acc
            rz += r[base + a] * acc
            largest = max(largest, abs(acc))
    return rz, largest


class BlockJacobi:
    """M = the block diagonal of A (ndof×ndof blocks): its inverse applied to all blocks at once.

    On numpy arrays the product is one compiled loop (a third of the batched
    matmul's time on 10,000 blocks, measured in docs/performance.md); other
    arrays (CuPy) take the batched product.
    """

    def __init__(self, diag: np.ndarray) -> None:
        try:
            np.linalg.cholesky(diag)  # a principal sub-matrix of an SPD matrix is SPD
        except np.linalg.LinAlgError as exc:
            raise IterativeSolverError("a diagonal block of the matrix is not positive definite: "
                                       "the conjugate gradient needs a symmetric positive definite system") from exc
        self.inverse = np.linalg.inv(diag)
        self.ndof = diag.shape[1]

    def __call__(self, r: Array) -> Array:
        if isinstance(r, np.ndarray):
            return _block_products(self.inverse, r)
        return (self.inverse @ r.reshape(-1, self.ndof, 1)).reshape(-1)

    def advance(self, x: np.ndarray, r: np.ndarray, z: np.ndarray, p: np.ndarray, q: np.ndarray,
                alpha: float) -> tuple[float, float]:
        """x += αp, r -= αq and z = M⁻¹r in place, in one compiled pass; returns (r·z, max|z|).

        What :func:`pcg` does with whole-array operations, fused: on the
        1,000-block slope the eight array operations of an iteration cost as
        much as the matrix product (docs/performance.md).
        """
        return _advance(self.inverse, x, r, z, p, q, alpha)


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
