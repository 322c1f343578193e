"""``srdda bench``: run the standard models for a fixed number of steps and time them.

Each model runs in a fresh Python process (``python -m srdda.apps.bench.runner``),
so that its peak memory (:func:`peak_memory_mb`) is its own and one
model's numba compilation, caches or leaks do not bias the next. The child
prints one JSON row; the parent collects the rows and prints them.

What a row measures, without changing the engine (the child wraps a few
functions of the engine with timers while the model runs, :class:`Probe`;
nothing is patched in the parent):

* ``steps``: accepted steps within the step count and the wall-time limit;
  ``steps_per_s`` = accepted steps / wall time of ``srdda.run`` (model
  building and numba compilation excluded); ``steps_per_cpu_s`` divides by the
  process's CPU time instead, which other processes on a busy machine distort
  less (on an idle machine the two agree while the run uses one core);
* ``solves_per_step``: mean solves per accepted step (what ``Result.iterations``
  holds); ``solves_total`` also counts the solves of rejected attempts;
* ``rejected_steps``: step attempts whose outcome was a cut (open-close cap,
  displacement or penetration check), counted by a wrapper around
  ``Stepper.step``; ``cuts_iteration``, ``cuts_displacement`` and
  ``cuts_penetration`` split them by cause (:data:`srdda.term.CUT_CAUSES`:
  only the first says that the contact solve gave up);
* ``cg_iterations``: conjugate-gradient iterations of the whole run, what the
  run's iterative solver records per solve (0 when every solve was direct);
  ``cg_iterations_per_solve`` divides by the solves it made. With
  ``solves_per_step`` it tells whether a slow model pays for many solves or
  for slow ones;
* ``factorizations``, ``analyses``: the direct backend's numerical factorisations and orderings with
  symbolic analyses over the run (``auto``: those of its direct tier; a solve whose matrix is the last
  one's reuses its factor). SuperLU orders at every factorisation and reports no analyses (None);
* ``device``: where the conjugate gradient ran: "cpu", or the GPU's name (``--device gpu``,
  :mod:`srdda.backends`); ``gpu_peak_mb``: the high-water mark of CuPy's memory pool (the GPU memory
  the run's arrays took; None on the CPU); ``gpu_upload_mb``: what the solves moved to the GPU;
* ``beyond_free_fall``: blocks whose centroid ended more than 0.1 % further from its start than a free
  body could have moved, |v₀|·t + ½|g|·t² (:func:`beyond_free_fall`; None when the wall-time limit
  stopped the run), and ``free_fall_ratio``, the largest distance moved over that bound. The standard models are
  loaded by gravity alone, so a block beyond it was pushed by contacts that put energy in (issue 29: on
  slope c at a fixed Δt the C code of Shi's DDA moves 479 of 1,014 blocks further than free fall);
* ``share_*``: the part of the run's wall time spent (exclusively, nested timed
  calls subtracted) in contact detection (``ContactModel.prepare``),
  assembly (``Stepper.assemble`` and ``base_system``: every term's
  ``add_to``, and ``BlockSystem`` to sparse/dense), the linear solve (the
  solver's ``solve`` minus the assembly it calls) and the open-close
  bookkeeping (``ContactStep.converged``/``commit``); ``share_other`` is the rest (the kinematic
  update, recording).
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ... import simulation
from ...assembly.system import BlockSystem
from ...backends.arrays import DeviceName
from ...contact.pipeline import ContactModel, ContactStep
from ...integrators.methods import MethodName
from ...model import Model
from ...modeldata.arrays import ModelArrays
from ...results import Result
from ...settings import RunSettings, ContactSolverName
from ...step import Stepper
from ...solvers import DEFAULT_TOLERANCE, solves_inexactly, takes_springs
from ...term import CUT_CAUSES
from .models import brick_wall, english_bond_wall, jointed_slope, jointed_slope_3d

__all__ = ["BenchCase", "CASES", "QUICK", "REQUIRED_KEYS", "run_cases", "format_table"]

REQUIRED_KEYS = ("model", "dim", "blocks", "method", "steps", "dt", "sim_time", "steps_per_s", "solves_per_step",
                 "rejected_steps", "peak_mb")
PHASES = ("detection", "assembly", "solve", "open_close")


@dataclass(frozen=True)
class BenchCase:
    """A standard model: how to build it (model and its run settings) and how many steps to run."""

    name: str
    dim: int
    build: Callable[[], tuple[Model, RunSettings]]
    steps: int
    quick_steps: int


CASES = {c.name: c for c in (
    BenchCase("slope_a", 2, lambda: jointed_slope("a"), 200, 20),
    BenchCase("slope_b", 2, lambda: jointed_slope("b"), 200, 20),
    BenchCase("slope_c", 2, lambda: jointed_slope("c"), 200, 20),
    BenchCase("wall_10k", 2, lambda: brick_wall(100, 100), 5, 1),
    BenchCase("wall_100k", 2, lambda: brick_wall(316, 316), 3, 1),
    BenchCase("slope3d_1k", 3, jointed_slope_3d, 5, 1),
    BenchCase("wall3d_10k", 3, lambda: english_bond_wall(50, 100), 3, 1),
)}
QUICK = ("slope_a", "slope_b")


class WallTimeLimit(Exception):
    """The model's wall-time limit was reached (not a RuntimeError: the engine must not catch it)."""


