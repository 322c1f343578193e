"""The step's contact problem solved as one complementarity problem: Newton's method with a line search.

With the contacts' penalty springs as their compliance, a step of the
implicit DDA step equation A·Δd = F (every other term: inertia, elasticity,
loads, springs, constraints) with contacts is the minimum of the step's
incremental potential (docs/contacts.md, *The contact solve*)

    Π(Δd) = ½ Δdᵀ A Δd − Fᵀ Δd + Σ_c [ ψ_n(g_c)/c_p + ψ_s(s_c)/c_p ],
    g_c = g_0' + c_p n·(T_a Δd_a − T_b Δd_b),   s_c = s_e0 + c_p E·(T_a(r_a) Δd_a − T_b(r_b) Δd_b),

c_p the scheme's penalty weight, g_0' the start gap of the step force (the
gap at t, c_p·g_0 where the contact was open at t:
:meth:`~srdda.contact.pipeline.ContactStep.start_gap`), over the feasible set
of the constraint rows. ψ_n(g) = ½k_n·g² while the contact is compressed (or bonded, up to its
tensile strength T: beyond, T·g), else 0;
ψ_s is an elastic-perfectly plastic shear spring with the yield force τ =
tan φ·N* + c·A (Tresca: N* the normal force of the last iterate, updated
until it settles): ½k_s|s|² within τ/k_s, τ|s| − τ²/(2k_s) beyond (the
spring's plastic slip is the part of s beyond τ/k_s, its dissipation τ·|slip|).
Π is convex and once differentiable, so its minimum is the solution and
Newton's method with a line search on Π reaches it:

* each iterate assembles the contacts' linear model at the last iterate
  (the active set: normal springs of the closed contacts, shear springs of
  the sticking ones, the yield force τ·ŝ and, in 3D, the consistent tangent
  (τ/|s|)(I − ŝŝᵀ) of the slipping ones) and the step solves the system;
* the step length α along δ = Δd* − Δd_k is the full step where it
  decreases Π enough (Armijo), else the backtracked one: Π(α) − Π(0) is
  (½α² − α)·δᵀHδ plus, contact by contact, the true springs' potentials
  less the linear model's, so a line search costs one block quadratic
  form and passes over the contacts, no solve. A direction that climbs Π
  is not taken (the iterate stays, the next model is its own states): so Π
  falls at every step taken and the iterates cannot cycle. A damped step stops short
  of where a spring takes hold: the next model has the springs that act at
  the full step already, and sticks the shear springs whose shear passes
  through their elastic range on the way (a slip that turns back);
* N* of the yield forces stays fixed while the active set settles (each
  such problem is convex), then, once at most 5 % of the contacts still
  change state (``NEARLY_SETTLED``), follows the solved normal forces: once,
  and again while the Tresca lag Σ|N − N*| / ΣN over the contacts whose
  friction is at its strength (or would be) exceeds ``friction_tolerance``,
  ``NORMAL_UPDATES`` times at most (each update restarts the active set's
  settling; a single update left lags of 9-13 % in the first steps of the
  3D slope and the brick wall, docs/dev/contact-solve.md);
  a contact new in the step sticks until a solve gave it a normal force
  (Shi: a contact that closes locks first);
* the passes over the contacts at an iterate (the springs' forces and
  potentials, their states) are compiled loops, one each;
* with an iterative backend the solves are inexact while the active set
  still moves: while more than ``MOVING`` (1 %) of the contacts changed
  state at the last iterate, a solve stops at ``INEXACT_FORCING`` × the last
  iterate's largest change instead of the run's ``solver_tolerance`` (the
  next model differs anyway), and the step ends with a solve at that
  tolerance (Eisenstat and Walker's forcing terms, on the active set's
  progress instead of the residual's);
* it has converged when the full step was taken, every contact's yield
  force came from a normal force, no contact changed state by more than the
  negligible force, and, unless N* was updated ``NORMAL_UPDATES`` times, no
  sliding contact's normal force (nor a sticking one's strength) moved by
  more than ``friction_tolerance`` (before the first update) or the Tresca
  lag is within it (after).

A bonded contact carries tension up to its tensile strength and, sliding, its
cohesion, both perfectly plastic within the step (so the problem stays
convex); the bond breaks when the step is committed (the law's ``keeps_bond``:
a contact that did not end the step locked loses it).
"""
from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from ..assembly.system import BlockSystem, PenaltyPairs, add_penalty_pairs, scatter_add
from ..term import StepContext
from .law import ContactLaw, JointResponse
from .openclose import LOCKED, OPEN, SLIDING, magnitudes, negligible_force
from .pipeline import ContactKind, ContactModel, ContactParameters, ContactSet, ContactStep, ContactTerm
from .record import ContactRecord

if TYPE_CHECKING:
    from collections.abc import Callable

__all__ = ["NewtonContactModel", "NewtonContactStep", "NewtonContactTerm", "ARMIJO", "MIN_STEP"]

