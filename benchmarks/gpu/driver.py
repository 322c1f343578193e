"""The measurements of issue 34 on a machine with a CUDA GPU (run by check.sh beside this file).

Each subcommand writes one JSON file and stops at its deadline (seconds since the epoch), reporting
what it could not do in the time left:

* ``systems``: the step systems of wall_10k, wall_100k and wall3d_10k (the first solves of the first
  steps, captured from a CPU run), each solved in the run's order by the CPU's compiled block-Jacobi
  CG and by the GPU's, with the time of a matrix product on each and the solutions' largest gap;
* ``compare``: 20 steps of wall_10k and slope3d_1k on the CPU, on the GPU and with the direct solver
  (SuperLU), and how far their final positions lie apart;
* ``bench``: ``python -m srdda bench --json`` of the large models on the GPU and on the CPU;
* ``wall1m``: a 1,000,000-block 2D wall, built first (one core), then stepped on the GPU once the file
  ``--go`` exists, until the deadline;
* ``profile``: where a step's time goes: ``--steps`` steps of ``--model`` on ``--device`` under cProfile (after
  one step that compiles), the functions that took the most time of their own;
* ``summary``: the short table of all of it.

``--fake-gpu`` runs the GPU path on numpy (the same array code) so that the script can be rehearsed on
a machine without a GPU; ``--small`` swaps the models for small ones for that rehearsal.
"""
from __future__ import annotations

import argparse
import copy
import json
import os
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from srdda import simulation
from srdda.assembly.system import BlockSystem
from srdda.backends import arrays as arrays_module
from srdda.solvers import _gpu as cg_module
from srdda.backends.arrays import ArrayBackend, cupy_backend, numpy_backend
from srdda.apps.bench.models import brick_wall, english_bond_wall
from srdda.apps.bench.runner import CASES, BenchCase, Probe, cg_iterations, measure
from srdda.solvers import ArrayConjugateGradient, ConjugateGradientSolver, SuperLUSolver
from srdda.solvers._iterative import _bsr_product
from srdda.state import initial_state
from srdda.step import Stepper

TOLERANCE = 1e-9  # the default solver_tolerance (m)
SMALL = {"wall_10k": lambda: brick_wall(24, 24), "wall_100k": lambda: brick_wall(40, 30),
         "wall3d_10k": lambda: english_bond_wall(6, 6), "slope3d_1k": lambda: english_bond_wall(5, 4),
         "wall_1m": lambda: brick_wall(60, 40)}


def _build(name: str, small: bool) -> tuple[Any, Any]:
    if small:
        return SMALL[name]()
    return brick_wall(1000, 1000) if name == "wall_1m" else CASES[name].build()


def _left(deadline: float) -> float:
    return deadline - time.time()


def _write(path: Path, data: Any) -> None:
    path.write_text(json.dumps(data, indent=1, default=float))
    print(f"wrote {path}", flush=True)


class _Recording:
    """The CPU's block-Jacobi CG that keeps a copy of every system it solves (the contact term may change a
    system's stacks in place after its solve)."""

    name = "recording"

    def __init__(self, limit: int) -> None:
        self.inner = ConjugateGradientSolver("jacobi", TOLERANCE)
        self.limit = limit
        self.systems: list[tuple[BlockSystem, np.ndarray]] = []

    def solve(self, system: BlockSystem, rhs: np.ndarray) -> np.ndarray:
        if len(self.systems) < self.limit:
            self.systems.append((copy.deepcopy(system), rhs.copy()))
        return self.inner.solve(system, rhs)


def _capture(model: Any, settings: Any, steps: int, limit: int) -> list[tuple[BlockSystem, np.ndarray]]:
    """The first ``limit`` systems that ``steps`` step attempts of ``model`` solve on the CPU."""
    arrays = model.arrays()
    recording = _Recording(limit)
    stepper = Stepper(arrays, settings, recording)
    state, dt = initial_state(arrays, stepper.method), settings.dt
    for _ in range(steps):
        outcome = stepper.step(state, dt)
        if outcome.status == "diverged":
            break
        state = outcome.state if outcome.status == "accepted" else state
        dt = outcome.dt_next
        if len(recording.systems) >= limit:
            break
    return recording.systems


