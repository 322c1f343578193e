"""Direct solves of the jointed slopes' step systems: SuperLU against the block Cholesky (docs/performance.md,
*Direct solves in blocks*).

The systems are those the contact iteration solves: ``--steps`` steps of each model are run with SuperLU
and every matrix it is given is kept (as block-sparse rows). Each is then solved by each backend:

* ``fresh``: a new solver object (ordering, symbolic analysis, factorisation, substitution);
* ``refactor``: the same pattern with other values (every block × 1.001), the analysis kept where the
  backend keeps one: what a later solve of a step costs while its contacts keep their pattern.

Times (ms) are the best of 3 repeats of each matrix's solve, from the block system (its conversion to a
sparse matrix included), and their median over the kept matrices. Where installed, QDLDL (scalar LDLᵀ,
``pip install qdldl``) and CHOLMOD through cholespy (``pip install cholespy``) are timed on the same
matrices for comparison; neither is a dependency.

Usage: python benchmarks/bench_block_cholesky.py [--model slope_a slope_b slope3d_slice] [--steps 10]
"""
from __future__ import annotations

import argparse
import importlib.util
import statistics
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from srdda.apps.bench.models import Slope3DSpec, jointed_slope_3d
from srdda.apps.bench.runner import CASES
from srdda.assembly.system import BlockSystem
from srdda.model import Model
from srdda.solvers import SuperLUSolver, get_solver
from srdda.state import initial_state
from srdda.step import Stepper, default_terms


BUILDERS = {name: case.build for name, case in CASES.items()}
# the 3D slope's 101-block slice (its 2D slope a, 4 m wide): 12×12 blocks below the conjugate gradient's 500
BUILDERS["slope3d_slice"] = lambda: jointed_slope_3d(Slope3DSpec(slope="a", width=4.0))


def kept_systems(name: str, steps: int, contact_solver: str) -> list[sp.bsr_matrix]:
    """The matrices SuperLU is given in ``steps`` steps of the model ``name`` (a bench model or the slice)."""
    model, settings = BUILDERS[name]()
    settings = replace(settings, solver="superlu", contact_solver=contact_solver)
    arrays = model.arrays() if isinstance(model, Model) else model
    kept: list[sp.bsr_matrix] = []

    class Keeping(SuperLUSolver):
        def solve(self, system: BlockSystem, rhs: np.ndarray, tolerance: float | None = None) -> np.ndarray:
            kept.append(system.to_bsr())
            return super().solve(system, rhs)

    stepper = Stepper(arrays, settings, Keeping(), default_terms(arrays, settings))
    state = initial_state(arrays, stepper.method)
    for _ in range(steps):
        outcome = stepper.step(state, settings.dt)
        state = outcome.state if outcome.state is not None else state
    return kept


def as_system(matrix: sp.bsr_matrix, scale: float = 1.0) -> BlockSystem:
    """A BlockSystem whose matrix is ``matrix`` × ``scale`` (its upper blocks as couplings)."""
    ndof = matrix.blocksize[0]
    n_blocks = matrix.shape[0] // ndof
    rows = np.repeat(np.arange(n_blocks), np.diff(matrix.indptr))
    cols = matrix.indices
    diag = np.zeros((n_blocks, ndof, ndof))
    on = rows == cols
    diag[rows[on]] = scale * matrix.data[on]
    system = BlockSystem(diag, np.ones((n_blocks, ndof)))
    upper = rows < cols
    system.add_off_diagonal(rows[upper], cols[upper], scale * matrix.data[upper])
    return system


def best_ms(action: Callable[[], object], repeats: int = 3) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        action()
        times.append(time.perf_counter() - start)
    return 1e3 * min(times)


def library_solvers() -> dict[str, Callable[[sp.csr_matrix, np.ndarray], np.ndarray]]:
    out: dict[str, Callable[[sp.csr_matrix, np.ndarray], np.ndarray]] = {}
    if importlib.util.find_spec("qdldl"):
        import qdldl

        out["qdldl (fresh)"] = lambda m, b: qdldl.Solver(sp.triu(m, format="csc")).solve(b)
    if importlib.util.find_spec("cholespy"):
        from cholespy import CholeskySolverD, MatrixType

        def cholmod(m: sp.csr_matrix, b: np.ndarray) -> np.ndarray:
            coo = m.tocoo()
            solver = CholeskySolverD(m.shape[0], coo.row.astype(np.int32), coo.col.astype(np.int32), coo.data,
                                     MatrixType.COO)
            x = np.zeros_like(b)
            solver.solve(b, x)
            return x

        out["cholmod via cholespy (fresh)"] = cholmod
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--model", nargs="+", default=["slope_a", "slope_b", "slope3d_slice"])
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--contact-solver", default="open-close")
    args = parser.parse_args()
    for name in args.model:
        matrices = kept_systems(name, args.steps, args.contact_solver)
        systems = [as_system(m) for m in matrices]
        scaled = [as_system(m, 1.001) for m in matrices]
        rows: dict[str, list[float]] = {"superlu (fresh)": [], "block-cholesky (fresh)": [],
                                        "block-cholesky (refactor)": []}
        libraries = library_solvers()
        for label in libraries:
            rows[label] = []
        backward_errors = {"superlu": 0.0, "block-cholesky": 0.0}
        for system, other in zip(systems, scaled):
            rhs = system.rhs.ravel()
            rows["superlu (fresh)"].append(best_ms(lambda: get_solver("superlu").solve(system, rhs)))
            rows["block-cholesky (fresh)"].append(best_ms(lambda: get_solver("block-cholesky").solve(system, rhs)))
            warm = get_solver("block-cholesky")
            warm.solve(other, rhs)
            rows["block-cholesky (refactor)"].append(
                best_ms(lambda: (warm.solve(system, rhs), warm.solve(other, rhs)), 2) / 2)
            for label, solve in libraries.items():  # from the block system, as the backends start
                rows[label].append(best_ms(lambda: solve(system.to_csr(), rhs)))
            matrix = system.to_csr()
            for label, backward in backward_errors.items():  # |A·x − b| / (|A|·|x|), largest entries
                x = get_solver(label).solve(system, rhs)
                error = np.max(np.abs(matrix @ x - rhs)) / (np.max(np.abs(matrix.data)) * np.max(np.abs(x)))
                backward_errors[label] = max(backward, float(error))
        m = matrices[-1]
        print(f"{name}: {len(matrices)} matrices of {m.shape[0]} unknowns ({args.contact_solver}, {args.steps} steps), "
              f"{len(m.indices)} blocks in the last; largest backward error: SuperLU "
              f"{backward_errors['superlu']:.1e}, block Cholesky {backward_errors['block-cholesky']:.1e}")
        for label, times in rows.items():
            print(f"  {label:32s} {statistics.median(times):8.3f} ms")


if __name__ == "__main__":
    main()
