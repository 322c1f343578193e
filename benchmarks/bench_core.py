"""Per-step cost of the core engine (contacts switched off), per method and solver.

* a 1-block model: the rod of paper 4.2 (pinned by a penalty spring);
* a chain of N blocks (1 × 0.2 m) tied by pairs of point springs, the first
  pinned, hanging under gravity: a banded sparse system of 6N unknowns.

Usage: python benchmarks/bench_core.py [--chain 1000] [--steps 200] [--json out.json]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import platform
import time

import numpy as np

import srdda
from srdda.solvers import available_solvers


def rod_model() -> srdda.Model:
    m = srdda.Model(gravity=(0.0, -10.0))
    m.add_material("rock", srdda.Material(2500.0, 2e16, 0.25))
    m.add_block([[0, -0.05], [10, -0.05], [10, 0.05], [0, 0.05]], "rock")
    m.add_fixed_point([0.0, 0.0], stiffness=2e16)
    return m


def bar_blocks(n: int) -> srdda.Model:
    """n bars 1 × 0.2 m end to end along x, untied (the chain benchmarks add their ties)."""
    m = srdda.Model(gravity=(0.0, -10.0))
    m.add_material("rock", srdda.Material(2500.0, 1e10, 0.25))
    for i in range(n):
        m.add_block([[i, -0.1], [i + 1, -0.1], [i + 1, 0.1], [i, 0.1]], "rock")
    return m


def chain_model(n: int) -> srdda.Model:
    m = bar_blocks(n)
    for i in range(1, n):
        for y in (-0.1, 0.1):
            m.add_point_spring([i, y], [i, y], 1e9, block_a=i - 1, block_b=i)
    m.add_fixed_point([0.0, 0.0], block=0, stiffness=1e10)
    return m


def time_steps(model: srdda.Model, method: str, steps: int, solver: str = "auto", penalty: float = 2e16) -> float:
    """Seconds per step, contacts off (best of two runs, after one warm-up step)."""
    arrays = model.arrays()
    settings = srdda.RunSettings(dt=1e-3, n_steps=steps, method=method, solver=solver, penalty=penalty,
                                 record_every=steps, contacts=False)
    srdda.run(arrays, dataclasses.replace(settings, n_steps=1))
    best = np.inf
    for _ in range(2):
        t0 = time.perf_counter()
        res = srdda.run(arrays, settings, keep_history=False)
        best = min(best, time.perf_counter() - t0)
        assert res.completed, res.status
    return best / steps


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--chain", type=int, default=1000)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    rows = []
    for method in srdda.METHODS:
        rows.append({"model": "1 block (rod)", "method": method, "solver": "auto",
                     "ms_per_step": 1e3 * time_steps(rod_model(), method, 2000, "auto")})
    chain = chain_model(args.chain)
    for solver in [s for s in available_solvers() if s not in ("dense", "auto")]:
        for method in srdda.METHODS:
            rows.append({"model": f"{args.chain}-block chain", "method": method, "solver": solver,
                         "ms_per_step": 1e3 * time_steps(chain, method, args.steps, solver)})
    report(rows, args.json)


def report(rows: list[dict], json_path: str | None) -> None:
    """Print the rows (model, method[, solver], ms per step) with the machine; write them as JSON if asked."""
    machine = f"{platform.processor() or platform.machine()}, {platform.python_implementation()} " \
              f"{platform.python_version()}, numpy {np.__version__}"
    print(f"machine: {machine}")
    for r in rows:
        print(f"{r['model']:22s} {r['method']:6s} {r.get('solver', ''):8s} {r['ms_per_step']:9.3f} ms/step")
    if json_path:
        with open(json_path, "w") as fh:
            json.dump({"machine": machine, "rows": rows}, fh, indent=1)


if __name__ == "__main__":
    main()