def _median_seconds(fn: Callable[[], Any], sync: Callable[[], None], repeats: int = 20) -> float:
    times = []
    for _ in range(repeats):
        sync()
        t0 = time.perf_counter()
        fn()
        sync()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def _products(backend: ArrayBackend, system: BlockSystem) -> dict[str, float]:
    """One matrix product's time on the CPU (compiled BSR, all cores) and on the device (CSR), and the read rates."""
    bsr = system.to_bsr()
    x = np.random.default_rng(0).standard_normal(system.size)
    y = np.empty_like(x)
    width = (0.0,) * system.ndof
    cpu = _median_seconds(lambda: _bsr_product(bsr.indptr, bsr.indices, bsr.data, x, y, width), lambda: None)
    solver = ArrayConjugateGradient(backend, TOLERANCE)
    solver.solve(system, system.full_rhs())  # builds the device matrix (and compiles CuPy's kernels)
    matrix = solver._pattern.matrix
    xd = backend.to_device(x)
    gpu = _median_seconds(lambda: matrix @ xd, backend.synchronize)
    gap = float(np.abs(backend.to_host(matrix @ xd) - y).max() / max(np.abs(y).max(), 1e-300))
    bsr_bytes = bsr.data.nbytes + bsr.indices.nbytes + bsr.indptr.nbytes
    csr_bytes = matrix.data.nbytes + matrix.indices.nbytes + matrix.indptr.nbytes
    return {"stored_blocks": int(len(bsr.indices)), "matrix_mb": bsr.data.nbytes / 2**20,
            "product_ms_cpu": 1e3 * cpu, "product_ms_gpu": 1e3 * gpu, "read_gbs_cpu": bsr_bytes / cpu / 1e9,
            "read_gbs_gpu": csr_bytes / gpu / 1e9, "product_relative_gap": gap}


def systems(args: argparse.Namespace, backend: ArrayBackend) -> None:
    plan = [("wall_10k", 2, 12), ("wall_100k", 2, 10), ("wall3d_10k", 1, 8)]
    rows = []
    for name, steps, limit in plan:
        if _left(args.deadline) < 60:
            rows.append({"model": name, "note": "skipped: less than 60 s left"})
            continue
        t0 = time.perf_counter()
        model, settings = _build(name, args.small)
        captured = _capture(model, replace(settings, solver="cg-jacobi", device="cpu"), steps, limit)
        row: dict[str, Any] = {"model": name, "blocks": captured[0][0].n_blocks, "ndof": captured[0][0].ndof,
                               "systems": len(captured), "capture_s": time.perf_counter() - t0}
        row.update(_products(backend, captured[0][0]))
        cpu, gpu = ConjugateGradientSolver("jacobi", TOLERANCE), ArrayConjugateGradient(backend, TOLERANCE)
        solves = []
        for system, rhs in captured:  # the run's order: each solve warm-started from the last
            t = time.perf_counter()
            x = cpu.solve(system, rhs)
            t_cpu = time.perf_counter() - t
            t = time.perf_counter()
            y = gpu.solve(system, rhs)
            t_gpu = time.perf_counter() - t
            solves.append({"cpu_s": t_cpu, "gpu_s": t_gpu, "gap": float(np.abs(x - y).max())})
            if _left(args.deadline) < 30:
                break
        for entry, i_cpu, i_gpu in zip(solves, cpu.iterations, gpu.iterations):
            entry.update(cpu_iterations=i_cpu, gpu_iterations=i_gpu)
        if name == "wall_10k":  # the direct solve of the first system: both within the tolerance of it?
            system, rhs = captured[0]
            exact = SuperLUSolver().solve(system, rhs)
            first_cpu = ConjugateGradientSolver("jacobi", TOLERANCE).solve(system, rhs)
            first_gpu = ArrayConjugateGradient(backend, TOLERANCE).solve(system, rhs)
            row["first_vs_direct"] = {"cpu": float(np.abs(first_cpu - exact).max()),
                                      "gpu": float(np.abs(first_gpu - exact).max())}
        row.update(solves=solves, pattern_builds=gpu.pattern_builds, upload_mb=gpu.uploaded_bytes / 2**20,
                   cpu_s=sum(s["cpu_s"] for s in solves), gpu_s=sum(s["gpu_s"] for s in solves),
                   max_gap=max(s["gap"] for s in solves))
        rows.append(row)
        print(json.dumps({k: v for k, v in row.items() if k != "solves"}, default=float), flush=True)
        del captured
    _write(args.out, {"tolerance": TOLERANCE, "rows": rows})


