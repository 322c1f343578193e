"""Probe (issue 29): two formulations of the step's contact problem measured against Newton and not kept.

``barrier``: a path of smoothed problems. Each spring's law is smoothed by a
log barrier on its force (normal γ < T, shear |t| < τ), Newton takes one
solve per smoothing, the smoothing falls by a factor after every full step,
and (``--exact-finish``) the exact Newton of ``srdda.contact.newton`` finishes
from the smoothed solution's states.

``interior``: a primal-dual interior-point method. The contact forces with
the gaps' slacks and the shear multipliers are unknowns beside the blocks'
increments; Newton's step on the perturbed complementarity conditions
eliminates them contact by contact, so that a solve is the same block system
(springs of stiffness D with a constant force); fraction-to-the-boundary step
lengths, μ̄ the mean scaled complementarity.

docs/dev/contact-solve.md (*(d)* and *(e)*) has what they measured. Usage:

    python benchmarks/probe_smoothed_contacts.py MODEL STEPS FORMULATION [options]

MODEL a bench case (slope_a, slope_b, ...) or ``slice`` (a 101-block slice
of slope3d); FORMULATION ``newton``, ``barrier`` or ``interior``. Prints the
solves of every step attempt and, per solve, log10 of the smoothing and the
step length.
"""
from __future__ import annotations

import argparse
import time
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from srdda import simulation
from srdda import step as stepmod
from srdda.apps.bench.models import Slope3DSpec, jointed_slope_3d
from srdda.apps.bench.runner import CASES
from srdda.assembly.system import BlockSystem, PenaltyPairs, add_penalty_pairs, scatter_add
from srdda.contact.newton import FORCE_FLOOR, NORMAL_UPDATES, UNBOUNDED, NewtonContactModel, NewtonContactStep, _units
from srdda.contact.openclose import LOCKED, OPEN, SLIDING, magnitudes, negligible_force
from srdda.contact.pipeline import ContactSet, ContactStep
from srdda.contact.record import ContactRecord
from srdda.term import StepContext

if TYPE_CHECKING:
    from collections.abc import Callable

    from srdda.contact.law import JointResponse

# -- (d) the barrier path --------------------------------------------------------------------------------

BARRIER_START = 1e4  # ν of the first solve: the kinks smoothed over about 1,000 negligible forces
BARRIER_SHRINK = 0.03 # ν's factor after a full Newton step
BARRIER_END = 1e-1  # the last ν (smoothing ≈ 0.1 negligible force)
EXACT_FINISH = 0  # 1: the exact Newton finishes from the path's end


