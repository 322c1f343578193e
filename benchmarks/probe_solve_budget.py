"""How many solves a step a contact solver may take for a bench model to reach a target speed.

Runs one model of ``srdda bench`` (its steps and Δt) under ``contact_solver`` and splits its wall time into
what every solve costs (the assembly, the linear solve and the contacts' test after it) and what every step
costs once (detection, the blocks' update, the rest). With a baseline's steps a second and a target factor
(issue 29's acceptance: 2.5 × f854ad9 on slope_a, 4 × on slope_b, 5 × on slope_c, 4 × on slope3d_1k), the
step's time budget is 1 / (factor × baseline), and a solver that keeps today's cost of a solve may take

    (budget − cost a step) / cost a solve

solves a step (docs/dev/contact-solve.md, *How few solves a step the acceptance allows*). Not the bench's own
timers (`srdda.apps.bench.runner.Probe`): its phases put work done once a step (the base system, the commit)
with the solves' assembly and contact test, and a budget needs the two apart. Measure the baseline
in the same sitting (`srdda bench --json --model M` on the baseline's tree), the machine otherwise idle.

    python benchmarks/probe_solve_budget.py slope_c --baseline 5.34 --target 5
"""
from __future__ import annotations

import argparse
import json
import time
from collections import defaultdict
from collections.abc import Callable
from dataclasses import replace
from typing import Any, get_args

from srdda import simulation
from srdda.apps.bench.runner import CASES, _warm_up
from srdda.contact.pipeline import ContactStep
from srdda.settings import ContactSolverName
from srdda.step import Stepper

PER_SOLVE = ("assemble", "solve", "converged")


def timed(seconds: dict[str, float], counts: dict[str, int], label: str,
          fn: Callable[..., Any]) -> Callable[..., Any]:
    """``fn`` with its wall time and calls added to ``seconds[label]`` and ``counts[label]``."""
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        start = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            seconds[label] += time.perf_counter() - start
            counts[label] += 1
    return wrapper


def measure(name: str, contact_solver: ContactSolverName, steps: int | None) -> dict[str, Any]:
    """The run's steps a second, solves a step, cost of a solve and cost of a step (ms)."""
    case = CASES[name]
    _warm_up(case.dim, "cpu")
    model, settings = case.build()
    arrays = model.arrays()
    n = case.steps if steps is None else steps
    settings = replace(settings, n_steps=n, record_every=n, contact_solver=contact_solver)
    seconds: dict[str, float] = defaultdict(float)
    counts: dict[str, int] = defaultdict(int)
    originals = [(Stepper, "assemble"), (Stepper, "begin"), (ContactStep, "converged")]
    saved = [getattr(owner, attr) for owner, attr in originals]
    make_solver = simulation.get_solver

    def timed_solver(*args: Any, **kwargs: Any) -> Any:
        solver = make_solver(*args, **kwargs)
        setattr(solver, "solve", timed(seconds, counts, "solve", solver.solve))
        return solver

    for (owner, attr), original in zip(originals, saved):
        setattr(owner, attr, timed(seconds, counts, attr if attr != "begin" else "steps", original))
    simulation.get_solver = timed_solver
    try:
        start = time.perf_counter()
        simulation.run(arrays, settings, keep_vertices=False)
        wall = time.perf_counter() - start
    finally:
        for (owner, attr), original in zip(originals, saved):
            setattr(owner, attr, original)
        simulation.get_solver = make_solver
    solves, attempts = counts["solve"], counts["steps"]
    per_solve = sum(seconds[label] for label in PER_SOLVE) / solves
    return {"model": name, "contact_solver": contact_solver, "attempts": attempts, "wall_s": wall,
            "steps_per_s": attempts / wall, "solves_per_step": solves / attempts,
            "solve_ms": 1e3 * per_solve, "step_ms": 1e3 * (wall - per_solve * solves) / attempts}


def positive(text: str) -> float:
    """A command-line number that must be above zero (a rate or a factor)."""
    value = float(text)
    if not value > 0.0:
        raise argparse.ArgumentTypeError(f"must be a number above zero, got {text}")
    return value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("model", choices=sorted(CASES))
    parser.add_argument("--contact-solver", default="open-close", choices=get_args(ContactSolverName))
    parser.add_argument("--steps", type=int, default=None, help="default: the bench's steps of the model")
    parser.add_argument("--baseline", type=positive, required=True, help="the baseline's steps a second")
    parser.add_argument("--target", type=positive, required=True, help="the speed-up asked for")
    args = parser.parse_args()
    if args.steps is not None and args.steps < 1:
        parser.error(f"argument --steps: must be at least 1, got {args.steps}")
    row = measure(args.model, args.contact_solver, args.steps)
    budget = 1e3 / (args.target * args.baseline)
    row.update(budget_ms=budget, solves_allowed=(budget - row["step_ms"]) / row["solve_ms"],
               solve_ms_for_this_count=(budget - row["step_ms"]) / row["solves_per_step"])
    print(json.dumps(row))


if __name__ == "__main__":
    main()
