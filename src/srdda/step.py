"""One time step: predict, iterate over the terms until all have settled, commit.

    begin      every term looks at the state at t (contacts are detected);
    iterate    assemble the terms into the block system, solve, ask each term
               whether its own iteration has settled (open-close, secant pass);
    update     velocities, accelerations, points, stresses and rotations at
               t + Δt from the increments (the method's kinematics);
    review     a term may cut the step (a vertex moved too far, too deep a
               penetration) or bound the next Δt;
    commit     terms store what they carry to the next step; the work of the
               step goes to the ledger (with what ``velocity_ratio`` < 1 took
               out of the velocities: ``dissipated_damping``).

:meth:`Stepper.step` returns a :class:`StepOutcome` (accepted, cut with the
reason, or diverged with a message); it raises nothing to steer the run.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

from .assembly.blocks import GyroscopicTerm, block_terms, mass_matrices
from .assembly.system import BlockSystem
from .constraints import point_terms
from .contact.law import ContactLaw
from .contact.newton import NewtonContactModel, NewtonContactTerm
from .contact.pipeline import ContactModel, ContactParameters, ContactTerm
from .integrators.methods import Method
from .integrators.secant import SecantPass
from .modeldata.arrays import ModelArrays
from .modeldata.materials import ModelError
from .settings import RunSettings
from .solvers import LinearSolver, SolverError, solves_inexactly, takes_springs
from .state import State
from .term import LEDGER, StepContext, StepCut, Term

__all__ = ["StepOutcome", "Stepper", "default_terms", "model_half_height", "contact_parameters", "shi_step_bound",
           "time_step_advice"]


@dataclass(frozen=True)
class StepOutcome:
    """How a step attempt ended: ``accepted`` (``state`` is the new state), ``cut`` or ``diverged``."""

    status: Literal["accepted", "cut", "diverged"]
    solves: int
    dt_next: float  # the Δt to use next: grown back after an accepted step, reduced after a cut
    state: State | None = None
    reason: str = ""
    cause: str = ""  # of a cut: one of srdda.term.CUT_CAUSES


def model_half_height(vertices: np.ndarray) -> float:
    """w0: half the height of the model (half its width if it is flat), Shi's length scale."""
    extent = np.ptp(vertices, axis=0)
    return 0.5 * float(extent[-1] if extent[-1] > 0 else extent[0])


def contact_parameters(arrays: ModelArrays, settings: RunSettings, w0: float) -> ContactParameters:
    """Contact stiffnesses and distances of a run (docs/contacts.md)."""
    kn = settings.contact_penalty if settings.contact_penalty is not None else settings.penalty
    if settings.auto_penalty is not None:
        young = 1.0 / arrays.block_compliance[:, 0, 0]  # E in plane stress, E/(1-ν²) in plane strain
        kn = settings.auto_penalty * float(np.max(young)) * 1.0  # × unit thickness
    d0 = settings.contact_distance_factor * settings.max_displacement_ratio * w0
    return ContactParameters(kn, settings.shear_ratio * kn, d0, np.radians(settings.contact_angle_tolerance),
                             settings.penetration_fraction * d0, settings.friction_tolerance,
                             settings.open_close_freeze_after, settings.open_close_settle_after,
                             settings.open_close_tolerance * w0, settings.open_close_force_tolerance)


def shi_step_bound(arrays: ModelArrays, settings: RunSettings) -> float | None:
    """Shi's bound on Δt (s): a vertex may move g2·w0 in one step, so a block starting from rest under
    gravity g may take steps of at most sqrt(2·g2·w0/|g|). None without gravity."""
    g = float(np.linalg.norm(arrays.gravity))
    if g == 0.0:
        return None
    return float(np.sqrt(2.0 * settings.max_displacement_ratio * model_half_height(arrays.vertex_position) / g))


def time_step_advice(arrays: ModelArrays, settings: RunSettings) -> str | None:
    """A warning when Δt is far too large for a contact model, else None (docs/reliability.md).

    Above ten times :func:`shi_step_bound`, the first steps are cut again and
    again and the run spends its time finding a Δt the user could have given.
    """
    bound = shi_step_bound(arrays, settings)
    if not settings.contacts or arrays.n_blocks < 2 or bound is None:
        return None
    reach = settings.max_displacement_ratio * model_half_height(arrays.vertex_position)
    if settings.dt <= 10.0 * bound:
        return None
    return (f"dt = {settings.dt:.3g} s is far too large for this contact model: a block falling from rest moves "
            f"g2·w0 = {reach:.3g} m (the most a step may move) in {bound:.3g} s; steps will be cut until Δt is "
            f"near that. Give dt ≤ {bound:.2g} s (or raise max_displacement_ratio)")