def compare(args: argparse.Namespace, backend: ArrayBackend) -> None:
    rows = []
    for name in ("wall_10k", "slope3d_1k"):
        if _left(args.deadline) < 60:
            rows.append({"model": name, "note": "skipped: less than 60 s left"})
            continue
        model, settings = _build(name, args.small)
        arrays = model.arrays()
        settings = replace(settings, n_steps=20, record_every=20, solver="auto")
        finals, runs = {}, {}
        for label, changes in (("cpu", {"device": "cpu"}), ("gpu", {"device": "gpu"}),
                               ("direct", {"device": "cpu", "solver": "superlu"})):
            if label not in args.runs.split(","):
                continue
            if label == "direct" and _left(args.deadline) < 20:
                runs[label] = {"note": "skipped: less than 20 s left"}
                continue
            t = time.perf_counter()
            with Probe(deadline=np.inf).installed() as probe:  # counts the solves and step attempts
                result = simulation.run(arrays, replace(settings, **changes), keep_history=False,
                                        keep_vertices=False, stop=lambda _: _left(args.deadline) < 0)
            state = result.final_state
            finals[label] = state
            runs[label] = {"status": result.status, "steps": int(state.step), "time": float(state.time),
                           "wall_s": time.perf_counter() - t, "solves": probe.solves, "rejected": probe.rejected,
                           "cg_iterations": sum(sum(cg_iterations(s)) for s in probe.solvers)}
        gaps = {f"{a}-{b}": {"vertices_m": float(np.abs(finals[a].vertices - finals[b].vertices).max()),
                             "velocity": float(np.abs(finals[a].velocity - finals[b].velocity).max()),
                             "same_time": bool(finals[a].time == finals[b].time)}
                for a, b in (("gpu", "cpu"), ("cpu", "direct"), ("gpu", "direct")) if a in finals and b in finals}
        steps = runs["cpu"]["steps"]
        # each step's increment within the tolerance on both paths: positions within steps × tolerance (a run
        # stopped at the deadline before its 20 steps is compared where it stopped, and reported as such)
        bound = steps * settings.solver_tolerance
        passed = gaps["gpu-cpu"]["same_time"] and gaps["gpu-cpu"]["vertices_m"] <= bound and steps == 20
        rows.append({"model": name, "blocks": arrays.n_blocks, "runs": runs, "gaps": gaps, "bound_m": bound,
                     "passed": bool(passed)})
        print(json.dumps(rows[-1]), flush=True)
    _write(args.out, {"tolerance": TOLERANCE, "rows": rows})


BENCH = [("wall_10k", 5), ("wall_100k", 3), ("wall3d_10k", 3), ("slope3d_1k", 5)]


def bench(args: argparse.Namespace) -> None:
    rows = []
    for device in args.devices.split(","):
        for name, steps in [("wall_10k", 1)] if args.small else BENCH:
            left = _left(args.deadline)
            if left < 45:
                rows.append({"model": name, "device": device, "status": "skipped", "note": "less than 45 s left"})
                continue
            timeout = min(args.timeout, left - 30)
            cmd = [sys.executable, "-m", "srdda", "bench", "--json", "--model", name, "--steps", str(steps),
                   "--device", device, "--timeout", f"{timeout:.0f}"]
            done = subprocess.run(cmd, capture_output=True, text=True)
            if done.returncode != 0:
                rows.append({"model": name, "device": device, "status": "failed", "note": done.stderr[-400:]})
            else:
                rows.extend(json.loads(done.stdout)["rows"])
            print(json.dumps({k: rows[-1].get(k) for k in ("model", "device", "steps", "steps_per_s", "status")}),
                  flush=True)
    _write(args.out, {"rows": rows})


def wall1m(args: argparse.Namespace, backend: ArrayBackend) -> None:
    t0 = time.perf_counter()
    model, settings = _build("wall_1m", args.small)
    arrays = model.arrays()
    built_s = time.perf_counter() - t0
    print(f"wall_1m: {arrays.n_blocks} blocks built in {built_s:.0f} s; waiting for {args.go}", flush=True)
    while not Path(args.go).exists() and _left(args.deadline) > 0:
        time.sleep(1.0)
    left = _left(args.deadline)
    if left < 30:
        _write(args.out, {"model": "wall_1m", "blocks": arrays.n_blocks, "build_s": built_s, "status": "skipped",
                          "note": f"{left:.0f} s left after the other measurements"})
        return

    class Built:  # measure() asks the case for a model and takes its arrays: hand it those already made
        def arrays(self) -> Any:
            return arrays

    case = BenchCase("wall_1m", 2, lambda: (Built(), settings), steps=args.steps, quick_steps=1)
    row = measure(case, args.steps, "dda0", None, timeout=left - 10, device="gpu")
    row["build_s"] = built_s
    _write(args.out, row)


