"""The time loop: ``run(model, settings)`` is a pure function of its inputs.

One step (paper Eqs. 60-70 or Shi 1988):

1. block integrals of the configuration at t (exact polygon moments);
2. block matrices: inertia M = ρ∫TᵀT, elasticity K = A·BᵀDB, initial stress
   -A·σ, body force ρ·A·g; scheme coefficients turn them into the effective
   matrix and right-hand side (:mod:`srdda.integrators.schemes`);
3. point terms (fixed points, point springs, point loads) with the shape
   function of the method's linearisation; assembly; sparse solve;
4. for the ``secant`` linearisation, repeat 3 with the new rotation increment
   until it stops changing;
5. velocity/acceleration update, point update by the method's kinematics,
   stress update.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np

from .assembly.system import BlockSystem, PenaltyPairs, add_penalty_pairs
from .constraints import LEDGER, link_energy, step_terms, step_work
from .contact.term import ContactModel, ContactParameters, ContactSet
from .geometry.polygon import BlockMoments
from .integrators.methods import Method, method_preset
from .integrators.schemes import SchemeCoefficients
from .kinematics.shape import NDOF, block_mass_matrix
from .kinematics.update import point_displacement, rotate_symmetric_components, secant_shape_function
from .model import Model, ModelArrays
from .solvers import LinearSolver, SolverError, get_solver

__all__ = ["RunSettings", "State", "Result", "DivergenceError", "StepRejected", "StepControl", "StepContext",
           "StepTerm", "Recorder",
           "run", "initial_state", "advance", "energies"]


class DivergenceError(RuntimeError):
    """The run produced non-finite values or an unbounded response."""


class StepRejected(RuntimeError):
    """A step must be repeated with Δt × ``factor`` (open-close not converged, too large a step)."""

    def __init__(self, message: str, factor: float = 1.0 / 3.0) -> None:
        super().__init__(message)
        self.factor = factor


@dataclass(frozen=True)
class RunSettings:
    """How to run a model. Times in s, stiffness in N/m."""

    dt: float
    n_steps: int
    method: str = "srdda"
    rho_inf: float = 1.0
    scheme: str | None = None  # override the method's time scheme
    linearization: str | None = None  # override the method's linearisation
    penalty: float = 1e9  # default stiffness of fixed points (N/m)
    solver: str = "auto"
    # The secant loop stops when |Δθ|·|δθ| (δθ: change of the rotation increment between two solves)
    # is below this: the mismatch between the linearised and the exact rotation displacement of a
    # point, per metre of lever arm, is about half of it.
    secant_tolerance: float = 1e-13
    secant_max_iterations: int = 8
    # Shi's dynamic ratio k01: velocities and accelerations are multiplied by it after every
    # step. 1 = dynamic; 0 = Shi's static analysis (each step starts at rest).
    velocity_ratio: float = 1.0
    record_every: int = 1
    # contacts and step control (docs/contacts.md); lengths relative to w0 = half the model height
    contacts: bool = True  # detect and resolve block contacts
    contact_penalty: float | None = None  # normal contact stiffness k_n (N/m); None: ``penalty``
    auto_penalty: float | None = None  # if set, k_n = auto_penalty × the largest Young's modulus × 1 m
    shear_ratio: float = 0.4  # k_s / k_n
    max_displacement_ratio: float = 0.01  # g2: largest vertex displacement of a step / w0
    contact_distance_factor: float = 2.5  # d0 = factor × g2 × w0 (two vertices closing at g2·w0 each)
    contact_angle_tolerance: float = 3.0  # degrees, Shi's angle criterion
    penetration_fraction: float = 0.4  # a step that penetrates deeper than this × d0 is cut
    open_close_max_iterations: int = 20  # state-changing solves of a step before it is cut and repeated
    friction_tolerance: float = 1e-3  # relative settling of a sliding contact's normal force
    open_close_freeze_after: int = 2  # state changes of one contact in a step after which it is held
    open_close_settle_after: int = 8  # solves after which contacts may only close, open clearly or slip
    step_cut_factor: float = 1.0 / 3.0  # Δt ← factor·Δt when a step is cut
    min_dt: float | None = None  # the run stops if Δt falls below this; None: 1e-6 × dt

    def __post_init__(self) -> None:
        if not self.dt > 0:
            raise ValueError(f"dt must be > 0, got {self.dt}")
        if self.n_steps < 0:
            raise ValueError(f"n_steps must be >= 0, got {self.n_steps}")
        if self.record_every < 1:
            raise ValueError("record_every must be >= 1")
        if not self.penalty > 0:
            raise ValueError("penalty must be > 0")
        if not 0.0 <= self.velocity_ratio <= 1.0:
            raise ValueError(f"velocity_ratio must lie in [0, 1], got {self.velocity_ratio}")
        for name in ("contact_penalty", "auto_penalty", "min_dt"):
            value = getattr(self, name)
            if value is not None and not value > 0:
                raise ValueError(f"{name} must be > 0, got {value}")
        for name in ("shear_ratio", "max_displacement_ratio", "contact_distance_factor", "penetration_fraction"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")
        if not 0.0 <= self.contact_angle_tolerance < 45.0:
            raise ValueError(f"contact_angle_tolerance must lie in [0, 45) degrees, got {self.contact_angle_tolerance}")
        for name in ("open_close_max_iterations", "open_close_freeze_after", "open_close_settle_after"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if not self.friction_tolerance > 0:
            raise ValueError(f"friction_tolerance must be > 0, got {self.friction_tolerance}")
        if not 0.0 < self.step_cut_factor < 1.0:
            raise ValueError(f"step_cut_factor must lie in (0, 1), got {self.step_cut_factor}")
        self.resolved_method()

    def resolved_method(self) -> Method:
        return method_preset(self.method, self.rho_inf, self.scheme, self.linearization)


@dataclass(frozen=True)
class State:
    """Everything that changes over a run, at one instant."""

    step: int
    time: float
    vertices: np.ndarray  # (nv, 2)
    points: np.ndarray  # (np, 2) block-attached points
    velocity: np.ndarray  # (nb, 6) generalized velocity
    acceleration: np.ndarray  # (nb, 6)
    stress: np.ndarray  # (nb, 3)
    rotation: np.ndarray  # (nb,) accumulated rotation (rad)
    moments: BlockMoments  # block integrals of ``vertices``, computed once per state
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0))  # μ of the last step (constraint rows)
    ledger: np.ndarray = field(default_factory=lambda: np.zeros(len(LEDGER)))  # cumulative work, see LEDGER
    contacts: ContactSet | None = None  # contacts as the step that led here ended them
    dt_next: float | None = None  # the step-size control's Δt for the next step (None: the run's dt)


class Recorder(Protocol):
    """Receives the recorded steps of a run (in memory, to a file, ...)."""

    def record(self, arrays: ModelArrays, state: State, penalty: float, solves: int) -> None: ...

    def finish(self, status: str, state: State) -> None: ...


@dataclass
class Result:
    """Recorded histories of a run (rows = recorded steps) and how it ended; the in-memory recorder."""

    block_names: tuple[str, ...]
    method: str
    step: list[int] = field(default_factory=list)
    time: list[float] = field(default_factory=list)
    centroid: list[np.ndarray] = field(default_factory=list)
    area: list[np.ndarray] = field(default_factory=list)
    rotation: list[np.ndarray] = field(default_factory=list)
    velocity: list[np.ndarray] = field(default_factory=list)
    stress: list[np.ndarray] = field(default_factory=list)
    measured_position: list[np.ndarray] = field(default_factory=list)
    measured_velocity: list[np.ndarray] = field(default_factory=list)
    energy: list[dict[str, float]] = field(default_factory=list)
    iterations: list[int] = field(default_factory=list)
    multipliers: list[np.ndarray] = field(default_factory=list)  # μ per step; force on point a = -μ (N/m)
    closed_contacts: list[int] = field(default_factory=list)  # closed (sliding or locked) contacts
    max_penetration: list[float] = field(default_factory=list)  # deepest closed contact (m)
    status: str = "running"
    final_state: State | None = None

    def array(self, name: str) -> np.ndarray:
        """A history as one array (first axis = recorded step)."""
        if name == "energy":
            keys = self.energy[0].keys() if self.energy else []
            return np.array([[e[k] for k in keys] for e in self.energy])
        return np.asarray(getattr(self, name))

    @property
    def completed(self) -> bool:
        return self.status == "completed"

    def record(self, arrays: ModelArrays, state: State, penalty: float, solves: int) -> None:
        """Append one step's histories."""
        mom = state.moments
        self.step.append(state.step)
        self.time.append(state.time)
        self.centroid.append(mom.centroid)
        self.area.append(mom.area)
        self.rotation.append(state.rotation.copy())
        self.velocity.append(state.velocity.copy())
        self.stress.append(state.stress.copy())
        pos, vel = measured_points(arrays, state)
        self.measured_position.append(pos)
        self.measured_velocity.append(vel)
        self.energy.append(energies(arrays, state, penalty))
        self.iterations.append(solves)
        self.multipliers.append(state.multipliers.copy())
        contacts = state.contacts
        self.closed_contacts.append(0 if contacts is None else int(np.count_nonzero(contacts.closed)))
        self.max_penetration.append(0.0 if contacts is None else contacts.max_penetration)

    def finish(self, status: str, state: State) -> None:
        self.status = status
        self.final_state = state