def default_terms(arrays: ModelArrays, settings: RunSettings, contact_law: ContactLaw | None = None) -> list[Term]:
    """The terms of a run of ``arrays`` under ``settings``, in assembly order (docs/architecture.md).

    Inertia, elasticity, initial stress and body force; the model's point
    terms (fixed points, loads, springs, hinges, driven points, base
    acceleration, bolts); the gyroscopic term of 3D blocks under the methods
    that have it; contacts (with ``contact_law``, Mohr-Coulomb by default)
    when the settings ask for them and some block may touch another.
    """
    method = settings.resolved_method()
    terms: list[Term] = [*block_terms(), *point_terms(arrays, settings.penalty)]
    bt = arrays.block_type
    if method.gyroscopic and bt.rotation.stop - bt.rotation.start > 1:  # rotations about several axes
        terms.append(GyroscopicTerm(settings.secant_tolerance))
    if settings.contacts and arrays.n_blocks > 1:
        w0 = model_half_height(arrays.vertex_position)
        newton = settings.contact_solver == "newton"
        if not np.all(np.isnan(arrays.joints.restitution)) and not method.scheme.is_shi:
            # the impact law's dashpot is calibrated to Shi's step
            raise ModelError("joint restitution needs Shi's time step (scheme 'shi', or 'paper' at rho_inf = 1); "
                             f"this run has scheme {method.scheme.name!r}, rho_inf = {method.scheme.rho_inf:g} "
                             "(docs/contacts.md, \"Impacts and restitution\")")
        model = (NewtonContactModel if newton else ContactModel)(arrays, contact_parameters(arrays, settings, w0),
                                                                 contact_law)
        if np.any(model.can_touch):
            cap = settings.newton_max_iterations if newton else settings.open_close_max_iterations
            terms.append((NewtonContactTerm if newton else ContactTerm)(model, cap, settings.max_displacement_ratio * w0,
                                                                       settings.dt))
    return terms


