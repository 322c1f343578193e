"""Cost of the saddle-point solve [[A, Cᵀ], [C, 0]]·[Δd; μ] = [F; g] for hinged block chains.

A chain of N blocks (1 × 0.2 m) hinged end to end by Lagrange multipliers
(2(N-1) + 2 constraint rows, the first block pinned), hanging under gravity.
Times: (1) one saddle-point factorisation and solve with SuperLU on the
assembled system of the first step (best of 5); (2) whole steps through
``srdda.run`` for dda0 and srdda; (3) the same chain tied by penalty point
springs instead (no constraint rows) for comparison.

Usage: python benchmarks/bench_constraints.py [--chain 1000] [--steps 50] [--json out.json]
"""
from __future__ import annotations

import argparse
import json
import platform
import time

import numpy as np

import srdda
from srdda.state import initial_state
from srdda.step import Stepper
from srdda.assembly.system import BlockSystem
from srdda.solvers import get_solver

from bench_core import bar_blocks


def hinged_chain(n: int) -> srdda.Model:
    m = bar_blocks(n)
    for i in range(1, n):
        m.add_hinge([i, 0.0], block_a=i - 1, block_b=i)
    m.add_pin([0.0, 0.0], block=0)
    return m


def spring_chain(n: int) -> srdda.Model:
    m = bar_blocks(n)
    for i in range(1, n):
        m.add_point_spring([i, 0.0], [i, 0.0], 1e10, block_a=i - 1, block_b=i)
    m.add_fixed_point([0.0, 0.0], block=0, stiffness=1e10)
    return m


def first_step_system(model: srdda.Model, dt: float = 1e-3) -> BlockSystem:
    """The assembled system of the first step (block terms and constraint rows)."""
    arrays = model.arrays()
    stepper = Stepper(arrays, srdda.RunSettings(dt=dt, n_steps=1, method="dda0", contacts=False),
                      get_solver("superlu"))
    ctx, terms = stepper.begin(initial_state(arrays, stepper.method), dt)
    return stepper.assemble(ctx, terms)


def best_of(fn, repeat: int = 5) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def per_step(model: srdda.Model, method: str, steps: int) -> float:
    arrays = model.arrays()
    settings = srdda.RunSettings(dt=1e-3, n_steps=steps, method=method, record_every=steps, contacts=False)
    srdda.run(arrays, srdda.RunSettings(dt=1e-3, n_steps=1, method=method, contacts=False))
    t0 = time.perf_counter()
    res = srdda.run(arrays, settings)
    assert res.completed, res.status
    return (time.perf_counter() - t0) / steps


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--chain", type=int, default=1000)
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    n = args.chain
    system = first_step_system(hinged_chain(n))
    solver = get_solver("superlu")
    rhs = system.full_rhs()
    x = solver.solve(system, rhs)
    C = system.constraint_matrix()
    residual = float(np.abs(C @ x[: system.size] - rhs[system.size:]).max())
    out = {
        "machine": f"{platform.machine()}, {platform.python_version()}, {platform.system()}",
        "blocks": n, "unknowns": system.size, "constraint_rows": system.n_constraints,
        "saddle_assemble_s": best_of(system.saddle_csr),
        "saddle_solve_s": best_of(lambda: solver.solve(system, rhs)),
        "constraint_residual_m": residual,
        "step_dda0_hinged_s": per_step(hinged_chain(n), "dda0", args.steps),
        "step_srdda_hinged_s": per_step(hinged_chain(n), "srdda", args.steps),
        "step_dda0_springs_s": per_step(spring_chain(n), "dda0", args.steps),
    }
    for k, v in out.items():
        print(f"{k:>24}: {v:.4g}" if isinstance(v, float) else f"{k:>24}: {v}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