@dataclass
class StepContext:
    """What a step term needs to add itself to the system of one step.

    ``theta`` is the rotation increment per block that the method linearises
    about (None: Shi's T at t; else the secant T_sec, see
    :mod:`srdda.kinematics.update`); it changes between iterations of a step.
    """

    arrays: ModelArrays
    state: State
    method: Method
    coeffs: SchemeCoefficients
    dt: float
    t_load: float
    penalty: float
    theta: np.ndarray | None = None

    def shape_at(self, blocks: np.ndarray, positions: np.ndarray) -> np.ndarray:
        """Shape functions (n, 2, 6) of points at ``positions`` (config. at t) of ``blocks``."""
        lever = positions - self.state.moments.centroid[blocks]
        return secant_shape_function(lever, None if self.theta is None else self.theta[blocks])


class StepTerm(Protocol):
    """A contribution to each step's system (contacts, constraints, ...).

    ``add_to`` adds matrices and forces; ``converged`` is asked after each
    solve and may update internal states (e.g. open-close), returning False
    to request another solve of the same step. A term whose ``cuts_step`` is
    True (contacts) has the step cut and repeated when it has not converged
    within the open-close cap; the others only ask for more solves.
    """

    cuts_step: bool

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None: ...

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool: ...


def initial_state(arrays: ModelArrays, method: Method) -> State:
    """The state at t = 0; the acceleration solves M·A = F(0) block by block."""
    mom = arrays.moments(arrays.vertices)
    M = arrays.density[:, None, None] * block_mass_matrix(mom.area, mom.sxx, mom.syy, mom.sxy)
    force = np.zeros((arrays.n_blocks, NDOF))
    force[:, :2] = (arrays.density * mom.area)[:, None] * arrays.gravity
    force[:, 3:] = -mom.area[:, None] * arrays.stress
    acc = np.zeros_like(force)
    massive = arrays.density > 0
    if np.any(massive):
        acc[massive] = np.linalg.solve(M[massive], force[massive][..., None])[..., 0]
    if method.scheme.name == "shi":
        acc[:] = 0.0
    acc[arrays.block_fixed] = 0.0
    velocity = arrays.velocity.copy()
    velocity[arrays.block_fixed] = 0.0
    return State(0, 0.0, arrays.vertices.copy(), arrays.points.copy(), velocity, acc,
                 arrays.stress.copy(), np.zeros(arrays.n_blocks), mom, np.zeros(arrays.links.n_multipliers))


