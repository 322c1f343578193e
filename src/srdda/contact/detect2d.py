"""Detection in 2D: the contacts of a configuration of polygons as a :class:`~srdda.contact.record.ContactRecord`.

A contact is vertex v of block a against edge p0 -> p1 of block b (Shi 1988,
ch. 4): the broad phase (:mod:`.broadphase2d`) and the vertex-edge and
vertex-vertex narrow phase (:mod:`.narrowphase2d`) find them; this module
gives their geometry. The edge's unit tangent t is the shear frame (k = 1),
n = (t_y, −t_x) the outward normal, x_b the projection q of v on the edge
(clipped to it), the gap n·(v − p0). The shear spring joins v (r_a) to the
edge point r_b = p0 + ρ·(p1 − p0) at its reference edge parameter ρ; a new
spring starts at the projection of v on the edge's line (not clipped: for a
vertex-vertex contact beyond the edge's end a clipped reference would start
the spring stretched by up to d0).
"""
from __future__ import annotations

import numpy as np

from ..assembly.system import PARALLEL_BLOCKS
from ..geometry.polygon import previous_vertex_index
from ..modeldata.arrays import ModelArrays
from .broadphase2d import candidate_pairs_2d
from .candidates import PairFinder
from .narrowphase2d import FOUND_EDGE, FOUND_VERTEX, narrow_phase_2d, narrow_phase_2d_parallel
from .record import ContactRecord

__all__ = ["Detector2D", "edge_shares"]


def edge_shares(vertices: np.ndarray, next_vertex: np.ndarray, previous_vertex: np.ndarray, vertex: np.ndarray,
                tangent: np.ndarray, cos_parallel: float
                ) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(bond, tributary) lengths of contacts at ``vertex`` against edges along ``tangent``, and the edges that
    make up the bonds (the record's ``bond_faces``: contact, edge by its start vertex, share ½).

    The bond, over which cohesion and tensile strength act, is half of each
    edge at the vertex that lies along the contacted edge (to within the
    angle tolerance): a face-to-face joint of length L is carried by its two
    end contacts, L/2 each; a corner touching an edge has none. The tributary
    length, which a joint's stiffness per area acts over, is the bond, or for
    a corner half its shorter edge (the least it could stand for).
    """
    bond = np.zeros(len(vertex))
    shortest = np.full(len(vertex), np.inf)
    owners, edges = [], []
    for other, edge in ((next_vertex[vertex], vertex), (previous_vertex[vertex], previous_vertex[vertex])):
        d = vertices[other] - vertices[vertex]
        length = np.hypot(d[:, 0], d[:, 1])
        along = np.abs(np.einsum("nk,nk->n", d, tangent)) >= cos_parallel * length
        bond += np.where(along, 0.5 * length, 0.0)
        shortest = np.minimum(shortest, 0.5 * length)
        owners.append(np.flatnonzero(along))
        edges.append(edge[along])
    owner = np.concatenate(owners)
    return bond, np.where(bond > 0.0, bond, shortest), (owner, np.concatenate(edges).astype(np.int64),
                                                        np.full(len(owner), 0.5))


class Detector2D:
    """Finds the contacts of a configuration of the model's polygons (hinged pairs left out)."""

    def __init__(self, arrays: ModelArrays, distance: float, angle_tolerance: float, max_penetration: float) -> None:
        self.arrays = arrays
        self.distance, self.max_penetration = distance, max_penetration
        self.previous_vertex = previous_vertex_index(arrays.block_ptr)
        self.sin_tol = float(np.sin(angle_tolerance))
        self.cos_parallel = float(np.cos(angle_tolerance))
        self.pairs = PairFinder(arrays, distance, candidate_pairs_2d)

    def detect(self, vertices: np.ndarray) -> ContactRecord | None:
        """The contacts of ``vertices``; None when no contact is near."""
        arr = self.arrays
        boxes, pairs = self.pairs(vertices)
        if len(pairs) == 0:
            return None
        narrow = narrow_phase_2d_parallel if arr.n_blocks > PARALLEL_BLOCKS else narrow_phase_2d
        found = narrow(vertices, arr.block_ptr, arr.vertex_block, arr.vertex_next, self.previous_vertex,
                                pairs, boxes, self.distance, self.sin_tol, self.max_penetration)
        if len(found) == 0:
            return None
        vertex, edge = found[:, FOUND_VERTEX], found[:, FOUND_EDGE]
        p = vertices[vertex]
        p0 = vertices[edge]
        d = vertices[arr.vertex_next[edge]] - p0
        length = np.hypot(d[:, 0], d[:, 1])
        tangent = d / length[:, None]
        normal = np.column_stack([tangent[:, 1], -tangent[:, 0]])
        rel = p - p0
        parameter = np.einsum("nk,nk->n", rel, d) / length**2
        ratio = np.clip(parameter, 0.0, 1.0)
        block_a, block_b = arr.vertex_block[vertex], arr.vertex_block[edge]
        named = arr.edge_joint[edge]
        joint = np.where(named >= 0, named, arr.material_joint[arr.block_material[block_a],
                                                                   arr.block_material[block_b]])
        bond, tributary, bond_faces = edge_shares(vertices, arr.vertex_next, self.previous_vertex, vertex, tangent,
                                                  self.cos_parallel)
        n = len(found)
        return ContactRecord(
            features=found, key=vertex.astype(np.int64) * len(vertices) + edge.astype(np.int64),
            block_a=block_a, block_b=block_b, point_a=p, point_b=p0 + ratio[:, None] * d, normal=normal,
            frame=tangent[:, None, :], gap=np.einsum("nk,nk->n", rel, normal), start_reference=parameter[:, None],
            anchor_a=p, axes_a=np.zeros((n, 1, vertices.shape[1])), anchor_b=p0, axes_b=d[:, None, :],
            joint=joint.astype(np.int64), bond=bond, tributary=tributary, draggable=np.zeros(n, dtype=bool),
            bond_faces=bond_faces)
