"""Per-step cost of 3D blocks (12 unknowns; contacts off), per method.

* one 1 × 0.5 × 0.2 m box spinning about a tilted axis (free flight);
* a chain of N boxes 1 × 0.2 × 0.2 m end to end, tied by four point springs at each joint, the first
  pinned by a penalty spring, hanging under gravity: a banded sparse system of 12N unknowns.

Usage: python benchmarks/bench_solid.py [--chain 1000] [--steps 100] [--json out.json]
"""
from __future__ import annotations

import argparse

import numpy as np

import srdda
from bench_core import report, time_steps
from srdda.geometry.polyhedron import box


def spinning_box() -> srdda.Model:
    m = srdda.Model(gravity=(0.0, 0.0, 0.0))
    m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
    m.add_polyhedron(*box((0, 0, 0), (1.0, 0.5, 0.2)), "rock", angular_velocity=(0.5, 0.2, 3.0))
    return m


def chain_3d(n: int) -> srdda.Model:
    m = srdda.Model(gravity=(0.0, 0.0, -10.0))
    m.add_material("rock", srdda.Material(2500.0, 1e10, 0.25))
    for i in range(n):
        m.add_polyhedron(*box((i, -0.1, -0.1), (i + 1, 0.1, 0.1)), "rock")
    for i in range(1, n):
        for y in (-0.1, 0.1):
            for z in (-0.1, 0.1):
                m.add_point_spring([i, y, z], [i, y, z], 1e9, block_a=i - 1, block_b=i)
    m.add_fixed_point([0.0, 0.0, 0.0], block=0, stiffness=1e10)
    return m


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--chain", type=int, default=1000)
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    rows = [{"model": "1 box (3D)", "method": m, "ms_per_step": 1e3 * time_steps(spinning_box(), m, 1000, penalty=1e9)}
            for m in srdda.METHODS]
    chain = chain_3d(args.chain)
    rows += [{"model": f"{args.chain}-box 3D chain", "method": m,
              "ms_per_step": 1e3 * time_steps(chain, m, args.steps, penalty=1e9)} for m in srdda.METHODS]
    report(rows, args.json)


if __name__ == "__main__":
    main()