def _point_terms(arrays: ModelArrays, state: State, lever: np.ndarray, theta: np.ndarray | None,
                 coeffs: SchemeCoefficients, penalty: float, t_load: float, system: BlockSystem) -> None:
    """Fixed points, point springs and point loads with T (or T_sec at θ)."""
    T = secant_shape_function(lever, None if theta is None else theta[arrays.point_block])
    fr = arrays.fixed_rows
    if len(fr):
        k = np.where(np.isnan(arrays.fixed_stiffness), penalty, arrays.fixed_stiffness)
        gap = state.points[fr] - arrays.points[fr]  # pull back to the original position
        add_penalty_pairs(system, PenaltyPairs(arrays.fixed_block, T[fr], np.full(len(fr), -1), None, gap, k),
                          coeffs.c_p)
    ra, rb = arrays.spring_rows_a, arrays.spring_rows_b
    if len(ra):
        gap = state.points[ra] - state.points[rb]
        add_penalty_pairs(system, PenaltyPairs(arrays.point_block[ra], T[ra], arrays.point_block[rb], T[rb], gap,
                                               arrays.spring_stiffness), coeffs.c_p)
    lr = arrays.load_rows
    if len(lr):
        forces = np.array([ld(t_load) for ld in arrays.loads])
        np.add.at(system.rhs, arrays.point_block[lr], np.einsum("nki,nk->ni", T[lr], forces))


