"""The step's contact problem by two formulations on the same steps: Newton (a) and a conic program (c).

:func:`held_tresca_step` runs one step of a model with ``contact_solver =
"newton"`` and the yield forces' N* held at given values (the Tresca problem
alone, convex), and returns the Newton increments with the step's problem
written out (:class:`srdda.contact.conic.StepProblem`). The reference test
(``tests/test_contact_solve_reference.py``) checks that the two agree;
:func:`compare` times them side by side (docs/contacts.md, *The contact
solve*): ``python benchmarks/compare_contact_formulations.py``.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...assembly.system import BlockSystem
from ...contact.conic import StepProblem, step_problem
from ...contact.newton import NewtonContactModel, NewtonContactStep, NewtonContactTerm
from ...contact.pipeline import ContactParameters
from ...model import JointMaterial, Material, Model, ModelArrays
from ...settings import RunSettings
from ...solvers import get_solver
from ...state import State, initial_state
from ...step import Stepper, contact_parameters, default_terms, model_half_height

__all__ = ["HeldTrescaStep", "held_tresca_step", "blocks_on_base", "compare", "GRAVITY"]

GRAVITY = 9.81  # m/s²
DENSITY = 2500.0  # kg/m³
BLOCK_HEIGHT = 0.5  # m: the blocks are 1 m wide (and deep, in 3D)


class _HeldTresca(NewtonContactModel):
    """The Newton contacts with N* held at given values (the Tresca problem alone)."""

    def __init__(self, arrays: ModelArrays, params: ContactParameters,
                 normal_star: Callable[[int], np.ndarray]) -> None:
        super().__init__(arrays, params)
        self.normal_star = normal_star

    def start(self, *args: Any) -> NewtonContactStep:
        step = super().start(*args)
        assert isinstance(step, NewtonContactStep)
        step.hold_normal_force(self.normal_star(len(step)))
        return step


@dataclass(frozen=True)
class HeldTrescaStep:
    """One step's Tresca problem and its Newton solution."""

    increments: np.ndarray  # (size,) the Newton iteration's block increments
    step: NewtonContactStep  # the step's contacts (their springs' rows, gaps, yield forces)
    others: BlockSystem  # the system of every other term
    c_p: float  # the scheme's penalty weight
    fixed: np.ndarray  # (nb,) the fixed blocks
    solves: int  # the Newton iteration's linear solves
    seconds: float  # wall time of the step (assembly, solves, line searches), detection excluded

    def problem(self) -> StepProblem:
        """The problem written out (dense: small models)."""
        return step_problem(self.step, self.others, self.c_p, self.step.yield_force(), self.fixed)


def held_tresca_step(arrays: ModelArrays, run: RunSettings, normal_star: Callable[[int], np.ndarray],
                     state: State | None = None, solver: str = "dense") -> HeldTrescaStep | None:
    """The step of ``arrays`` from ``state`` (default: the start) under ``run`` (``contact_solver = "newton"``),
    N* of the yield forces ``normal_star(n)``; None where no contact is near or the step was not accepted."""
    terms = default_terms(arrays, run)
    contact = next((t for t in terms if isinstance(t, NewtonContactTerm)), None)
    if contact is None:
        return None
    contact.model = _HeldTresca(arrays, contact_parameters(arrays, run, model_half_height(arrays.vertex_position)),
                                normal_star)
    stepper = Stepper(arrays, run, get_solver(solver), terms)
    state = initial_state(arrays, stepper.method) if state is None else state
    last: dict[str, Any] = {}
    converged = contact.converged

    def capture(dd: np.ndarray, ctx: Any) -> bool:
        last["dd"], last["ctx"] = dd.copy(), ctx
        return converged(dd, ctx)

    begin = contact.begin

    def timed_begin(ctx: Any) -> None:  # detection, timed apart
        start = time.perf_counter()
        begin(ctx)
        last["detection"] = time.perf_counter() - start

    # the instance's methods wrapped for the timing (mypy refuses assigning to a method)
    contact.converged = capture  # type: ignore[method-assign]
    contact.begin = timed_begin  # type: ignore[method-assign]
    start = time.perf_counter()
    outcome = stepper.step(state, run.dt)
    seconds = time.perf_counter() - start - last.get("detection", 0.0)
    step = contact.step
    if step is None or outcome.status != "accepted":
        return None
    ctx = last["ctx"]
    others = stepper.assemble(ctx, [t for t in terms if t is not contact])
    return HeldTrescaStep(last["dd"].ravel(), step, others, ctx.coeffs.c_p, arrays.block_fixed, outcome.solves,
                          seconds)