def smoothed_normal(gap: np.ndarray, stiffness: np.ndarray, tension: np.ndarray,
                    mu: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(γ, dγ/dg, ψ_n,μ) of the smoothed normal springs at gaps ``gap`` (module doc; ψ up to a constant).

    γ = T − u with u the positive root of u² + (k_n g − T)u − k_n μ = 0."""
    x = stiffness * gap - tension
    root = np.sqrt(x * x + 4.0 * stiffness * mu)
    # u = (−x + root)/2, without cancellation where x > 0 (an open contact)
    u = np.where(x > 0.0, 2.0 * stiffness * mu / np.where(x + root > 0.0, x + root, 1.0), 0.5 * (root - x))
    force = tension - u
    tangent = np.where(root > 0.0, stiffness * u / np.where(root > 0.0, root, 1.0), stiffness)
    with np.errstate(divide="ignore"):
        barrier = np.where(mu > 0.0, mu * np.log(np.where(u > 0.0, u, 1.0)), 0.0)
    potential = force * gap - force**2 / (2.0 * stiffness) + barrier
    return force, tangent, potential


@njit(cache=True)
def _shear_roots(trial: np.ndarray, eta: np.ndarray, w: np.ndarray) -> None:
    """w = 1 − ρ of ρ + η·ρ/(1 − ρ²) = M (M = ``trial``, per contact), ρ = |t|/τ in [0, 1): safeguarded Newton
    on g(w) = 1 − w + η(1 − w)/(w(2 − w)) − M, decreasing from +∞ at w → 0 to −M at w = 1."""
    for i in range(len(trial)):
        m, e = trial[i], eta[i]
        if e <= 0.0:  # no smoothing: the exact return map
            w[i] = max(1.0 - m, 0.0)
            continue
        lo, hi = 0.0, 1.0
        x = 1.0 - m if m < 1.0 else 0.5 * e / (m - 1.0 + e)  # the root without smoothing, or its expansion
        x = min(max(x, 1e-300), 1.0)
        for _ in range(200):
            q = (1.0 - x) / (x * (2.0 - x))
            g = 1.0 - x + e * q - m
            if g > 0.0:
                lo = x
            else:
                hi = x
            dq = -(x * x - 2.0 * x + 2.0) / (x * (2.0 - x)) ** 2
            slope = -1.0 + e * dq
            step = x - g / slope
            if not (lo < step < hi):  # outside the bracket: halve it (geometrically near zero)
                step = np.sqrt(lo * hi) if lo > 0.0 else 0.5 * hi
            if abs(step - x) <= 1e-15 * x:
                x = step
                break
            x = step
        w[i] = x


def smoothed_shear(shear: np.ndarray, stiffness: np.ndarray, tau: np.ndarray,
                   mu: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(t (n, k), the tangent along ŝ, the tangent across ŝ, ψ_s,μ) of the smoothed shear springs at shears
    ``shear`` (module doc; ψ up to a constant). Unbounded τ: the elastic spring; τ = 0: no force."""
    size = magnitudes(shear)
    elastic = tau >= UNBOUNDED
    bounded = (tau > 0.0) & ~elastic
    t_safe = np.where(bounded, tau, 1.0)
    eta = np.where(bounded, stiffness * mu / t_safe**2, 0.0)
    trial = np.where(bounded, stiffness * size / t_safe, 0.0)
    w = np.empty(len(size))
    _shear_roots(trial, eta, w)
    rho = 1.0 - w
    along = stiffness / (1.0 + eta * (1.0 + rho**2) / (w * (2.0 - w))**2)
    across = np.where(size > 0.0, t_safe * rho / np.where(size > 0.0, size, 1.0), along)
    with np.errstate(divide="ignore", invalid="ignore"):
        potential = t_safe**2 / stiffness * (rho * trial - 0.5 * rho**2) \
            + np.where(mu > 0.0, 0.5 * mu * np.log(w * (2.0 - w)), 0.0)
    magnitude = np.where(bounded, t_safe * rho, np.where(elastic, stiffness * size, 0.0))
    along = np.where(bounded, along, np.where(elastic, stiffness, 0.0))
    across = np.where(bounded, across, np.where(elastic, stiffness, 0.0))
    potential = np.where(bounded, potential, np.where(elastic, 0.5 * stiffness * size**2, 0.0))
    return magnitude[:, None] * _units(shear), along, across, potential


class BarrierContactStep(NewtonContactStep):
    """:class:`~.newton.NewtonContactStep` that first follows the smoothed problems' path (module doc)."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.nu = BARRIER_START  # ν of the smoothing; 0 once the exact Newton took over
        self._scale: np.ndarray | None = None  # f²: the negligible force squared of each contact (N²)
        # the smoothed model of the last solve: (g_k, γ_k, γ'_k, s_k, t_k, along, across, ŝ)
        self._linear: tuple[np.ndarray, ...] | None = None

    @property
    def smoothing(self) -> bool:
        return self.nu > 0.0

    def _mus(self) -> tuple[np.ndarray, np.ndarray]:
        assert self._scale is not None
        return (self.nu * self._scale / self.response.normal_stiffness,
                self.nu * self._scale / self.response.shear_stiffness)

    def yield_force(self) -> np.ndarray:
        return np.where(self.known, self.response.strength(np.maximum(self.normal_star, 0.0)), UNBOUNDED)

    # -- the smoothed functions and their linear model ------------------------
    def _about_last(self, shear: np.ndarray) -> tuple[tuple[np.ndarray, ...], np.ndarray, np.ndarray]:
        """The last solve's linear model, the shears' change since it (n, k) and that change along ŝ (n,)."""
        assert self._linear is not None
        ds = shear - self._linear[3]
        return self._linear, ds, np.einsum("nk,nk->n", ds, self._linear[7])

    def _forces(self, gap: np.ndarray, shear: np.ndarray, model: bool) -> tuple[np.ndarray, np.ndarray]:
        if not self.smoothing:
            return super()._forces(gap, shear, model)
        if model:
            (g_k, f_k, df_k, _, t_k, along, across, direction), ds, on = self._about_last(shear)
            shear_force = t_k + along[:, None] * on[:, None] * direction + across[:, None] * (ds - on[:, None]
                                                                                                * direction)
            return f_k + df_k * (gap - g_k), shear_force
        mu_n, mu_s = self._mus()
        normal, _, _ = smoothed_normal(gap, self.response.normal_stiffness, self.response.tension, mu_n)
        shear_force, _, _, _ = smoothed_shear(shear, self.response.shear_stiffness, self.yield_force(), mu_s)
        return normal, shear_force

    def _potentials(self, gap: np.ndarray, shear: np.ndarray, model: bool) -> float:
        if not self.smoothing:
            return super()._potentials(gap, shear, model)
        if model:
            (g_k, f_k, df_k, _, t_k, along, across, direction), ds, on = self._about_last(shear)
            rest = np.einsum("nk,nk->n", ds, ds) - on**2
            quadratic = 0.5 * (along * on**2 + across * rest)
            return float(np.sum(f_k * gap + 0.5 * df_k * (gap - g_k)**2)
                         + np.sum(np.einsum("nk,nk->n", t_k, shear) + quadratic))
        mu_n, mu_s = self._mus()
        _, _, normal = smoothed_normal(gap, self.response.normal_stiffness, self.response.tension, mu_n)
        _, _, _, shear_energy = smoothed_shear(shear, self.response.shear_stiffness, self.yield_force(), mu_s)
        return float(np.sum(normal) + np.sum(shear_energy))

    def _first_kink(self, gap: np.ndarray, shear: np.ndarray, dgap: np.ndarray, dshear: np.ndarray) -> float:
        return 1.0 if self.smoothing else super()._first_kink(gap, shear, dgap, dshear)

    # -- a solve -------------------------------------------------------------
    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        if not self.smoothing:
            super().add_to(system, ctx)
            return
        r = self.record
        springs = self._springs_at(ctx)
        c_p = ctx.coeffs.c_p
        self._c_p = c_p
        if self._scale is None:
            compression = np.maximum(-self.response.normal_stiffness * self.start_gap(c_p), 0.0)
            force = negligible_force(ctx.arrays.block_mass, ctx.arrays.gravity, r.block_a, r.block_b, compression,
                                     max(self.params.force_tolerance, FORCE_FLOOR))
            self._scale = force**2
        gap, shear = self._at_alpha_point(c_p)
        mu_n, mu_s = self._mus()
        force, tangent, _ = smoothed_normal(gap, self.response.normal_stiffness, self.response.tension, mu_n)
        shear_force, along, across, _ = smoothed_shear(shear, self.response.shear_stiffness, self.yield_force(),
                                                       mu_s)
        direction = _units(shear)
        if r.frame_width == 1:
            direction = np.where(direction == 0.0, 1.0, direction)
        else:
            direction[~np.any(direction != 0.0, axis=1)] = (1.0, 0.0)
        self._linear = (gap, force, tangent, shear, shear_force, along, across, direction)
        every = np.arange(len(self))
        # the normal springs γ'_k·(g₀' + c_p·Δg) plus the constant γ_k − γ'_k·g_k along n
        add_penalty_pairs(system, PenaltyPairs(r.block_a, springs.normal_a[:, None], r.block_b,
                                               springs.normal_b[:, None], springs.gap[:, None], tangent), c_p)
        constant = force - tangent * gap
        scatter_add(system.rhs, r.block_a, -constant[:, None] * springs.normal_a)
        scatter_add(system.rhs, r.block_b, constant[:, None] * springs.normal_b)
        # the shear springs: the tangent along ŝ and across it, about s₀, plus the constant t_k − K·s_k
        ways = [(direction, along)]
        if r.frame_width == 2:
            ways.append((np.stack([-direction[:, 1], direction[:, 0]], axis=1), across))
        offset = shear_force.copy()
        for way, stiffness in ways:
            rows_a = np.einsum("nk,nki->ni", way, springs.shear_a)[:, None]
            rows_b = np.einsum("nk,nki->ni", way, springs.shear_b)[:, None]
            start = np.einsum("nk,nk->n", way, self.shear0)[:, None]
            add_penalty_pairs(system, PenaltyPairs(r.block_a[every], rows_a, r.block_b[every], rows_b, start,
                                                   stiffness), c_p)
            offset -= (stiffness * np.einsum("nk,nk->n", way, shear))[:, None] * way
        scatter_add(system.rhs, r.block_a, -np.einsum("nk,nki->ni", offset, springs.shear_a))
        scatter_add(system.rhs, r.block_b, np.einsum("nk,nki->ni", offset, springs.shear_b))
        self.add_water(system, springs)
        self.slip_shear = shear

    def step_length(self, dd_before: np.ndarray, delta: np.ndarray, curvature: Callable[[], float]) -> float:
        alpha = super().step_length(dd_before, delta, curvature)
        if self.smoothing:
            self._stiffer = None
        return alpha

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        if not self.smoothing:
            return super().converged(dd, ctx)
        self._moved(dd)
        self.iterations += 1
        full = not self.step_lengths or self.step_lengths[-1] == 1.0
        gap, shear = self._at_alpha_point(ctx.coeffs.c_p)
        kn, ks = self.response.normal_stiffness, self.response.shear_stiffness
        # how far the last solve's linear model is from the smoothed springs where it ended
        model_n, model_s = self._forces(gap, shear, model=True)
        true_n, true_s = self._forces(gap, shear, model=False)
        assert self._scale is not None
        limit = np.sqrt(self._scale)
        off = (np.abs(true_n - model_n) > limit) | (magnitudes(true_s - model_s) > limit)
        done = full and self.nu <= BARRIER_END and not np.any(off) and EXACT_FINISH == 0
        if full:
            self.nu = max(self.nu * BARRIER_SHRINK, BARRIER_END)
        normal_on = kn * gap < self.response.tension
        stick = ks * magnitudes(shear) <= self.yield_force()
        self.state = np.where(normal_on, np.where(stick, LOCKED, SLIDING), OPEN).astype(np.int8)
        self.normal_force = -np.minimum(kn * gap, self.response.tension)
        self.unsettled_pairs = np.column_stack([self.record.block_a[off], self.record.block_b[off]])
        if done:
            return True
        # Coulomb along the path: the yield forces follow the normal forces after every solve (N* of the next)
        self.normal_star = np.maximum(-kn * gap, 0.0)
        self.known[:] = True
        if EXACT_FINISH and full and self.nu <= BARRIER_END:  # the exact Newton from the smoothed solution's states
            self.nu = 0.0
            self.normal_on, self.stick, self.slip = normal_on, stick, ~stick
            self.slip_direction = np.where(self.slip[:, None], _units(shear), 0.0)
            self.normal_updates = NORMAL_UPDATES  # N* followed the path: the exact Newton keeps the last one
        return False


class BarrierContactModel(NewtonContactModel):
    """The contacts of a model solved by :class:`BarrierContactStep`."""

    def start(self, record: ContactRecord, previous: ContactSet, old: np.ndarray, bonded: np.ndarray,
              response: JointResponse, normal_force: np.ndarray) -> ContactStep:
        step = super().start(record, previous, old, bonded, response, normal_force)
        assert isinstance(step, NewtonContactStep)
        out = BarrierContactStep.__new__(BarrierContactStep)
        out.__dict__.update(step.__dict__)
        out.nu, out._scale, out._linear = BARRIER_START, None, None
        return out


# -- (e) the interior-point method ----------------------------------------------------------------------
P = dict(
    START=1e6,  # μ̄ of the start (the smoothed laws' point at the start gaps)
    END=1e-2,  # converged at μ̄ ≤ END (and every product ≤ CENTRAL·END)
    CENTRAL=10.0,
    FREEZE=1.0,  # N* follows the iterate while μ̄ > FREEZE
    BOUNDARY=0.99,
    SIGMA=0.05,  # μ̄'s factor after a near-full step
)


def _room(x: np.ndarray, dx: np.ndarray) -> float:
    """The largest α ≤ 1 with x + α·dx ≥ (1 − BOUNDARY)·x (x > 0)."""
    falling = dx < 0.0
    if not np.any(falling):
        return 1.0
    return min(1.0, float(np.min(-P["BOUNDARY"] * x[falling] / dx[falling])))


class InteriorContactStep(NewtonContactStep):
    """The contacts of one step attempt by the primal-dual interior-point method (module doc)."""

    def _setup(self) -> None:
        self.mean = P["START"]  # μ̄: the scaled complementarity the next solve aims at (× σ)
        self.sigma = 1.0
        self._scale: np.ndarray | None = None
        self.gamma = self.w = self.zeta = np.zeros(0)
        self.t = np.zeros((0, 1))
        self._model: tuple[np.ndarray, ...] | None = None
        self._pending: tuple[np.ndarray, ...] | None = None
        self.history: list[str] = []

    def yield_force(self) -> np.ndarray:
        return np.where(self.known, self.response.strength(np.maximum(self.normal_star, 0.0)), UNBOUNDED)

    def _bounded(self, tau: np.ndarray) -> np.ndarray:
        return (tau > 0.0) & (tau < UNBOUNDED)

    def _products(self) -> tuple[np.ndarray, np.ndarray]:
        """Scaled complementarity of every contact: normal w·u·k/f², shear 2ζv·k_s/f² (0 where unbounded)."""
        assert self._scale is not None
        kn, ks = self.response.normal_stiffness, self.response.shear_stiffness
        tau = self.yield_force()
        u = self.response.tension - self.gamma
        v = tau**2 - np.einsum("nk,nk->n", self.t, self.t)
        bounded = self._bounded(tau)
        return self.w * u * kn / self._scale, np.where(bounded, 2.0 * self.zeta * v * ks / self._scale, 0.0)

    def _recenter_shear(self, mu_s: np.ndarray) -> None:
        """t inside |t| ≤ BOUNDARY·τ for τ changed by N*, ζ on the path where τ changed."""
        tau = self.yield_force()
        bounded = self._bounded(tau)
        size = magnitudes(self.t)
        cap = P["BOUNDARY"] * np.where(bounded, tau, np.inf)
        self.t = np.where((size > cap)[:, None], self.t * (cap / np.where(size > 0, size, 1.0))[:, None], self.t)
        self.t[tau == 0.0] = 0.0
        v = tau**2 - np.einsum("nk,nk->n", self.t, self.t)
        self.zeta = np.where(bounded, 0.5 * mu_s / np.where(bounded, v, 1.0), 0.0)

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        r = self.record
        springs = self._springs_at(ctx)
        c_p = ctx.coeffs.c_p
        self._c_p = c_p
        kn, ks, tension = self.response.normal_stiffness, self.response.shear_stiffness, self.response.tension
        gap, shear = self._at_alpha_point(c_p)
        tau = self.yield_force()
        if self._scale is None:  # the start: the smoothed laws' point at the start gaps and shears (central)
            compression = np.maximum(-kn * self.start_gap(c_p), 0.0)
            force = negligible_force(ctx.arrays.block_mass, ctx.arrays.gravity, r.block_a, r.block_b, compression,
                                     max(self.params.force_tolerance, FORCE_FLOOR))
            self._scale = force**2
            mu_n, mu_s = self.mean * self._scale / kn, self.mean * self._scale / ks
            self.gamma, _, _ = smoothed_normal(gap, kn, tension, mu_n)
            self.w = mu_n / (tension - self.gamma)
            self.t, _, _, _ = smoothed_shear(shear, ks, tau, mu_s)
            self._recenter_shear(mu_s)
        target = self.sigma * self.mean
        mu_n, mu_s = target * self._scale / kn, target * self._scale / ks
        gamma, t, w, zeta = self.gamma, self.t, self.w, self.zeta
        # normal: dγ = D_n(dg + g − γ/k − μ/u), D_n = 1/(1/k + w/u)
        u = tension - gamma
        d_n = 1.0 / (1.0 / kn + w / u)
        c_n = gamma + d_n * (-gamma / kn - mu_n / u)  # γ + D_n(r' − g_k) with r' = g_k − γ/k − μ/u
        # shear: J dt = ds + s − t/k_s − 2ζt − t(μ − 2ζv)/v, J = (1/k_s + 2ζ)I + (4ζ/v) t tᵀ
        bounded = self._bounded(tau)
        elastic = tau >= UNBOUNDED
        v = np.where(bounded, tau**2 - np.einsum("nk,nk->n", t, t), 1.0)
        size2 = np.einsum("nk,nk->n", t, t)
        q = 1.0 / ks + 2.0 * zeta
        d_along = np.where(bounded, 1.0 / (q + 4.0 * zeta * size2 / v), np.where(elastic, ks, 0.0))
        d_across = np.where(bounded, 1.0 / q, np.where(elastic, ks, 0.0))
        residual = -t / ks[:, None] - np.where(bounded, 2.0 * zeta + (mu_s - 2.0 * zeta * v) / v, 0.0)[:, None] * t
        direction = _units(t)
        if r.frame_width == 1:
            direction = np.where(direction == 0.0, 1.0, direction)
        else:
            direction[~np.any(direction != 0.0, axis=1)] = (1.0, 0.0)
        ways = [(direction, d_along)]
        if r.frame_width == 2:
            ways.append((np.stack([-direction[:, 1], direction[:, 0]], axis=1), d_across))
        c_s = np.where((bounded | elastic)[:, None], t, 0.0)
        for way, stiffness in ways:
            c_s = c_s + (stiffness * np.einsum("nk,nk->n", way, residual))[:, None] * way
        self._model = (gap, shear, c_n, d_n, c_s, d_along, d_across, direction, mu_n, mu_s)
        add_penalty_pairs(system, PenaltyPairs(r.block_a, springs.normal_a[:, None], r.block_b,
                                               springs.normal_b[:, None], springs.gap[:, None], d_n), c_p)
        scatter_add(system.rhs, r.block_a, -c_n[:, None] * springs.normal_a)
        scatter_add(system.rhs, r.block_b, c_n[:, None] * springs.normal_b)
        for way, stiffness in ways:
            rows_a = np.einsum("nk,nki->ni", way, springs.shear_a)[:, None]
            rows_b = np.einsum("nk,nki->ni", way, springs.shear_b)[:, None]
            start = np.einsum("nk,nk->n", way, self.shear0)[:, None]
            add_penalty_pairs(system, PenaltyPairs(r.block_a, rows_a, r.block_b, rows_b, start, stiffness), c_p)
        scatter_add(system.rhs, r.block_a, -np.einsum("nk,nki->ni", c_s, springs.shear_a))
        scatter_add(system.rhs, r.block_b, np.einsum("nk,nki->ni", c_s, springs.shear_b))
        self.add_water(system, springs)

    def step_length(self, dd_before: np.ndarray, delta: np.ndarray, curvature: Callable[[], float]) -> float:
        assert self._model is not None
        g_k, s_k, c_n, d_n, c_s, d_along, d_across, direction, mu_n, mu_s = self._model
        dn, ds = self._increments(delta)
        gap, shear = g_k + self._c_p * dn, s_k + self._c_p * ds
        gamma_full = c_n + d_n * gap
        on = np.einsum("nk,nk->n", shear, direction)
        t_full = c_s + (d_along * on)[:, None] * direction + d_across[:, None] * (shear - on[:, None] * direction)
        d_gamma, d_t = gamma_full - self.gamma, t_full - self.t
        u = self.response.tension - self.gamma
        d_w = (mu_n - self.w * u + self.w * d_gamma) / u
        alpha = min(_room(u, -d_gamma), _room(self.w, d_w))
        tau = self.yield_force()
        bounded = self._bounded(tau)
        v = np.where(bounded, tau**2 - np.einsum("nk,nk->n", self.t, self.t), 1.0)
        d_zeta = np.where(bounded, (0.5 * mu_s - self.zeta * v + 2.0 * self.zeta
                                    * np.einsum("nk,nk->n", self.t, d_t)) / v, 0.0)
        alpha = min(alpha, _room(self.zeta[bounded], d_zeta[bounded]))
        a = np.einsum("nk,nk->n", d_t, d_t)
        b = 2.0 * np.einsum("nk,nk->n", self.t, d_t)
        moving = bounded & (a > 0.0)
        if np.any(moving):
            c = -P["BOUNDARY"] * v[moving]  # |t + α dt|² − |t|² ≤ BOUNDARY·v
            root = (-b[moving] + np.sqrt(np.maximum(b[moving]**2 - 4.0 * a[moving] * c, 0.0))) / (2.0 * a[moving])
            alpha = min(alpha, float(np.min(root)))
        alpha = max(alpha, 0.0)
        self._pending = (d_gamma, d_t, d_w, d_zeta)
        self.step_lengths.append(alpha)
        return alpha

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        assert self._pending is not None and self._scale is not None
        self._moved(dd)
        self.iterations += 1
        alpha = self.step_lengths[-1]
        d_gamma, d_t, d_w, d_zeta = self._pending
        self.gamma = self.gamma + alpha * d_gamma
        self.t = self.t + alpha * d_t
        self.w = self.w + alpha * d_w
        self.zeta = self.zeta + alpha * d_zeta
        gap, shear = self._at_alpha_point(ctx.coeffs.c_p)
        kn, ks, tension = self.response.normal_stiffness, self.response.shear_stiffness, self.response.tension
        limit = np.sqrt(self._scale)
        tau = self.yield_force()
        bounded = self._bounded(tau)
        p_n, p_s = self._products()
        count = len(p_n) + int(np.sum(bounded))
        self.mean = float((np.sum(p_n) + np.sum(p_s)) / max(count, 1))
        off_n = np.abs(kn * (gap - self.gamma / kn - self.w)) > limit
        residual_s = shear - self.t / ks[:, None] - np.where(bounded, 2.0 * self.zeta, 0.0)[:, None] * self.t
        off_s = (tau > 0.0) & (ks * magnitudes(residual_s) > limit)
        off_c = (p_n > P["CENTRAL"] * P["END"]) | (p_s > P["CENTRAL"] * P["END"])
        off = off_n | off_s | off_c
        self.history.append(f"{np.log10(max(self.mean, 1e-300)):.1f}:{alpha:.2g}/{int(np.sum(off_n | off_s))}"
                            f"/{int(np.sum(off_c))}")
        done = not np.any(off)
        self.unsettled_pairs = np.column_stack([self.record.block_a[off], self.record.block_b[off]])
        normal_on = kn * gap < tension
        stick = ks * magnitudes(shear) <= tau
        self.state = np.where(normal_on, np.where(stick, LOCKED, SLIDING), OPEN).astype(np.int8)
        self.normal_force = -np.minimum(kn * gap, tension)
        if done:
            return True
        self.sigma = P["SIGMA"] if alpha >= 0.9 else (0.3 if alpha >= 0.5 else 0.6)
        if self.mean > P["FREEZE"] or not np.all(self.known):  # Coulomb along the path
            self.normal_star = np.maximum(-self.gamma, 0.0)
            self.known[:] = True
            self._recenter_shear(self.mean * self._scale / ks)
        return False


class InteriorContactModel(NewtonContactModel):
    """The contacts of a model solved by :class:`InteriorContactStep`."""

    def start(self, record: ContactRecord, previous: ContactSet, old: np.ndarray, bonded: np.ndarray,
              response: JointResponse, normal_force: np.ndarray) -> ContactStep:
        step = super().start(record, previous, old, bonded, response, normal_force)
        out = InteriorContactStep.__new__(InteriorContactStep)
        out.__dict__.update(step.__dict__)
        out._setup()
        return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("model")
    parser.add_argument("steps", type=int)
    parser.add_argument("formulation", choices=("newton", "barrier", "interior"))
    parser.add_argument("--exact-finish", action="store_true", help="barrier: the exact Newton finishes")
    parser.add_argument("--start", type=float, help="barrier ν / interior μ̄ of the first solve")
    parser.add_argument("--shrink", type=float, help="barrier ν's / interior σ's factor after a full step")
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args()
    global BARRIER_START, BARRIER_SHRINK, EXACT_FINISH
    EXACT_FINISH = int(args.exact_finish)
    if args.formulation == "barrier":
        BARRIER_START = args.start or BARRIER_START
        BARRIER_SHRINK = args.shrink or BARRIER_SHRINK
        stepmod.NewtonContactModel = BarrierContactModel  # type: ignore[misc]
    elif args.formulation == "interior":
        P["START"] = args.start or P["START"]
        P["SIGMA"] = args.shrink or P["SIGMA"]
        stepmod.NewtonContactModel = InteriorContactModel  # type: ignore[misc]
    build = (lambda: jointed_slope_3d(Slope3DSpec(slope="a", width=4.0))) if args.model == "slice" \
        else CASES[args.model].build
    model, settings = build()
    settings = replace(settings, n_steps=args.steps, contact_solver="newton")
    attempts: list[tuple[str, int]] = []
    plain_step = stepmod.Stepper.step

    def step(self: stepmod.Stepper, state: object, dt: float) -> stepmod.StepOutcome:
        out = plain_step(self, state, dt)  # type: ignore[arg-type]
        attempts.append((out.status, out.solves))
        if not args.quiet:
            print(out.status, out.solves, flush=True)
        return out

    stepmod.Stepper.step = step  # type: ignore[method-assign]
    start = time.time()
    result = simulation.run(model, settings)
    accepted = [s for status, s in attempts if status == "accepted"]
    end = result.final_state.time if result.final_state is not None else float("nan")
    print(f"{args.formulation}: {result.status}, t = {end:.4g} s, {len(accepted)} steps, "
          f"{np.mean(accepted) if accepted else float('nan'):.2f} solves a step (largest {max(accepted, default=0)}), "
          f"{len(attempts) - len(accepted)} cut, {time.time() - start:.1f} s; per step {accepted}")


if __name__ == "__main__":
    main()