UNBOUNDED = 1e100  # N: the yield force of a contact whose normal force no solve has given yet (it sticks; τ² finite)
ARMIJO = 1e-4  # a step must decrease Π by this fraction of what its slope at the start promises (Armijo)
MIN_STEP = 1e-6  # the backtracking stops at this step length
FORCE_FLOOR = 1e-9  # the iteration's force tolerance (× the blocks' force scale) when the run's is below: rounding
NORMAL_UPDATES = 3  # the Tresca fixed point's updates of N* at most (the 1-3 outer updates); then N* is held
NEARLY_SETTLED = 0.05  # N* is updated once no more than this fraction of the contacts still changes state
# while more than MOVING of the contacts changed state at the last iterate, an iterative backend solves to
# INEXACT_FORCING of the last iterate's largest change (inexact Newton, docs/contacts/solve.md)
MOVING = 0.01
INEXACT_FORCING = 0.3
KINK_PASS = 1e-6  # a damped step goes this fraction past the first kink of Π along the Newton direction
ROUNDING = 64 * np.finfo(float).eps  # relative rounding of Π's sums over contacts: decreases below it are noise


def _units(vectors: np.ndarray) -> np.ndarray:
    """v/|v| row by row (zero rows stay zero)."""
    size = magnitudes(vectors)
    return np.where(size[:, None] > 0.0, vectors / np.where(size > 0.0, size, 1.0)[:, None], 0.0)


@njit(cache=True)
def _distance(u: np.ndarray, v: np.ndarray) -> float:
    """|u − v| of two rows (k = 1: the absolute value, as :func:`magnitudes`)."""
    if u.shape[0] == 1:
        return abs(u[0] - v[0])
    total = 0.0
    for j in range(u.shape[0]):
        total += (u[j] - v[j]) ** 2
    return float(np.sqrt(total))


@njit(cache=True)
def _norm(v: np.ndarray) -> float:
    """|v| of one row (k = 1: its absolute value, as :func:`magnitudes`)."""
    if v.shape[0] == 1:
        return abs(v[0])
    total = 0.0
    for x in v:
        total += x * x
    return float(np.sqrt(total))


