"""Contacts as a step term (:class:`ContactTerm`), and their state between steps.

Per step attempt: :meth:`ContactModel.prepare` detects contacts in the
configuration at t (broad + narrow phase), carries over what persisting
contacts knew (:class:`ContactSet` on ``State.contacts``) and returns the
step's :class:`ContactStep`, which adds the springs and friction forces of the
assumed states; after each solve it runs the open-close rules and asks for
another solve while a state changes. After the update the term cuts a step
whose vertices moved more than g2·w0 or penetrated too deep, and commits the
:class:`ContactSet` of an accepted step to its state.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from ..assembly.system import BlockSystem, scatter_add
from ..model import JOINT_COHESION, JOINT_FRICTION, JOINT_TENSION, ModelArrays
from ..term import LEDGER, StepContext, StepCut, Term
from .broadphase import block_boxes, candidate_pairs
from .candidates import KeptCandidates
from ..geometry.polygon import previous_vertex_index
from .narrowphase import FOUND_EDGE, FOUND_FIELDS, FOUND_KIND, FOUND_VERTEX, detect_contacts
from .openclose import (LOCKED, OPEN, SLIDING, deepest_penetration, negligible_changes, negligible_force, never_held,
                        next_states)
from .penalty import ContactSprings, directional_rows, is_large
from .springs import ContactGeometry, bond_length, contact_geometry
from .transfer import contact_keys, match_previous

if TYPE_CHECKING:
    from ..state import State

__all__ = ["ContactParameters", "ContactSet", "ContactStep", "ContactModel", "ContactTerm"]


@dataclass(frozen=True)
class ContactParameters:
    """Resolved contact settings of a run (SI)."""

    normal_stiffness: float  # k_n (N/m)
    shear_stiffness: float  # k_s (N/m)
    distance: float  # d0 (m): contact search distance
    angle_tolerance: float  # rad, Shi's angle criterion
    max_penetration: float  # m: a step that penetrates deeper is cut
    friction_tolerance: float = 1e-3  # relative settling of the friction normal force
    freeze_after: int = 2  # state changes of one contact in a step after which its state is kept
    settle_after: int = 8  # solves after which no contact reopens or relocks, friction is not re-iterated
    tolerance: float = 0.0  # m, Shi's f0·w0: the open and reverse-slip bands, the settled friction displacement
    force_tolerance: float = 0.0  # × the pair's force scale (openclose.negligible_force): below, no further solve


@dataclass(frozen=True)
class ContactSet:
    """Contacts at the end of an accepted step (stored on ``State.contacts``)."""

    vertex: np.ndarray  # (n,) contact vertex
    edge: np.ndarray  # (n,) contacted edge (its start vertex)
    kind: np.ndarray  # (n,) 0 vertex-edge, 1 vertex-vertex
    state: np.ndarray  # (n,) OPEN / SLIDING / LOCKED
    sign: np.ndarray  # (n,) slip direction along the edge of sliding contacts
    reference: np.ndarray  # (n,) edge parameter of the shear reference point
    bonded: np.ndarray  # (n,) cohesion and tensile strength still act
    normal_force: np.ndarray  # (n,) N (compression positive)
    gap: np.ndarray  # (n,) end-of-step normal gap (negative: penetration)
    shear: np.ndarray  # (n,) end-of-step shear spring displacement (locked); the step's slip (sliding)
    energy: float  # J per m: ½k_n g_n² (closed) + ½k_s s² (locked)

    @staticmethod
    def empty() -> ContactSet:
        i = np.empty(0, dtype=np.int64)
        f = np.empty(0)
        return ContactSet(i, i, i, i.astype(np.int8), i.astype(np.int8), f, i.astype(bool), f, f, f, 0.0)

    @property
    def closed(self) -> np.ndarray:
        return self.state != OPEN

    @property
    def max_penetration(self) -> float:
        return deepest_penetration(self.state, self.gap)


class ContactStep:
    """The contacts of one step attempt: springs, friction and the open-close iteration."""

    def __init__(self, geometry: ContactGeometry, found: np.ndarray, params: ContactParameters, state: np.ndarray,
                 sign: np.ndarray, reference: np.ndarray, bonded: np.ndarray, normal_force: np.ndarray,
                 joint: np.ndarray, length: np.ndarray) -> None:
        self.geometry = geometry
        self.found = found
        self.params = params
        self.state = state
        self.sign = sign
        self.reference = reference
        self.bonded = bonded
        self.normal_force = normal_force
        self.tan_phi = np.tan(joint[:, JOINT_FRICTION])
        self.cohesion_force = np.where(bonded, joint[:, JOINT_COHESION] * length, 0.0)
        self.tension_force = np.where(bonded, joint[:, JOINT_TENSION] * length, 0.0)
        self.shear0 = geometry.shear(reference)
        self.gap = geometry.gap.copy()
        self.shear = self.shear0.copy()
        self.iterations = 0
        self.closed_this_step = np.zeros(len(state), dtype=bool)
        self.flips = np.zeros(len(state), dtype=np.int64)  # state changes of each contact in this step
        self.friction_normal = normal_force.copy()  # N used for the friction of sliding contacts
        self._secant: tuple[np.ndarray, np.ndarray] | None = None  # previous (N used, residual)
        self._shapes: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._shapes_theta: np.ndarray | None = None  # the rotation increment the shapes were made with
        self._springs: ContactSprings | None = None  # the springs at the shapes (add_to)
        self._foot_tangent: np.ndarray | None = None  # t·T_q at the shapes (friction of large systems)
        self._solved_state = state
        self._force_limit: np.ndarray | float = 0.0  # N, per contact: a state change below needs no solve
        # block pairs of the last solve's state changes (for the message of a cut step)
        self.unsettled_pairs = np.column_stack([geometry.vertex_block[:0], geometry.edge_block[:0]])

    def __len__(self) -> int:
        return len(self.state)

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        g = self.geometry
        a, b = g.vertex_block, g.edge_block
        if self._shapes is None or self._shapes_theta is not ctx.theta:  # the points are fixed in a step
            self._shapes = (ctx.shape_at(a, g.point), ctx.shape_at(b, g.foot),
                            ctx.shape_at(b, g.point_on_edge(self.reference)))
            self._shapes_theta = ctx.theta
            self._foot_tangent = None
            tv, tq, tr = self._shapes
            # the springs' unit rows n·T and t·T of every contact, whatever its state in the solves
            self._springs = ContactSprings(a, b, directional_rows(g.normal, tv), directional_rows(g.normal, tq),
                                           directional_rows(g.tangent[:, None], tv),
                                           directional_rows(g.tangent[:, None], tr), g.gap,
                                           self.shear0[:, None], self.params.normal_stiffness,
                                           self.params.shear_stiffness)
        tv, tq, tr = self._shapes
        self._solved_state = self.state.copy()  # the states of this solve's forces (for work)
        # by changes while the shapes stay those of the step (Shi's T at t, not the secant pass's)
        assert self._springs is not None
        self._springs.add_to(system, self.state, ctx.coeffs.c_p, by_changes=ctx.theta is None)
        sliding = self.state == SLIDING
        # friction of this solve along the tangent, on v's block (kept for the ledger: work)
        self.friction = np.where(sliding, -self.sign * self.tan_phi * self.friction_normal, 0.0)
        if np.any(sliding):
            # Coulomb friction opposing the slip of v along the edge, N of the last solve (Shi 1988)
            magnitude = self.friction[sliding]
            if is_large(system.n_blocks):  # f·(t·T): the rows t·T_v (the shear spring's) and t·T_q
                if self._foot_tangent is None:
                    self._foot_tangent = directional_rows(g.tangent, tq)
                scatter_add(system.rhs, a[sliding], magnitude[:, None] * self._springs.shear_a[sliding, 0])
                scatter_add(system.rhs, b[sliding], -magnitude[:, None] * self._foot_tangent[sliding])
            else:  # T·(f t): the order of sums the paper's rows were made with
                force = magnitude[:, None] * g.tangent[sliding]
                scatter_add(system.rhs, a[sliding], np.einsum("nki,nk->ni", tv[sliding], force))
                scatter_add(system.rhs, b[sliding], -np.einsum("nki,nk->ni", tq[sliding], force))

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        assert self._shapes is not None
        g = self.geometry
        if is_large(len(dd)):  # the springs' rows n·T, t·T times Δd: one compiled pass
            assert self._springs is not None
            normal_increment, shear_increment = self._springs.increments(dd)
            self.gap = g.gap + normal_increment
            self.shear = self.shear0 + shear_increment[:, 0]
        else:  # n·(T_v·Δd_v - T_q·Δd_q): the order of sums the paper's rows were made with
            tv, tq, tr = self._shapes
            ua = np.einsum("nki,ni->nk", tv, dd[g.vertex_block])
            self.gap = g.gap + np.einsum("nk,nk->n", g.normal, ua - np.einsum("nki,ni->nk", tq, dd[g.edge_block]))
            self.shear = self.shear0 + np.einsum("nk,nk->n", g.tangent,
                                                 ua - np.einsum("nki,ni->nk", tr, dd[g.edge_block]))
        p = self.params
        self.closed_this_step |= (self.state == OPEN) & (self.gap < 0)
        normal = np.maximum(-p.normal_stiffness * self.gap, 0.0)
        self._force_limit = negligible_force(ctx.arrays.block_mass, ctx.arrays.gravity, g.vertex_block,
                                             g.edge_block, normal, p.force_tolerance)
        state, sign, changed, unsettled = next_states(self.state, self.sign, self.gap, self.shear, p.normal_stiffness,
                                           p.shear_stiffness, self.tan_phi, self.cohesion_force, self.tension_force,
                                           self.closed_this_step, self.friction_normal, p.friction_tolerance,
                                           p.tolerance, self._force_limit)
        # a contact that has already changed state ``freeze_after`` times in this step keeps its state,
        # so that the iteration ends (it may carry a little tension for one step; the next step
        # starts from the actual gap), except the changes of ``never_held``. After ``settle_after``
        # solves every contact is held so, to settle cascades in large systems.
        band = 1e-6 * p.distance  # clearly open or penetrating, not by rounding at a zero gap
        safe = never_held(self.state, state, self.gap, band, self.flips, p.freeze_after)
        limit = 0 if self.iterations >= p.settle_after else p.freeze_after
        frozen = (self.flips >= limit) & (state != self.state) & ~safe
        # a contact held SLIDING whose slip reversed had its friction push the block the way it
        # moves (creating energy): it keeps sliding with no friction, a force inside the friction cone,
        # and the step is solved once more so that the accepted solution never has that friction
        reversed_slip = frozen & (self.state == SLIDING) & (np.sign(self.shear) == -self.sign)
        state = np.where(frozen, self.state, state).astype(np.int8)
        sign = np.where(frozen & ~reversed_slip, self.sign, sign).astype(np.int8)
        sign = np.where(reversed_slip, 0, sign).astype(np.int8)
        changed = np.where(frozen, reversed_slip, changed) & ~self._negligible(state)
        if self.iterations < p.settle_after:  # then friction forces are taken as they are
            changed = changed | unsettled
        self.flips += state != self.state
        self.normal_force = np.maximum(-p.normal_stiffness * self.gap, 0.0)
        self.friction_normal = self._next_friction_normal(state)
        self.state, self.sign = state, sign
        self.iterations += 1
        g = self.geometry
        self.unsettled_pairs = np.column_stack([g.vertex_block[changed], g.edge_block[changed]])
        return not bool(np.any(changed))

    def _negligible(self, new_state: np.ndarray) -> np.ndarray:
        """Closings and slips below :func:`negligible_force`: they take their new state without another
        solve and act from the next solve or step. They bring no work into the step: a late closing stores
        at most ½(limit)²/k_n, a late slip only loses its spring's energy."""
        p = self.params
        if p.force_tolerance == 0.0:
            return np.zeros(len(new_state), dtype=bool)
        normal = np.maximum(-p.normal_stiffness * self.gap, 0.0)
        return negligible_changes(self.state, new_state, normal, p.shear_stiffness * np.abs(self.shear),
                                  normal * self.tan_phi + self.cohesion_force, self._force_limit)

    def _next_friction_normal(self, new_state: np.ndarray) -> np.ndarray:
        """N for the next solve's friction: a per-contact secant step on N_used -> N_solved.

        Plain substitution (Shi) converges slowly when friction feeds back on
        the normal force (a glancing impact: factor about -1/3 per solve); the
        secant step on the scalar residual N_solved - N_used settles it in two
        or three solves. Contacts that were not sliding take N_solved.
        """
        used, solved = self.friction_normal, self.normal_force
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

        A contact held closed in the open-close band (a gap below f0·w0, pulling)
        ends the step open: its spring's energy is dropped (counted as dissipated
        by :meth:`work`), never carried into the next step.
        """
        energy = self.stored_energy()
        self.state = np.where(self._held_in_band(), OPEN, self.state).astype(np.int8)
        locked = self.state == LOCKED
        slip = np.where(self.state == SLIDING, self.shear - self.shear0, 0.0)  # for the next step's start
        found = self.found
        return ContactSet(found[:, FOUND_VERTEX], found[:, FOUND_EDGE], found[:, FOUND_KIND], self.state.copy(),
                          self.sign.copy(), self.reference.copy(), self.bonded & locked, self.normal_force.copy(),
                          self.gap.copy(), np.where(locked, self.shear, slip), energy)

    @property
    def max_penetration(self) -> float:
        return deepest_penetration(self.state, self.gap)

    def _held_in_band(self) -> np.ndarray:
        """Closed contacts in tension beyond their strength (and the negligible force, see
        :meth:`_negligible`): held closed only by the open-close band."""
        return (self.state != OPEN) & (self.params.normal_stiffness * self.gap > self.tension_force
                                       + self._force_limit)

    def stored_energy(self) -> float:
        """J per m the contacts keep after the step: ½k_n g² of the closed contacts + ½k_s s² of the locked
        ones, those held in the open-close band left out (they are committed open)."""
        p = self.params
        kept = ~self._held_in_band()
        return 0.5 * p.normal_stiffness * float(np.sum(self.gap[(self.state != OPEN) & kept] ** 2)) \
            + 0.5 * p.shear_stiffness * float(np.sum(self.shear[(self.state == LOCKED) & kept] ** 2))

    def work(self, dd: np.ndarray, c_p: float) -> tuple[float, float]:
        """Work (J per m) over the increments ``dd`` of the last solve's friction forces and contact springs.

        The forces are those ``add_to`` put on the right-hand side: friction
        on v's block at v and the opposite on the edge's block at the foot, so a
        sliding contact gives -tanφ·N·|slip|; the springs' -k(g₀ + c_p·Δg) on the
        closed contacts' normal gap and the locked ones' shear. The springs'
        work minus the change of their stored energy is what the penalty took
        out: c_p = 1 gives -½k·Δg² per step (the impact loss of the step's
        backward-Euler spring force), plus the energy of springs that open or
        unlock while stretched.
        """
        if self._shapes is None:
            return 0.0, 0.0
        tv, tq, _ = self._shapes
        g = self.geometry
        slip = np.einsum("nk,nk->n", g.tangent, np.einsum("nki,ni->nk", tv, dd[g.vertex_block])
                         - np.einsum("nki,ni->nk", tq, dd[g.edge_block]))
        friction = float(np.sum(self.friction * slip))
        p = self.params
        closed, locked = self._solved_state != OPEN, self._solved_state == LOCKED
        dg, ds = self.gap - g.gap, self.shear - self.shear0
        springs = -p.normal_stiffness * float(np.sum(((g.gap + c_p * dg) * dg)[closed])) \
            - p.shear_stiffness * float(np.sum(((self.shear0 + c_p * ds) * ds)[locked]))
        return friction, springs


UNSETTLED_SHOWN = 3  # block pairs named in the message of a step cut by the open-close


def pair_keys(pairs: np.ndarray, n_blocks: int) -> np.ndarray:
    """One integer per unordered block pair (k, 2): min·n + max."""
    return np.min(pairs, axis=1) * n_blocks + np.max(pairs, axis=1) if len(pairs) else np.zeros(0, np.int64)


class ContactModel:
    """Detects the contacts of a configuration (hinged block pairs left out) and builds each step's contacts."""

    def __init__(self, arrays: ModelArrays, params: ContactParameters) -> None:
        self.arrays = arrays
        self.params = params
        self.previous_vertex = previous_vertex_index(arrays.block_ptr)
        self.movable = ~arrays.block_fixed
        self.sin_tol = float(np.sin(params.angle_tolerance))
        self.cos_parallel = float(np.cos(params.angle_tolerance))
        # blocks joined by a hinge turn about a shared point: their faces are not joints
        self.excluded = np.unique(pair_keys(arrays.links.hinged_block_pairs, arrays.n_blocks))
        first, second = np.divmod(self.excluded, arrays.n_blocks)
        partners_left_out = np.bincount(np.concatenate([first, second]), minlength=arrays.n_blocks)
        self.can_touch = partners_left_out < arrays.n_blocks - 1  # some other block may touch it
        # the broad phase with a margin of d0, run again once a vertex has moved d0/2 (contact.candidates)
        self.candidates = KeptCandidates(lambda boxes, d: candidate_pairs(boxes, d, self.movable),
                                         params.distance, params.distance)

    def detect(self, vertices: np.ndarray) -> np.ndarray:
        """Contacts (k, 3) [vertex, edge start, kind] of a configuration."""
        arr = self.arrays
        boxes = block_boxes(vertices, arr.block_ptr)
        pairs = self.candidates(vertices, boxes)
        if len(self.excluded):
            pairs = pairs[~np.isin(pair_keys(pairs, arr.n_blocks), self.excluded)]
        if len(pairs) == 0:
            return np.empty((0, FOUND_FIELDS), dtype=np.int64)
        return detect_contacts(vertices, arr.block_ptr, arr.vertex_block, arr.next_vertex, self.previous_vertex,
                               pairs, boxes, self.params.distance, self.sin_tol, self.params.max_penetration)

    def prepare(self, vertices: np.ndarray, previous: ContactSet | None, first_step: bool) -> ContactStep | None:
        """The term of the step starting at ``vertices``; None when no contact is near."""
        found = self.detect(vertices)
        if len(found) == 0:
            return None
        arr = self.arrays
        vertex, edge = found[:, FOUND_VERTEX], found[:, FOUND_EDGE]
        geom = contact_geometry(vertices, arr.vertex_block, arr.next_vertex, vertex, edge)
        previous = previous if previous is not None else ContactSet.empty()
        nv = len(vertices)
        old = match_previous(contact_keys(vertex, edge, nv),
                             contact_keys(previous.vertex, previous.edge, nv))
        kept = old >= 0
        src = old[kept]
        state = np.where(geom.gap <= 0.0, LOCKED, OPEN).astype(np.int8)
        state[kept] = previous.state[src]
        sign = np.zeros(len(found), dtype=np.int8)
        sign[kept] = previous.sign[src]
        # one held sliding without friction (its slip reversed, see ContactStep.converged) locks
        # again, unstretched: the slip reversal locks a contact (Shi 1988)
        state[(state == SLIDING) & (sign == 0)] = LOCKED
        # one that slid less than Shi's band f0·w0 in the last step starts locked, unstretched: at rest
        # it would keep a full friction force in a direction it no longer moves, and the iteration on
        # that force's normal force, not a state change, would set the step's solves (docs/contacts.md,
        # "Contacts at rest start locked"); still driven past its strength, it slips again at the first solve
        slip = np.zeros(len(found))
        slip[kept] = previous.shear[src]
        at_rest = (state == SLIDING) & (np.abs(slip) <= self.params.tolerance) & (self.params.tolerance > 0.0)
        state[at_rest] = LOCKED
        sign[at_rest] = 0
        # a new, sliding or open contact starts its shear spring unstretched: the reference is the
        # projection of v on the edge's line, beyond the edge's end for a vertex-vertex contact
        # (clipped to the end, a new locked spring would start stretched by up to d0)
        reference = geom.parameter.copy()
        keep_reference = kept.copy()
        keep_reference[kept] = previous.state[src] == LOCKED
        reference[keep_reference] = previous.reference[old[keep_reference]]
        # contacts present at the start are bonded joints; ones formed later never are
        bonded = np.full(len(found), first_step)
        bonded[kept] = previous.bonded[src]
        normal_force = self.params.normal_stiffness * np.maximum(-geom.gap, 0.0)
        normal_force[kept] = previous.normal_force[src]
        joint_index = arr.edge_joint[edge]
        by_materials = arr.joint_by_materials[arr.block_material[geom.vertex_block],
                                              arr.block_material[geom.edge_block]]
        joint = arr.joint_properties[np.where(joint_index >= 0, joint_index, by_materials)]
        length = bond_length(vertices, arr.next_vertex, self.previous_vertex, vertex, geom.tangent,
                             self.cos_parallel)
        return ContactStep(geom, found, self.params, state, sign, reference, bonded, normal_force, joint, length)