def blocks_on_base(dim: int, rng: np.random.Generator, n_blocks: int, spacing: float = 1.2) -> Model:
    """A row of ``n_blocks`` 1 m × 0.5 m blocks (1 m deep in 3D), ``spacing`` m apart, each starting up to 0.2 mm
    into a fixed base, touching it or a little above it, with random speeds and spins; a random joint
    (φ 0-40°, cohesion and tensile strength 0 or up to 20 kPa)."""
    model = Model(gravity=(0.0, -GRAVITY) if dim == 2 else (0.0, 0.0, -GRAVITY))
    model.add_material("rock", Material(DENSITY, 1e10, 0.25))
    model.add_joint_material("j", JointMaterial(friction_angle=float(rng.uniform(0, 40)),
                                                cohesion=float(rng.choice([0.0, rng.uniform(0, 2e4)])),
                                                tensile_strength=float(rng.choice([0.0, rng.uniform(0, 2e4)]))),
                             between=[("rock", "rock")])
    model.allow_overlap = True  # a block may start a little into the base: a penetrating contact
    right = max(3.0, spacing * n_blocks)
    if dim == 2:
        model.add_block([[-3, -1], [right, -1], [right, 0], [-3, 0]], "rock", fixed=True)
    else:
        model.add_box([-3, -3, -1], [right, 3, 0], "rock", fixed=True)
    for k in range(n_blocks):
        lift = float(rng.uniform(-2e-4, 2e-4))  # into the base, touching, or a little above it
        v = rng.uniform(-0.5, 0.5, dim)
        x0 = spacing * k - 1.5
        if dim == 2:
            model.add_block([[x0, lift], [x0 + 1, lift], [x0 + 1, lift + BLOCK_HEIGHT], [x0, lift + BLOCK_HEIGHT]],
                            "rock", velocity=tuple(v),
                            angular_velocity=float(rng.uniform(-0.5, 0.5)))
        else:
            model.add_box([x0, -0.5, lift], [x0 + 1, 0.5, lift + BLOCK_HEIGHT], "rock", velocity=tuple(v),
                          angular_velocity=tuple(rng.uniform(-0.5, 0.5, 3)))
    return model


def reference_run(force_tolerance: float = 1e-9) -> RunSettings:
    """One step of 1 ms under dda1, k_n 1e10 N/m, the Newton solver stopped at force errors below
    ``force_tolerance`` of the blocks' weight (1e-4 in runs)."""
    return RunSettings(dt=1e-3, n_steps=1, method="dda1", penalty=1e10, contact_solver="newton",
                       open_close_force_tolerance=force_tolerance)


def compare(dims: tuple[int, ...] = (2, 3), sizes: tuple[int, ...] = (1, 5, 20), seeds: int = 10,
            force_tolerance: float = 1e-4) -> list[dict[str, float | int]]:
    """Rows of one random step each (:func:`blocks_on_base`, touching neighbours): the Newton solve's solves and
    time against clarabel's interior-point iterations and time (cvxpy's compilation apart), and how far apart
    the two solutions are. ``force_tolerance``: Newton's stop, that of runs by default."""
    rows: list[dict[str, float | int]] = []
    for dim in dims:
        for n_blocks in sizes:
            for seed in range(seeds):
                rng = np.random.default_rng(seed)
                arrays = blocks_on_base(dim, rng, n_blocks, spacing=1.0 + 1e-4).arrays()
                weight = DENSITY * BLOCK_HEIGHT * GRAVITY
                got = held_tresca_step(arrays, reference_run(force_tolerance),
                                       lambda n: rng.uniform(0.0, weight, n))
                if got is None:
                    continue
                problem = got.problem()
                start = time.perf_counter()
                reference, program = problem.solve_conic(tolerance=1e-10)
                total = time.perf_counter() - start
                stats = program.solver_stats
                pi_newton, pi_conic = problem.potential(got.increments), problem.potential(reference)
                rows.append({"dim": dim, "blocks": n_blocks, "seed": seed, "contacts": len(problem.gap),
                             "unknowns": len(got.increments), "newton_solves": got.solves,
                             "newton_s": got.seconds, "conic_iterations": int(stats.num_iters),
                             "conic_solve_s": float(stats.solve_time), "conic_total_s": total,
                             "potential_gap": (pi_newton - pi_conic) / abs(pi_conic),
                             "distance": float(np.linalg.norm(got.increments - reference))})
    return rows
