"""The step's contact problem by Newton (formulation a) and by clarabel (formulation c), side by side.

Random rows of touching blocks on a fixed base (``srdda.apps.bench.formulations.blocks_on_base``), 2D and 3D,
1, 5 and 20 blocks, ten seeds each; one step of each, the yield forces' N* held (the Tresca problem). Prints
the medians: contacts, unknowns, Newton's solves and time for the step (assembly, solves, line searches; the
dense solver), clarabel's interior-point iterations, its solve time and its time with cvxpy's compilation,
and the largest relative Π excess of Newton over clarabel (negative: Newton lower) and distance between them.

    python benchmarks/compare_contact_formulations.py [seeds]
"""
from __future__ import annotations

import platform
import sys
from itertools import groupby

import numpy as np

from srdda.apps.bench.formulations import compare


def main() -> None:
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    compare(dims=(2, 3), sizes=(1,), seeds=1)  # compile the kernels outside the timing
    rows = compare(seeds=seeds)
    print(f"# {platform.processor() or platform.machine()}, Python {platform.python_version()}, {seeds} seeds")
    print("| dim | blocks | contacts | unknowns | Newton solves | Newton ms | clarabel iterations | clarabel ms "
          "| with cvxpy ms | Π excess, max | distance, max (m) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for (dim, blocks), group in groupby(rows, key=lambda r: (r["dim"], r["blocks"])):
        g = list(group)

        def median(key: str) -> float:
            return float(np.median([r[key] for r in g]))

        print(f"| {dim}D | {blocks} | {median('contacts'):.0f} | {median('unknowns'):.0f} "
              f"| {median('newton_solves'):.1f} | {1e3 * median('newton_s'):.2f} | {median('conic_iterations'):.0f} "
              f"| {1e3 * median('conic_solve_s'):.2f} | {1e3 * median('conic_total_s'):.1f} "
              f"| {max(r['potential_gap'] for r in g):.1e} | {max(r['distance'] for r in g):.1e} |")


if __name__ == "__main__":
    main()