class ContactTerm(Term):
    """Block contacts as a step term (module doc): open-close iteration, step cuts, contact energy."""

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
                           min(0.9, 0.9 * self.max_displacement / moved))
        step = self.step
        if step is not None and step.max_penetration > step.params.max_penetration:
            return StepCut(f"penetration {step.max_penetration:.3g} m > {step.params.max_penetration:.3g} m "
                           "(raise the contact penalty)", 0.0)
        # grow Δt back towards the set value, at most ×1.5, aiming at 90% of g2·w0 for the next step
        growth = 1.5 if moved == 0 else min(1.5, 0.9 * self.max_displacement / moved)
        return min(self.dt_max, ctx.dt * growth)

    def commit(self, new: State) -> State:
        return replace(new, contacts=self.step.commit() if self.step is not None else None)

    def energy(self, arrays: ModelArrays, state: State) -> float:
        return state.contacts.energy if state.contacts is not None else 0.0

    def work(self, ctx: StepContext, new: State, dd: np.ndarray, multipliers: np.ndarray) -> np.ndarray | None:
        """What the contacts took out over the step: by friction, and by their penalty springs.

        ``dissipated_contact`` is the springs' negative work minus the change of
        their stored energy (from the contacts at t to those of this step).
        """
        if self.step is None and ctx.state.contacts is None:
            return None
        friction, springs = (0.0, 0.0) if self.step is None else self.step.work(dd, ctx.coeffs.c_p)
        stored = 0.0 if self.step is None else self.step.stored_energy()
        out = np.zeros(len(LEDGER))
        out[LEDGER.index("dissipated_friction")] = -friction
        out[LEDGER.index("dissipated_contact")] = -springs - (stored - self.energy(ctx.arrays, ctx.state))
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
