"""Detection in 3D: the contacts of a configuration of polyhedra as a :class:`~srdda.contact.record.ContactRecord`.

The broad phase (:mod:`.broadphase3d`) and the narrow phase (:mod:`.narrowphase3d`)
find vertex-face and edge-edge contacts; this module gives their geometry
(Shi 2001; docs/contacts.md):

* vertex-face: x_a the vertex, x_b its projection on the face's plane, n the
  face's outward normal, e1 along the face's first edge, e2 = n × e1; the
  shear spring joins the vertex (r_a) to a point of the face stored in the
  coordinates of the face's two edges at its first vertex f_0 (r_b = f_0 +
  ρ_1 (f_1 − f_0) + ρ_2 (f_last − f_0): a material point of the face, also
  when the block strains);
* edge-edge: x_a, x_b the closest points of the two edges, n their cross
  product turned outward from b, e1 along b's edge; the spring joins points
  of the two edges at edge parameters (ρ_1 on a's, ρ_2 on b's).

A contact's joint is its face's (``ModelArrays.face_joint``), else the one of
its two blocks' materials; its bond area (cohesion, tension) is its share of
a's faces that lie on the contacted face.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numba import njit

from ..geometry.polyhedron import PolyhedronMesh
from ..modeldata.arrays import ModelArrays
from ..modeldata.materials import ModelError
from .broadphase3d import candidate_pairs_3d
from .candidates import PairFinder
from .narrowphase3d import EDGE_EDGE, VERTEX_FACE, narrow_phase_3d
from .record import ContactRecord

__all__ = ["PolyhedronTopology", "SurfaceGeometry", "surface_geometry", "contact_record_3d", "Detector3D"]

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



def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1)[:, None]


def contact_record_3d(vertices: np.ndarray, mesh: PolyhedronMesh, topo: PolyhedronTopology,
                      surface: SurfaceGeometry, found: np.ndarray, key_size: int) -> ContactRecord:
    """Points, normals, frames, gaps and spring anchors of detected contacts (k, 5) (whole-array); the
    joint, bond and tributary areas are left for :class:`Detector3D` to fill in."""
    kind, fa, fb, a, b = found.T
    is_edge = kind == EDGE_EDGE
    n = len(found)
    # vertex-face
    face = np.where(is_edge, 0, fb)
    normal = surface.face_normal[face]
    f0 = vertices[mesh.face_vertex[mesh.face_ptr[face]]]
    f1 = vertices[mesh.face_vertex[mesh.face_ptr[face] + 1]]
    f_last = vertices[mesh.face_vertex[mesh.face_ptr[face + 1] - 1]]
    v = vertices[np.where(is_edge, 0, fa)]
    gap = np.einsum("ni,ni->n", normal, v - surface.face_point[face])
    point_a = v.copy()
    point_b = v - gap[:, None] * normal
    e1 = _unit(f1 - f0)
    anchor_a, anchor_b = v.copy(), f0.copy()
    axes_a = np.zeros((n, _FRAME, _DIM))
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
        anchor_a[is_edge], anchor_b[is_edge] = p, q
        axes_a[is_edge, 0] = u
        parameter[is_edge] = np.column_stack([s, t])
    frame = np.stack([e1, np.cross(normal, e1)], axis=1)
    on_face = ~is_edge
    # a face's spring point in the coordinates of its two edges at f0: a material point of the face under
    # any affine motion of b (its strain included), as the edge parameters are (unit axes are not: a strained
    # face would move a spring point ρ from f0 by strain × ρ a step, a stretch far beyond τ/k_s)
    axes_b = np.stack([f1 - f0, f_last - f0], axis=1)
    in_plane = np.einsum("nji,nki->njk", frame[on_face], axes_b[on_face])
    parameter[on_face] = np.linalg.solve(in_plane, np.einsum("nki,ni->nk", frame[on_face],
                                                             point_b[on_face] - anchor_b[on_face])[..., None])[..., 0]
    if np.any(is_edge):
        axes_b[is_edge, 0] = 0.0
        axes_b[is_edge, 1] = w
    key = (fa.astype(np.int64) * key_size + fb.astype(np.int64)) * 2 + kind.astype(np.int64)
    empty = np.zeros(n)
    return ContactRecord(features=found, key=key, block_a=a, block_b=b, point_a=point_a, point_b=point_b,
                         normal=normal, frame=frame, gap=gap, start_reference=parameter, anchor_a=anchor_a,
                         axes_a=axes_a, anchor_b=anchor_b, axes_b=axes_b, joint=np.zeros(n, dtype=np.int64),
                         bond=empty, tributary=empty, draggable=on_face)


def corner_twins(found: np.ndarray, vertices: np.ndarray, face_normal: np.ndarray, distance: float,
                 cos_parallel: float) -> np.ndarray:
    """Which detected contacts (k, 5) are the second spring of a corner pair: a vertex-face contact of a corner
    of block a on a face of b whose twin, a corner of b within ``distance`` on a face of a, faces it (normals
    opposite to the angle tolerance). Blocks whose corners coincide (cut or stacked blocks meeting face to face)
    find each corner from both sides; both springs would double the corner's stiffness and its bond area.
    The contact kept is the one from the block of the smaller index (2D keeps one contact per corner pair
    the same way).

    Twins share their two blocks, so they are sought among the vertex-face contacts of each pair of blocks
    (:func:`_twins_by_pair`), not among all corners within ``distance`` of each other: a k-d tree over the
    corners met every coincident corner of a block's neighbours (a fifth of slope3d_1k's detection)."""
    kind, fa, fb, a, b = found.T
    twin = np.zeros(len(found), dtype=bool)
    vf = np.flatnonzero(kind == VERTEX_FACE)
    if len(vf) < 2:
        return twin
    low, high = np.minimum(a[vf], b[vf]), np.maximum(a[vf], b[vf])
    by_pair = vf[np.lexsort((high, low))]
    corner, normal = np.zeros((len(found), vertices.shape[1])), np.zeros((len(found), vertices.shape[1]))
    corner[vf], normal[vf] = vertices[fa[vf]], face_normal[fb[vf]]
    _twins_by_pair(by_pair, a, b, corner, normal, distance * distance, cos_parallel, twin)
    return twin


@njit(cache=True)
def _twins_by_pair(by_pair: np.ndarray, a: np.ndarray, b: np.ndarray, corner: np.ndarray, normal: np.ndarray,
                   distance2: float, cos_parallel: float, twin: np.ndarray) -> None:
    """Mark in ``twin`` the contact from the block of the larger index of every facing corner pair: contacts
    i, j of ``by_pair`` (vertex-face contacts sorted by their unordered pair of blocks) from opposite sides of
    one pair, corners within √``distance2`` (the squared distance, as a k-d tree's query compares it), face
    normals opposite beyond ``cos_parallel``."""
    n = len(by_pair)
    start = 0
    while start < n:
        first = by_pair[start]
        low, high = min(a[first], b[first]), max(a[first], b[first])
        stop = start + 1
        while stop < n and min(a[by_pair[stop]], b[by_pair[stop]]) == low \
                and max(a[by_pair[stop]], b[by_pair[stop]]) == high:
            stop += 1
        for p in range(start, stop):
            i = by_pair[p]
            for q in range(p + 1, stop):
                j = by_pair[q]
                if a[i] != b[j] or b[i] != a[j]:
                    continue
                d2 = 0.0
                facing = 0.0
                for k in range(corner.shape[1]):
                    d2 += (corner[i, k] - corner[j, k]) ** 2
                    facing += normal[i, k] * normal[j, k]
                if d2 <= distance2 and facing < -cos_parallel:
                    twin[i if a[i] > b[i] else j] = True
        start = stop


class Detector3D:
    """Finds the contacts of a configuration of the model's polyhedra (hinged pairs left out)."""

    def __init__(self, arrays: ModelArrays, distance: float, angle_tolerance: float, max_penetration: float) -> None:
        if arrays.mesh is None:
            raise ModelError("3D contacts need polyhedral blocks")
        self.arrays = arrays
        self.distance, self.max_penetration = distance, max_penetration
        self.mesh = arrays.mesh
        self.topology = PolyhedronTopology.of(arrays.mesh)
        self.sin_tol = float(np.sin(angle_tolerance))
        self.cos_parallel = float(np.cos(angle_tolerance))
        self.key_size = max(len(arrays.vertex_position), len(self.mesh.face_block), len(self.topology.edge_v0)) + 1
        self.pairs = PairFinder(arrays, distance, candidate_pairs_3d)

    def detect(self, vertices: np.ndarray) -> ContactRecord | None:
        """The contacts of ``vertices``; None when no contact is near."""
        arr, topo, mesh = self.arrays, self.topology, self.mesh
        surface = surface_geometry(vertices, mesh, topo, self.sin_tol)
        boxes, pairs = self.pairs(vertices)
        if len(pairs) == 0:
            return None
        found = narrow_phase_3d(vertices, pairs, boxes, arr.block_ptr, topo.block_face_ptr, mesh.face_ptr,
                                mesh.face_vertex, surface.face_normal, surface.face_point, topo.neighbour_ptr,
                                topo.neighbour, surface.vertex_convex, topo.block_edge_ptr, topo.edge_v0,
                                topo.edge_v1, topo.edge_faces, surface.edge_convex, self.distance, self.sin_tol,
                                self.max_penetration)
        found = found[~corner_twins(found, vertices, surface.face_normal, self.distance, self.cos_parallel)]
        if len(found) == 0:
            return None
        record = contact_record_3d(vertices, mesh, topo, surface, found, self.key_size)
        bond, tributary, bond_faces = self.face_shares(found, surface, record.normal)
        return replace(record, joint=self.joint_index(found, record), bond=bond, tributary=tributary,
                       bond_faces=bond_faces)

    def joint_index(self, found: np.ndarray, record: ContactRecord) -> np.ndarray:
        """Row of the joint table of every contact: the contacted face's joint material.

        A vertex-face contact takes its face's (``ModelArrays.face_joint``), an
        edge-edge contact the one named on either face of b's edge, else a's
        (the larger index when both are named); contacts on faces with none
        take the joint chosen by the two blocks' materials (as 2D edges do).
        """
        arr = self.arrays
        by_materials = arr.material_joint[arr.block_material[record.block_a], arr.block_material[record.block_b]]
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

    def face_shares(self, found: np.ndarray, surface: SurfaceGeometry, normal: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """(bond, tributary) areas of the contacts, and the faces that make up the bonds (the record's
        ``bond_faces``: contact, mesh face, share 1 / its vertex count).

        The bond, over which cohesion and tensile strength act: each face of a
        at a vertex-face contact's vertex whose normal is opposite the
        contact's (to within the angle tolerance) gives area / its vertex
        count, so a face-to-face joint of area A is carried by its corner
        contacts, A in all; edge-edge contacts and corners touching a face
        have none. The tributary area, which a joint's stiffness per area
        acts over: the bond, or for a point contact the smallest such share of
        the faces at its vertex (edge-edge: at its two edges), the least it
        could stand for.
        """
        topo = self.topology
        vf = found[:, 0] == VERTEX_FACE
        vertex = np.where(vf, found[:, 1], 0)
        start, stop = topo.vertex_corner_ptr[vertex], topo.vertex_corner_ptr[vertex + 1]
        counts = np.where(vf, stop - start, 0)
        owner = np.repeat(np.arange(len(found)), counts)
        corner = topo.vertex_corner[np.repeat(start - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())]
        face = topo.corner_face[corner]
        count = np.diff(self.mesh.face_ptr)[face]
        share = surface.face_area[face] / count
        facing = np.einsum("ni,ni->n", surface.face_normal[face], normal[owner]) <= -self.cos_parallel
        bond = np.bincount(owner, weights=np.where(facing, share, 0.0), minlength=len(found))
        smallest = np.full(len(found), np.inf)
        np.minimum.at(smallest, owner, share)
        if np.any(~vf):
            edges = np.concatenate([topo.edge_faces[found[~vf, 1]], topo.edge_faces[found[~vf, 2]]], axis=1)
            faces = surface.face_area[edges] / np.diff(self.mesh.face_ptr)[edges]
            smallest[~vf] = np.min(faces, axis=1)
        return bond, np.where(bond > 0.0, bond, smallest), (owner[facing], face[facing].astype(np.int64),
                                                             1.0 / count[facing])
