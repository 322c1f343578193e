"""The contact pipeline of both dimensions: detector → record → set, step, term → law.

Per step attempt :meth:`ContactModel.prepare` has the model's detector find
the contacts of the configuration at t (a :class:`~srdda.contact.record.ContactRecord`),
carries over what persisting contacts knew (the :class:`ContactSet` the last
step left on the state) and returns the step's :class:`ContactStep`, which
adds the springs (:mod:`.penalty`) and friction forces of the assumed states
to every solve; after each solve it runs the open-close rules
(:mod:`.openclose`) with the joints' response (:mod:`.law`) and asks for
another solve while a state changes. After the update the term
(:class:`ContactTerm`) cuts a step whose vertices moved more than g2·w0 or
penetrated too deep, and commits the :class:`ContactSet` of an accepted step.

Which detector a model gets, and the two open-close choices that differ
between the dimensions, come from one table keyed by the block type,
:data:`CONTACT_KINDS` (as Box2D picks its contact functions from a table keyed
by the shape types); docs/contacts.md gives the reason of each difference.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
from numba import njit

from ..assembly.system import BlockSystem, scatter_add
from ..geometry.facets import boundary_simplices
from ..modeldata.arrays import ModelArrays
from ..term import LEDGER, StepContext, StepCut, Term
from .candidates import pair_keys
from .detect2d import Detector2D
from .detect3d import Detector3D
from .impact import ImpactSprings
from .law import ContactLaw, ContactStiffness, JointResponse, MohrCoulomb
from .openclose import (LOCKED, OPEN, SLIDING, deepest_penetration, magnitudes, negligible_changes,
                        negligible_force, never_held, next_states)
from .penalty import ContactSprings, directional_rows, is_large
from .record import ContactRecord, match_previous
from .water import contact_water

if TYPE_CHECKING:
    from ..state import State

__all__ = ["ContactParameters", "ContactSet", "ContactStep", "ContactModel", "ContactTerm", "ContactKind",
           "CONTACT_KINDS"]


@dataclass(frozen=True)
class ContactParameters:
    """Resolved contact settings of a run (SI)."""

    normal_stiffness: float  # k_n (N/m) of contacts whose joint gives no stiffness per area
    shear_stiffness: float  # k_s (N/m), likewise
    distance: float  # d0 (m): contact search distance
    angle_tolerance: float  # rad, Shi's angle criterion
    max_penetration: float  # m: a step that penetrates deeper is cut
    friction_tolerance: float = 1e-3  # relative settling of the friction normal force
    freeze_after: int = 2  # state changes of one contact in a step after which its state is kept
    settle_after: int = 8  # solves after which no contact reopens or relocks, friction is not re-iterated
    tolerance: float = 0.0  # m, Shi's f0·w0: the open and reverse-slip bands, the settled friction displacement
    force_tolerance: float = 0.0  # × the pair's force scale (openclose.negligible_force): below, no further solve

    @property
    def stiffness(self) -> ContactStiffness:
        return ContactStiffness(self.normal_stiffness, self.shear_stiffness)


@dataclass(frozen=True)
class ContactKind:
    """One row of :data:`CONTACT_KINDS`: a dimension's detector and the two open-close choices that differ,
    each for a reason docs/contacts.md gives: how a sliding contact's friction normal force follows the solves
    (``"secant"``: a secant step per contact; ``"substitution"``: the last solve's N where no contact of the
    same blocks changed state) and whether Shi's band f0·w0 acts."""

    detector: type[Detector2D] | type[Detector3D]
    friction_normal: Literal["secant", "substitution"]
    band: bool


CONTACT_KINDS: dict[str, ContactKind] = {
    "plane": ContactKind(Detector2D, "secant", band=True),
    "solid": ContactKind(Detector3D, "substitution", band=False),
}