@njit(cache=True)
def _spring_forces(gap: np.ndarray, shear: np.ndarray, kn: np.ndarray, ks: np.ndarray, tension: np.ndarray,
                   tau: np.ndarray, normal_on: np.ndarray, stick: np.ndarray, slip: np.ndarray,
                   slip_direction: np.ndarray, tangent: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The springs' forces γ = ∂ψ/∂g (n,) and ∂ψ/∂s (n, k) at effective gaps and shears, of the true springs
    and of the linear model (``normal_on``, ``stick``, ``slip``, ``slip_direction``, ``tangent``) the last solve
    was assembled with, in one pass (impact laws apart: :meth:`NewtonContactStep._at_impacts`)."""
    n, k = shear.shape
    true_n, true_s = np.empty(n), np.empty((n, k))
    model_n, model_s = np.empty(n), np.empty((n, k))
    for c in range(n):
        s = shear[c]
        true_n[c] = min(kn[c] * gap[c], tension[c])
        model_n[c] = kn[c] * gap[c] if normal_on[c] else tension[c]
        trial = ks[c] * s
        size = _norm(trial)
        if size <= tau[c]:
            true_s[c] = trial
        else:
            length = _norm(s)
            for j in range(k):
                true_s[c, j] = tau[c] * (s[j] / length) if length > 0.0 else 0.0
        if stick[c]:
            model_s[c] = trial
        elif slip[c]:
            d = slip_direction[c]
            along = 0.0
            for j in range(k):
                along += s[j] * d[j]
            for j in range(k):
                model_s[c, j] = tau[c] * d[j] + tangent[c] * (s[j] - along * d[j])
        else:
            model_s[c] = 0.0
    return true_n, true_s, model_n, model_s


@njit(cache=True)
def _spring_potentials(gap: np.ndarray, shear: np.ndarray, kn: np.ndarray, ks: np.ndarray, tension: np.ndarray,
                       tau: np.ndarray, normal_on: np.ndarray, stick: np.ndarray, slip: np.ndarray,
                       slip_direction: np.ndarray, tangent: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The springs' potentials ψ_n (n,) and ψ_s (n,) (up to constants) at effective gaps and shears, of the
    true springs and of the linear model, in one pass (the integrals of :func:`_spring_forces`)."""
    n, k = shear.shape
    true_n, true_s = np.empty(n), np.empty(n)
    model_n, model_s = np.empty(n), np.empty(n)
    for c in range(n):
        s, g = shear[c], gap[c]
        if kn[c] * g > tension[c]:
            true_n[c] = tension[c] * g - 0.5 * tension[c] ** 2 / kn[c]
        else:
            true_n[c] = 0.5 * kn[c] * g**2
        model_n[c] = 0.5 * kn[c] * g**2 if normal_on[c] else tension[c] * g
        size = _norm(s)
        limit = tau[c] / ks[c]
        true_s[c] = 0.5 * ks[c] * size**2 if size <= limit else tau[c] * size - 0.5 * tau[c] * limit
        squared = 0.0
        for j in range(k):
            squared += s[j] * s[j]
        if stick[c]:
            model_s[c] = 0.5 * ks[c] * squared
        elif slip[c]:
            d = slip_direction[c]
            along = 0.0
            for j in range(k):
                along += s[j] * d[j]
            across = 0.0
            for j in range(k):
                x = s[j] - along * d[j]
                across += x * x
            model_s[c] = along * tau[c] + 0.5 * tangent[c] * across
        else:
            model_s[c] = 0.0
    return true_n, true_s, model_n, model_s


@njit(cache=True)
def _states_at(gap: np.ndarray, shear: np.ndarray, true_n: np.ndarray, true_s: np.ndarray, model_n: np.ndarray,
               model_s: np.ndarray, kn: np.ndarray, ks: np.ndarray, tension: np.ndarray, tau: np.ndarray,
               friction: np.ndarray, cohesion: np.ndarray, normal_star: np.ndarray, limit: np.ndarray,
               friction_tolerance: float, stiffer_normal: np.ndarray, stiffer_stick: np.ndarray,
               normal_on: np.ndarray, stick: np.ndarray, flipping: np.ndarray, unsettled_friction: np.ndarray,
               friction_limited: np.ndarray, slip_direction: np.ndarray) -> None:
    """The springs' true states at an iterate, in one pass (:meth:`NewtonContactStep.converged`): ``normal_on``
    (compressed, or bonded within its tensile strength), ``stick`` (within the yield force; or either held by a
    damped step's ``stiffer_*``), ``flipping`` (the true force differs from the model's by more than ``limit``),
    ``unsettled_friction`` (friction acts, and a slipping contact's N* is off its normal force by more than the
    tolerance, or a sticking one would slip at its normal force), and ŝ of the slipping ones."""
    n, k = shear.shape
    for c in range(n):
        s = shear[c]
        size = _norm(s)
        trial = ks[c] * size
        on = kn[c] * gap[c] < tension[c] or stiffer_normal[c]
        sticks = trial <= tau[c] or stiffer_stick[c]
        normal_on[c], stick[c] = on, sticks
        flipping[c] = abs(true_n[c] - model_n[c]) > limit[c] or _distance(true_s[c], model_s[c]) > limit[c]
        compression = max(-true_n[c], 0.0)
        off = abs(compression - normal_star[c]) > max(friction_tolerance * compression, limit[c])
        would_slip = trial > compression * friction[c] + cohesion[c] + limit[c]
        unsettled_friction[c] = friction[c] > 0.0 and on and ((not sticks and off) or (sticks and would_slip))
        friction_limited[c] = friction[c] > 0.0 and on and (not sticks or would_slip)
        for j in range(k):
            slip_direction[c, j] = 0.0 if sticks or size == 0.0 else s[j] / size


class NewtonContactStep(ContactStep):
    """The contacts of one step attempt as one complementarity problem (module doc)."""

    def __init__(self, record: ContactRecord, kind: ContactKind, params: ContactParameters,
                 response: JointResponse, law: ContactLaw, state: np.ndarray, direction: np.ndarray,
                 reference: np.ndarray, bonded: np.ndarray, normal_force: np.ndarray, known: np.ndarray) -> None:
        """``known``: the contacts whose normal force the last step gave (the others stick until a solve has)."""
        # a bond's tension holds a contact closed at t, not one open at t: the convex tension cap would pull
        # such a contact with T across its whole gap (a stack built with gaps: 4e-4 of its energy in play)
        response = replace(response, tension=np.where(state == OPEN, 0.0, response.tension))
        super().__init__(record, kind, params, response, law, state, direction, reference, bonded, normal_force)
        # the linear model of the next solve: normal springs, sticking shear springs, slipping yield forces
        self.normal_on = state != OPEN
        self.stick = state == LOCKED
        self.slip = ~self.stick  # an open contact's spring slips too: at a yield force of zero once N* is
        self.normal_star = normal_force.copy()  # N* of the yield forces (Tresca)
        # a contact new in this step has no normal force yet: it sticks until a solve gave it one (Shi: a
        # contact that closes locks first)
        self.known = known.copy()
        self._tau = self._yield_forces()
        self.slip_direction = direction.copy()  # ŝ of the slipping contacts' linear model
        self.slip_shear = self.shear0.copy()  # the effective shear the slipping contacts' tangent was taken at
        self.model_tangent = np.zeros(len(state))  # the slipping springs' stiffness across ŝ in the last model
        self.step_lengths: list[float] = []  # α of every solve's line search
        self._stiffer: tuple[np.ndarray, np.ndarray] | None = None  # springs acting at a damped solve's full step
        self.follow_normal_force = True  # False: N* stays as given (the Tresca problem alone: tests)
        self.normal_updates = 0  # N* updates of the Tresca fixed point so far (NORMAL_UPDATES at most)
        self._c_p = 1.0  # the scheme's penalty weight (set by add_to)
        # inexact Newton: the last iterate, its largest change, whether many contacts changed state at it, and
        # whether the last solve was looser than the run's tolerance (then the step is not done yet)
        self._last_iterate: np.ndarray | None = None
        self._change = 0.0
        self._unsettled = False
        self._loose = False

    # -- the contact model ---------------------------------------------------
    def yield_force(self) -> np.ndarray:
        """τ (n,) of the shear springs: tan φ·N* + c·A (Tresca); unbounded while N* is not known."""
        return self._tau

    def _yield_forces(self) -> np.ndarray:
        """τ (n,) at the present N* (kept until N* or the known normal forces change: every pass reads it)."""
        return np.where(self.known, self.response.strength(np.maximum(self.normal_star, 0.0)), UNBOUNDED)

    def hold_normal_force(self, normal_star: np.ndarray) -> None:
        """Hold the yield forces' N* at ``normal_star`` (n,) for the whole step: the Tresca problem alone."""
        self.follow_normal_force = False
        self.known[:] = True
        self.normal_star = normal_star
        self._tau = self._yield_forces()

    def _model(self) -> tuple[np.ndarray, ...]:
        """The springs and the linear model of the last solve, as the compiled passes take them."""
        r = self.response
        return (r.normal_stiffness, r.shear_stiffness, r.tension, self._tau, self.normal_on, self.stick, self.slip,
                self.slip_direction, self.model_tangent)

    def _forces(self, gap: np.ndarray, shear: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The springs' forces γ_n (n,), γ_s (n, k) (∂ψ/∂g, ∂ψ/∂s) at effective gaps and shears: of the true
        functions, then of the linear model the last solve was assembled with."""
        true_n, true_s, model_n, model_s = _spring_forces(gap, np.ascontiguousarray(shear), *self._model())
        return (self._at_impacts(true_n, gap, False, potential=False), true_s,
                self._at_impacts(model_n, gap, True, potential=False), model_s)

    def _at_impacts(self, normal: np.ndarray, gap: np.ndarray, model: bool, potential: bool) -> np.ndarray:
        """The normal springs' forces γ_n (or, ``potential``, their ψ_n) (n,) with the contacts of a restitution
        given their impact law's −N (or ψ) at effective gaps ``gap``: the law's, or (``model``) that of the last
        solve's linearisation (:class:`~srdda.contact.impact.ImpactSprings`)."""
        impacts = self.impacts
        if impacts is None:
            return normal
        end = gap[impacts.index]
        out = normal.copy()
        out[impacts.index] = impacts.potential(end, model) if potential else \
            -(impacts.applied(end) if model else impacts.law(end))
        return out

    def _tangent_stiffness(self, tau: np.ndarray) -> np.ndarray:
        """τ/|s| of the slipping contacts' consistent tangent across ŝ (3D; zero for k = 1: no direction
        across the slip in 2D), at most k_s.

        A contact modelled slipping at an iterate whose shear lies within its elastic range |s| ≤ τ/k_s
        (its yield force τ rose when N* followed the normal forces after its state was set) would get τ/|s|
        above k_s: up to 1e21 N/m on slope3d_1k, where the conjugate gradient then stopped after 5,000
        iterations and the step fell back to a factorisation. At |s| = τ/k_s the two agree, and any positive
        definite model keeps the line search on the true Π a descent: the cap changes the model, not the
        problem (docs/dev/contact-solve.md, *A bounded tangent across the slip*).
        """
        if self.record.frame_width == 1:
            return np.zeros(len(tau))
        size = magnitudes(self.slip_shear)
        turning = self.slip & (size > 0.0) & np.any(self.slip_direction != 0.0, axis=1)
        return np.where(turning, np.minimum(tau / np.where(size > 0.0, size, 1.0),
                                            self.response.shear_stiffness), 0.0)

    # -- a solve -------------------------------------------------------------
    def _increments(self, dd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The gaps' and shears' increments by the springs' rows in one compiled pass, at every size: a Newton
        run is not the paper's, whose small models keep the contact terms' einsums to the last bit."""
        assert self._springs is not None
        return self._springs.increments(dd)

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        r = self.record
        springs = self._springs_at(ctx)
        c_p = ctx.coeffs.c_p
        self._c_p = c_p
        # by changes to the last solve's sums at every size (as :meth:`_increments`)
        springs.add_to(system, self._shi_normal(self.normal_on), self.stick, c_p, by_changes=ctx.theta is None)
        self.add_water(system, springs)
        if self.impacts is not None:  # the impact law linearised at the last iterate's gaps
            i = self.impacts.index
            self.impacts.add_to(system, springs.normal_a[i], springs.normal_b[i], ctx)
        capped = np.flatnonzero(~self.normal_on & (self.response.tension > 0.0))
        if len(capped):  # bonded contacts pulled to their tensile strength: the constant force T along n
            pull = self.response.tension[capped]
            scatter_add(system.rhs, r.block_a[capped], -pull[:, None] * springs.normal_a[capped])
            scatter_add(system.rhs, r.block_b[capped], pull[:, None] * springs.normal_b[capped])
        self.slip_shear = self.shear0 + c_p * (self.shear - self.shear0)  # the effective shear of the iterate
        tau = self.yield_force()
        self.model_tangent = self._tangent_stiffness(tau)
        if not np.any(self.slip):
            return
        # the slipping contacts: the yield force τ·ŝ on a (its reverse on b) through the shear rows, and in 3D
        # the consistent tangent as a spring of stiffness τ/|s| across ŝ
        # (the open contacts without strength slip at τ = 0: they add nothing, and a coupling block of zeros for
        # each cost every conjugate-gradient iteration: 35,404 of 38,350 blocks on slope3d_1k)
        sl = np.flatnonzero(self.slip & (tau > 0.0))
        force = -tau[sl, None] * self.slip_direction[sl]
        scatter_add(system.rhs, r.block_a[sl], np.einsum("nk,nki->ni", force, springs.shear_a[sl]))
        scatter_add(system.rhs, r.block_b[sl], -np.einsum("nk,nki->ni", force, springs.shear_b[sl]))
        stiffness = self.model_tangent[sl]
        turning = stiffness > 0.0
        tl = sl[turning]
        if len(tl):
            across = np.stack([-self.slip_direction[tl, 1], self.slip_direction[tl, 0]], axis=1)  # ŝ turned 90°
            rows_a = np.einsum("nk,nki->ni", across, springs.shear_a[tl])[:, None]
            rows_b = np.einsum("nk,nki->ni", across, springs.shear_b[tl])[:, None]
            gap = np.einsum("nk,nk->n", across, self.shear0[tl])[:, None]
            add_penalty_pairs(system, PenaltyPairs(r.block_a[tl], rows_a, r.block_b[tl], rows_b, gap,
                                                   stiffness[turning]), c_p)

    def solve_tolerance(self, tight: float) -> float:
        """The next solve's displacement tolerance for an iterative backend: ``tight`` once at most
        ``MOVING`` of the contacts changed state at the last iterate, else ``INEXACT_FORCING`` × the
        last iterate's largest change (the active set is still moving, so a tighter solve buys nothing)."""
        tolerance = max(tight, INEXACT_FORCING * self._change) if self._unsettled else tight
        self._loose = tolerance > tight
        return tolerance

    def _potentials(self, gap: np.ndarray, shear: np.ndarray) -> tuple[float, float]:
        """Σ ψ of the springs at effective gaps and shears (up to a constant): of the true functions, and of the
        linear model the last solve was assembled with (the integrals of :meth:`_forces`)."""
        true_n, true_s, model_n, model_s = _spring_potentials(gap, np.ascontiguousarray(shear), *self._model())
        return (float(np.sum(self._at_impacts(true_n, gap, False, potential=True)) + np.sum(true_s)),
                float(np.sum(self._at_impacts(model_n, gap, True, potential=True)) + np.sum(model_s)))

    def step_length(self, dd_before: np.ndarray, delta: np.ndarray, curvature: Callable[[], float]) -> float:
        """α in (0, 1] along Δd_k + α·δ that decreases Π enough (Armijo, backtracking); ``curvature()`` gives
        δᵀHδ. The full step is tried first: near the solution it is taken (Newton's fast convergence)."""
        gap_k, shear_k = self.start_gap(self._c_p), self.shear0
        dn0, ds0 = self._increments(dd_before)
        dn, ds = self._increments(delta)
        c_p = self._c_p

        def along(alpha: float) -> tuple[np.ndarray, np.ndarray]:
            return gap_k + c_p * (dn0 + alpha * dn), shear_k + c_p * (ds0 + alpha * ds)

        gap0, shear0 = along(0.0)
        true_n, true_s, lin_n, lin_s = self._forces(gap0, shear0)
        c = curvature()
        slope0 = -c + float(np.dot(true_n - lin_n, dn) + np.sum((true_s - lin_s) * ds))
        alpha = 1.0
        true0, model0 = self._potentials(gap0, shear0)
        # below the rounding of Π's contact parts no line search can tell values apart: the full step is taken
        resolution = ROUNDING * (abs(true0) + abs(model0)) / c_p
        resolvable, resolvable_rise = -slope0 > resolution, slope0 > resolution
        if slope0 < 0.0 and resolvable:  # a descent direction (not so, at most, the first solve's predicted states)
            base = true0 - model0

            def rise(alpha: float) -> float:  # Π(α) − Π(0)
                gap, shear = along(alpha)
                true, model = self._potentials(gap, shear)
                contacts = true - model - base
                return (0.5 * alpha**2 - alpha) * c + contacts / c_p

            value = rise(alpha)
            while value > ARMIJO * alpha * slope0 and alpha > MIN_STEP:
                # the minimum of the quadratic through Π(0), Π'(0) and Π(α), kept within [α/10, α/2]
                guess = -slope0 * alpha**2 / (2.0 * (value - slope0 * alpha))
                alpha = min(max(guess, 0.1 * alpha), 0.5 * alpha)
                value = rise(alpha)
            if alpha < 1.0:
                # backtracking stops short of the first kink of Π along δ; past it a spring changes state, so
                # the next model differs. Up to the kink Π is at most the model's quadratic, which decreases to
                # α = 1: step just past the kink where Π allows (else the iterates approach it and never cross)
                kink = self._first_kink(gap0, shear0, c_p * dn, c_p * ds)
                beyond = min(1.0, kink * (1.0 + KINK_PASS))
                if alpha < beyond < 1.0 and rise(beyond) <= ARMIJO * beyond * slope0:
                    alpha = beyond
        elif slope0 > 0.0 and resolvable_rise and self.step_lengths:
            # uphill: the model held springs that the iterate does not have (those of a damped step's full
            # step). Taken, the step would raise Π and the iteration can cycle; the iterate stays and the next
            # model is its own states, whose Newton direction descends (Π is convex)
            alpha = 0.0
        if 0.0 < alpha < 1.0:
            # a damped step stops short of where a spring takes hold: the next model has the springs that act
            # at the full step already (a contact closed, a shear spring sticking at the full step or on the way
            # to it), or it would stop short again
            gap1, shear1 = along(1.0)
            self._stiffer = (self.response.normal_stiffness * gap1 < self.response.tension,
                             self._sticks_on_the_way(shear0, shear1))
        self.step_lengths.append(alpha)
        return alpha

    def _sticks_on_the_way(self, start: np.ndarray, end: np.ndarray) -> np.ndarray:
        """(n,) bool: the shear springs whose shear on the segment from ``start`` to ``end`` (n, k) comes within
        their elastic range |s| ≤ τ/k_s somewhere, the end included.

        A slipping spring's model is its constant yield force τ·ŝ: where the full step carries the shear back
        through the elastic range (the slip turns back in 2D, turns by much in 3D), that force pushed on past
        the point where the spring holds, and a model slipping the other way would overshoot back. Modelled
        sticking, the next solve stops it there (the damped steps of α ≈ 0.1 this ended: docs/dev/contact-solve.md,
        *Slip that turns back within a solve*)."""
        path = end - start
        length2 = np.einsum("nk,nk->n", path, path)
        along = np.clip(-np.einsum("nk,nk->n", start, path) / np.where(length2 > 0.0, length2, 1.0), 0.0, 1.0)
        nearest = magnitudes(start + along[:, None] * path)
        return self.response.shear_stiffness * nearest <= self.yield_force()

    def _first_kink(self, gap: np.ndarray, shear: np.ndarray, dgap: np.ndarray, dshear: np.ndarray) -> float:
        """The smallest α in (0, 1] at which a spring's true state changes along gap + α·dgap, shear + α·dshear
        (a normal spring reaches its tensile strength or zero force, a shear spring its yield force); 1 if none."""
        kn, ks = self.response.normal_stiffness, self.response.shear_stiffness
        ways = [np.divide(self.response.tension / kn - gap, dgap, out=np.full(len(gap), np.inf),
                          where=dgap != 0.0)]
        # |s + α·ds| = τ/k_s: a·α² + b·α + c = 0
        limit = self.yield_force() / ks
        a = np.einsum("nk,nk->n", dshear, dshear)
        b = 2.0 * np.einsum("nk,nk->n", shear, dshear)
        c = np.einsum("nk,nk->n", shear, shear) - limit**2
        root = np.sqrt(np.maximum(b * b - 4.0 * a * c, 0.0))
        for sign in (-1.0, 1.0):
            ways.append(np.divide(-b + sign * root, 2.0 * a, out=np.full(len(a), np.inf), where=a > 0.0))
        alphas = np.concatenate(ways)
        ahead = alphas[(alphas > KINK_PASS) & (alphas <= 1.0)]
        return float(ahead.min()) if len(ahead) else 1.0

    def _at_alpha_point(self, c_p: float) -> tuple[np.ndarray, np.ndarray]:
        """The effective gaps g₀' + c_p·Δg (n,) and shears s₀ + c_p·Δs (n, k) of the last solve: where the
        step's spring forces act (module doc)."""
        return (self.start_gap(c_p) + c_p * (self.gap - self.record.gap),
                self.shear0 + c_p * (self.shear - self.shear0))

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        self._moved(dd)
        r, p = self.record, self.params
        c_p = ctx.coeffs.c_p
        gap, shear = self._at_alpha_point(c_p)
        kn, ks = self.response.normal_stiffness, self.response.shear_stiffness
        # where the true springs' forces differ from the model's by more than the negligible force, another solve
        true_n, true_s, model_n, model_s = self._forces(gap, shear)
        compression = np.maximum(-true_n, 0.0)
        self._force_limit = negligible_force(ctx.arrays.block_mass, ctx.arrays.gravity, r.block_a, r.block_b,
                                             compression, max(p.force_tolerance, FORCE_FLOOR))
        # a bonded contact carries tension up to its tensile strength (beyond, that force), a sliding one the
        # cohesion: both perfectly plastic within the step, so that the step's problem stays convex; the bond
        # then breaks when the step is committed (ContactLaw.keeps_bond)
        n, k = shear.shape
        normal_on, stick, flipping = np.empty(n, dtype=bool), np.empty(n, dtype=bool), np.empty(n, dtype=bool)
        unsettled_friction, slip_direction = np.empty(n, dtype=bool), np.empty((n, k))
        friction_limited = np.empty(n, dtype=bool)
        held = self._stiffer if self._stiffer is not None else (np.zeros(n, dtype=bool),) * 2
        self._stiffer = None
        response = self.response
        _states_at(gap, np.ascontiguousarray(shear), true_n, true_s, model_n, model_s, kn, ks, response.tension,
                   self._tau, response.friction, response.cohesion, self.normal_star, self._force_limit,
                   p.friction_tolerance, held[0], held[1], normal_on, stick, flipping, unsettled_friction,
                   friction_limited, slip_direction)
        # the Tresca lag: how far the yield forces' N* are from the iterate's normal forces where friction is at
        # its strength (or would be), Σ|N − N*| / ΣN
        limited = compression[friction_limited]
        total = float(np.sum(limited))
        lag = float(np.sum(np.abs(limited - self.normal_star[friction_limited]))) / total if total > 0.0 else 0.0
        # N* follows the normal forces once, and again (up to NORMAL_UPDATES times) while the lag exceeds the
        # friction tolerance
        friction_unsettled = self.follow_normal_force and self.normal_updates < NORMAL_UPDATES \
            and bool(np.any(unsettled_friction)) and (self.normal_updates == 0 or lag > p.friction_tolerance)
        full_step = not self.step_lengths or self.step_lengths[-1] == 1.0
        last = np.zeros_like(dd) if self._last_iterate is None else self._last_iterate
        self._change = float(np.max(np.abs(dd - last), initial=0.0))
        self._last_iterate = dd.copy()
        flips = int(np.count_nonzero(flipping))
        self._unsettled = flips > MOVING * n
        settled_states = full_step and flips == 0
        # Tresca: the yield forces' N* stay fixed while the active set settles (each such problem is convex, the
        # line search on its Π converges), then follow the solved normal forces until these settle too.
        # A contact new in the step stuck at an unbounded yield force in this solve (frictionless ones too):
        # the step is done only after a solve with every yield force from a normal force
        all_known = bool(np.all(self.known))
        done = settled_states and not friction_unsettled and all_known
        changed = flipping | (unsettled_friction if settled_states and friction_unsettled else False)
        self.unsettled_pairs = np.column_stack([r.block_a[changed], r.block_b[changed]])
        self.normal_on, self.stick, self.slip = normal_on, stick, ~stick
        self.slip_direction = slip_direction
        # N* follows once the active set has nearly settled: the last few contacts' changes hardly move the
        # normal forces, and waiting for them would restart the settling after them
        nearly_settled = full_step and flips <= NEARLY_SETTLED * n
        update = (settled_states or nearly_settled) and friction_unsettled
        follows = self.follow_normal_force and not done and (update or not all_known)
        if follows:
            self.normal_updates += bool(update)
            self.normal_star = compression
        if follows or not all_known:  # the yield forces change with N* or with the contacts that gained one
            self.known[:] = True
            self._tau = self._yield_forces()
        self.normal_force = -true_n
        if self.impacts is not None:  # the next solve linearises the impact law at this iterate
            self.impacts.at = gap[self.impacts.index].copy()
        self.state = np.where(normal_on, np.where(stick, LOCKED, SLIDING), OPEN).astype(np.int8)
        self.iterations += 1
        return done and not self._loose  # a loose solve is not the answer: one more at the run's tolerance

    # -- after the step ------------------------------------------------------
    def elastic_shear(self, shear: np.ndarray) -> np.ndarray:
        """The springs' elastic stretch s_e (n, k): s within τ/k_s, else τ/k_s along s (the return map)."""
        ks = self.response.shear_stiffness
        tau = self.yield_force()
        limit = tau / ks
        return np.where((magnitudes(shear) <= limit)[:, None], shear, limit[:, None] * _units(shear))

    def commit(self) -> ContactSet:
        """The contacts as they ended the accepted step: the shear springs' references moved by their plastic
        slip, so that each spring carries its elastic stretch into the next step."""
        r = self.record
        elastic, shear = self._carried_shear()
        reference = self.reference + r.reference_shift(elastic - shear)
        energy = self.stored_energy()
        ks = self.response.shear_stiffness
        return ContactSet(r.key, r.features, r.block_a, r.block_b, self.state.copy(), self.slip_direction.copy(),
                          reference, self.law.keeps_bond(self.bonded, self.state), self.normal_force.copy(),
                          np.where((self.state != OPEN)[:, None], -ks[:, None] * elastic, 0.0), self.gap.copy(),
                          elastic, r.joint, r.point_a, r.point_b, r.normal, energy)

    def _carried_shear(self) -> tuple[np.ndarray, np.ndarray]:
        """(s_e, s) (n, k): the stretch s = s₀ + Δs the shear springs end the step with (the α-point's at
        c_p = 1), and the elastic part s_e of it they carry into the next step (s returned to the yield force).
        Not the α-point's elastic stretch plus the rest of the step, (1 − c_p)·Δs: a slipping spring would carry
        a stretch beyond its yield force and the energy of it."""
        _, shear = self._at_alpha_point(1.0)
        return self.elastic_shear(shear), shear

    def _held_in_band(self) -> np.ndarray:
        """No band here: a contact is closed exactly where it is compressed or bonded."""
        return np.zeros(len(self.state), dtype=bool)

    def stored_energy(self) -> float:
        """J (per m in 2D) the closed contacts' springs keep at the end of the step (t + Δt, not the α-point):
        ½k_n g² at the end gap (½T²/k_n where a bonded one ends pulled beyond its tensile strength T), and
        ½k_s|s_e|² of the elastic stretch the shear spring carries into the next step (:meth:`_carried_shear`).
        With c_p = 1 both are the α-point's."""
        carried, _ = self._carried_shear()
        closed = self.state != OPEN
        kn, ks, tension = self.response.normal_stiffness, self.response.shear_stiffness, self.response.tension
        normal = np.where(kn * self.gap < tension, 0.5 * kn * self.gap**2, 0.5 * tension**2 / kn)
        return float(np.sum(normal[self._shi_normal(closed)])) \
            + 0.5 * float(np.sum((ks[:, None] * carried**2)[closed])) + self._impact_energy(self.gap)

    def start_energy(self) -> float:
        """J (per m in 2D) the springs of the contacts closed at t hold at the step's detected gaps and the
        stretches they carried in (as :meth:`stored_energy` at the end)."""
        closed = ~self.open_at_start
        kn, ks, tension = self.response.normal_stiffness, self.response.shear_stiffness, self.response.tension
        gap = self.record.gap
        normal = np.where(kn * gap < tension, 0.5 * kn * gap**2, 0.5 * tension**2 / kn)
        return float(np.sum(normal[self._shi_normal(closed)])) \
            + 0.5 * float(np.sum((ks[:, None] * self.shear0**2)[closed])) + self._impact_energy(gap)

    def _impact_energy(self, gap: np.ndarray) -> float:
        """½k_n·p² (J, per m in 2D) of the impact springs (contacts of a restitution) at gaps ``gap``."""
        return 0.0 if self.impacts is None else self.impacts.energy(gap[self.impacts.index])

    def impact_loss(self) -> float:
        """What the impact springs took out over the step: the negative work of the law's force (the force of
        :meth:`work`, not the last linearisation's) less the change of ½k_n·p²."""
        return 0.0 if self.impacts is None else self.impacts.loss(self.gap[self.impacts.index], law=True)

    def work(self, dd: np.ndarray, c_p: float) -> tuple[float, float]:
        """(friction, springs): minus the plastic dissipation τ·|slip| of the step, and the work of every
        contact force (normal springs, shear springs at their yield force, at the α-point) over the step's
        increments. The slip is the plastic part of the stretch the step ends with (what :meth:`commit` moves
        the spring's reference by), not the α-point's over c_p: that one is off by (|s₀| − τ/k_s)(1/c_p − 1)
        and would book friction that the springs' loss then gave back."""
        dn, ds = self._increments(dd)
        gap = self.start_gap(c_p) + c_p * dn
        shear = self.shear0 + c_p * ds
        normal, shear_force, _, _ = self._forces(gap, shear)
        springs = -float(np.dot(normal, dn)) - float(np.sum(shear_force * ds))
        end = self.shear0 + ds
        plastic = magnitudes(end - self.elastic_shear(end))
        friction = -float(np.sum(self.yield_force() * plastic))
        return friction, springs - friction


class NewtonContactModel(ContactModel):
    """The contacts of a model solved by :class:`NewtonContactStep` (``contact_solver = "newton"``)."""

    def start(self, record: ContactRecord, previous: ContactSet, old: np.ndarray, bonded: np.ndarray,
              response: JointResponse, normal_force: np.ndarray) -> ContactStep:
        """A kept contact predicts the state it ended the last step in and, if it ended closed, keeps its
        spring's material points (its elastic stretch); a new one is predicted closed where it penetrates, and
        it and one that ended open start with the spring unstretched (an open contact holds no shear force; a
        stretch kept through it, such as dda1's exact rotation leaves at the new points, would do work that no
        stored energy booked: ``dissipated_contact`` fell by 6e-6 of the energy in play in a drop)."""
        kept = old >= 0
        state = np.where(record.gap <= 0.0, LOCKED, OPEN).astype(np.int8)
        state[kept] = previous.state[old[kept]]
        direction = np.zeros((len(record), record.frame_width))
        direction[kept] = previous.direction[old[kept]]
        reference = record.start_reference.copy()
        held = kept & (state != OPEN)
        reference[held] = previous.reference[old[held]]
        return NewtonContactStep(record, self.kind, self.params, response, self.law, state, direction, reference,
                                 bonded, normal_force, kept)


class NewtonContactTerm(ContactTerm):
    """The contact term of ``contact_solver = "newton"``: each solve's increments damped by the contacts' line
    search (:meth:`NewtonContactStep.step_length`)."""

    step: NewtonContactStep | None

    @property
    def line_search(self) -> bool:
        return self.step is not None

    def step_length(self, dd_before: np.ndarray, delta: np.ndarray, curvature: Callable[[], float]) -> float:
        assert self.step is not None
        return self.step.step_length(dd_before, delta, curvature)

    def solve_tolerance(self, tight: float) -> float:
        return tight if self.step is None else self.step.solve_tolerance(tight)