class Probe:
    """Timers and counters wrapped around engine functions while :meth:`installed` is active."""

    def __init__(self, deadline: float) -> None:
        self.deadline = deadline
        self.seconds = dict.fromkeys(PHASES, 0.0)
        self._stack: list[list[float]] = []  # [start, time of nested timed calls]
        self.attempts = 0
        self.rejected = 0
        self.cuts = dict.fromkeys(CUT_CAUSES, 0)
        self.accepted_solves: list[int] = []
        self.accepted_dt: list[float] = []
        self.sim_time = 0.0
        self.solves = 0
        self.contacts: list[int] = []
        self.solvers: list[Any] = []  # the run's solvers, as the engine made them
        self._originals: list[tuple[Any, str, Any]] = []  # (class or module, name, what was there)

    def timed(self, phase: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        """``fn`` with its exclusive wall time added to ``phase``."""
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            frame = [time.perf_counter(), 0.0]
            self._stack.append(frame)
            try:
                return fn(*args, **kwargs)
            finally:
                elapsed = time.perf_counter() - frame[0]
                self._stack.pop()
                self.seconds[phase] += elapsed - frame[1]
                if self._stack:
                    self._stack[-1][1] += elapsed
        return wrapper

    @contextmanager
    def installed(self) -> Iterator[Probe]:
        """The engine's functions wrapped (class attributes and module globals of this process), restored after."""
        try:
            self._install()
            yield self
        finally:
            for owner, name, original in reversed(self._originals):
                setattr(owner, name, original)
            self._originals.clear()

    def _wrap(self, owner: Any, name: str, wrapper: Callable[[Any], Any]) -> None:
        original = getattr(owner, name)
        self._originals.append((owner, name, original))
        setattr(owner, name, wrapper(original))

    def _install(self) -> None:
        """Count step attempts, solves and contacts; time the phases (module doc)."""
        def counted_steps(step: Callable[..., Any]) -> Callable[..., Any]:
            def counted_step(stepper: Stepper, state: Any, dt: float) -> Any:
                if time.perf_counter() > self.deadline:
                    raise WallTimeLimit
                self.attempts += 1
                outcome = step(stepper, state, dt)
                if outcome.status == "cut":
                    self.rejected += 1
                    self.cuts[outcome.cause] += 1
                elif outcome.status == "accepted":
                    self.accepted_solves.append(outcome.solves)
                    self.accepted_dt.append(outcome.state.time - state.time)
                    self.sim_time = outcome.state.time
                return outcome
            return counted_step

        def counted(prepare: Callable[..., Any]) -> Callable[..., Any]:
            def counted_prepare(model: Any, *args: Any) -> Any:
                term = prepare(model, *args)
                self.contacts.append(0 if term is None else len(term))
                return term
            return counted_prepare

        def timed_solvers(get_solver: Callable[..., Any]) -> Callable[..., Any]:
            def timed_solver(name: str = "auto", tolerance: float = DEFAULT_TOLERANCE, device: str = "cpu") -> Any:
                return _TimedSolver(get_solver(name, tolerance, device), self)
            return timed_solver

        def timer(phase: str) -> Callable[[Any], Any]:
            return lambda fn: self.timed(phase, fn)

        self._wrap(Stepper, "step", counted_steps)
        self._wrap(ContactModel, "prepare", lambda fn: self.timed("detection", counted(fn)))
        self._wrap(simulation, "get_solver", timed_solvers)
        for name in ("assemble", "base_system"):
            self._wrap(Stepper, name, timer("assembly"))
        for name in ("block_rows", "to_bsr", "to_csr", "to_dense", "saddle_csr", "saddle_dense"):
            self._wrap(BlockSystem, name, timer("assembly"))
        for name in ("converged", "commit"):
            self._wrap(ContactStep, name, timer("open_close"))


class _TimedSolver:
    """A linear solver whose solves are counted, timed and stopped at the wall-time limit."""

    def __init__(self, inner: Any, probe: Probe) -> None:
        probe.solvers.append(inner)
        self.name = inner.name
        self._inner = inner
        self._probe = probe
        self._solve = probe.timed("solve", inner.solve)

    def inexact(self, system: BlockSystem) -> bool:
        return solves_inexactly(self._inner, system)

    def takes_springs(self, n_blocks: int) -> bool:
        return takes_springs(self._inner, n_blocks)

    def solve(self, system: BlockSystem, rhs: np.ndarray, tolerance: float | None = None) -> np.ndarray:
        if time.perf_counter() > self._probe.deadline:
            raise WallTimeLimit
        self._probe.solves += 1
        return self._solve(system, rhs) if tolerance is None else self._solve(system, rhs, tolerance)


def direct_work(solvers: list[Any]) -> tuple[int, int | None]:
    """(factorisations, analyses) of the run's direct backends (``auto``: its direct tier); analyses None
    where no backend counts them."""
    direct = [getattr(solver, "direct", solver) for solver in solvers]
    analyses = [s.analyses for s in direct if hasattr(s, "analyses")]
    return sum(getattr(s, "factorizations", 0) for s in direct), sum(analyses) if analyses else None


def cg_iterations(solver: Any) -> list[int]:
    """The iterations of each conjugate-gradient solve ``solver`` made (``auto``: its iterative backend)."""
    return list(getattr(getattr(solver, "iterative", solver), "iterations", []))


def device_columns(solvers: list[Any]) -> dict[str, Any]:
    """``device``, ``gpu_peak_mb`` and ``gpu_upload_mb`` of a row (module doc) from the run's solvers."""
    devices = [s for s in (getattr(solver, "iterative", solver) for solver in solvers) if hasattr(s, "backend")]
    if not devices:
        return {"device": "cpu", "gpu_peak_mb": None, "gpu_upload_mb": None}
    backend = devices[0].backend
    peak = backend.memory_high_water_bytes()
    return {"device": backend.device_name(), "gpu_peak_mb": None if peak is None else peak / 2**20,
            "gpu_upload_mb": sum(s.uploaded_bytes for s in devices) / 2**20}


def peak_memory_mb() -> float:
    """Peak resident memory of this process (MB).

    Linux's ``ru_maxrss`` carries over an exec the peak of the process that
    forked it (here the parent, which may have run other benchmarks), so the
    resident high-water mark of this process's own address space (``VmHWM``)
    is read where it exists.
    """
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0  # kB
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # kB on Linux


def _warm_up(dim: int, device: DeviceName) -> None:
    """Compile the numba kernels (contact detection) on a tiny wall of the model's dimension, outside the timing;
    on a GPU also CuPy's kernels, through its conjugate gradient."""
    model, settings = brick_wall(2, 2) if dim == 2 else english_bond_wall(1, 2)
    simulation.run(model, replace(settings, n_steps=2, device=device,
                                  solver="cg-jacobi" if device == "gpu" else settings.solver))


# relative: a block falling freely reaches its bound to rounding; contact springs that pull in the first steps
# (open-close's band, docs/contacts/open-close.md) take a free-falling block up to 0.5 % further (slope_a, 2
# steps); a contact that blows a model up takes blocks many times further (the C code's slope c: 11.75 m up)
FREE_FALL_TOLERANCE = 1e-3


def beyond_free_fall(arrays: ModelArrays, result: Result) -> tuple[int, float]:
    """(blocks, ratio): how many blocks' centroids ended further from where they started than a free body
    could have moved in the run, |v₀|·t + ½|g|·t² (v₀ the block's initial velocity), by more than
    ``FREE_FALL_TOLERANCE`` of it; and the largest distance moved over that bound among the blocks that can
    move (0 when none can). For models loaded by gravity alone, as the standard ones are: any other load may
    move a block further."""
    t = float(result.time[-1])
    centroid = result.array("centroid")
    moved = np.linalg.norm(centroid[-1] - centroid[0], axis=1)
    v0 = np.linalg.norm(arrays.block_velocity[:, arrays.block_type.translation], axis=1)
    bound = v0 * t + 0.5 * float(np.linalg.norm(arrays.gravity)) * t * t
    free = ~arrays.block_fixed & (bound > 0.0)
    ratio = float(np.max(moved[free] / bound[free])) if np.any(free) else 0.0
    return int(np.sum(moved[free] > bound[free] * (1.0 + FREE_FALL_TOLERANCE))), ratio


def measure(case: BenchCase, steps: int, method: MethodName, dt: float | None, timeout: float,
            contact_solver: ContactSolverName | None = None, device: DeviceName = "cpu") -> dict[str, Any]:
    """Build and run one model in this process, its solves on ``device``; the row of ``srdda bench --json``
    (``contact_solver`` None: the model's own)."""
    start = time.perf_counter()
    _warm_up(case.dim, device)
    t0 = time.perf_counter()
    model, settings = case.build()
    arrays = model.arrays()
    build_s = time.perf_counter() - t0
    settings = replace(settings, n_steps=steps, method=method, dt=settings.dt if dt is None else dt,
                       record_every=max(steps, 1), device=device,
                       contact_solver=settings.contact_solver if contact_solver is None else contact_solver)
    probe = Probe(deadline=start + timeout)
    note = ""
    with probe.installed():
        t0, cpu0 = time.perf_counter(), time.process_time()
        try:
            result = simulation.run(arrays, settings, keep_vertices=False)  # the histories as before
            status = result.status
            beyond, ratio = beyond_free_fall(arrays, result)
        except WallTimeLimit:
            beyond, ratio = None, None
            status = "time limit"
            note = (f"wall-time limit {timeout:g} s reached after {len(probe.accepted_solves)} accepted steps "
                    f"and {probe.attempts} attempts")
        wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    if status not in ("completed", "time limit"):
        note = status
    n = len(probe.accepted_solves)
    iterations = [k for solver in probe.solvers for k in cg_iterations(solver)]
    factorizations, analyses = direct_work(probe.solvers)
    row: dict[str, Any] = {
        "model": case.name, "dim": case.dim, "blocks": arrays.n_blocks, "method": settings.method,
        "contact_solver": settings.contact_solver, "steps": n,
        "dt": settings.dt, "sim_time": probe.sim_time, "steps_per_s": n / wall if wall > 0 else 0.0,
        "solves_per_step": float(np.mean(probe.accepted_solves)) if n else None,
        "rejected_steps": probe.rejected, **{f"cuts_{cause}": n for cause, n in probe.cuts.items()},
        "peak_mb": peak_memory_mb(),
        "steps_requested": steps, "attempts": probe.attempts, "solves_total": probe.solves,
        "mean_accepted_dt": float(np.mean(probe.accepted_dt)) if n else None,
        "contacts_per_attempt": float(np.mean(probe.contacts)) if probe.contacts else 0.0,
        "cg_iterations": int(sum(iterations)),
        "cg_iterations_per_solve": float(np.mean(iterations)) if iterations else None,
        "factorizations": factorizations, "analyses": analyses,
        "wall_s": wall, "cpu_s": cpu, "steps_per_cpu_s": n / cpu if cpu > 0 else 0.0, "build_s": build_s,
        "beyond_free_fall": beyond, "free_fall_ratio": ratio,
        "status": status, "note": note, **device_columns(probe.solvers),
    }
    for phase in PHASES:
        row[f"share_{phase}"] = probe.seconds[phase] / wall if wall > 0 else 0.0
    row["share_other"] = max(0.0, 1.0 - sum(row[f"share_{p}"] for p in PHASES))
    return row


def _failed_row(case: BenchCase, steps: int, method: str, dt: float | None, device: str,
                note: str) -> dict[str, Any]:
    return {"model": case.name, "dim": case.dim, "blocks": None, "method": method, "steps": 0, "dt": dt,
            "sim_time": 0.0, "steps_per_s": 0.0, "solves_per_step": None, "rejected_steps": None,
            "peak_mb": None, "steps_requested": steps, "device": device, "status": "failed", "note": note}


def run_cases(names: list[str], steps: int | None, quick: bool, method: str, dt: float | None,
              timeout: float, progress: Callable[[str], None] | None = None,
              contact_solver: str | None = None, device: str = "cpu") -> list[dict[str, Any]]:
    """Run each named case in its own child process, its solves on ``device``; one row per case, in order."""
    rows = []
    for name in names:
        case = CASES[name]
        n = steps if steps is not None else (case.quick_steps if quick else case.steps)
        if progress is not None:
            progress(name)
        cmd = [sys.executable, "-m", "srdda.apps.bench.runner", name, "--steps", str(n), "--method", method,
               "--timeout", str(timeout), "--device", device] + ([] if dt is None else ["--dt", repr(dt)]) \
            + ([] if contact_solver is None else ["--contact-solver", contact_solver])
        try:
            # the child stops itself at the limit (between solves); this margin covers one long solve
            done = subprocess.run(cmd, capture_output=True, text=True, timeout=2.0 * timeout + 120.0)
        except subprocess.TimeoutExpired:
            rows.append(_failed_row(case, n, method, dt, device,
                                    f"killed: no answer within {2.0 * timeout + 120.0:g} s"))
            continue
        lines = done.stdout.strip().splitlines()
        if done.returncode != 0 or not lines:
            err = done.stderr.strip().splitlines()
            rows.append(_failed_row(case, n, method, dt, device,
                                    f"child exited with {done.returncode}: {err[-1] if err else 'no message'}"))
            continue
        rows.append(json.loads(lines[-1]))
    return rows


def _num(x: Any, fmt: str) -> str:
    return "-" if x is None else format(x, fmt)


def format_table(rows: list[dict[str, Any]]) -> str:
    """The rows as an aligned text table (time shares in %); the device and GPU memory when a row ran on a GPU."""
    on_gpu = any(r.get("device", "cpu") != "cpu" for r in rows)
    gpu_header = ("device", "GPU MB") if on_gpu else ()
    header = ("model", "blocks", "method", "contacts", "steps", "dt", "sim time", "steps/s", "solves/step",
              "CG it/solve", "cuts it/disp/pen", "detect%", "assembly%", "solve%", "open-close%", "other%", "peak MB",
              *gpu_header, "note")
    lines = [header]
    for r in rows:
        shares = [_num(None if f"share_{p}" not in r else 100 * r[f"share_{p}"], ".0f")
                  for p in (*PHASES, "other")]
        gpu = (r.get("device", "cpu"), _num(r.get("gpu_peak_mb"), ".0f")) if on_gpu else ()
        lines.append((r["model"], _num(r["blocks"], "d"), r["method"], r.get("contact_solver", "-"),
                      f"{r['steps']}/{r.get('steps_requested', '-')}",
                      _num(r["dt"], "g"), _num(r["sim_time"], ".4g"), _num(r["steps_per_s"], ".3g"),
                      _num(r["solves_per_step"], ".1f"), _num(r.get("cg_iterations_per_solve"), ".0f"),
                      "/".join(_num(r.get(f"cuts_{c}"), "d") for c in CUT_CAUSES), *shares,
                      _num(r["peak_mb"], ".0f"), *gpu, r.get("note", "")))
    widths = [max(len(str(line[i])) for line in lines) for i in range(len(header))]
    return "\n".join("  ".join(str(c).ljust(w) for c, w in zip(line, widths)).rstrip() for line in lines)


def _main() -> None:
    """Child process: measure one case and print its row as one JSON line."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("model", choices=sorted(CASES))
    ap.add_argument("--steps", type=int, required=True)
    ap.add_argument("--method", default="dda0")
    ap.add_argument("--dt", type=float, default=None)
    ap.add_argument("--timeout", type=float, required=True)
    ap.add_argument("--contact-solver", default=None)
    ap.add_argument("--device", choices=("cpu", "gpu"), default="cpu")
    args = ap.parse_args()
    row = measure(CASES[args.model], args.steps, args.method, args.dt, args.timeout, args.contact_solver,
                  args.device)
    print(json.dumps(row), flush=True)


if __name__ == "__main__":
    _main()