@dataclass(frozen=True)
class ContactSet:
    """Contacts at the end of an accepted step (the state carries it to the next step; checkpointed field by
    field). k = shear components (1 in 2D, 2 in 3D)."""

    key: np.ndarray  # (n,) int64: the contact's identity (its features)
    features: np.ndarray  # (n, f) int64: the detector's description (2D: vertex, edge, kind; 3D: kind, a, b, ...)
    block_a: np.ndarray  # (n,)
    block_b: np.ndarray  # (n,)
    state: np.ndarray  # (n,) OPEN / SLIDING / LOCKED
    direction: np.ndarray  # (n, k) slip direction of sliding contacts in the contact's frame
    reference: np.ndarray  # (n, k) the shear spring's reference (record.start_reference's coordinates)
    bonded: np.ndarray  # (n,) cohesion and tensile strength still act
    normal_force: np.ndarray  # (n,) N (compression positive)
    shear_force: np.ndarray  # (n, k) N: the shear force on block a in the frame (spring or friction; 0 open)
    gap: np.ndarray  # (n,) end-of-step normal gap (negative: penetration)
    shear: np.ndarray  # (n, k) end-of-step shear spring stretch (locked); the step's slip (sliding)
    joint: np.ndarray  # (n,) row of the model's joint table
    point: np.ndarray  # (n, dim) contact point x_a at the start of the step
    point_b: np.ndarray  # (n, dim) its foot x_b on block b
    normal: np.ndarray  # (n, dim) contact normal (outward from b)
    energy: float  # J (J per m in 2D): ½k_n g_n² (closed) + ½k_s |s|² (locked)

    @staticmethod
    def empty(record: ContactRecord) -> ContactSet:
        """No contacts, with the array widths of ``record``'s dimension."""
        i, f = np.empty(0, dtype=np.int64), np.empty(0)
        k, dim, fields = record.frame_width, record.point_a.shape[1], record.features.shape[1]
        shear, point = np.empty((0, k)), np.empty((0, dim))
        return ContactSet(i, np.empty((0, fields), dtype=np.int64), i, i, i.astype(np.int8), shear, shear,
                          i.astype(bool), f, shear, f, shear, i, point, point, point, 0.0)

    @property
    def closed(self) -> np.ndarray:
        return self.state != OPEN

    @property
    def max_penetration(self) -> float:
        return deepest_penetration(self.state, self.gap)