def advance(arrays: ModelArrays, state: State, method: Method, dt: float, penalty: float,
            solver: LinearSolver, secant_tolerance: float = 1e-13, secant_max_iterations: int = 8,
            terms: Sequence[StepTerm] = (), term_max_iterations: int = 20,
            velocity_ratio: float = 1.0) -> tuple[State, int]:
    """One time step from ``state``; returns the new state and the number of solves.

    The model's hinges, pins, springs, driven points and base acceleration
    (:func:`srdda.constraints.step_terms`) come before ``terms``.
    ``term_max_iterations`` caps the solves after which the contacts' open-close
    still changes its assumptions: reaching it raises :class:`StepRejected`.
    """
    terms = [*step_terms(arrays), *terms]
    coeffs = method.scheme.coefficients(dt)
    mom = state.moments
    area = mom.area
    M = arrays.density[:, None, None] * block_mass_matrix(area, mom.sxx, mom.syy, mom.sxy)
    V, A = state.velocity, state.acceleration
    diag = coeffs.c_m * M
    diag[:, 3:, 3:] += coeffs.c_k * area[:, None, None] * arrays.elasticity
    rhs = np.einsum("nij,nj->ni", M, coeffs.m_v * V + coeffs.m_a * A)
    if coeffs.k_v or coeffs.k_a:
        strain_rate = coeffs.k_v * V[:, 3:] + coeffs.k_a * A[:, 3:]
        rhs[:, 3:] += area[:, None] * np.einsum("nij,nj->ni", arrays.elasticity, strain_rate)
    rhs[:, 3:] -= area[:, None] * state.stress
    rhs[:, :2] += (arrays.density * area)[:, None] * arrays.gravity

    lever = state.points - mom.centroid[arrays.point_block]
    has_point_terms = len(arrays.points) > 0 and (
        len(arrays.fixed_rows) + len(arrays.spring_rows_a) + len(arrays.load_rows) > 0)
    secant = method.linearization == "secant" and (has_point_terms or len(terms) > 0)
    ctx = StepContext(arrays, state, method, coeffs, dt, state.time + coeffs.load_time_fraction * dt, penalty,
                      dt * V[:, 2] if secant else None)
    solves = 0
    changes = 0  # solves after which a term (open-close) changed its assumptions
    while True:
        system = BlockSystem(diag.copy(), rhs.copy())
        if has_point_terms:
            _point_terms(arrays, state, lever, ctx.theta, coeffs, penalty, ctx.t_load, system)
        for term in terms:
            term.add_to(system, ctx)
        system.fix_blocks(arrays.block_fixed)
        try:
            solution = solver.solve(system, system.full_rhs())
        except SolverError as exc:
            raise DivergenceError(f"step {state.step + 1}: {exc}") from exc
        dd = solution[: system.size].reshape(-1, NDOF)
        multipliers = solution[system.size:]
        solves += 1
        flags = [term.converged(dd, ctx) for term in terms]
        terms_done = all(flags)
        contacts_pending = any(not ok for term, ok in zip(terms, flags) if term.cuts_step)
        if contacts_pending:
            changes += 1
            if changes >= term_max_iterations:
                raise StepRejected(f"step {state.step + 1}: open-close did not converge in {solves} solves")
        done = terms_done
        if secant:
            mismatch = np.max(np.abs(dd[:, 2] - ctx.theta) * np.abs(dd[:, 2]))
            ctx.theta = dd[:, 2].copy()
            done = done and mismatch <= secant_tolerance
        if done or (not contacts_pending and solves >= secant_max_iterations + changes):
            break

    new_v = velocity_ratio * (coeffs.v_d * dd + coeffs.v_v * V + coeffs.v_a * A)
    new_a = velocity_ratio * (coeffs.a_d * dd + coeffs.a_v * V + coeffs.a_a * A)
    owner_v = arrays.vertex_block
    vlever = state.vertices - mom.centroid[owner_v]
    vertices = state.vertices + point_displacement(vlever, dd[owner_v], method.kinematics)
    points = state.points + point_displacement(lever, dd[arrays.point_block], method.kinematics)
    stress = state.stress + np.einsum("nij,nj->ni", arrays.elasticity, dd[:, 3:])
    if method.objective_stress:
        stress = rotate_symmetric_components(stress, dd[:, 2], 1.0)
        new_v[:, 3:] = rotate_symmetric_components(new_v[:, 3:], dd[:, 2], 2.0)
        new_a[:, 3:] = rotate_symmetric_components(new_a[:, 3:], dd[:, 2], 2.0)
    new_state = State(state.step + 1, state.time + dt, vertices, points, new_v, new_a, stress,
                      state.rotation + dd[:, 2], arrays.moments(vertices), multipliers, state.ledger)
    if arrays.links.active or len(arrays.load_rows):
        new_state = replace(new_state, ledger=state.ledger + step_work(arrays, state, new_state, dd, multipliers,
                                                                       ctx.t_load, dt, penalty))
    if not (np.all(np.isfinite(vertices)) and np.all(np.isfinite(new_v))):
        raise DivergenceError(f"step {new_state.step}: non-finite displacement or velocity")
    return new_state, solves


