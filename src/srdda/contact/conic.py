"""One step's contact problem written out as a convex program: the reference for the Newton solve.

A step with contacts minimises the incremental potential of :mod:`.newton`;
with the yield forces' N* held (the Tresca problem) it is the convex program

    min  ½ xᵀAx − Fᵀx + Σ_c [ ½k_n (g_c − z_c)² + T_c z_c + ½k_s |s_c − p_c|² + τ_c |p_c| ] / c_p,
    z ≥ 0,   g = g_0 + c_p N x,   s = s_e0 + c_p S x,   x = 0 on fixed blocks,

the penalty springs' potentials written as Moreau envelopes (z: the part of
the gap beyond the tensile strength's stretch, p: the plastic slip). A, F:
every other term of the step; N, S: the contacts' rows. In 2D it is a
quadratic program with one box per contact, in 3D a second-order cone program
(|p_c| of two components): formulation (c) of docs/contacts.md, *The contact
solve*. :meth:`StepProblem.solve_conic` hands it to clarabel through cvxpy
(both test extras: ``pip install srdda[test]``); the tests compare the Newton
solve with it, and ``benchmarks/compare_contact_formulations.py`` times both.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..assembly.system import BlockSystem
from .openclose import magnitudes
from .pipeline import ContactStep

__all__ = ["StepProblem", "step_problem"]


@dataclass(frozen=True)
class StepProblem:
    """One step's Tresca contact problem in the blocks' increments x (module doc), dense: small models."""

    matrix: np.ndarray  # A (size, size): every term of the step but the contacts
    rhs: np.ndarray  # F (size,)
    normal_rows: np.ndarray  # N (n, size): the gaps' rows n·T
    shear_rows: np.ndarray  # S (n·k, size): the shears' rows e·T, contact by contact
    gap: np.ndarray  # g_0 (n,)
    shear: np.ndarray  # s_e0 (n, k)
    normal_stiffness: np.ndarray  # k_n (n,)
    shear_stiffness: np.ndarray  # k_s (n,)
    tension: np.ndarray  # T (n,): tensile strength (N)
    yield_force: np.ndarray  # τ (n,) = tan φ·N* + c·A
    c_p: float  # the scheme's penalty weight
    held: np.ndarray  # (size,) bool: degrees of freedom of fixed blocks

    def gaps_and_shears(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """g (n,) and s (n, k) at increments ``x``."""
        n, k = self.shear.shape
        return (self.gap + self.c_p * (self.normal_rows @ x),
                (self.shear.ravel() + self.c_p * (self.shear_rows @ x)).reshape(n, k))

    def potential(self, x: np.ndarray) -> float:
        """Π at increments ``x`` (the fixed blocks' taken as zero), z and p at their optimum in closed form."""
        x = np.where(self.held, 0.0, x)
        g, s = self.gaps_and_shears(x)
        kn, ks, tension, tau = self.normal_stiffness, self.shear_stiffness, self.tension, self.yield_force
        beyond = np.maximum(g - tension / kn, 0.0)
        size = magnitudes(s)
        slip = np.maximum(size - tau / ks, 0.0)
        springs = np.sum(0.5 * kn * (g - beyond) ** 2 + tension * beyond + 0.5 * ks * (size - slip) ** 2
                         + tau * slip)
        return float(0.5 * x @ self.matrix @ x - self.rhs @ x + springs / self.c_p)

    @property
    def convexity(self) -> float:
        """The smallest eigenvalue of A over the free degrees of freedom: Π is at least this convex."""
        free = np.flatnonzero(~self.held)
        return float(np.linalg.eigvalsh(self.matrix[np.ix_(free, free)]).min())

    def solve_conic(self, tolerance: float = 1e-10) -> tuple[np.ndarray, Any]:
        """The minimum by clarabel (an interior-point conic solver) through cvxpy: the increments x and
        cvxpy's problem (its ``solver_stats`` hold clarabel's iterations and time)."""
        import cvxpy as cp  # a test extra, not a dependency of runs

        n, k = self.shear.shape
        x = cp.Variable(len(self.rhs))
        z = cp.Variable(n, nonneg=True)
        plastic = cp.Variable((n, k))
        gap = self.gap + self.c_p * self.normal_rows @ x
        shear = cp.reshape(self.shear.ravel() + self.c_p * self.shear_rows @ x, (n, k), order="C")
        springs = (cp.sum(cp.multiply(self.normal_stiffness / 2, cp.square(gap - z))) + self.tension @ z
                   + cp.sum(cp.multiply(self.shear_stiffness / 2, cp.sum(cp.square(shear - plastic), axis=1)))
                   + self.yield_force @ cp.norm(plastic, 2, axis=1))
        symmetric = cp.psd_wrap(0.5 * (self.matrix + self.matrix.T))
        objective = 0.5 * cp.quad_form(x, symmetric) - self.rhs @ x + springs / self.c_p
        problem = cp.Problem(cp.Minimize(objective), [x[np.flatnonzero(self.held)] == 0])
        problem.solve(solver=cp.CLARABEL, tol_gap_abs=tolerance, tol_gap_rel=tolerance, tol_feas=tolerance)
        if problem.status != "optimal":
            raise RuntimeError(f"clarabel ended the step's contact problem {problem.status}")
        return np.asarray(x.value), problem


def step_problem(step: ContactStep, others: BlockSystem, c_p: float, yield_force: np.ndarray,
                 fixed: np.ndarray) -> StepProblem:
    """The problem of a step's contacts ``step`` (its springs made by a solve) over ``others``, the system of
    every other term; ``fixed`` (nb,) the fixed blocks."""
    springs = step._springs
    assert springs is not None, "the step's contacts have not been solved"
    r = step.record
    n, k, size, ndof = len(step), r.frame_width, others.size, others.ndof
    columns = np.arange(ndof)
    normal_rows, shear_rows = np.zeros((n, size)), np.zeros((n, k, size))
    rows = np.arange(n)[:, None]
    np.add.at(normal_rows, (rows, r.block_a[:, None] * ndof + columns), springs.normal_a)
    np.add.at(normal_rows, (rows, r.block_b[:, None] * ndof + columns), -springs.normal_b)
    np.add.at(shear_rows, (rows[:, :, None], np.arange(k)[None, :, None],
                           (r.block_a[:, None] * ndof + columns)[:, None, :]), springs.shear_a)
    np.add.at(shear_rows, (rows[:, :, None], np.arange(k)[None, :, None],
                           (r.block_b[:, None] * ndof + columns)[:, None, :]), -springs.shear_b)
    return StepProblem(others.to_dense(), others.rhs.ravel(), normal_rows, shear_rows.reshape(n * k, size),
                       r.gap, step.shear0, step.response.normal_stiffness, step.response.shear_stiffness,
                       step.response.tension, yield_force, c_p, np.repeat(fixed, ndof))
