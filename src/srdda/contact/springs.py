"""Contact geometry at the start of a step and the contact springs' rows.

A contact is vertex v of block a against edge p0 -> p1 of block b (unit
tangent t, outward normal n). With the shape functions T of the method
(:meth:`srdda.term.StepContext.shape_at`) the end-of-step normal gap
and shear displacement are, to first order in the step's unknowns Δd,

    g_n = g_0 + n·(T_a(v) Δd_a - T_b(q) Δd_b),        q the projection of v,
    s   = s_0 + t·(T_a(v) Δd_a - T_b(r) Δd_b),        r the reference point,

(Shi 1988, ch. 4: the normal and shear contact springs). A closed contact
adds ½k_n g_n², a locked one also ½k_s s² to the step's energy: they are
point-to-point penalty rows (:func:`srdda.assembly.system.add_penalty_pairs`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ContactGeometry", "contact_geometry", "bond_length"]


@dataclass(frozen=True)
class ContactGeometry:
    """Geometry of n contacts in the configuration at the start of the step."""

    vertex_block: np.ndarray  # (n,) block a (owns the vertex)
    edge_block: np.ndarray  # (n,) block b (owns the edge)
    point: np.ndarray  # (n, 2) the vertex v
    normal: np.ndarray  # (n, 2) outward normal of the edge
    tangent: np.ndarray  # (n, 2) unit edge direction
    projection: np.ndarray  # (n,) edge parameter of the projection of v, clipped to [0, 1]
    parameter: np.ndarray  # (n,) edge parameter of the projection of v on the edge's line, not clipped
    foot: np.ndarray  # (n, 2) projection point q on the edge
    gap: np.ndarray  # (n,) signed normal distance (negative: penetration)
    edge_start: np.ndarray  # (n, 2)
    edge_vector: np.ndarray  # (n, 2) p1 - p0

    def point_on_edge(self, ratio: np.ndarray) -> np.ndarray:
        return self.edge_start + ratio[:, None] * self.edge_vector

    def shear(self, ratio: np.ndarray) -> np.ndarray:
        """Shear displacement t·(v - r) of v from the reference point at edge parameter ``ratio``."""
        return np.einsum("nk,nk->n", self.tangent, self.point - self.point_on_edge(ratio))


def contact_geometry(vertices: np.ndarray, vertex_block: np.ndarray, next_vertex: np.ndarray, vertex: np.ndarray,
                     edge: np.ndarray) -> ContactGeometry:
    """Normal, tangent, gap and projection of contacts (vertex, edge start) of ``vertices``."""
    p = vertices[vertex]
    p0 = vertices[edge]
    d = vertices[next_vertex[edge]] - p0
    length = np.hypot(d[:, 0], d[:, 1])
    tangent = d / length[:, None]
    normal = np.column_stack([tangent[:, 1], -tangent[:, 0]])
    rel = p - p0
    parameter = np.einsum("nk,nk->n", rel, d) / length**2
    ratio = np.clip(parameter, 0.0, 1.0)
    return ContactGeometry(vertex_block[vertex], vertex_block[edge], p, normal, tangent, ratio, parameter,
                           p0 + ratio[:, None] * d, np.einsum("nk,nk->n", rel, normal), p0, d)


def bond_length(vertices: np.ndarray, next_vertex: np.ndarray, previous_vertex: np.ndarray, vertex: np.ndarray,
                tangent: np.ndarray, cos_parallel: float) -> np.ndarray:
    """Length over which a contact's cohesion and tensile strength act.

    Half of each edge at the vertex that lies along the contacted edge (to
    within the angle tolerance): a face-to-face joint of length L is carried by
    its two end contacts, L/2 each; a corner touching an edge has no length and
    no cohesion.
    """
    total = np.zeros(len(vertex))
    for other in (next_vertex[vertex], previous_vertex[vertex]):
        d = vertices[other] - vertices[vertex]
        length = np.hypot(d[:, 0], d[:, 1])
        along = np.abs(np.einsum("nk,nk->n", d, tangent)) >= cos_parallel * length
        total += np.where(along, 0.5 * length, 0.0)
    return total
