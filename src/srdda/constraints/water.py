"""Water in the joints: a phreatic surface and tension cracks filled to a depth (docs/water.md).

Below the phreatic surface (a plane: a horizontal level, or a point and an
upward normal) the water in the joints has the hydrostatic pressure

    p(x) = γ_w · max(h(x), 0),    h(x) = (x_s − x)·n / (n·u),

γ_w the unit weight, x_s a point of the surface, n its upward normal and u
the unit vector against gravity: h is the height of the surface straight
above x. Every contact below the surface (:func:`srdda.contact.water.contact_water`) carries the water
on the joint area its bond stands for (the faces of its corner's block that
lie on the other block, :class:`~srdda.contact.record.ContactRecord`'s
``bond_faces``: each face's exact ∫p dA shared among its corners as the bond
shares the face's area) along its normal, pushing its two blocks apart; the contact's spring then carries the
effective normal force N' = N − U, which is what Mohr-Coulomb's
N'·tan φ + c·A sees (UDEC's and 3DEC's joint water pressure).

A tension crack (:class:`TensionCrack`, a plane given by a point and a
normal) is an open joint: the block faces lying on it at the start get the
hydrostatic pressure of the water standing in it to ``depth`` above its
bottom (the lowest point of those faces now: the crack stays filled to that
depth as its faces move), integrated exactly over each face's
wetted part (:class:`WaterCrackTerm`), pushing each face's block away from
the crack. Contacts on a crack's plane get no pressure of the phreatic
surface (the crack has its own water).

Both are dead loads over a step: taken at the configuration at t, their work
over the step's increments goes to the ledger's ``work_water``.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..assembly.system import scatter_add
from ..geometry.facets import area_vectors, boundary_simplices
from ..modeldata.water import UNIT_WEIGHT, TensionCrack, WaterTable, water_table
from ..term import LEDGER, StepContext, Term

if TYPE_CHECKING:
    from ..assembly.system import BlockSystem
    from ..modeldata.arrays import ModelArrays
    from ..state import State

__all__ = ["UNIT_WEIGHT", "TensionCrack", "WaterTable", "water_table", "face_pressures", "submerged_integrals",
           "crack_facets", "WaterCrackTerm"]

ON_PLANE = 1e-6  # × the model's extent: a vertex this close to a crack's plane lies on it
PARALLEL = 0.999  # |n·n_c| of a contact normal along a crack's normal (within 2.6°)


def face_pressures(water: WaterTable, vertices: np.ndarray, faces: np.ndarray,
                   facets: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    """∫p dA (m,) over each of ``faces`` (the ``boundary_simplices`` face numbers) at ``vertices``: exact, the
    wetted part of each of its simplices (:func:`submerged_integrals`), N (per m in 2D)."""
    simplices, simplex_face, _ = facets
    wanted, back = np.unique(faces, return_inverse=True)
    mine = np.flatnonzero(np.isin(simplex_face, wanted))
    x = vertices[simplices[mine]]
    integral, _ = submerged_integrals(x, water.head(x.reshape(-1, x.shape[-1])).reshape(x.shape[:-1]))
    total = np.zeros((len(wanted), x.shape[-1]))
    np.add.at(total, np.searchsorted(wanted, simplex_face[mine]), integral[:, None] * area_vectors(x))
    return water.unit_weight * np.linalg.norm(total, axis=1)[back]


def submerged_integrals(points: np.ndarray, head: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(∫ max(h, 0), ∫ max(h, 0)·x) over simplices ``points`` (n, m, dim) of unit measure with linear ``head``
    h (n, m) given at their vertices: exact.

    A simplex of measure V has ∫h = V·mean(h_i) and ∫h·x = V/(m(m+1))·(Σh_i x_i + Σh_i Σx_i). Where h
    changes sign the wetted part is the corner simplex at the one vertex above water (or the whole less the
    corner at the one vertex below), its other vertices where h = 0 on the edges from it, its measure the
    product of their edge fractions.
    """
    n, m = head.shape
    scale = 1.0 / (m * (m + 1))

    def moments(h: np.ndarray, x: np.ndarray, measure: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        total = np.sum(h, axis=1)
        first = scale * (np.einsum("nm,nmi->ni", h, x) + total[:, None] * np.sum(x, axis=1))
        return measure * total / m, measure[:, None] * first

    whole, whole_x = moments(head, points, np.ones(n))
    wet = head > 0.0
    count = np.sum(wet, axis=1)
    # the odd vertex: the one wet vertex, or the one dry vertex of a simplex with all others wet
    single = count == 1
    odd = np.where(single, np.argmax(wet, axis=1), np.argmin(wet, axis=1))
    rows = np.arange(n)
    h_odd, x_odd = head[rows, odd], points[rows, odd]
    others = np.ones((n, m), dtype=bool)
    others[rows, odd] = False
    denominator = np.where(others, h_odd[:, None] - head, 1.0)
    fraction = np.where(others, h_odd[:, None] / np.where(denominator != 0.0, denominator, 1.0), 1.0)
    cut = np.where(others[..., None], x_odd[:, None] + fraction[..., None] * (points - x_odd[:, None]),
                   x_odd[:, None])
    corner_head = np.where(others, 0.0, head)
    corner_head[rows, odd] = h_odd
    corner, corner_x = moments(corner_head, cut, np.prod(fraction, axis=1))
    inside = count == m
    partial_inside = (count == m - 1) & ~single
    out = np.where(inside, whole, np.where(single, corner, np.where(partial_inside, whole - corner, 0.0)))
    out_x = np.where(inside[:, None], whole_x, np.where(single[:, None], corner_x,
                                                        np.where(partial_inside[:, None], whole_x - corner_x, 0.0)))
    return out, out_x


def crack_facets(arrays: ModelArrays, crack: TensionCrack) -> tuple[np.ndarray, np.ndarray]:
    """(simplices (n, m), blocks (n,)) of the moving blocks' boundary lying on ``crack``'s plane in the model as
    built; ValueError naming none found."""
    simplices, _, block = boundary_simplices(arrays)
    tolerance = ON_PLANE * float(np.max(np.ptp(arrays.vertex_position, axis=0)))
    distance = np.abs((arrays.vertex_position - np.asarray(crack.point)) @ np.asarray(crack.normal))
    on = np.all(distance[simplices] <= tolerance, axis=1) & ~arrays.block_fixed[block]
    if not np.any(on):
        raise ValueError(f"no face of a moving block lies on the crack through {list(crack.point)} with normal "
                         f"{list(crack.normal)}")
    return simplices[on], block[on]


class WaterCrackTerm(Term):
    """The water standing in the tension cracks, on the faces lying on them (module doc): per wetted simplex the
    resultant −γ_w·∫h dA·n at its centre of pressure, through the block's shape functions."""

    def __init__(self, arrays: ModelArrays) -> None:
        self._resolved: tuple[tuple[tuple[float, ...], tuple[float, ...]], ...] = ()
        self._facets = np.empty((0, 1), dtype=np.int64)
        self._blocks = self._crack = np.empty(0, dtype=np.int64)
        self.blocks, self.points, self.forces = self._blocks, np.empty((0, 1)), np.empty((0, 1))
        self._resolve(arrays)

    def _resolve(self, arrays: ModelArrays) -> None:
        """Find the faces on the cracks of ``arrays.water`` (again only where the cracks' planes changed)."""
        water = arrays.water
        cracks = () if water is None else water.cracks
        planes = tuple((c.point, c.normal) for c in cracks)
        if planes == self._resolved:
            return
        found = [crack_facets(arrays, c) for c in cracks]
        self._facets = np.concatenate([f for f, _ in found]) if found else self._facets
        self._blocks = np.concatenate([b for _, b in found]) if found else self._blocks
        self._crack = np.repeat(np.arange(len(found)), [len(b) for _, b in found])
        self._resolved = planes

    @property
    def at_points(self) -> bool:
        return True

    def begin(self, ctx: StepContext) -> None:
        """The wetted simplices' resultants at the configuration at t."""
        self.blocks, self.points, self.forces = self.resultants(ctx.arrays, ctx.state.vertices)

    def resultants(self, arrays: ModelArrays, vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(blocks (n,), centres of pressure (n, dim), forces (n, dim)) of the wetted crack simplices of
        ``arrays.water`` at ``vertices``, N (per m in 2D)."""
        water = arrays.water
        dim = vertices.shape[1]
        if water is None or not water.cracks:
            return self._blocks[:0], np.empty((0, dim)), np.empty((0, dim))
        self._resolve(arrays)
        x = vertices[self._facets]
        elevation = x @ np.asarray(water.up)
        bottom = np.full(len(water.cracks), np.inf)  # each crack's lowest point now
        np.minimum.at(bottom, self._crack, np.min(elevation, axis=1))
        surface = bottom + np.array([c.depth for c in water.cracks])
        head = surface[self._crack][:, None] - elevation
        integral, first = submerged_integrals(x, head)
        wet = integral > 0.0
        return (self._blocks[wet], first[wet] / integral[wet, None],
                -water.unit_weight * integral[wet, None] * area_vectors(x[wet]))

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        if len(self.blocks):
            shapes = ctx.shape_at(self.blocks, self.points)
            scatter_add(system.rhs, self.blocks, np.einsum("nki,nk->ni", shapes, self.forces))

    def work(self, ctx: StepContext, new: State, dd: np.ndarray, multipliers: np.ndarray) -> np.ndarray | None:
        """F·T(x_c)·Δd of every resultant: the work of the forces the solve had."""
        out = np.zeros(len(LEDGER))
        if len(self.blocks):
            moved = np.einsum("nki,ni->nk", ctx.shape_at(self.blocks, self.points), dd[self.blocks])
            out[LEDGER.index("work_water")] = float(np.sum(self.forces * moved))
        return out
