"""Time of block cutting (Shi's DC step) on the jointed-slope benchmark models.

Reads the DDAML slope files (default: /work/shared/benchmarks/slopes, or a
directory given with --dir), cuts each with the edge-node distance of the
file (1.25 e00 w0, as DC), and reports blocks, vertices and the best of
--repeat cut times; --model also times building the srdda Model.

--synthetic S1,S2,... also cuts the benchmark slope by two generated persistent
joint sets (dips 25° and 100°) of each spacing S (m), to see how cutting scales.

Usage: python benchmarks/bench_cutting.py [--dir DIR] [--repeat 5] [--model] [--synthetic 1,0.5,0.25]
       [--json out.json]
"""
from __future__ import annotations

import argparse
import json
import platform
import time
import warnings
from pathlib import Path

import numpy as np

from srdda.geometry.cutting2d import cut_blocks
from srdda.geometry.jointsets2d import JointSet, joint_traces
from srdda.io.ddaml import read_ddaml

SLOPE = np.array([(0, -5), (60, -5), (60, 20), (35, 20), (15, 0), (0, 0)], dtype=float)


def best_time(fn, repeat: int) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


SHARED_SLOPES = Path(__file__).resolve().parents[2] / "shared" / "benchmarks" / "slopes"  # beside the repo


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dir", default=str(SHARED_SLOPES), help="folder of DDAML slope models (*.geo, *.ana)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--model", action="store_true", help="also time building the Model from the cut")
    ap.add_argument("--synthetic", default="", help="comma-separated joint spacings (m) for generated sets")
    ap.add_argument("--json", help="write the results to this file")
    args = ap.parse_args()
    if not args.synthetic and not list(Path(args.dir).glob("*.geo")):
        print(f"no slope models in {args.dir}: timing generated joint sets instead")
        args.synthetic = "2,1,0.5"
    rows = []
    for spacing in [float(v) for v in args.synthetic.split(",") if v]:
        sets = [JointSet(dip=25.0, spacing=spacing, joint_type=2), JointSet(dip=100.0, spacing=spacing, joint_type=3)]
        t0 = time.perf_counter()
        segs, types = joint_traces(SLOPE, sets, seed=0)
        t_traces = time.perf_counter() - t0
        seconds, cut = best_time(lambda: cut_blocks(segs, types, edge_node_distance=0.01 * spacing, boundary=SLOPE,
                                                    boundary_type=1), args.repeat)
        row = {"model": f"synthetic spacing {spacing:g} m", "joints": len(segs), "blocks": cut.n_blocks,
               "vertices": int(cut.block_ptr[-1]), "traces_seconds": t_traces, "cut_seconds": seconds}
        rows.append(row)
        print(", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in row.items()))
    for geo in sorted(Path(args.dir).glob("*.geo")):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            data = read_ddaml(geo, geo.with_suffix(".ana"))
            seconds, cut = best_time(data.cut, args.repeat)
            row = {"model": geo.stem, "joints": len(data.joints), "edge_node_distance": data.edge_node_distance,
                   "blocks": cut.n_blocks, "vertices": int(cut.block_ptr[-1]), "cut_seconds": seconds}
            if args.model:
                row["model_seconds"], _ = best_time(lambda: data.to_model(cut), 1)
        rows.append(row)
        print(", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in row.items()))
    info = {"python": platform.python_version(), "machine": platform.machine(), "processor": platform.processor()}
    print(info)
    if args.json:
        Path(args.json).write_text(json.dumps({"machine": info, "rows": rows}, indent=2))


if __name__ == "__main__":
    main()
