"""Contacts between polyhedra as a step term: the 3D counterpart of :mod:`srdda.contact.term`.

Per step attempt :meth:`SolidContactModel.prepare` detects the contacts of the
configuration at t (:mod:`.polyhedra_broadphase`, :mod:`.polyhedra_narrowphase`),
carries over what persisting contacts knew (:class:`SolidContactSet` on
``State.contacts``) and returns the step's :class:`SolidContactStep`.

A contact joins a point x_a of block a and a point x_b of block b along the
unit normal n (outward from b) and has a shear frame (e1, e2) in its plane:

* vertex-face: x_a the vertex, x_b its projection on the face's plane, n the
  face's normal, e1 along the face's first edge;
* edge-edge: x_a, x_b the closest points of the two edges, n their cross
  product turned outward from b, e1 along b's edge.

With the method's shape functions (``StepContext.shape_at``) the end-of-step
normal gap and the shear vector are, to first order in Δd (Shi 2001, the 3D
form of the 2D springs of :mod:`.springs`),

    g_n = g_0 + n·(T_a(x_a) Δd_a − T_b(x_b) Δd_b)
    s_k = s_k0 + e_k·(T_a(r_a) Δd_a − T_b(r_b) Δd_b),   k = 1, 2,

r_a, r_b the material reference points of the shear spring (the vertex and a
point of the face stored in the face's frame; points of the two edges stored
as edge parameters). A closed contact adds ½k_n g_n², a locked one also
½k_s |s|² (three penalty rows, :func:`srdda.assembly.system.add_penalty_pairs`);
a sliding one the Coulomb force −tan φ·N·ŝ at x_a (and its reverse at x_b),
ŝ the slip direction of the previous solve, N its normal force (Shi). The
open-close rules are those of :mod:`.openclose` with a 2-vector shear
(:func:`next_states_3d`). The friction force's work over each accepted step
goes to the ledger's ``dissipated_friction``.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..assembly.system import BlockSystem, scatter_add
from ..geometry.polyhedron import PolyhedronMesh
from ..model import JOINT_COHESION, JOINT_FRICTION, JOINT_TENSION, ModelArrays, ModelError
from ..term import LEDGER, StepContext
from .openclose import LOCKED, OPEN, SLIDING, deepest_penetration, negligible_changes, negligible_force, never_held
from .candidates import KeptCandidates
from .penalty import ContactSprings, directional_rows, is_large
from .polyhedra_broadphase import block_boxes_3d, candidate_pairs_3d
from .polyhedra_narrowphase import EDGE_EDGE, FOUND_FIELDS, VERTEX_FACE, detect_polyhedra_contacts
from .term import ContactParameters, ContactTerm, pair_keys
from .transfer import match_previous

if TYPE_CHECKING:
    from ..state import State

__all__ = ["PolyhedronTopology", "SolidContactSet", "SolidContactStep", "SolidContactModel", "SolidContactTerm",
           "next_states_3d"]

_DIM = 3  # points of a polyhedron
_FRAME = 2  # shear components in the contact plane


@dataclass(frozen=True)
class PolyhedronTopology:
    """What detection needs of the blocks' surfaces and never changes: edges, faces per block, vertex rings.

    Edge e runs from ``edge_v0`` to ``edge_v1`` in the counter-clockwise order
    of its first face ``edge_faces[e, 0]``; ``edge_faces[e, 1]`` is the other.
    """

    block_face_ptr: np.ndarray  # (nb + 1,) faces of block b: block_face_ptr[b]:block_face_ptr[b+1]
    block_edge_ptr: np.ndarray  # (nb + 1,)
    edge_v0: np.ndarray  # (ne,)
    edge_v1: np.ndarray
    edge_faces: np.ndarray  # (ne, 2)
    neighbour_ptr: np.ndarray  # (nv + 1,) vertices joined to v by an edge: neighbour[ptr[v]:ptr[v+1]]
    neighbour: np.ndarray
    corner_face: np.ndarray  # (corners,) face of each entry of mesh.face_vertex
    vertex_corner_ptr: np.ndarray  # (nv + 1,) corners at vertex v (indices into face_vertex), sorted by vertex
    vertex_corner: np.ndarray

    @classmethod
    def of(cls, mesh: PolyhedronMesh) -> PolyhedronTopology:
        fp, fv = mesh.face_ptr, mesh.face_vertex
        nv, nb = len(mesh.vertices), mesh.n_blocks
        corner_face = np.repeat(np.arange(len(fp) - 1), np.diff(fp))
        nxt = np.arange(1, len(fv) + 1)
        nxt[fp[1:] - 1] = fp[:-1]
        tail, head = fv, fv[nxt]
        key = np.minimum(tail, head) * nv + np.maximum(tail, head)
        order = np.argsort(key, kind="stable")  # a valid polyhedron uses every edge twice
        first, second = order[0::2], order[1::2]
        edge_block = mesh.vertex_block[tail[first]]
        by_block = np.argsort(edge_block, kind="stable")
        first, second = first[by_block], second[by_block]
        v0, v1 = tail[first], head[first]
        ends = np.concatenate([v0, v1])
        others = np.concatenate([v1, v0])
        ring = np.argsort(ends, kind="stable")
        by_vertex = np.argsort(fv, kind="stable")
        return cls(block_face_ptr=np.searchsorted(mesh.face_block, np.arange(nb + 1)),
                   block_edge_ptr=np.searchsorted(edge_block[by_block], np.arange(nb + 1)),
                   edge_v0=v0, edge_v1=v1, edge_faces=np.column_stack([corner_face[first], corner_face[second]]),
                   neighbour_ptr=np.searchsorted(ends[ring], np.arange(nv + 1)), neighbour=others[ring],
                   corner_face=corner_face, vertex_corner_ptr=np.searchsorted(fv[by_vertex], np.arange(nv + 1)),
                   vertex_corner=by_vertex)


@dataclass(frozen=True)
class SurfaceGeometry:
    """The faces' planes and the edges' convexity in one configuration."""

    face_normal: np.ndarray  # (nf, 3) outward unit normal (Newell)
    face_point: np.ndarray  # (nf, 3) mean of the face's vertices (on its plane)
    face_area: np.ndarray  # (nf,)
    edge_convex: np.ndarray  # (ne,) dihedral angle at most 180° + tolerance
    vertex_convex: np.ndarray  # (nv,) every edge at the vertex convex


def surface_geometry(vertices: np.ndarray, mesh: PolyhedronMesh, topo: PolyhedronTopology,
                     sin_tol: float) -> SurfaceGeometry:
    """Face planes (Newell's normal) and edge / vertex convexity of ``vertices``."""
    fp, fv, owner = mesh.face_ptr, mesh.face_vertex, topo.corner_face
    counts = np.diff(fp)
    centre = np.add.reduceat(vertices[fv], fp[:-1], axis=0) / counts[:, None]
    p = vertices[fv] - centre[owner]
    nxt = np.arange(1, len(fv) + 1)
    nxt[fp[1:] - 1] = fp[:-1]
    newell = np.zeros((len(counts), _DIM))
    np.add.at(newell, owner, 0.5 * np.cross(p, p[nxt]))
    area = np.linalg.norm(newell, axis=1)
    normal = newell / area[:, None]
    e = vertices[topo.edge_v1] - vertices[topo.edge_v0]
    bend = np.einsum("ij,ij->i", np.cross(normal[topo.edge_faces[:, 0]], normal[topo.edge_faces[:, 1]]), e)
    convex = bend >= -sin_tol * np.linalg.norm(e, axis=1)
    vertex_convex = np.ones(len(vertices), dtype=bool)
    vertex_convex[topo.edge_v0[~convex]] = False
    vertex_convex[topo.edge_v1[~convex]] = False
    return SurfaceGeometry(normal, centre, area, convex, vertex_convex)


@dataclass(frozen=True)
class SolidContactGeometry:
    """n contacts in the configuration at the start of the step (module doc)."""

    block_a: np.ndarray  # (n,)
    block_b: np.ndarray
    point_a: np.ndarray  # (n, 3) x_a
    point_b: np.ndarray  # (n, 3) x_b
    normal: np.ndarray  # (n, 3) outward from b
    frame: np.ndarray  # (n, 2, 3) e1, e2
    gap: np.ndarray  # (n,) n·(x_a − x_b), negative: penetration
    parameter: np.ndarray  # (n, 2) where a new shear spring starts: x_b in the face frame, or (s, t) on the edges
    origin: np.ndarray  # (n, 3) V-F: the face frame's origin; E-E: start of a's edge
    edge_a: np.ndarray  # (n, 3) E-E: a's edge vector (zero for V-F)
    edge_b_start: np.ndarray  # (n, 3) E-E: start of b's edge
    edge_b: np.ndarray  # (n, 3) E-E: b's edge vector
    is_edge: np.ndarray  # (n,) bool

    def reference_points(self, reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The shear spring's material points (r_a, r_b) for references (n, 2) (module doc)."""
        e = self.is_edge[:, None]
        on_face = self.origin + np.einsum("nk,nki->ni", reference, self.frame)
        r_a = np.where(e, self.origin + reference[:, :1] * self.edge_a, self.point_a)
        r_b = np.where(e, self.edge_b_start + reference[:, 1:] * self.edge_b, on_face)
        return r_a, r_b

    def shear(self, reference: np.ndarray) -> np.ndarray:
        """Shear (n, 2) of the springs at ``reference``: (r_a − r_b) in the frame."""
        r_a, r_b = self.reference_points(reference)
        return np.einsum("nki,ni->nk", self.frame, r_a - r_b)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1)[:, None]


def contact_geometry_3d(vertices: np.ndarray, mesh: PolyhedronMesh, topo: PolyhedronTopology,
                        surface: SurfaceGeometry, found: np.ndarray) -> SolidContactGeometry:
    """Points, normals, frames and gaps of detected contacts (k, 5) (whole-array)."""
    kind, fa, fb, a, b = found.T
    is_edge = kind == EDGE_EDGE
    n = len(found)
    # vertex-face
    face = np.where(is_edge, 0, fb)
    normal = surface.face_normal[face]
    f0 = vertices[mesh.face_vertex[mesh.face_ptr[face]]]
    f1 = vertices[mesh.face_vertex[mesh.face_ptr[face] + 1]]
    v = vertices[np.where(is_edge, 0, fa)]
    gap = np.einsum("ni,ni->n", normal, v - surface.face_point[face])
    point_a = v.copy()
    point_b = v - gap[:, None] * normal
    e1 = _unit(f1 - f0)
    origin = f0.copy()
    edge_a = np.zeros((n, _DIM))
    edge_b_start = np.zeros((n, _DIM))
    edge_b = np.zeros((n, _DIM))
    parameter = np.zeros((n, _FRAME))
    # edge-edge
    if np.any(is_edge):
        ea, eb = fa[is_edge], fb[is_edge]
        p, q = vertices[topo.edge_v0[ea]], vertices[topo.edge_v0[eb]]
        u, w = vertices[topo.edge_v1[ea]] - p, vertices[topo.edge_v1[eb]] - q
        c = np.cross(u, w)
        r = p - q
        cc = np.einsum("ni,ni->n", c, c)
        uw, ur, wr = (np.einsum("ni,ni->n", x, y) for x, y in ((u, w), (u, r), (w, r)))
        uu, ww = np.einsum("ni,ni->n", u, u), np.einsum("ni,ni->n", w, w)
        s = (uw * wr - ww * ur) / cc
        t = (uu * wr - uw * ur) / cc
        m = _unit(c)
        outward = surface.face_normal[topo.edge_faces[eb, 0]] + surface.face_normal[topo.edge_faces[eb, 1]]
        m = np.where((np.einsum("ni,ni->n", m, outward) < 0)[:, None], -m, m)
        xa, xb = p + s[:, None] * u, q + t[:, None] * w
        normal[is_edge] = m
        point_a[is_edge], point_b[is_edge] = xa, xb
        gap[is_edge] = np.einsum("ni,ni->n", m, xa - xb)
        e1[is_edge] = _unit(w)
        origin[is_edge] = p
        edge_a[is_edge] = u
        edge_b_start[is_edge] = q
        edge_b[is_edge] = w
        parameter[is_edge] = np.column_stack([s, t])
    frame = np.stack([e1, np.cross(normal, e1)], axis=1)
    on_face = ~is_edge
    parameter[on_face] = np.einsum("nki,ni->nk", frame[on_face], point_b[on_face] - origin[on_face])
    return SolidContactGeometry(a, b, point_a, point_b, normal, frame, gap, parameter, origin, edge_a, edge_b_start,
                                edge_b, is_edge)


def next_states_3d(state: np.ndarray, direction: np.ndarray, gap: np.ndarray, shear: np.ndarray,
                   slip: np.ndarray, kn: float, ks: float, tan_phi: np.ndarray, cohesion_force: np.ndarray,
                   tension_force: np.ndarray, closed_this_step: np.ndarray, friction_normal: np.ndarray,
                   friction_tolerance: float = 1e-3
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """New (state, friction direction, trial direction, changed, unsettled) for end-of-step gaps, shear, slip.

    ``shear`` is the shear spring's stretch s, ``slip`` the step's tangential
    relative displacement s − s_0. The rules of
    :func:`srdda.contact.openclose.next_states` with the shear a vector:

    * an OPEN or LOCKED contact that is closed is LOCKED while k_s|s| is
      within the strength, else SLIDING along s/|s| (the direction of the
      load its spring carried); one that closes is LOCKED first;
    * a SLIDING contact locks when its slip turns back against its direction
      (any turn back: the step's slip s − s_0 has a negative component along it);
    * the glancing rule: a contact that closed in this step and then pulls
      in tension while LOCKED slides instead.

    The friction direction (n, 2) of a contact that keeps sliding is held
    for the whole step; the *trial direction* is the one the next step
    starts from: that of the trial force of a spring held at its strength,
    ŝ·strength/k_s + slip (an elastic predictor and plastic corrector, Simo
    & Hughes 1998, ch. 2), so the slip turns it and rounding of a slip near
    zero does not. (Turning it within the step couples every contact's
    direction to its normal force through the strength; the iteration then
    oscillated on a block at rest on an incline.) A contact that starts to
    slide takes its trial direction at once. ``unsettled``: sliding
    contacts whose normal force moved by more than ``friction_tolerance``
    (relative) since the solve that used it.
    """
    normal = -kn * gap
    closed = normal >= -tension_force
    strength = np.maximum(normal, 0.0) * tan_phi + cohesion_force
    size = np.linalg.norm(shear, axis=1)
    holds = ks * size <= strength
    sliding = state == SLIDING
    limit = strength / ks
    trial = np.where(sliding[:, None], direction * limit[:, None] + slip, shear)
    trial_size = np.linalg.norm(trial, axis=1)
    unit = np.where(trial_size[:, None] > 0, trial / np.where(trial_size > 0, trial_size, 1.0)[:, None], 0.0)
    reversed_slip = sliding & (np.einsum("nk,nk->n", slip, direction) < 0) & (strength > 0)
    stays = ~holds & ~reversed_slip & (state != OPEN)
    glancing = (state == LOCKED) & ~closed & closed_this_step
    new_state = np.where(closed, np.where(stays, SLIDING, LOCKED), OPEN)
    new_state = np.where(glancing, SLIDING, new_state).astype(np.int8)
    now_sliding = new_state == SLIDING
    trial_direction = np.where(now_sliding[:, None], unit, 0.0)
    new_direction = np.where((now_sliding & sliding)[:, None], direction, trial_direction)
    changed = new_state != state
    force = np.maximum(normal, 0.0)
    unsettled = now_sliding & sliding & (tan_phi > 0) & (np.abs(force - friction_normal) > friction_tolerance * force)
    return new_state, new_direction, trial_direction, changed, unsettled


@dataclass(frozen=True)
class SolidContactSet:
    """3D contacts at the end of an accepted step (stored on ``State.contacts``; checkpointed field by field)."""

    kind: np.ndarray  # (n,) 0 vertex-face, 1 edge-edge
    feature_a: np.ndarray  # (n,) vertex, or edge of block a
    feature_b: np.ndarray  # (n,) face, or edge of block b
    block_a: np.ndarray
    block_b: np.ndarray
    state: np.ndarray  # (n,) OPEN / SLIDING / LOCKED
    direction: np.ndarray  # (n, 2) slip direction of sliding contacts in the contact frame
    reference: np.ndarray  # (n, 2) the shear spring's reference (face frame, or edge parameters)
    bonded: np.ndarray  # (n,) cohesion and tensile strength still act
    normal_force: np.ndarray  # (n,) N (compression positive)
    gap: np.ndarray  # (n,) end-of-step normal gap
    shear: np.ndarray  # (n, 2) end-of-step shear spring displacement
    point: np.ndarray  # (n, 3) contact point x_a at the start of the step
    normal: np.ndarray  # (n, 3) contact normal (outward from b)
    energy: float  # J: ½k_n g_n² (closed) + ½k_s |s|² (locked)

    @staticmethod
    def empty() -> SolidContactSet:
        i = np.empty(0, dtype=np.int64)
        f = np.empty(0)
        v2, v3 = np.empty((0, _FRAME)), np.empty((0, _DIM))
        return SolidContactSet(i, i, i, i, i, i.astype(np.int8), v2, v2, i.astype(bool), f, f, v2, v3, v3, 0.0)

    @property
    def closed(self) -> np.ndarray:
        return self.state != OPEN

    @property
    def max_penetration(self) -> float:
        return deepest_penetration(self.state, self.gap)


def _keys(kind: np.ndarray, fa: np.ndarray, fb: np.ndarray, size: int) -> np.ndarray:
    """One integer per contact (kind, feature a, feature b) for the transfer between steps."""
    return (fa.astype(np.int64) * size + fb.astype(np.int64)) * 2 + kind.astype(np.int64)


class SolidContactStep:
    """The 3D contacts of one step attempt: springs, friction and the open-close iteration (module doc)."""

    def __init__(self, geometry: SolidContactGeometry, found: np.ndarray, params: ContactParameters,
                 state: np.ndarray, direction: np.ndarray, reference: np.ndarray, bonded: np.ndarray,
                 normal_force: np.ndarray, joint: np.ndarray, area: np.ndarray) -> None:
        self.geometry = geometry
        self.found = found
        self.params = params
        self.state = state
        self.started = state.copy()  # the states the step started from
        self.direction = direction
        self.reference = reference
        self.bonded = bonded
        self.normal_force = normal_force
        self.tan_phi = np.tan(joint[:, JOINT_FRICTION])
        self.cohesion_force = np.where(bonded, joint[:, JOINT_COHESION] * area, 0.0)
        self.tension_force = np.where(bonded, joint[:, JOINT_TENSION] * area, 0.0)
        self.shear_a, self.shear_b = geometry.reference_points(reference)
        self.shear0 = np.einsum("nki,ni->nk", geometry.frame, self.shear_a - self.shear_b)
        self.gap = geometry.gap.copy()
        self.shear = self.shear0.copy()
        self.iterations = 0
        self.closed_this_step = np.zeros(len(state), dtype=bool)
        self.flips = np.zeros(len(state), dtype=np.int64)
        self.frictionless = np.zeros(len(state), dtype=bool)  # held sliding after their slip turned back
        self.trial_direction = direction.copy()  # the friction direction the next step starts from
        self.friction_normal = normal_force.copy()
        self.applied = np.zeros((len(state), _FRAME))  # friction force of the last solve in the frame (N)
        # block pairs of the last solve's state changes (for the message of a cut step)
        self.unsettled_pairs = np.column_stack([geometry.block_a[:0], geometry.block_b[:0]])
        self._shapes: tuple[np.ndarray, ...] | None = None
        self._shapes_theta: np.ndarray | None = None  # the rotation increment the shapes were made with
        self._springs: ContactSprings | None = None  # the springs at the shapes (add_to)

    def __len__(self) -> int:
        return len(self.state)

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        g = self.geometry
        a, b = g.block_a, g.block_b
        if self._shapes is None or self._shapes_theta is not ctx.theta:  # the points are fixed in a step
            self._shapes = (ctx.shape_at(a, g.point_a), ctx.shape_at(b, g.point_b), ctx.shape_at(a, self.shear_a),
                            ctx.shape_at(b, self.shear_b))
            self._shapes_theta = ctx.theta
            ta, tb, tra, trb = self._shapes
            # the springs' unit rows n·T and e·T of every contact, whatever its state in the solves
            self._springs = ContactSprings(a, b, directional_rows(g.normal, ta), directional_rows(g.normal, tb),
                                           directional_rows(g.frame, tra), directional_rows(g.frame, trb),
                                           g.gap, self.shear0,
                                           self.params.normal_stiffness, self.params.shear_stiffness)
        ta, tb, tra, trb = self._shapes
        # by changes while the shapes stay those of the step (Shi's T at t, not the secant pass's)
        assert self._springs is not None
        self._springs.add_to(system, self.state, ctx.coeffs.c_p, by_changes=ctx.theta is None)
        sliding = self.state == SLIDING
        self.applied = np.where(sliding[:, None],
                                -(self.tan_phi * self.friction_normal)[:, None] * self.direction, 0.0)
        if np.any(sliding):
            # Coulomb friction opposing the slip of x_a over b, N of the last solve (Shi)
            force = np.einsum("nk,nki->ni", self.applied[sliding], g.frame[sliding])
            scatter_add(system.rhs, a[sliding], np.einsum("nij,ni->nj", ta[sliding], force))
            scatter_add(system.rhs, b[sliding], -np.einsum("nij,ni->nj", tb[sliding], force))

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        assert self._shapes is not None
        g = self.geometry
        # the gap and shear moved by n·(T_a·Δd_a - T_b·Δd_b) and e·(...): the rows n·T, e·T of add_to, so
        # that a solve's check costs 12 products a row, not the 3 × 12 of T·Δd
        rows = self._springs
        assert rows is not None
        if is_large(len(dd)):  # one compiled pass over the same rows (other last bits)
            normal_increment, shear_increment = rows.increments(dd)
            self.gap = g.gap + normal_increment
            self.shear = self.shear0 + shear_increment
        else:
            da, db = dd[g.block_a], dd[g.block_b]
            self.gap = g.gap + (np.einsum("ni,ni->n", rows.normal_a, da) - np.einsum("ni,ni->n", rows.normal_b, db))
            self.shear = self.shear0 + (np.einsum("nki,ni->nk", rows.shear_a, da)
                                        - np.einsum("nki,ni->nk", rows.shear_b, db))
        p = self.params
        self.closed_this_step |= (self.state == OPEN) & (self.gap < 0)
        state, direction, trial_direction, changed, unsettled = next_states_3d(
            self.state, self.direction, self.gap, self.shear, self.shear - self.shear0, p.normal_stiffness,
            p.shear_stiffness, self.tan_phi, self.cohesion_force, self.tension_force, self.closed_this_step,
            self.friction_normal, p.friction_tolerance)
        # as in 2D (srdda.contact.term): a contact that changed state ``freeze_after`` times keeps it,
        # except the changes of ``never_held``; after ``settle_after`` solves every contact is held so
        band = 1e-6 * p.distance
        safe = never_held(self.state, state, self.gap, band, self.flips, p.freeze_after)
        limit = 0 if self.iterations >= p.settle_after else p.freeze_after
        frozen = (self.flips >= limit) & (state != self.state) & ~safe
        # a contact held SLIDING whose slip turned back had its friction push the block the way it
        # moves (creating energy): it slides without friction for the rest of the step (a force inside
        # the friction cone), and the step is solved again so that the accepted solve has no such force
        turned_back = frozen & (self.state == SLIDING) & (np.einsum("nk,nk->n", self.shear - self.shear0,
                                                                    self.direction) < 0)
        state = np.where(frozen, self.state, state).astype(np.int8)
        direction = np.where((frozen & ~turned_back)[:, None], self.direction, direction)
        changed = (np.where(frozen, False, changed) & ~self._negligible(state, ctx.arrays)) \
            | (turned_back & ~self.frictionless)
        self.frictionless |= turned_back
        direction = np.where(self.frictionless[:, None], 0.0, direction)
        if self.iterations < p.settle_after:
            changed = changed | unsettled
        flipped = state != self.state
        self.flips += flipped
        self.trial_direction = np.where(self.frictionless[:, None], 0.0, trial_direction)
        self.normal_force = np.maximum(-p.normal_stiffness * self.gap, 0.0)
        # Shi's substitution: the next solve's friction uses this solve's N. (The 2D term's per-contact
        # secant step diverges here: the contacts of one face share the block's tilt, so each contact's
        # N depends on the others' friction more than on its own; substitution contracts by the
        # coupling, measured 0.06 on the sliding incline.) N is taken only from a solve in which no
        # contact of the same blocks changed state: a transitional solve (locked springs stopping a
        # sliding box dead in one step) gives normal forces a hundred times the weight, whose
        # friction tipped the box over (docs/contacts-3d.md).
        a, b = self.geometry.block_a, self.geometry.block_b
        touched = np.zeros(len(ctx.arrays.block_fixed), dtype=bool)
        touched[a[flipped]] = True
        touched[b[flipped]] = True
        touched[ctx.arrays.block_fixed] = False
        stable = ~(touched[a] | touched[b])
        self.friction_normal = np.where(stable, self.normal_force, self.friction_normal)
        self.state, self.direction = state, direction
        self.iterations += 1
        self.unsettled_pairs = np.column_stack([a[changed], b[changed]])
        return not bool(np.any(changed))

    def _negligible(self, new_state: np.ndarray, arrays: ModelArrays) -> np.ndarray:
        """Closings and slips below :func:`negligible_force`, as in 2D (``ContactStep._negligible``)."""
        p = self.params
        if p.force_tolerance == 0.0:
            return np.zeros(len(new_state), dtype=bool)
        g = self.geometry
        normal = np.maximum(-p.normal_stiffness * self.gap, 0.0)
        limit = negligible_force(arrays.block_mass, arrays.gravity, g.block_a, g.block_b, normal, p.force_tolerance)
        return negligible_changes(self.state, new_state, normal,
                                  p.shear_stiffness * np.linalg.norm(self.shear, axis=1),
                                  normal * self.tan_phi + self.cohesion_force, limit)

    def friction_work(self) -> float:
        """Work (J) of friction over the step that is dissipated; ≤ 0 when friction opposes the slip.

        The friction forces of the last solve times the step's slip, less the
        energy ½k_s|s_0|² of the springs that started the step dragged at their
        strength (sliding) and end it locked: that part of the friction work
        was stored in the spring, which the contact energy now counts.
        """
        relocked = (self.started == SLIDING) & (self.state == LOCKED)
        stored = 0.5 * self.params.shear_stiffness * float(np.sum(self.shear0[relocked] ** 2))
        return float(np.sum(self.applied * (self.shear - self.shear0))) - stored

    def commit(self) -> SolidContactSet:
        """The contacts as they ended the accepted step."""
        p = self.params
        closed = self.state != OPEN
        locked = self.state == LOCKED
        energy = 0.5 * p.normal_stiffness * float(np.sum(self.gap[closed] ** 2)) \
            + 0.5 * p.shear_stiffness * float(np.sum(self.shear[locked] ** 2))
        f = self.found
        return SolidContactSet(f[:, 0].copy(), f[:, 1].copy(), f[:, 2].copy(), f[:, 3].copy(), f[:, 4].copy(),
                               self.state.copy(), self.trial_direction.copy(), self.reference.copy(),
                               self.bonded & locked,
                               self.normal_force.copy(), self.gap.copy(), np.where(locked[:, None], self.shear, 0.0),
                               self.geometry.point_a.copy(), self.geometry.normal.copy(), energy)

    @property
    def max_penetration(self) -> float:
        return deepest_penetration(self.state, self.gap)


class SolidContactModel:
    """Detects the contacts of a configuration of polyhedra (hinged pairs left out) and builds each step's contacts."""

    def __init__(self, arrays: ModelArrays, params: ContactParameters) -> None:
        if arrays.mesh is None:
            raise ModelError("3D contacts need polyhedral blocks")
        self.arrays = arrays
        self.params = params
        self.mesh = arrays.mesh
        self.topology = PolyhedronTopology.of(arrays.mesh)
        self.movable = ~arrays.block_fixed
        self.sin_tol = float(np.sin(params.angle_tolerance))
        self.cos_parallel = float(np.cos(params.angle_tolerance))
        self.excluded = np.unique(pair_keys(arrays.links.hinged_block_pairs, arrays.n_blocks))
        first, second = np.divmod(self.excluded, arrays.n_blocks)
        partners_left_out = np.bincount(np.concatenate([first, second]), minlength=arrays.n_blocks)
        self.can_touch = partners_left_out < arrays.n_blocks - 1
        self.key_size = max(len(arrays.vertices), len(self.mesh.face_block), len(self.topology.edge_v0)) + 1
        # as in 2D: the broad phase with a margin of d0, run again once a vertex has moved d0/2
        self.candidates = KeptCandidates(lambda boxes, d: candidate_pairs_3d(boxes, d, self.movable),
                                         params.distance, params.distance)

    def detect(self, vertices: np.ndarray) -> tuple[np.ndarray, SurfaceGeometry]:
        """Contacts (k, 5) [kind, feature a, feature b, block a, block b] of a configuration, and its surfaces."""
        arr, topo, mesh = self.arrays, self.topology, self.mesh
        surface = surface_geometry(vertices, mesh, topo, self.sin_tol)
        boxes = block_boxes_3d(vertices, arr.block_ptr)
        pairs = self.candidates(vertices, boxes)
        if len(self.excluded):
            pairs = pairs[~np.isin(pair_keys(pairs, arr.n_blocks), self.excluded)]
        if len(pairs) == 0:
            return np.empty((0, FOUND_FIELDS), dtype=np.int64), surface
        found = detect_polyhedra_contacts(vertices, pairs, boxes, arr.block_ptr, topo.block_face_ptr, mesh.face_ptr,
                                          mesh.face_vertex, surface.face_normal, surface.face_point,
                                          topo.neighbour_ptr, topo.neighbour, surface.vertex_convex,
                                          topo.block_edge_ptr, topo.edge_v0, topo.edge_v1, topo.edge_faces,
                                          surface.edge_convex, self.params.distance, self.sin_tol,
                                          self.params.max_penetration)
        return found, surface

    def joint_index(self, found: np.ndarray, geom: SolidContactGeometry) -> np.ndarray:
        """Row of ``joint_properties`` of every contact: the contacted face's joint material.

        A vertex-face contact takes its face's (``ModelArrays.face_joint``), an
        edge-edge contact the one named on either face of b's edge, else a's
        (the larger index when both are named); contacts on faces with none
        take the joint chosen by the two blocks' materials (as 2D edges do).
        """
        arr = self.arrays
        by_materials = arr.joint_by_materials[arr.block_material[geom.block_a], arr.block_material[geom.block_b]]
        face_joint = arr.face_joint
        if face_joint is None or not np.any(face_joint >= 0):
            return by_materials
        named = np.full(len(found), -1, dtype=np.int64)
        vf = found[:, 0] == VERTEX_FACE
        named[vf] = face_joint[found[vf, 2]]
        ee = ~vf
        if np.any(ee):
            faces_b = self.topology.edge_faces[found[ee, 2]]
            faces_a = self.topology.edge_faces[found[ee, 1]]
            on_b = np.max(face_joint[faces_b], axis=1)
            named[ee] = np.where(on_b >= 0, on_b, np.max(face_joint[faces_a], axis=1))
        return np.where(named >= 0, named, by_materials)

    def bond_area(self, found: np.ndarray, surface: SurfaceGeometry, normal: np.ndarray) -> np.ndarray:
        """Area over which a V-F contact's cohesion and tension act: its share of a's faces that lie on the face.

        Each face of a at the vertex whose normal is opposite the contact's
        (to within the angle tolerance) gives area / its vertex count, so a
        face-to-face joint of area A is carried by its corner contacts, A in
        all; edge-edge contacts and corners touching a face have none.
        """
        topo = self.topology
        vertex = np.where(found[:, 0] == VERTEX_FACE, found[:, 1], 0)
        start, stop = topo.vertex_corner_ptr[vertex], topo.vertex_corner_ptr[vertex + 1]
        counts = np.where(found[:, 0] == VERTEX_FACE, stop - start, 0)
        owner = np.repeat(np.arange(len(found)), counts)
        corner = topo.vertex_corner[np.repeat(start - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())]
        face = topo.corner_face[corner]
        facing = np.einsum("ni,ni->n", surface.face_normal[face], normal[owner]) <= -self.cos_parallel
        share = np.where(facing, surface.face_area[face] / np.diff(self.mesh.face_ptr)[face], 0.0)
        return np.bincount(owner, weights=share, minlength=len(found))

    def prepare(self, vertices: np.ndarray, previous: SolidContactSet | None,
                first_step: bool) -> SolidContactStep | None:
        """The contacts of the step starting at ``vertices``; None when no contact is near."""
        found, surface = self.detect(vertices)
        if len(found) == 0:
            return None
        arr = self.arrays
        geom = contact_geometry_3d(vertices, self.mesh, self.topology, surface, found)
        previous = previous if previous is not None else SolidContactSet.empty()
        old = match_previous(_keys(found[:, 0], found[:, 1], found[:, 2], self.key_size),
                             _keys(previous.kind, previous.feature_a, previous.feature_b, self.key_size))
        kept = old >= 0
        src = old[kept]
        state = np.where(geom.gap <= 0.0, LOCKED, OPEN).astype(np.int8)
        state[kept] = previous.state[src]
        direction = np.zeros((len(found), _FRAME))
        direction[kept] = previous.direction[src]
        # a new or open contact starts its shear spring unstretched (as in 2D); a locked one keeps its
        # reference; a sliding vertex-face contact starts it stretched to its strength along its slip
        # direction (an elastic-plastic spring dragged along, Simo & Hughes 1998), so that if it locks
        # again it carries the friction force it had, not zero (docs/contacts-3d.md)
        reference = geom.parameter.copy()
        keep_reference = kept.copy()
        keep_reference[kept] = previous.state[src] == LOCKED
        reference[keep_reference] = previous.reference[old[keep_reference]]
        joint = arr.joint_properties[self.joint_index(found, geom)]
        dragged = kept.copy()
        dragged[kept] = previous.state[src] == SLIDING
        dragged &= ~geom.is_edge
        cap = np.tan(joint[dragged, JOINT_FRICTION]) * previous.normal_force[old[dragged]] \
            / self.params.shear_stiffness
        reference[dragged] -= cap[:, None] * previous.direction[old[dragged]]
        bonded = np.full(len(found), first_step)
        bonded[kept] = previous.bonded[src]
        normal_force = self.params.normal_stiffness * np.maximum(-geom.gap, 0.0)
        normal_force[kept] = previous.normal_force[src]
        area = self.bond_area(found, surface, geom.normal)
        return SolidContactStep(geom, found, self.params, state, direction, reference, bonded, normal_force, joint,
                                area)


class SolidContactTerm(ContactTerm):
    """Contacts between polyhedra as a step term: the 2D term's begin, open-close, step control and commit
    (:class:`srdda.contact.term.ContactTerm`, over a :class:`SolidContactModel`); friction in the ledger."""

    def work(self, ctx: StepContext, new: State, dd: np.ndarray, multipliers: np.ndarray) -> np.ndarray | None:
        """Friction dissipation of the step: minus the work of the friction forces over the slip."""
        if self.step is None:
            return None
        out = np.zeros(len(LEDGER))
        out[LEDGER.index("dissipated_friction")] = -self.step.friction_work()
        return out