class ContactStep:
    """The contacts of one step attempt: springs, friction and the open-close iteration."""

    def __init__(self, record: ContactRecord, kind: ContactKind, params: ContactParameters,
                 response: JointResponse, law: ContactLaw, state: np.ndarray, direction: np.ndarray,
                 reference: np.ndarray, bonded: np.ndarray, normal_force: np.ndarray) -> None:
        self.record = record
        self.kind = kind
        self.params = params
        self.response = response
        self.law = law
        self.state = state
        self.direction = direction
        self.trial = direction.copy()  # the direction a dragged sliding contact takes into the next step
        self.reference = reference
        self.bonded = bonded
        self.normal_force = normal_force
        self.dragged = record.draggable
        self.band = params.tolerance if kind.band else 0.0
        self.shear_points = record.reference_points(reference)
        self.shear0 = np.einsum("nki,ni->nk", record.frame, self.shear_points[0] - self.shear_points[1])
        self.gap = record.gap.copy()
        self.shear = self.shear0.copy()
        self.open_at_start = state == OPEN  # no spring force at t (start_gap)
        self.locked_at_start = state == LOCKED
        self.iterations = 0
        self.closed_this_step = np.zeros(len(state), dtype=bool)
        self.flips = np.zeros(len(state), dtype=np.int64)  # state changes of each contact in this step
        self.friction_normal = normal_force.copy()  # N used for the friction of sliding contacts
        self.applied = np.zeros_like(self.shear)  # friction force of the last solve in the frame (N, on a)
        self.frictionless = np.zeros(len(state), dtype=bool)  # held sliding after their slip turned back
        self._secant: tuple[np.ndarray, np.ndarray] | None = None  # previous (N used, residual)
        self._shapes: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None
        self._shapes_theta: np.ndarray | None = None  # the rotation increment the shapes were made with
        self._springs: ContactSprings | None = None  # the springs at the shapes (add_to)
        self._friction_rows: tuple[np.ndarray, np.ndarray] | None = None  # e·T_a, e·T_b (large systems)
        self._solved_state = state
        self._force_limit: np.ndarray = np.zeros(len(state))  # N, per contact: a change below needs no solve
        # block pairs of the last solve's state changes (for the message of a cut step)
        self.unsettled_pairs = np.column_stack([record.block_a[:0], record.block_b[:0]])
        # the water force of each contact (N, pushing its blocks apart along n: constraints.water), None: dry
        self.water: np.ndarray | None = None
        # contacts whose joint has a restitution and carries no tension: the impact law instead of Shi's
        # normal spring (law.impact_force); None where there are none
        self.impacts: ImpactSprings | None = None
        if response.restitution is not None:
            index = np.flatnonzero(~np.isnan(response.restitution) & (response.tension == 0.0))
            if len(index):
                self.impacts = ImpactSprings(index, record.block_a[index], record.block_b[index], record.gap[index],
                                             response.normal_stiffness[index], response.restitution[index])

    def __len__(self) -> int:
        return len(self.state)

    def _shapes_at(self, ctx: StepContext) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """T at x_a, x_b and at the shear spring's points r_a, r_b (r_a = x_a where the record's a-axes are
        zero: the same array)."""
        r = self.record
        a, b = r.block_a, r.block_b
        ta = ctx.shape_at(a, r.point_a)
        on_edge = np.any(r.axes_a != 0.0, axis=(1, 2))
        tra = ta
        if np.any(on_edge):
            tra = ta.copy()
            tra[on_edge] = ctx.shape_at(a[on_edge], self.shear_points[0][on_edge])
        return ta, ctx.shape_at(b, r.point_b), tra, ctx.shape_at(b, self.shear_points[1])

    def _springs_at(self, ctx: StepContext) -> ContactSprings:
        """The springs' rows at the step's shapes (made again when the secant pass changes the shapes)."""
        r = self.record
        if self._springs is None or self._shapes_theta is not ctx.theta:  # the points are fixed in a step
            self._shapes = self._shapes_at(ctx)
            self._shapes_theta = ctx.theta
            self._friction_rows = None
            ta, tb, tra, trb = self._shapes
            # the springs' unit rows n·T and e·T of every contact, whatever its state in the solves
            self._springs = ContactSprings(r.block_a, r.block_b, directional_rows(r.normal, ta),
                                           directional_rows(r.normal, tb), directional_rows(r.frame, tra),
                                           directional_rows(r.frame, trb), self.start_gap(ctx.coeffs.c_p),
                                           self.shear0, self.response.normal_stiffness,
                                           self.response.shear_stiffness)
        return self._springs

    def start_gap(self, c_p: float) -> np.ndarray:
        """g₀' (n,) of the normal springs' step force -k_n(g₀' + c_p·Δg) = -k_n((1 − c_p)·g_t + c_p·g).

        The force at the scheme's α-point weighs the spring's force at t,
        -k_n·g_t, by 1 − c_p (α_f of Chung-Hulbert; 0 for Shi and the paper's
        scheme: then g₀' = g₀). That force is what the contact carried at t:
        none if it was open, at most its tensile strength T if closed, so g_t
        is g₀ capped at 0, or at T/k_n. With g_t = g₀ > 0 the spring would
        pull the blocks across the gap for the part of the step before they
        touch: ½k_n·g₀² from nothing per impact (docs/dev/contacts-history.md,
        *Energy from the α-point force of an impact*).
        """
        gap, response = self.record.gap, self.response
        cap = np.where(self.open_at_start, 0.0, response.tension / response.normal_stiffness)
        return np.where(gap > cap, c_p * gap + (1.0 - c_p) * cap, gap)

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        r = self.record
        a, b = r.block_a, r.block_b
        springs = self._springs_at(ctx)
        assert self._shapes is not None
        ta, tb, tra, _ = self._shapes
        self._solved_state = self.state.copy()  # the states of this solve's forces (for work)
        # by changes while the shapes stay those of the step (Shi's T at t, not the secant pass's)
        springs.add_to(system, self._shi_normal(self.state != OPEN), self.state == LOCKED, ctx.coeffs.c_p,
                       by_changes=ctx.theta is None and is_large(system.n_blocks))
        self.add_water(system, springs)
        if self.impacts is not None:
            i = self.impacts.index
            self.impacts.add_to(system, springs.normal_a[i], springs.normal_b[i], ctx)
        sliding = self.state == SLIDING
        # Coulomb friction opposing the slip of x_a over b, N of an earlier solve (Shi 1988), on a's block
        self.applied = np.where(sliding[:, None],
                                -(self.response.friction * self.friction_normal)[:, None] * self.direction, 0.0)
        if not np.any(sliding):
            return
        applied = self.applied[sliding]
        if is_large(system.n_blocks):  # f·(e·T): the rows e·T_a (the shear spring's where r_a = x_a) and e·T_b
            if self._friction_rows is None:
                rows_a = springs.shear_a if tra is ta else directional_rows(r.frame, ta)
                self._friction_rows = (rows_a, directional_rows(r.frame, tb))
            rows_a, rows_b = self._friction_rows
            scatter_add(system.rhs, a[sliding], np.einsum("nk,nki->ni", applied, rows_a[sliding]))
            scatter_add(system.rhs, b[sliding], -np.einsum("nk,nki->ni", applied, rows_b[sliding]))
        else:  # T·(f e): the order of sums the paper's rows were made with
            force = np.einsum("nk,nki->ni", applied, r.frame[sliding])
            scatter_add(system.rhs, a[sliding], np.einsum("nki,nk->ni", ta[sliding], force))
            scatter_add(system.rhs, b[sliding], -np.einsum("nki,nk->ni", tb[sliding], force))

    def add_water(self, system: BlockSystem, springs: ContactSprings) -> None:
        """The water force W of each contact along n on a, −n on b, through the springs' rows n·T."""
        if self.water is None:
            return
        r, w = self.record, self.water[:, None]
        scatter_add(system.rhs, r.block_a, w * springs.normal_a)
        scatter_add(system.rhs, r.block_b, -w * springs.normal_b)

    def water_work(self, dd: np.ndarray) -> float:
        """Work (J, per m in 2D) of the water forces over the increments ``dd``: W × the gaps' increments."""
        if self.water is None or self._shapes is None:
            return 0.0
        return float(np.dot(self.water, self._increments(dd)[0]))

    def _shi_normal(self, closed: np.ndarray) -> np.ndarray:
        """Of contacts ``closed``, those with Shi's normal spring: all but the impact springs'."""
        if self.impacts is None:
            return closed
        out = closed.copy()
        out[self.impacts.index] = False
        return out

    def _increments(self, dd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """How the gaps (n,) and shears (n, k) move with increments ``dd``: n·(T_a·Δd_a − T_b·Δd_b) and
        e·(T_a(r_a)·Δd_a − T_b(r_b)·Δd_b)."""
        r = self.record
        assert self._shapes is not None and self._springs is not None
        if is_large(len(dd)):  # the springs' rows n·T, e·T times Δd: one compiled pass
            return self._springs.increments(dd)
        # displacements first, then their components: the order of sums the paper's rows were made with
        ta, tb, tra, trb = self._shapes
        da, db = dd[r.block_a], dd[r.block_b]
        ua = np.einsum("nki,ni->nk", ta, da)
        ura = ua if tra is ta else np.einsum("nki,ni->nk", tra, da)
        return (np.einsum("nk,nk->n", r.normal, ua - np.einsum("nki,ni->nk", tb, db)),
                np.einsum("nki,ni->nk", r.frame, ura - np.einsum("nki,ni->nk", trb, db)))

    def _moved(self, dd: np.ndarray) -> None:
        """The gaps and shears after a solve with increments ``dd``."""
        normal_increment, shear_increment = self._increments(dd)
        self.gap = self.record.gap + normal_increment
        self.shear = self.shear0 + shear_increment

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        self._moved(dd)
        r, p, response = self.record, self.params, self.response
        kn = response.normal_stiffness
        self.closed_this_step |= (self.state == OPEN) & (self.gap < 0)
        compression = np.maximum(-kn * self.gap, 0.0)
        self._force_limit = negligible_force(ctx.arrays.block_mass, ctx.arrays.gravity, r.block_a, r.block_b,
                                             compression, p.force_tolerance)
        slip = self.shear - self.shear0
        state, direction, trial, changed, unsettled = next_states(
            self.state, self.direction, self.gap, self.shear, slip, kn, response.shear_stiffness,
            response.strength(compression), response.friction, response.tension, self.closed_this_step,
            self.friction_normal, self.dragged, p.friction_tolerance, self.band, self._force_limit)
        # a contact that has already changed state ``freeze_after`` times in this step keeps its state,
        # so that the iteration ends (it may carry a little tension for one step; the next step
        # starts from the actual gap), except the changes of ``never_held``. After ``settle_after``
        # solves every contact is held so, to settle cascades in large systems.
        band = 1e-6 * p.distance  # clearly open or penetrating, not by rounding at a zero gap
        safe = never_held(self.state, state, self.gap, band, self.flips, p.freeze_after)
        limit = 0 if self.iterations >= p.settle_after else p.freeze_after
        frozen = (self.flips >= limit) & (state != self.state) & ~safe
        # a contact held SLIDING whose slip reversed had its friction push the block the way it
        # moves (creating energy): it keeps sliding with no friction (direction zero), a force inside
        # the friction cone, and the step is solved once more so that the accepted solution never has
        # that friction
        measure = np.where(self.dragged[:, None], slip, self.shear)
        turned_back = frozen & (self.state == SLIDING) & (np.einsum("nk,nk->n", measure, self.direction) < 0)
        state = np.where(frozen, self.state, state).astype(np.int8)
        direction = np.where((frozen & ~turned_back)[:, None], self.direction, direction)
        # a dragged spring stays without friction for the rest of the step (it starts the next one sliding
        # free, from the trial direction of its slip); Shi's spring may slide with friction again after it
        # relocked, and locks at the next step's start (ContactModel.prepare)
        self.frictionless |= turned_back
        free = turned_back | (self.frictionless & self.dragged)
        direction = np.where(free[:, None], 0.0, direction)
        self.trial = np.where(self.frictionless[:, None], 0.0, trial)
        changed = np.where(frozen, turned_back, changed) & ~self._negligible(state, compression)
        if self.iterations < p.settle_after:  # then friction forces are taken as they are
            changed = changed | unsettled
        flipped = state != self.state
        self.flips += flipped
        self.normal_force = compression
        self.friction_normal = self._next_friction_normal(state, flipped, ctx.arrays.block_fixed)
        self.state, self.direction = state, direction
        self.iterations += 1
        self.unsettled_pairs = np.column_stack([r.block_a[changed], r.block_b[changed]])
        impacts_settled = self.impacts is None or self.impacts.settled(self.gap[self.impacts.index])
        return not bool(np.any(changed)) and impacts_settled

    def _negligible(self, new_state: np.ndarray, compression: np.ndarray) -> np.ndarray:
        """Closings and slips below :func:`negligible_force`: they take their new state without another
        solve and act from the next solve or step. They bring no work into the step: a late closing stores
        at most ½(limit)²/k_n, a late slip only loses its spring's energy."""
        if self.params.force_tolerance == 0.0:
            return np.zeros(len(new_state), dtype=bool)
        response = self.response
        return negligible_changes(self.state, new_state, compression,
                                  response.shear_stiffness * magnitudes(self.shear),
                                  response.strength(compression), self._force_limit)

    def _next_friction_normal(self, new_state: np.ndarray, flipped: np.ndarray, fixed: np.ndarray) -> np.ndarray:
        """N for the next solve's friction, by the kind's rule (:class:`ContactKind`).

        ``"secant"``: plain substitution (Shi) converges slowly when friction
        feeds back on the normal force (a glancing impact: factor about −1/3
        per solve); the secant step on the scalar residual N_solved − N_used
        settles it in two or three solves; contacts that were not sliding take
        N_solved. ``"substitution"``: N_solved, only from a solve in which no
        contact of the same blocks changed state (fixed blocks do not count):
        a transitional solve (locked springs stopping a sliding box dead in
        one step) gives normal forces a hundred times the weight, whose
        friction tipped the box over (docs/contacts.md).
        """
        used, solved = self.friction_normal, self.normal_force
        if self.kind.friction_normal == "substitution":
            a, b = self.record.block_a, self.record.block_b
            touched = np.zeros(len(fixed), dtype=bool)
            touched[a[flipped]] = True
            touched[b[flipped]] = True
            touched[fixed] = False
            return np.where(touched[a] | touched[b], used, solved)
        residual = solved - used
        sliding = (self.state == SLIDING) & (new_state == SLIDING)
        nxt = solved.copy()
        if self._secant is not None:
            _secant_normal(used, solved, residual, *self._secant, sliding, nxt)
        self._secant = (used.copy(), residual)
        return nxt

    # -- after the step ---------------------------------------------------
    def commit(self) -> ContactSet:
        """The contacts as they ended the accepted step.

        A contact held closed in the open-close band or by the freezing rules
        (a positive gap, pulling beyond its tensile strength) ends the step
        open: its spring's energy is dropped (counted as dissipated by
        :meth:`work`), never carried into the next step.
        """
        energy = self.stored_energy()
        self.state = np.where(self._held_in_band(), OPEN, self.state).astype(np.int8)
        locked, sliding = (self.state == LOCKED)[:, None], (self.state == SLIDING)[:, None]
        slip = np.where(sliding, self.shear - self.shear0, 0.0)  # for the next step's start
        spring = -self.response.shear_stiffness[:, None] * self.shear
        r = self.record
        return ContactSet(r.key, r.features, r.block_a, r.block_b, self.state.copy(),
                          np.where(self.dragged[:, None], self.trial, self.direction), self.reference.copy(),
                          self.law.keeps_bond(self.bonded, self.state), self.normal_force.copy(),
                          np.where(locked, spring, np.where(sliding, self.applied, 0.0)), self.gap.copy(),
                          np.where(locked, self.shear, slip), r.joint, r.point_a, r.point_b, r.normal, energy)

    @property
    def max_penetration(self) -> float:
        return deepest_penetration(self.state, self.gap)

    def _held_in_band(self) -> np.ndarray:
        """Closed contacts in tension beyond their strength (and the negligible force, see
        :meth:`_negligible`): held closed only by the open-close band or the freezing rules."""
        return (self.state != OPEN) & (self.response.normal_stiffness * self.gap > self.response.tension
                                       + self._force_limit)

    def stored_energy(self) -> float:
        """J (per m in 2D) the contacts keep after the step: ½k_n g² of the closed contacts + ½k_s |s|² of
        the locked ones, those held in tension beyond their strength left out (they are committed open)."""
        kept = ~self._held_in_band()
        closed, locked = self._shi_normal(self.state != OPEN) & kept, (self.state == LOCKED) & kept
        response = self.response
        energy = 0.5 * float(np.sum(response.normal_stiffness[closed] * self.gap[closed] ** 2)) \
            + 0.5 * float(np.sum(response.shear_stiffness[locked, None] * self.shear[locked] ** 2))
        return energy if self.impacts is None else energy + self.impacts.energy(self.gap[self.impacts.index])

    def start_energy(self) -> float:
        """J (per m in 2D) the springs hold at t at the step's detected gaps and stretches: ½k_n g₀² of the
        contacts closed at t, ½k_s|s₀|² of those locked (what :meth:`work`'s springs did work from)."""
        closed, locked = ~self.open_at_start, self.locked_at_start
        response = self.response
        return 0.5 * float(np.sum(response.normal_stiffness[closed] * self.record.gap[closed] ** 2)) \
            + 0.5 * float(np.sum(response.shear_stiffness[locked, None] * self.shear0[locked] ** 2))

    def work(self, dd: np.ndarray, c_p: float) -> tuple[float, float]:
        """Work (J, per m in 2D) over the increments ``dd`` of the last solve's friction forces and springs.

        The forces are those ``add_to`` put on the right-hand side: friction
        at x_a and its reverse at x_b, so a sliding contact gives
        −tanφ·N·|slip|; the springs' −k(g₀ + c_p·Δg) on the closed contacts'
        normal gap and the locked ones' shear. The springs' work minus the
        change of their stored energy is what the penalty took out: c_p = 1
        gives −½k·Δg² per step (the impact loss of the step's backward-Euler
        spring force), plus the energy of springs that open or unlock while
        stretched.
        """
        if self._shapes is None:
            return 0.0, 0.0
        ta, tb, _, _ = self._shapes
        r = self.record
        slip = np.einsum("nki,ni->nk", r.frame, np.einsum("nki,ni->nk", ta, dd[r.block_a])
                         - np.einsum("nki,ni->nk", tb, dd[r.block_b]))
        friction = float(np.sum(self.applied * slip))
        closed, locked = self._shi_normal(self._solved_state != OPEN), self._solved_state == LOCKED
        dg, ds = self.gap - r.gap, self.shear - self.shear0
        kn, ks = self.response.normal_stiffness, self.response.shear_stiffness
        springs = -float(np.sum((kn * (self.start_gap(c_p) + c_p * dg) * dg)[closed])) \
            - float(np.sum((ks[:, None] * (self.shear0 + c_p * ds) * ds)[locked]))
        if self.impacts is not None:
            springs += self.impacts.work(self.gap[self.impacts.index])
        return friction, springs

    def impact_loss(self) -> float:
        """What the impact springs (contacts with a restitution) took out over the step (J, per m in 2D)."""
        return 0.0 if self.impacts is None else self.impacts.loss(self.gap[self.impacts.index])


UNSETTLED_SHOWN = 3  # block pairs named in the message of a step cut by the open-close


class ContactModel:
    """The contacts of a model: its dimension's detector, its joint law, and each step's contacts."""

    def __init__(self, arrays: ModelArrays, params: ContactParameters, law: ContactLaw | None = None) -> None:
        self.arrays = arrays
        self.params = params
        self.law = law if law is not None else MohrCoulomb()
        self.kind = CONTACT_KINDS[arrays.block_type.name]
        self.detector = self.kind.detector(arrays, params.distance, params.angle_tolerance, params.max_penetration)

    @property
    def can_touch(self) -> np.ndarray:
        """(nb,) the blocks some other block may touch (not those hinged to every other block)."""
        return self.detector.pairs.can_touch

    def prepare(self, vertices: np.ndarray, previous: ContactSet | None, first_step: bool) -> ContactStep | None:
        """The contacts of the step starting at ``vertices``; None when no contact is near."""
        record = self.detector.detect(vertices)
        if record is None:
            return None
        previous = previous if previous is not None else ContactSet.empty(record)
        old = match_previous(record.key, previous.key)
        kept = old >= 0
        # contacts present at the start are bonded joints; ones formed later never are
        bonded = np.full(len(record), first_step)
        bonded[kept] = previous.bonded[old[kept]]
        response = self.law.response(self.arrays.joints, record, bonded, self.params.stiffness)
        normal_force = response.normal_stiffness * np.maximum(-record.gap, 0.0)
        normal_force[kept] = previous.normal_force[old[kept]]
        return self.start(record, previous, old, bonded, response, normal_force)

    def start(self, record: ContactRecord, previous: ContactSet, old: np.ndarray, bonded: np.ndarray,
              response: JointResponse, normal_force: np.ndarray) -> ContactStep:
        """The step's contacts from what the last step's ``previous[old]`` knew (``old`` -1: a new contact):
        the open-close's starting states and springs."""
        kept = old >= 0
        src = old[kept]
        n, k = len(record), record.frame_width
        state = np.where(record.gap <= 0.0, LOCKED, OPEN).astype(np.int8)
        state[kept] = previous.state[src]
        direction = np.zeros((n, k))
        direction[kept] = previous.direction[src]
        # one held sliding without friction (its slip reversed, see ContactStep.converged) locks
        # again, unstretched: the slip reversal locks a contact (Shi 1988); a dragged spring slides on
        # free until it holds (openclose module doc)
        state[(state == SLIDING) & ~np.any(direction != 0.0, axis=1) & ~record.draggable] = LOCKED
        # one that slid less than Shi's band f0·w0 in the last step starts locked, unstretched: at rest
        # it would keep a full friction force in a direction it no longer moves, and the iteration on
        # that force's normal force, not a state change, would set the step's solves (docs/contacts.md,
        # "Contacts at rest start locked"); still driven past its strength, it slips again at the first solve
        band = self.params.tolerance if self.kind.band else 0.0
        slip = np.zeros(n)
        slip[kept] = magnitudes(previous.shear[src])
        at_rest = (state == SLIDING) & (slip <= band) & (band > 0.0)
        state[at_rest] = LOCKED
        direction[at_rest] = 0.0
        # a new, sliding or open contact starts its shear spring unstretched (the record's start
        # reference); a locked one keeps its reference
        reference = record.start_reference.copy()
        keep_reference = kept.copy()
        keep_reference[kept] = previous.state[src] == LOCKED
        reference[keep_reference] = previous.reference[old[keep_reference]]
        # a sliding contact whose spring is dragged starts it stretched to its strength along its slip
        # direction (an elastic-plastic spring dragged along, Simo & Hughes 1998), so that if it locks
        # again it carries the friction force it had, not zero (docs/contacts.md)
        dragged = kept & record.draggable
        dragged[kept] &= previous.state[src] == SLIDING
        cap = response.friction[dragged] * previous.normal_force[old[dragged]] / response.shear_stiffness[dragged]
        reference[dragged] += record.reference_shift(cap[:, None] * previous.direction[old[dragged]], dragged)
        return ContactStep(record, self.kind, self.params, response, self.law, state, direction, reference, bonded,
                           normal_force)


class ContactTerm(Term):
    """Block contacts as a step term (module doc): open-close iteration, step cuts, contact energy; the
    :class:`ContactSet` of the last step is carried in ``State.carried["contacts"]``."""

    name = "contacts"
    energy_kind = "contact"
    cuts_step = True  # an open-close that does not settle within ``max_iterations`` solves cuts Δt

    def __init__(self, model: ContactModel, max_iterations: int, max_displacement: float, dt_max: float) -> None:
        self.model = model
        self.max_iterations = max_iterations
        self.max_displacement = max_displacement  # g2·w0: how far a vertex may move in one step
        self.dt_max = dt_max  # the run's Δt, which the step grows back to
        self.step: ContactStep | None = None

    def begin(self, ctx: StepContext) -> None:
        state = ctx.state
        self.step = self.model.prepare(state.vertices, state.contacts, state.step == 0)
        water = ctx.arrays.water
        if self.step is not None and water is not None:
            self.step.water = contact_water(water, self.step.record, self.model.params.distance, state.vertices,
                                            boundary_simplices(ctx.arrays))

    @property
    def at_points(self) -> bool:
        return self.step is not None

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        if self.step is not None:
            self.step.add_to(system, ctx)

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        return self.step is None or self.step.converged(dd, ctx)

    def pending(self) -> str:
        """The open-close message of a cut step: how many contacts still changed, and between which blocks."""
        if self.step is None:
            return "open-close did not converge"
        pairs, arrays = self.step.unsettled_pairs, self.model.arrays
        keys, counts = np.unique(pair_keys(pairs, arrays.n_blocks), return_counts=True)
        top = np.argsort(-counts, kind="stable")[:UNSETTLED_SHOWN]
        shown = ", ".join(f"{arrays.block_names[k // arrays.n_blocks]}/{arrays.block_names[k % arrays.n_blocks]}"
                          + (f" ({n} contacts)" if n > 1 else "") for k, n in zip(keys[top], counts[top]))
        more = len(keys) - len(top)
        return (f"open-close did not converge ({len(pairs)} contacts still changing state, between blocks "
                f"{shown}{f' and {more} more pairs' if more > 0 else ''})")

    def review(self, ctx: StepContext, new: State) -> StepCut | float | None:
        """Cut a step whose vertices moved more than g2·w0 or that penetrated too deep; else grow Δt.

        g2 keeps contacts detectable between two detections, so it bounds the
        vertices of blocks that some other block may touch (not those whose every
        neighbour is hinged to them).
        """
        touching = self.model.can_touch[ctx.arrays.vertex_block]
        moved = float(np.max(np.hypot.reduce(new.vertices[touching] - ctx.state.vertices[touching], axis=1)))
        if moved > self.max_displacement:
            return StepCut(f"a vertex moved {moved:.3g} m > g2·w0 = {self.max_displacement:.3g} m",
                           min(0.9, 0.9 * self.max_displacement / moved), "displacement")
        step = self.step
        if step is not None and step.max_penetration > step.params.max_penetration:
            return StepCut(f"penetration {step.max_penetration:.3g} m > {step.params.max_penetration:.3g} m "
                           "(raise the contact penalty)", 0.0, "penetration")
        # grow Δt back towards the set value, at most ×1.5, aiming at 90% of g2·w0 for the next step
        growth = 1.5 if moved == 0 else min(1.5, 0.9 * self.max_displacement / moved)
        return min(self.dt_max, ctx.dt * growth)

    def commit(self, new: State) -> State:
        return new.carrying(self.name, self.step.commit() if self.step is not None else None)

    def energy(self, arrays: ModelArrays, state: State) -> float:
        return state.contacts.energy if state.contacts is not None else 0.0

    def work(self, ctx: StepContext, new: State, dd: np.ndarray, multipliers: np.ndarray) -> np.ndarray | None:
        """What the contacts took out over the step: by friction, and by their penalty springs.

        ``dissipated_contact`` is the springs' negative work minus the change of
        their stored energy, from what this step's springs held at t
        (:meth:`ContactStep.start_energy`) to the end. Not from the energy the
        last step committed: its gaps moved by the linearised increments, this
        step's are detected at the exact vertices, and the difference (second
        order in the step: a vertex sliding along an edge that turns) is the
        linearisation's, left in the balance with D_numerical (srdda.ledger),
        as is the energy of a contact found already penetrating.
        """
        if self.step is None:
            return None
        friction, springs = self.step.work(dd, ctx.coeffs.c_p)
        stored = self.step.stored_energy() - self.step.start_energy()
        out = np.zeros(len(LEDGER))
        impact = self.step.impact_loss()
        out[LEDGER.index("dissipated_friction")] = -friction
        out[LEDGER.index("dissipated_contact")] = -springs - stored - impact
        out[LEDGER.index("dissipated_impact")] = impact
        out[LEDGER.index("work_water")] = self.step.water_work(dd)
        return out


@njit(cache=True)
def _secant_normal(used: np.ndarray, solved: np.ndarray, residual: np.ndarray, prev_used: np.ndarray,
                   prev_residual: np.ndarray, sliding: np.ndarray, nxt: np.ndarray) -> None:
    """The secant step of :meth:`ContactStep._next_friction_normal` where it applies, into ``nxt``.

    Safeguarded: taken only between N_used and N_solved, where the fixed point
    of a map with slope in (-1, 0] lies; elsewhere ``nxt`` keeps plain
    substitution (a far extrapolation would load friction past any N of the step).
    """
    for c in range(len(used)):
        slope = residual[c] - prev_residual[c]
        if sliding[c] and abs(slope) > 1e-12 * max(abs(residual[c]), 1e-300) and used[c] != prev_used[c]:
            secant = used[c] - residual[c] * (used[c] - prev_used[c]) / slope
            if min(used[c], solved[c]) <= secant <= max(used[c], solved[c]) and solved[c] > 0.0:
                nxt[c] = secant