class Stepper:
    """The terms of a run and the step that loops over them."""

    def __init__(self, arrays: ModelArrays, settings: RunSettings, solver: LinearSolver,
                 terms: Sequence[Term] | None = None) -> None:
        """``terms``: the step's terms (default: :func:`default_terms`)."""
        self.arrays = arrays
        self.settings = settings
        self.method: Method = settings.resolved_method()
        self.solver = solver
        self.terms: list[Term] = list(terms) if terms is not None else default_terms(arrays, settings)
        self.secant = SecantPass(settings.secant_tolerance, settings.secant_max_iterations)
        self.keeps_springs = takes_springs(solver, arrays.n_blocks)  # the solver applies the contact springs

    def begin(self, state: State, dt: float) -> tuple[StepContext, list[Term]]:
        """The context of a step attempt from ``state`` and the terms that take part, each begun."""
        method = self.method
        coeffs = method.scheme.coefficients(dt)
        ctx = StepContext(self.arrays, state, method, coeffs, dt, state.time + coeffs.load_time_fraction * dt)
        terms = list(self.terms)
        for term in terms:
            term.begin(ctx)
        if method.linearization == "secant" and any(t.at_points for t in terms):
            terms.append(self.secant)
            self.secant.begin(ctx)
        return ctx, terms

    def assemble(self, ctx: StepContext, terms: list[Term], base: BlockSystem | None = None) -> BlockSystem:
        """The step's system: ``base`` (the terms that are the same every solve) plus the others; fixed blocks held.

        Without ``base`` every term is added.
        """
        if base is None:
            system = BlockSystem.empty(self.arrays.n_blocks, self.arrays.block_type.ndof)
            added = terms
        else:
            system = BlockSystem(base.diag.copy(), base.rhs.copy())
            added = [t for t in terms if not t.same_every_solve]
        system.keeps_springs = self.keeps_springs
        for term in added:
            term.add_to(system, ctx)
        system.fix_blocks(self.arrays.block_fixed)
        return system

    def base_system(self, ctx: StepContext, terms: list[Term]) -> BlockSystem:
        """The sum of the terms that add the same to every solve of the step."""
        system = BlockSystem.empty(self.arrays.n_blocks, self.arrays.block_type.ndof)
        for term in terms:
            if term.same_every_solve:
                term.add_to(system, ctx)
        return system

    def step(self, state: State, dt: float) -> StepOutcome:
        """One step of Δt = ``dt`` from ``state`` (module doc)."""
        s = self.settings
        ctx, terms = self.begin(state, dt)
        label = f"step {state.step + 1}"
        ndof = self.arrays.block_type.ndof
        base = self.base_system(ctx, terms)
        solves = 0
        changes = 0  # solves after which a step-cutting term (open-close) had not settled
        searching = [t for t in terms if t.line_search]
        before: np.ndarray | None = None  # the last iterate (increments then multipliers) of a line search
        while True:
            system = self.assemble(ctx, terms, base)
            tolerance = None  # an iterative backend's own, unless a Newton iteration asks for a looser one
            if searching and solves_inexactly(self.solver, system):
                tolerance = min(t.solve_tolerance(s.solver_tolerance) for t in searching)
            try:
                rhs = system.full_rhs()
                solution = self.solver.solve(system, rhs) if tolerance is None else \
                    self.solver.solve(system, rhs, tolerance)
            except SolverError as exc:
                return StepOutcome("diverged", solves, dt, reason=f"{label}: {exc}")
            if searching:  # Newton: from the last iterate (zero increments at first) towards the solution
                before = np.zeros_like(solution) if before is None else before
                delta = solution - before
                blocks = delta[: system.size].reshape(-1, ndof)
                alpha = min(t.step_length(before[: system.size].reshape(-1, ndof), blocks,
                                          lambda: system.quadratic_form(blocks)) for t in searching)
                solution = before + alpha * delta
                before = solution
            dd = solution[: system.size].reshape(-1, ndof)
            multipliers = solution[system.size:]
            solves += 1
            pending = [t for t in terms if not t.converged(dd, ctx)]
            cutting = [t for t in pending if t.cuts_step]
            if cutting:
                changes += 1
                if changes >= min(t.max_iterations for t in cutting):
                    return StepOutcome("cut", solves, dt * s.step_cut_factor,
                                       reason=f"{label}: {cutting[0].pending()} in {solves} solves", cause="iteration")
            elif all(solves - changes >= t.max_iterations for t in pending):
                break
        new, damped = self._update(ctx, dd, multipliers)
        if not (np.all(np.isfinite(new.vertices)) and np.all(np.isfinite(new.velocity))):
            return StepOutcome("diverged", solves, dt, reason=f"step {new.step}: non-finite displacement or velocity")
        bounds = []  # the largest Δt each term allows for the next step
        for term in terms:
            verdict = term.review(ctx, new)
            if isinstance(verdict, StepCut):
                return StepOutcome("cut", solves, dt * max(s.step_cut_factor, verdict.factor),
                                   reason=f"step {new.step}: {verdict.reason}", cause=verdict.cause)
            if verdict is not None:
                bounds.append(verdict)
        dt_next = min(bounds) if bounds else dt
        work = [w for w in (t.work(ctx, new, dd, multipliers) for t in terms) if w is not None]
        if damped:
            damping = np.zeros(len(LEDGER))
            damping[LEDGER.index("dissipated_damping")] = damped
            work.append(damping)
        if work:
            new = replace(new, ledger=state.ledger + np.sum(work, axis=0))
        for term in terms:
            new = term.commit(new)
        return StepOutcome("accepted", solves, dt_next, new)

    def _update(self, ctx: StepContext, dd: np.ndarray, multipliers: np.ndarray) -> tuple[State, float]:
        """The state at t + Δt from the increments ``dd`` (the method's kinematics and stress update), and the
        kinetic energy the velocities' scaling by ``velocity_ratio`` r took out: (1 − r²)·½v*ᵀMv* of the
        scheme's velocity v* at t + Δt (J, per m in 2D; 0 for r = 1)."""
        arrays, state, method, c = ctx.arrays, ctx.state, ctx.method, ctx.coeffs
        bt = arrays.block_type
        V, A = state.velocity, state.acceleration
        ratio = self.settings.velocity_ratio
        scheme_v = c.v_d * dd + c.v_v * V + c.v_a * A  # the scheme's velocity at t + Δt, before the scaling
        new_v = ratio * scheme_v
        new_a = ratio * (c.a_d * dd + c.a_v * V + c.a_a * A)
        centroid = state.moments.centroid
        owner = arrays.vertex_block
        vertices = state.vertices + bt.point_displacement(state.vertices - centroid[owner], dd[owner],
                                                          method.kinematics)
        pb = arrays.attached.point_block
        points = state.points + bt.point_displacement(state.points - centroid[pb], dd[pb], method.kinematics)
        s = bt.strain
        stress = state.stress + np.einsum("nij,nj->ni", arrays.block_elasticity, dd[:, s])
        if method.objective_stress:
            stress = bt.rotate_symmetric(stress, dd, 1.0)
            new_v[:, s] = bt.rotate_symmetric(new_v[:, s], dd, 2.0)
            new_a[:, s] = bt.rotate_symmetric(new_a[:, s], dd, 2.0)
        new = State(state.step + 1, state.time + ctx.dt, vertices, points, new_v, new_a, stress,
                    bt.compose_rotation(state.rotation, dd), arrays.moments(vertices), multipliers, state.ledger)
        if ratio == 1.0:
            return new, 0.0
        if method.objective_stress:
            scheme_v[:, s] = bt.rotate_symmetric(scheme_v[:, s], dd, 2.0)
        kinetic = 0.5 * float(np.einsum("ni,nij,nj->", scheme_v, mass_matrices(arrays, new), scheme_v))
        return new, (1.0 - ratio**2) * kinetic