def energies(arrays: ModelArrays, state: State, penalty: float) -> dict[str, float]:
    """Kinetic, gravitational, elastic strain and spring/penalty energy (J per m thickness)."""
    mom = state.moments
    M = arrays.density[:, None, None] * block_mass_matrix(mom.area, mom.sxx, mom.syy, mom.sxy)
    V = state.velocity
    kinetic = 0.5 * float(np.einsum("ni,nij,nj->", V, M, V))
    gravity = -float(np.sum(arrays.density * mom.area * (mom.centroid @ arrays.gravity)))
    ds = state.stress - arrays.stress
    elastic = 0.5 * float(np.sum(mom.area * np.einsum("ni,nij,nj->n", ds, arrays.compliance, ds)))
    spring = 0.0
    fr = arrays.fixed_rows
    if len(fr):
        k = np.where(np.isnan(arrays.fixed_stiffness), penalty, arrays.fixed_stiffness)
        spring += 0.5 * float(np.sum(k * np.sum((state.points[fr] - arrays.points[fr]) ** 2, axis=1)))
    if len(arrays.spring_rows_a):
        gap = state.points[arrays.spring_rows_a] - state.points[arrays.spring_rows_b]
        spring += 0.5 * float(np.sum(arrays.spring_stiffness * np.sum(gap**2, axis=1)))
    spring += link_energy(arrays, state, penalty)
    contact = state.contacts.energy if state.contacts is not None else 0.0
    total = kinetic + gravity + elastic + spring + contact
    out = {"kinetic": kinetic, "gravity": gravity, "elastic": elastic, "spring": spring, "contact": contact,
           "total": total}
    out.update(zip(LEDGER, map(float, state.ledger)))
    out["balance"] = total - out["work_loads"] - out["work_prescribed"] - out["work_constraints"] + out["dissipated"]
    return out


def measured_points(arrays: ModelArrays, state: State) -> tuple[np.ndarray, np.ndarray]:
    """Positions and velocities (n, 2) of the measured points."""
    mr = arrays.measured_rows
    blocks = arrays.point_block[mr]
    lever = state.points[mr] - state.moments.centroid[blocks]
    T = secant_shape_function(lever, None)
    return state.points[mr].copy(), np.einsum("nij,nj->ni", T, state.velocity[blocks])


def run(model: Model | ModelArrays, settings: RunSettings, progress: Callable[[int], None] | None = None,
        state: State | None = None, recorders: Sequence[Recorder] = ()) -> Result:
    """Run ``settings.n_steps`` steps of ``model``; pure (no global state).

    Steps are recorded every ``settings.record_every`` steps (and the first and
    last) into the returned :class:`Result` and every extra ``recorders``. A
    step that fails (singular system, non-finite values) ends the run with
    ``result.status`` saying why; every step before it stays recorded.
    """
    arrays = model.arrays() if isinstance(model, Model) else model
    method = settings.resolved_method()
    solver = get_solver(settings.solver)
    state = state if state is not None else initial_state(arrays, method)
    result = Result(arrays.block_names, method.name)
    sinks: list[Recorder] = [result, *recorders]
    for sink in sinks:
        sink.record(arrays, state, settings.penalty, 0)
    control = StepControl.of(arrays, settings)
    last_step = state.step + settings.n_steps
    status = "completed"
    dt = state.dt_next if state.dt_next is not None else settings.dt
    while state.step < last_step:
        try:
            state, solves, dt = control.step(arrays, state, method, dt, solver)
            state = replace(state, dt_next=dt)
        except StepRejected as exc:
            dt *= exc.factor
            if dt < control.min_dt:
                status = f"stopped: {exc}; the time step {dt:.3g} s fell below the minimum {control.min_dt:.3g} s"
                break
            continue
        except DivergenceError as exc:
            status = f"diverged: {exc}"
            break
        if state.step % settings.record_every == 0 or state.step == last_step:
            for sink in sinks:
                sink.record(arrays, state, settings.penalty, solves)
        if progress is not None:
            progress(state.step)
    for sink in sinks:
        sink.finish(status, state)
    return result


