"""Cost of writing the results file: time per recorded step and bytes per step.

Runs a chain of N blocks (as in bench_core.py) with and without a
``ResultsStore``, recording every step, for a few flush intervals; also times
reading the file back and writing VTU files.

Usage: python benchmarks/bench_results.py [--blocks 1 100 1000] [--steps 200]
"""
from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

import srdda
from srdda.io.results_store import ResultsStore, read_results
from srdda.io.vtk import write_vtu_series

from bench_core import chain_model as core_chain_model


def chain_model(n: int) -> srdda.Model:
    m = core_chain_model(n)
    m.add_measured_point([n, 0.0], block=n - 1)
    return m


def best_of_two(fn) -> float:
    best = np.inf
    for _ in range(2):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--blocks", type=int, nargs="+", default=[1, 100, 1000])
    ap.add_argument("--steps", type=int, default=200)
    args = ap.parse_args()
    print(f"machine: {os.cpu_count()} cores, {platform.python_implementation()} {platform.python_version()}, "
          f"numpy {np.__version__}")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.h5"
        for n in args.blocks:
            arrays = chain_model(n).arrays()
            settings = srdda.RunSettings(dt=1e-3, n_steps=args.steps, method="srdda", contacts=False)
            plain = best_of_two(lambda: srdda.run(arrays, settings))
            for flush in (10, 100):
                stored = best_of_two(lambda: srdda.run(
                    arrays, settings, recorders=[ResultsStore(path, settings, flush_every=flush)]))
                size = path.stat().st_size / (args.steps + 1)
                print(f"{n:5d} blocks, flush every {flush:3d}: run {1e3 * plain / args.steps:7.3f} ms/step, "
                      f"with store {1e3 * stored / args.steps:7.3f} ms/step "
                      f"(+{1e3 * (stored - plain) / args.steps:6.3f}), {size / 1024:7.1f} KiB/step")
            read = best_of_two(lambda: read_results(path))
            vtu = best_of_two(lambda: write_vtu_series(path, Path(tmp) / "vtu", every=20))
            print(f"{n:5d} blocks: read_results {1e3 * read:7.1f} ms, "
                  f"VTU of {args.steps // 20 + 1} steps {1e3 * vtu:7.1f} ms")


if __name__ == "__main__":
    main()
