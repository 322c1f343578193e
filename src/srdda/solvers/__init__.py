"""The linear solvers of a step (``srdda.solvers``): one small interface, several backends.

``get_solver(name, tolerance)`` returns an object with ``solve(system, rhs) -> x``
(an iterative backend also takes one solve's ``tolerance`` and says where it is
``inexact``) for a :class:`~srdda.assembly.system.BlockSystem`; one instance serves one run and
keeps what the next solve can reuse (a factor, an analysis, a preconditioner,
the last solution). The public API, by group (the modules behind it are private):

Choosing a solver
-----------------
- :func:`get_solver`: the backend called ``name`` for one run (``device="cpu"`` or ``"gpu"``).
- :func:`available_solvers`: the names usable on this machine.
- :func:`register_solver`: add a backend, ``register_solver(name, factory, device=, requires=)``,
  ``factory(tolerance)`` making one solver per run; srdda's own backends are registered the same way.
- :func:`best_direct`: the fastest installed direct backend.
- :func:`blas_threads_for_steps`: the context holding BLAS to one thread while a run steps.
- ``LinearSolver`` (the interface), ``SolverFactory``, ``SolverError``, ``DEFAULT_TOLERANCE``.
- :func:`solves_inexactly`: whether a backend stops a system at a tolerance (then a Newton iteration may
  loosen it for one solve).
- :func:`takes_springs`: whether a backend applies a system's penalty springs itself, unsummed (the device's
  conjugate gradient; the step then asks the contact springs for their rows, not their sums).

Direct backends (``_direct``)
-----------------------------
- ``dense``: :class:`DenseSolver`, LAPACK (numpy) on the dense matrix; fastest for a handful of blocks.
- ``superlu``: :class:`SuperLUSolver`, scipy's SuperLU with a symmetric ordering; always available. It
  keeps its factor while the matrix is unchanged; it cannot keep an ordering
  or a symbolic analysis, so every new matrix is ordered and factorised anew.
- ``block-cholesky``: :class:`BlockCholeskySolver`, a sparse Cholesky whose entries are the system's dense
  ndof×ndof blocks (compiled, always available): the ordering (SuperLU's minimum degree on the blocks' graph)
  and the symbolic factorisation per block pattern, kept for the patterns that recur; 3-4 times faster than
  SuperLU on the jointed slopes' systems (docs/performance.md, *Direct solves in blocks*). Its results depend
  on the matrix only, not on the matrices solved before it, so a resumed run repeats the uninterrupted one.
- ``cholmod``: :class:`CholmodSolver`, CHOLMOD via scikit-sparse (``pip install srdda[cholmod]``) and
  ``pardiso``: :class:`PardisoSolver`, MKL PARDISO via pypardiso (``pip install srdda[pardiso]``):
  Cholesky of the symmetric positive definite matrix (every unconstrained DDA
  system), with the fill-reducing ordering and the symbolic analysis made once
  per block pattern and reused while the pattern of later matrices lies inside
  it: contacts that open and close change values, not the analysis.

Iterative backends (``_iterative``)
-----------------------------------
- ``cg-amg``, ``cg-jacobi``: :class:`ConjugateGradientSolver`, the preconditioned conjugate gradient
  with smoothed-aggregation multigrid (pyamg) or block-Jacobi, warm-started from the previous
  solution, stopping when every unknown of Δd is estimated within ``tolerance`` (m) of the exact solution.
- Its parts, written on whole arrays (a GPU passes CuPy arrays): :func:`pcg`, :func:`block_jacobi_pcg`,
  :func:`smallest_eigenvalue_estimate`, :class:`BlockJacobi`, :class:`SmoothedAggregation`,
  :func:`block_modes`, :class:`PCGResult`, :class:`IterativeSolverError`.

By size (``_auto``)
-------------------
- ``auto``: :class:`AutoSolver`, dense up to ``DENSE_LIMIT`` unknowns, the best installed direct
  backend (pardiso, cholmod, block-cholesky) up to ``ITERATIVE_LIMIT`` blocks, ``cg-jacobi`` above
  (falling back to the direct backend for a solve it cannot make).

On a GPU (``_gpu``)
-------------------
- ``device="gpu"`` (``cg-jacobi`` and ``auto``): :func:`gpu_solver`, the same conjugate gradient with its
  iterations on a CUDA GPU through CuPy (:class:`ArrayConjugateGradient`, :class:`BlockPatternCSR`,
  :func:`block_diagonal_csr`; the array backend is :mod:`srdda.backends`).

Backends are measured in docs/performance.md. A system with constraint rows
(``system.n_constraints > 0``) is the saddle point [[A, Cᵀ], [C, 0]]·[Δd; μ] = [F; g];
``rhs`` then has n + nc entries and the solution holds Δd followed by μ. It is
symmetric indefinite, so it is solved by LU of the augmented matrix with
pivoting: LAPACK's Bunch-Kaufman LDLᵀ (``dense``), SuperLU with partial pivoting
and a COLAMD ordering (every sparse backend: Cholesky and the conjugate gradient
need a definite matrix). See docs/constraints.md.
"""
# The order of these imports is the order of available_solvers(): each module registers its backends.
from ._registry import (DEFAULT_TOLERANCE, LinearSolver, SolverError, SolverFactory, available_solvers, best_direct,
                        get_solver, register_solver, solves_inexactly, takes_springs)
from ._direct import (BlockCholeskySolver, CholmodSolver, DenseSolver, PardisoSolver, SuperLUSolver,
                      blas_threads_for_steps)
from ._iterative import (BlockJacobi, ConjugateGradientSolver, IterativeSolverError, PCGResult, SmoothedAggregation,
                         block_jacobi_pcg, block_modes, pcg, smallest_eigenvalue_estimate)
from ._auto import DENSE_LIMIT, ITERATIVE_LIMIT, AutoSolver
from ._gpu import ArrayConjugateGradient, BlockPatternCSR, block_diagonal_csr, gpu_solver

__all__ = [
    # choosing a solver
    "get_solver", "available_solvers", "register_solver", "best_direct", "blas_threads_for_steps",
    "LinearSolver", "SolverFactory", "SolverError", "DEFAULT_TOLERANCE", "solves_inexactly", "takes_springs",
    # direct backends
    "DenseSolver", "SuperLUSolver", "BlockCholeskySolver", "CholmodSolver", "PardisoSolver",
    # iterative backends and their parts
    "ConjugateGradientSolver", "pcg", "block_jacobi_pcg", "smallest_eigenvalue_estimate", "BlockJacobi",
    "SmoothedAggregation", "block_modes", "PCGResult", "IterativeSolverError",
    # by size
    "AutoSolver", "DENSE_LIMIT", "ITERATIVE_LIMIT",
    # on a GPU
    "gpu_solver", "ArrayConjugateGradient", "BlockPatternCSR", "block_diagonal_csr",
]