def model_half_height(vertices: np.ndarray) -> float:
    """w0: half the height of the model (half its width if it is flat), Shi's length scale."""
    extent = np.ptp(vertices, axis=0)
    return 0.5 * float(extent[1] if extent[1] > 0 else extent[0])


def contact_parameters(arrays: ModelArrays, settings: RunSettings, w0: float) -> ContactParameters:
    """Contact stiffnesses and distances of a run (docs/contacts.md)."""
    kn = settings.contact_penalty if settings.contact_penalty is not None else settings.penalty
    if settings.auto_penalty is not None:
        young = 1.0 / arrays.compliance[:, 0, 0]  # E in plane stress, E/(1-ν²) in plane strain
        kn = settings.auto_penalty * float(np.max(young)) * 1.0  # × unit thickness
    d0 = settings.contact_distance_factor * settings.max_displacement_ratio * w0
    return ContactParameters(kn, settings.shear_ratio * kn, d0, np.radians(settings.contact_angle_tolerance),
                             settings.penetration_fraction * d0, settings.friction_tolerance,
                             settings.open_close_freeze_after, settings.open_close_settle_after)


@dataclass(frozen=True)
class StepControl:
    """One accepted step: contacts, the displacement-ratio check, Δt for the next step (Shi 1988).

    Without contacts (one block, or ``contacts=False``) a step is never cut:
    the displacement ratio g2 only bounds how far a vertex may travel between
    two contact detections.
    """

    settings: RunSettings
    max_displacement: float  # g2·w0
    min_dt: float
    contacts: ContactModel | None

    @staticmethod
    def of(arrays: ModelArrays, settings: RunSettings) -> StepControl:
        w0 = model_half_height(arrays.vertices)
        contacts = None
        if settings.contacts and arrays.n_blocks > 1:
            contacts = ContactModel(arrays, contact_parameters(arrays, settings, w0))
        min_dt = settings.min_dt if settings.min_dt is not None else 1e-6 * settings.dt
        return StepControl(settings, settings.max_displacement_ratio * w0, min_dt, contacts)

    def step(self, arrays: ModelArrays, state: State, method: Method, dt: float,
             solver: LinearSolver) -> tuple[State, int, float]:
        """(new state, solves, Δt for the next step); :class:`StepRejected` if Δt must be cut."""
        s = self.settings
        term = None
        if self.contacts is not None:
            term = self.contacts.prepare(state.vertices, state.contacts, state.step == 0)
        terms: list[StepTerm] = [term] if term is not None else []
        try:
            new, solves = advance(arrays, state, method, dt, s.penalty, solver, s.secant_tolerance,
                                  s.secant_max_iterations, terms, s.open_close_max_iterations, s.velocity_ratio)
        except StepRejected as exc:
            raise StepRejected(str(exc), s.step_cut_factor) from exc
        if self.contacts is None:  # g2 exists to keep contacts detectable (d0 = 2.5·g2·w0)
            return new, solves, dt
        moved = float(np.max(np.hypot(*(new.vertices - state.vertices).T)))
        if moved > self.max_displacement:
            raise StepRejected(f"step {new.step}: a vertex moved {moved:.3g} m > g2·w0 = "
                               f"{self.max_displacement:.3g} m",
                               max(s.step_cut_factor, min(0.9, 0.9 * self.max_displacement / moved)))
        if term is not None and term.max_penetration > term.params.max_penetration:
            raise StepRejected(f"step {new.step}: penetration {term.max_penetration:.3g} m > "
                               f"{term.params.max_penetration:.3g} m (raise the contact penalty)", s.step_cut_factor)
        # grow Δt back towards the set value, at most ×1.5, aiming at 90% of g2·w0 for the next step
        growth = 1.5 if moved == 0 else min(1.5, 0.9 * self.max_displacement / moved)
        next_dt = min(s.dt, dt * growth)
        return replace(new, contacts=term.commit() if term is not None else None), solves, next_dt


def with_steps(settings: RunSettings, n_steps: int) -> RunSettings:
    """A copy of ``settings`` with another number of steps."""
    return replace(settings, n_steps=n_steps)