def profile(args: argparse.Namespace) -> None:
    import cProfile
    import pstats

    from srdda.solvers import get_solver
    from srdda.step import default_terms

    t0 = time.perf_counter()
    model, settings = _build(args.model, args.small)
    arrays = model.arrays()
    settings = replace(settings, device=args.device)
    solver = get_solver(settings.solver, settings.solver_tolerance, settings.resolved_device(arrays.n_unknowns))
    stepper = Stepper(arrays, settings, solver, default_terms(arrays, settings))
    state, dt = initial_state(arrays, stepper.method), settings.dt
    built = time.perf_counter() - t0
    t0 = time.perf_counter()
    outcome = stepper.step(state, dt)  # compiles
    first = time.perf_counter() - t0
    state = outcome.state if outcome.status == "accepted" else state
    steps = []
    profiler = cProfile.Profile()
    for _ in range(args.steps):
        if _left(args.deadline) < 0:
            break
        t0 = time.perf_counter()
        profiler.enable()
        outcome = stepper.step(state, dt)
        profiler.disable()
        steps.append({"status": outcome.status, "solves": outcome.solves, "s": time.perf_counter() - t0})
        state = outcome.state if outcome.status == "accepted" else state
    stats = pstats.Stats(profiler)
    top = sorted(stats.stats.items(), key=lambda kv: -kv[1][2])[:args.top]  # type: ignore[attr-defined]
    rows = [{"function": f"{Path(f).name}:{line}({name})", "calls": int(nc), "own_s": own, "total_s": total}
            for (f, line, name), (_, nc, own, total, _) in top]
    result = {"model": args.model, "device": args.device, "blocks": arrays.n_blocks, "build_s": built,
              "first_step_s": first, "steps": steps, "threads": os.environ.get("NUMBA_NUM_THREADS"), "top": rows}
    for r in rows:
        print(f"{r['own_s']:8.3f} {r['total_s']:8.3f} {r['calls']:6d}  {r['function']}", flush=True)
    print(json.dumps(steps), flush=True)
    _write(args.out, result)


def _fmt(x: Any, spec: str) -> str:
    return "-" if x is None else format(x, spec)


