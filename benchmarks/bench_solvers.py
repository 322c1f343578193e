"""Linear-solver backends on the systems of a brick wall's step (issue 14; figures in docs/performance.md).

For each wall size and backend, in a child process of its own (so that its
peak memory is its own), the system of the first solve of the first step is
assembled as the step does (``Stepper.begin`` and ``assemble``), then solved:

* ``first``: the first solve (ordering and analysis, factorisation or
  preconditioner set-up, and the solve; CG from zero);
* ``same``: the same matrix, a right-hand side 0.1 % away (a factor reused;
  CG warm-started);
* ``values``: every stiffness scaled by 1.001 and one coupling block in 100
  dropped, as when contacts open (a new factorisation of a pattern inside the
  analysed one; CG warm-started with the same hierarchy);
* ``step``: one whole step attempt (``Stepper.step``, its open-close
  iteration included) with a fresh backend: its solves and the seconds per
  solve;
* ``peak_mb``: the peak resident memory of the solves above the memory held
  once the system was assembled (``VmHWM`` reset through ``clear_refs``).

Usage: python benchmarks/bench_solvers.py [--blocks 1000 10000 100000] [--solvers ...] [--json out.json]
(default: 1,000 blocks, every installed backend but ``dense`` and ``auto``).
"""
from __future__ import annotations

import argparse
import json
import math
import platform
import subprocess
import sys
import time
from typing import Any

import numpy as np
import scipy

from srdda.assembly.system import BlockSystem
from srdda.apps.bench.models import brick_wall
from srdda.apps.bench.runner import peak_memory_mb
from srdda.solvers import available_solvers, get_solver
from srdda.state import initial_state
from srdda.step import Stepper


def _rss_mb() -> float:
    with open("/proc/self/status", encoding="ascii") as status:
        return next(int(line.split()[1]) / 1024.0 for line in status if line.startswith("VmRSS:"))


def _reset_peak() -> None:
    """Reset this process's VmHWM to its current resident size (Linux ≥ 4.0; no-op elsewhere)."""
    try:
        with open("/proc/self/clear_refs", "w", encoding="ascii") as refs:
            refs.write("5")
    except OSError:
        pass


def _opened(system: BlockSystem, step: int = 100) -> BlockSystem:
    """``system`` with its values scaled by 1.001 and every ``step``-th coupling block (pair) dropped."""
    keep = [np.arange(len(b)) % step != 0 for b in system.pair_blocks[::2]]
    pair_i, pair_j, blocks = [], [], []
    for k, mask in enumerate(keep):  # pairs come as (i, j) and its transpose (j, i)
        for part in (2 * k, 2 * k + 1):
            pair_i.append(system.pair_i[part][mask])
            pair_j.append(system.pair_j[part][mask])
            blocks.append(1.001 * system.pair_blocks[part][mask])
    return BlockSystem(1.001 * system.diag, system.rhs.copy(), pair_i, pair_j, blocks)


def _stats(solver: Any) -> dict[str, Any]:
    return {k: (list(v) if isinstance(v, list) else v) for k in ("iterations", "setups", "analyses", "factorizations")
            if (v := getattr(solver, k, None)) is not None}


def measure(blocks: int, name: str) -> dict[str, Any]:
    """One row: a wall of about ``blocks`` bricks solved by the backend ``name``."""
    side = round(math.sqrt(blocks))
    model, settings = brick_wall(side, side)
    arrays = model.arrays()
    stepper = Stepper(arrays, settings, get_solver("superlu"))
    state = initial_state(arrays, stepper.method)
    ctx, terms = stepper.begin(state, settings.dt)
    system = stepper.assemble(ctx, terms)
    rhs = system.full_rhs()
    row: dict[str, Any] = {"blocks": arrays.n_blocks, "unknowns": system.size, "solver": name,
                           "coupling_blocks": int(sum(len(b) for b in system.pair_blocks)),
                           "system_mb": _rss_mb()}
    solver = get_solver(name)
    _reset_peak()
    base = _rss_mb()
    reference = None
    for label, sys_, b in (("first", system, rhs), ("same", system, 1.001 * rhs), ("values", None, None)):
        if sys_ is None:
            sys_ = _opened(system)
            b = sys_.full_rhs()
        t0 = time.perf_counter()
        x = solver.solve(sys_, b)
        row[f"{label}_s"] = time.perf_counter() - t0
        if label == "first":
            reference = x
    row["peak_mb"] = peak_memory_mb() - base
    row["solution_max_m"] = float(np.max(np.abs(reference)))
    row.update(_stats(solver))
    stepper.solver = timed = _Timed(get_solver(name))
    t0 = time.perf_counter()
    outcome = stepper.step(state, settings.dt)
    row["step_s"] = time.perf_counter() - t0
    row["step_status"] = outcome.status
    row["step_solves"] = len(timed.seconds)
    row["step_s_per_solve"] = float(np.mean(timed.seconds))
    row["step_iterations"] = list(getattr(timed.inner, "iterations", []))
    return row


class _Timed:
    """A backend whose solve times are kept."""

    def __init__(self, inner: Any) -> None:
        self.inner, self.name, self.seconds = inner, inner.name, []

    def solve(self, system: BlockSystem, rhs: np.ndarray) -> np.ndarray:
        t0 = time.perf_counter()
        x = self.inner.solve(system, rhs)
        self.seconds.append(time.perf_counter() - t0)
        return x


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--blocks", type=int, nargs="+", default=[1000])
    ap.add_argument("--solvers", nargs="+", default=[s for s in available_solvers() if s not in ("dense", "auto")])
    ap.add_argument("--json", default=None)
    ap.add_argument("--child", nargs=2, metavar=("BLOCKS", "SOLVER"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(measure(int(args.child[0]), args.child[1])), flush=True)
        return
    machine = (f"{platform.machine()}, {platform.python_implementation()} {platform.python_version()}, "
               f"numpy {np.__version__}, scipy {scipy.__version__}")
    print(f"machine: {machine}")
    print(f"{'blocks':>7} {'solver':10} {'first s':>8} {'same s':>8} {'values s':>9} {'peak MB':>8} "
          f"{'step solves':>11} {'s/solve':>8}  iterations (first, same, values | step)")
    rows = []
    for blocks in args.blocks:
        for name in args.solvers:
            done = subprocess.run([sys.executable, __file__, "--child", str(blocks), name], capture_output=True,
                                  text=True)
            if done.returncode != 0:
                print(f"{blocks:>7} {name:10} failed: {done.stderr.strip().splitlines()[-1:]}", flush=True)
                continue
            r = json.loads(done.stdout.strip().splitlines()[-1])
            rows.append(r)
            counts = f"{r.get('iterations', '')} | {r['step_iterations']}" if "iterations" in r else \
                f"analyses {r.get('analyses', '-')}, factorisations {r.get('factorizations', '-')}"
            print(f"{r['blocks']:>7} {name:10} {r['first_s']:8.3f} {r['same_s']:8.3f} {r['values_s']:9.3f} "
                  f"{r['peak_mb']:8.0f} {r['step_solves']:>11} {r['step_s_per_solve']:8.3f}  {counts}", flush=True)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as out:
            json.dump({"machine": machine, "rows": rows}, out, indent=1)


if __name__ == "__main__":
    main()