def summary(args: argparse.Namespace) -> None:
    folder = Path(args.out)

    def load(name: str) -> Any:
        path = folder / name
        return json.loads(path.read_text()) if path.exists() else None

    lines = []
    for name, wanted in (("env.txt", lambda line: line.startswith(("gpu:", "python "))),
                         ("tests.log", lambda line: any(k in line for k in (" passed", " failed", " error")))):
        path = folder / name
        text = path.read_text().splitlines() if path.exists() else []
        lines += [f"{name}: {line}" for line in text if wanted(line)][-2:]
    cg = load("cg.json")
    if cg:
        lines.append("CG on step systems (CPU: compiled block-Jacobi on all cores; GPU: CuPy):")
        lines.append("  model       blocks  product ms cpu/gpu  GB/s cpu/gpu  solves  it cpu/gpu   s cpu/gpu    "
                     "max gap m")
        for r in cg["rows"]:
            if "note" in r:
                lines.append(f"  {r['model']:<11} {r['note']}")
                continue
            it_cpu = sum(s["cpu_iterations"] for s in r["solves"])
            it_gpu = sum(s["gpu_iterations"] for s in r["solves"])
            lines.append(f"  {r['model']:<11} {r['blocks']:>7}  {r['product_ms_cpu']:7.2f}/{r['product_ms_gpu']:<7.3f}"
                         f"   {r['read_gbs_cpu']:5.0f}/{r['read_gbs_gpu']:<5.0f}  {len(r['solves']):>5}  "
                         f"{it_cpu:>5}/{it_gpu:<5}  {r['cpu_s']:6.2f}/{r['gpu_s']:<6.2f}  {r['max_gap']:.2e}")
    cmp_ = load("compare.json")
    if cmp_:
        lines.append("20 steps, final positions (bound: steps x tolerance):")
        for r in cmp_["rows"]:
            if "note" in r:
                lines.append(f"  {r['model']:<11} {r['note']}")
                continue
            g = r["gaps"]
            direct = "  ".join(f"{k} {v['vertices_m']:.2e}" for k, v in g.items() if k != "gpu-cpu")
            lines.append(f"  {r['model']:<11} gpu-cpu {g['gpu-cpu']['vertices_m']:.2e} m (bound {r['bound_m']:.1e}) "
                         f"{'PASS' if r['passed'] else 'FAIL'}  {direct}  solves cpu/gpu "
                         f"{r['runs']['cpu']['solves']}/{r['runs']['gpu']['solves']}")
    rows = (load("bench.json") or {"rows": []})["rows"]
    one = load("wall_1m.json")
    if one:
        rows.append(one)
    if rows:
        lines.append("srdda bench (dda0):")
        lines.append("  model       device                  blocks  steps  steps/s  solves/step  CG it/solve  solve%  "
                     "GPU MB  peak MB  status")
        for r in rows:
            lines.append(f"  {r['model']:<11} {str(r.get('device'))[:22]:<22} {_fmt(r.get('blocks'), '>7')}  "
                         f"{r.get('steps', 0)!s:>5}  {_fmt(r.get('steps_per_s'), '7.3f')}  "
                         f"{_fmt(r.get('solves_per_step'), '11.1f')}  {_fmt(r.get('cg_iterations_per_solve'), '11.0f')}"
                         f"  {_fmt(None if 'share_solve' not in r else 100 * r['share_solve'], '5.0f')}  "
                         f"{_fmt(r.get('gpu_peak_mb'), '6.0f')}  {_fmt(r.get('peak_mb'), '7.0f')}  "
                         f"{r.get('status')} {r.get('note', '')[:60]}")
        speed = {(r.get("model"), r.get("device", "cpu") != "cpu"): r.get("steps_per_s") for r in rows}
        for name in dict.fromkeys(r.get("model") for r in rows):
            cpu, gpu = speed.get((name, False)), speed.get((name, True))
            if cpu and gpu:
                lines.append(f"  {name}: GPU / CPU steps per second = {gpu / cpu:.2f}")
        targets = {"wall_100k": 5.0, "wall3d_10k": 2.0}
        for r in rows:
            if r.get("model") in targets and r.get("device", "cpu") != "cpu" and r.get("steps"):
                ok = r["steps_per_s"] >= targets[r["model"]] and r.get("rejected_steps") == 0
                lines.append(f"  target {r['model']} >= {targets[r['model']]} steps/s, every step accepted: "
                             f"{'met' if ok else 'not met'} ({r['steps_per_s']:.3f} steps/s, "
                             f"{r.get('rejected_steps')} rejected)")
    text = "\n".join(lines)
    (folder / "summary.txt").write_text(text + "\n")
    print(text, flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=("systems", "compare", "bench", "wall1m", "profile", "summary"))
    ap.add_argument("--out", type=Path, required=True, help="the JSON file to write (summary: the folder)")
    ap.add_argument("--deadline", type=float, default=time.time() + 3600.0)
    ap.add_argument("--go", default=None, help="wall1m: steps once this file exists")
    ap.add_argument("--steps", type=int, default=3, help="wall1m, profile: steps to make at most")
    ap.add_argument("--model", default="wall_100k", help="profile: the bench model")
    ap.add_argument("--device", default="gpu", help="profile: the device")
    ap.add_argument("--top", type=int, default=40, help="profile: how many functions to list")
    ap.add_argument("--timeout", type=float, default=120.0, help="bench: wall-time limit per model (s)")
    ap.add_argument("--devices", default="gpu,cpu", help="bench: the devices, in order")
    ap.add_argument("--runs", default="cpu,gpu,direct", help="compare: the runs (cpu, gpu, direct; cpu and gpu needed)")
    ap.add_argument("--fake-gpu", action="store_true", help="the GPU path on numpy (a rehearsal without a GPU)")
    ap.add_argument("--small", action="store_true", help="small models (a rehearsal)")
    args = ap.parse_args()
    if args.fake_gpu:
        arrays_module.gpu_problem = lambda: None
        cg_module.cupy_backend = numpy_backend
        args.devices = "cpu"  # the bench's children cannot be faked
    if args.what == "summary":
        summary(args)
    elif args.what == "bench":
        bench(args)
    elif args.what == "profile":
        profile(args)
    else:
        backend = numpy_backend() if args.fake_gpu else cupy_backend()
        {"systems": systems, "compare": compare, "wall1m": wall1m}[args.what](args, backend)


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    main()
