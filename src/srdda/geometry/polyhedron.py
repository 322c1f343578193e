"""Polyhedral blocks: validation, a flat multi-block layout, exact volume integrals.

A 3D block is a closed 2-manifold surface of planar polygonal faces (convex or
concave), stored as vertices (n, 3) and faces (lists of vertex indices, outward
counter-clockwise). :func:`normalize_polyhedron` validates one block and repairs
its face orientation; :class:`PolyhedronMesh` lays all blocks out flat (CSR over
vertices, faces and a fan triangulation of the faces) so that
:func:`polyhedron_moments` integrates every block at once with whole-array numpy.

Integrals (divergence theorem): each face's fan triangle (v0, vi, vi+1) and a
reference point O of its block span a signed tetrahedron; their signed sum is
the block exactly, for planar faces even when a face or the block is concave
(the signed fan of a simple planar polygon sums to its indicator function).
Per tetrahedron with O at the origin and vertices a, b, c (F. Tonon, "Explicit
exact formulas for the 3-D tetrahedron inertia tensor in terms of its vertex
coordinates", J. Math. Stat. 1(1):8-11, 2005; written in the covariance form of
J. Blow & A. Binstock, "How to find the inertia tensor of a 3D solid body
represented by a triangle mesh", 2004: the canonical tetrahedron's ∫x_i x_j
mapped by the linear map [a b c]):

    V      = det[a, b, c] / 6
    ∫ x dV = V (a + b + c) / 4
    ∫ x_i x_j dV = V/20 · (Σ_k p_k,i p_k,j + (Σ_k p_k,i)(Σ_k p_k,j)),  p_k ∈ {a, b, c}

(the fourth vertex O = 0 drops out of both sums). Tolerances of the validation
are documented in docs/theory-3d.md.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import shapely
from numpy.typing import ArrayLike
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order, connected_components

from .polygon import PolygonError, normalize_polygon

if TYPE_CHECKING:
    import meshio  # the mesh type of polyhedra_from_meshio (meshio ships no stubs)

__all__ = [
    "polyhedron_covers",
    "PLANARITY_TOLERANCE",
    "PolyhedronError",
    "PolyhedronMesh",
    "PolyhedronMoments",
    "box",
    "normalize_polyhedra",
    "normalize_polyhedron",
    "polyhedra_from_meshio",
    "polyhedron_moments",
    "prism",
]

# A face vertex may lie this far from the face's plane, relative to the block
# size (the diagonal of its bounding box). Faces smaller than
# PLANARITY_TOLERANCE·size² in area and blocks smaller than
# PLANARITY_TOLERANCE·size³ in volume count as degenerate (zero).
PLANARITY_TOLERANCE = 1e-9

Block3D = tuple[np.ndarray, list[np.ndarray]]  # (vertices (n, 3), outward faces)


class PolyhedronError(ValueError):
    """A block is not a closed, manifold polyhedron of planar faces with positive volume."""


@dataclass(frozen=True)
class PolyhedronMoments:
    """Volume, centroid and central second moments ``second[b, i, j] = ∫ X_i X_j dV`` (X = x - centroid)."""

    volume: np.ndarray  # (nb,)
    centroid: np.ndarray  # (nb, 3)
    second: np.ndarray  # (nb, 3, 3)


@dataclass(frozen=True)
class _FaceRings:
    """Faces of one block as a CSR of vertex indices, with each face vertex's successor."""

    ptr: np.ndarray  # (nf + 1,)
    vertex: np.ndarray  # (ptr[-1],) vertex at each corner (= tail of the corner's directed edge)
    owner: np.ndarray  # face of each corner
    nxt: np.ndarray  # next corner of the same face (cyclic)

    @classmethod
    def of(cls, faces: Sequence[np.ndarray]) -> _FaceRings:
        counts = np.array([len(f) for f in faces])
        ptr = np.concatenate([[0], np.cumsum(counts)])
        nxt = np.arange(1, ptr[-1] + 1)
        nxt[ptr[1:] - 1] = ptr[:-1]
        return cls(ptr=ptr, vertex=np.concatenate(faces), owner=np.repeat(np.arange(len(counts)), counts), nxt=nxt)


def _fan(face_ptr: np.ndarray, face_vertex: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fan triangles (f0, f_i, f_i+1), i = 1..len-2, of every face; returns (tri (nt, 3), face of each)."""
    n_tri = np.diff(face_ptr) - 2
    tri_face = np.repeat(np.arange(len(n_tri)), n_tri)
    i = np.arange(len(tri_face)) - np.repeat(np.cumsum(n_tri) - n_tri, n_tri) + 1
    start = face_ptr[tri_face]
    tri = np.column_stack([face_vertex[start], face_vertex[start + i], face_vertex[start + i + 1]])
    return tri, tri_face


def _as_vertices(vertices: object, label: str) -> np.ndarray:
    """Vertices as a finite (n >= 4, 3) float array."""
    try:
        v = np.array(vertices, dtype=float)
    except (TypeError, ValueError):
        raise PolyhedronError(f"block '{label}': vertices must be a list of [x, y, z] triples") from None
    if v.ndim != 2 or v.shape[1] != 3:
        raise PolyhedronError(f"block '{label}': vertices must be a list of [x, y, z] triples")
    if len(v) < 4:
        raise PolyhedronError(f"block '{label}': a polyhedron needs at least 4 vertices, got {len(v)}")
    if not np.all(np.isfinite(v)):
        raise PolyhedronError(f"block '{label}': vertex coordinates must be finite numbers")
    return v


def _as_faces(faces: object, n_vertices: int, label: str) -> list[np.ndarray]:
    """Faces as integer index arrays: each >= 3 distinct indices in range, at least 4 faces."""
    if isinstance(faces, np.ndarray) and faces.ndim == 2:
        faces = list(faces)
    if not isinstance(faces, Sequence) or isinstance(faces, str):
        raise PolyhedronError(f"block '{label}': faces must be a list of vertex-index lists")
    out = []
    for k, face in enumerate(faces):
        f = np.asarray(face)
        if f.ndim != 1 or not (np.issubdtype(f.dtype, np.integer) or f.size == 0):
            raise PolyhedronError(f"block '{label}': face {k} must be a list of integer vertex indices")
        f = f.astype(np.int64)
        if len(f) < 3:
            raise PolyhedronError(f"block '{label}': face {k} has {len(f)} vertices, a face needs at least 3")
        outside = f[(f < 0) | (f >= n_vertices)]
        if len(outside):
            raise PolyhedronError(
                f"block '{label}': face {k} refers to vertex {int(outside[0])}, but the block has {n_vertices} "
                f"vertices (indices 0..{n_vertices - 1})")
        if len(np.unique(f)) != len(f):
            raise PolyhedronError(f"block '{label}': face {k} repeats a vertex ({f.tolist()})")
        out.append(f)
    if len(out) < 4:
        raise PolyhedronError(f"block '{label}': a closed polyhedron needs at least 4 faces, got {len(out)}")
    return out


@dataclass(frozen=True)
class _Batch:
    """Several blocks validated together: global vertex and face numbering, mapped back for messages."""

    labels: Sequence[str]
    vertices: np.ndarray  # (nv, 3)
    vertex_ptr: np.ndarray  # (nb + 1,)
    vertex_block: np.ndarray  # (nv,)
    face_first: np.ndarray  # (nb + 1,) first global face of each block
    face_block: np.ndarray  # (nf,)
    rings: _FaceRings  # faces with global vertex indices

    def block_of_vertex(self, v: int) -> str:
        b = int(self.vertex_block[v])
        return f"block '{self.labels[b]}'"

    def local_vertex(self, v: int) -> int:
        return int(v - self.vertex_ptr[self.vertex_block[v]])

    def face(self, k: int) -> str:
        b = int(self.face_block[k])
        return f"block '{self.labels[b]}': face {int(k - self.face_first[b])}"


def _check_distinct_and_used(batch: _Batch) -> None:
    """No two vertices of a block coincide; every vertex lies on a face of its block."""
    v, owner = batch.vertices, batch.vertex_block
    order = np.lexsort((v[:, 2], v[:, 1], v[:, 0], owner))
    same = np.all(v[order[1:]] == v[order[:-1]], axis=1) & (owner[order[1:]] == owner[order[:-1]])
    if np.any(same):
        i = int(np.flatnonzero(same)[0])
        a, b = sorted((int(order[i]), int(order[i + 1])))
        raise PolyhedronError(f"{batch.block_of_vertex(a)}: vertices {batch.local_vertex(a)} and "
                              f"{batch.local_vertex(b)} coincide")
    used = np.zeros(len(v), dtype=bool)
    used[batch.rings.vertex] = True
    if not np.all(used):
        a = int(np.flatnonzero(~used)[0])
        raise PolyhedronError(f"{batch.block_of_vertex(a)}: vertex {batch.local_vertex(a)} is on no face")


def _block_size(batch: _Batch) -> np.ndarray:
    """Diagonal of each block's bounding box; (nb,)."""
    starts = batch.vertex_ptr[:-1]
    span = np.maximum.reduceat(batch.vertices, starts, axis=0) - np.minimum.reduceat(batch.vertices, starts, axis=0)
    return np.linalg.norm(span, axis=1)


def _check_faces_planar_and_simple(batch: _Batch, size: np.ndarray) -> None:
    """Every face planar within PLANARITY_TOLERANCE·size, of non-zero area, and simple in its plane."""
    rings, v = batch.rings, batch.vertices
    n_faces = len(rings.ptr) - 1
    counts = np.diff(rings.ptr)
    centre = np.add.reduceat(v[rings.vertex], rings.ptr[:-1], axis=0) / counts[:, None]
    p = v[rings.vertex] - centre[rings.owner]
    normal = np.zeros((n_faces, 3))  # Newell's vector area ½ Σ p_i × p_i+1
    np.add.at(normal, rings.owner, 0.5 * np.cross(p, p[rings.nxt]))
    area = np.linalg.norm(normal, axis=1)
    tol = PLANARITY_TOLERANCE * size[batch.face_block]  # per face
    flat = np.flatnonzero(area <= tol * size[batch.face_block])
    if len(flat):
        raise PolyhedronError(f"{batch.face(flat[0])} has zero area (collinear vertices or an outline that cancels itself)")
    unit = normal / area[:, None]
    dist = np.abs(np.einsum("ij,ij->i", p, unit[rings.owner]))
    off = np.flatnonzero(dist > tol[rings.owner])
    if len(off):
        c = off[0]
        k = rings.owner[c]
        raise PolyhedronError(
            f"{batch.face(k)} is not planar (vertex {batch.local_vertex(rings.vertex[c])} lies {dist[c]:.3g} from "
            f"the face's plane; tolerance {tol[k]:.3g} = {PLANARITY_TOLERANCE:g} x block size)")
    # in-plane coordinates, then a simple-polygon test (shapely/GEOS) of faces with 4 or more vertices
    big = np.flatnonzero(counts > 3)
    if len(big) == 0:
        return
    helper = np.where(np.abs(unit[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    e1 = np.cross(unit, helper)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(unit, e1)
    corners = np.isin(rings.owner, big)
    own = rings.owner[corners]
    uv = np.column_stack([np.einsum("ij,ij->i", p[corners], e1[own]), np.einsum("ij,ij->i", p[corners], e2[own])])
    polys = shapely.polygons(shapely.linearrings(uv, indices=np.searchsorted(big, own)))
    bad = np.flatnonzero(~shapely.is_valid(polys))
    if len(bad):
        raise PolyhedronError(f"{batch.face(big[bad[0]])} is not a simple polygon "
                              f"({shapely.is_valid_reason(polys[bad[0]])})")


def _edge_pairs(batch: _Batch) -> tuple[np.ndarray, np.ndarray]:
    """The two corners (directed edges) using each undirected edge; errors unless every edge has two."""
    rings = batch.rings
    tail, head = rings.vertex, rings.vertex[rings.nxt]
    lo, hi = np.minimum(tail, head), np.maximum(tail, head)
    key = lo * len(batch.vertices) + hi
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    starts = np.flatnonzero(np.r_[True, sorted_key[1:] != sorted_key[:-1]])
    uses = np.diff(np.r_[starts, len(key)])
    bad = np.flatnonzero(uses != 2)
    if len(bad):
        c = order[starts[bad[0]]]
        n = uses[bad[0]]
        a, b = batch.local_vertex(lo[c]), batch.local_vertex(hi[c])
        problem = "the surface is not closed (a hole or a missing face)" if n == 1 else "the surface is not manifold"
        raise PolyhedronError(f"{batch.block_of_vertex(lo[c])}: edge ({a}, {b}) is used by {n} "
                              f"face{'s' if n != 1 else ''}, {problem}")
    return order[0::2], order[1::2]


def _check_vertex_manifold(batch: _Batch, d1: np.ndarray, d2: np.ndarray) -> None:
    """The faces around every vertex form one fan (no two cones touching at a vertex)."""
    # Corner c is (face owner[c], vertex vertex[c]). Edge t→h of corner d1 links the corners of the two
    # faces at t and at h; corner d2 runs either t→h (same direction) or h→t.
    rings = batch.rings
    n1, n2 = rings.nxt[d1], rings.nxt[d2]
    same = rings.vertex[d2] == rings.vertex[d1]
    at_tail = np.where(same, d2, n2)  # corner of face 2 at the tail of d1
    at_head = np.where(same, n2, d2)  # corner of face 2 at the head of d1
    rows, cols = np.concatenate([d1, n1]), np.concatenate([at_tail, at_head])
    n = len(rings.vertex)
    _, comp = connected_components(coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n)), directed=False)
    fan_key = np.unique(rings.vertex * n + comp)
    fans_per_vertex = np.bincount(fan_key // n, minlength=len(batch.vertices))
    pinched = np.flatnonzero(fans_per_vertex > 1)
    if len(pinched):
        a = int(pinched[0])
        raise PolyhedronError(f"{batch.block_of_vertex(a)}: the surface touches itself at vertex "
                              f"{batch.local_vertex(a)} (not manifold)")


def _orientation_flips(batch: _Batch) -> np.ndarray:
    """Which faces to reverse so every edge is traversed once each way; checks closed, manifold, connected."""
    rings = batch.rings
    d1, d2 = _edge_pairs(batch)
    f1, f2 = rings.owner[d1], rings.owner[d2]
    same_direction = rings.vertex[d1] == rings.vertex[d2]  # then exactly one of the two faces must flip
    nf = len(rings.ptr) - 1
    _, comp = connected_components(coo_matrix((np.ones(len(f1)), (f1, f2)), shape=(nf, nf)), directed=False)
    n_surfaces = np.bincount(batch.face_block[np.unique(comp, return_index=True)[1]], minlength=len(batch.labels))
    split = np.flatnonzero(n_surfaces != 1)
    if len(split):
        b = split[0]
        raise PolyhedronError(f"block '{batch.labels[b]}': the faces form {n_surfaces[b]} separate closed "
                              f"surfaces; one block must be one surface")
    _check_vertex_manifold(batch, d1, d2)
    # one shared edge per face pair decides the relative orientation along a BFS tree; a virtual root
    # (node nf) joins the first face of every block so one search covers all blocks
    pair = np.column_stack([np.minimum(f1, f2), np.maximum(f1, f2)])
    _, one = np.unique(pair[:, 0] * nf + pair[:, 1], return_index=True)
    root = np.column_stack([batch.face_first[:-1], np.full(len(batch.labels), nf)])
    tree_pairs = np.vstack([pair[one], root])
    differ = np.concatenate([same_direction[one], np.zeros(len(root), dtype=bool)])
    tree = coo_matrix((np.ones(len(tree_pairs)), (tree_pairs[:, 0], tree_pairs[:, 1])), shape=(nf + 1, nf + 1))
    visit, parent = breadth_first_order(tree, nf, directed=False, return_predecessors=True)
    lookup = dict(zip((tree_pairs[:, 0] * (nf + 1) + tree_pairs[:, 1]).tolist(), differ.tolist()))
    flip = np.zeros(nf + 1, dtype=bool)
    for f in visit[1:].tolist():  # parents come before children in BFS order
        g = int(parent[f])
        flip[f] = flip[g] ^ lookup[min(f, g) * (nf + 1) + max(f, g)]
    flip = flip[:nf]
    wrong = np.flatnonzero((flip[f1] ^ flip[f2]) != same_direction)
    if len(wrong):
        raise PolyhedronError(f"block '{batch.labels[batch.face_block[f1[wrong[0]]]]}': the surface is not "
                              f"orientable (its faces cannot all point outward)")
    return flip


def _signed_volumes(batch: _Batch, flip: np.ndarray) -> np.ndarray:
    """Signed volume of every block with faces ``flip``-ped: fan tetrahedra from each block's vertex mean."""
    rings = batch.rings
    # a reversed face integrates to the opposite sign of its original fan
    tri, tri_face = _fan(rings.ptr, rings.vertex)
    starts = batch.vertex_ptr[:-1]
    ref = np.add.reduceat(batch.vertices, starts, axis=0) / np.diff(batch.vertex_ptr)[:, None]
    p = batch.vertices - ref[batch.vertex_block]
    vol6 = np.einsum("ij,ij->i", p[tri[:, 0]], np.cross(p[tri[:, 1]], p[tri[:, 2]]))
    vol6 = np.where(flip[tri_face], -vol6, vol6)
    return np.bincount(batch.face_block[tri_face], weights=vol6, minlength=len(batch.labels)) / 6.0


def _normalize_blocks(blocks: Sequence[tuple[object, object]], labels: Sequence[str]) -> list[Block3D]:
    """Validate several blocks at once (whole-array checks) and return them outward-oriented."""
    vs, fss = [], []
    for (vertices, faces), label in zip(blocks, labels, strict=True):
        v = _as_vertices(vertices, label)
        vs.append(v)
        fss.append(_as_faces(faces, len(v), label))
    n_vert = np.array([len(v) for v in vs])
    vertex_ptr = np.concatenate([[0], np.cumsum(n_vert)])
    n_face = np.array([len(fs) for fs in fss])
    batch = _Batch(
        labels=labels,
        vertices=np.concatenate(vs),
        vertex_ptr=vertex_ptr,
        vertex_block=np.repeat(np.arange(len(vs)), n_vert),
        face_first=np.concatenate([[0], np.cumsum(n_face)]),
        face_block=np.repeat(np.arange(len(vs)), n_face),
        rings=_FaceRings.of([f + vertex_ptr[b] for b, fs in enumerate(fss) for f in fs]),
    )
    _check_distinct_and_used(batch)
    size = _block_size(batch)
    _check_faces_planar_and_simple(batch, size)
    flip = _orientation_flips(batch)
    volume = _signed_volumes(batch, flip)
    flat = np.flatnonzero(np.abs(volume) <= PLANARITY_TOLERANCE * size**3)
    if len(flat):
        raise PolyhedronError(f"block '{labels[flat[0]]}': the polyhedron has zero volume (it is flat)")
    flip ^= (volume < 0)[batch.face_block]  # an inward surface is turned outward
    all_faces = [f for fs in fss for f in fs]
    out_faces = [f[::-1].copy() if fl else f for f, fl in zip(all_faces, flip.tolist())]
    return [(vs[b], out_faces[batch.face_first[b]:batch.face_first[b + 1]]) for b in range(len(vs))]


def normalize_polyhedron(vertices: object, faces: object, label: str = "polyhedron") -> Block3D:
    """Validate one block and return (vertices (n, 3), faces with outward counter-clockwise orientation).

    Checks, each failure a :class:`PolyhedronError` naming ``label`` and the
    problem: >= 4 finite vertices, no two coinciding, every vertex on a face;
    >= 4 faces of >= 3 distinct in-range indices, planar within
    ``PLANARITY_TOLERANCE`` x block size, of non-zero area and simple in their
    plane; every edge shared by exactly two faces (closed, manifold), one fan
    of faces around every vertex, one connected surface; positive volume.
    Inconsistent face orientations are repaired by reversing faces; an inward
    surface is turned outward. Intersections between non-adjacent faces are
    not checked.
    """
    return _normalize_blocks([(vertices, faces)], [label])[0]


def normalize_polyhedra(blocks: Sequence[tuple[object, object]], labels: Sequence[str]) -> list[Block3D]:
    """:func:`normalize_polyhedron` of many blocks at once (whole-array checks); the first failure is raised."""
    return _normalize_blocks(blocks, labels)


@dataclass(frozen=True)
class PolyhedronMesh:
    """All polyhedral blocks laid out flat, for whole-array work in the time loop.

    Block ``b`` owns ``vertices[block_ptr[b]:block_ptr[b+1]]``; face ``k`` is
    ``face_vertex[face_ptr[k]:face_ptr[k+1]]`` (global vertex indices, outward
    counter-clockwise) of block ``face_block[k]``. ``tri`` is the fan
    (v0, vi, vi+1) of every face, grouped by block (``tri_ptr`` over blocks),
    ``tri_face`` its face. For a concave face some fan triangles are negative
    (they overlap): the fan is exact for integrals, not a tiling for drawing.
    """

    vertices: np.ndarray  # (nv, 3)
    block_ptr: np.ndarray  # (nb + 1,)
    vertex_block: np.ndarray  # (nv,)
    face_ptr: np.ndarray  # (nf + 1,)
    face_vertex: np.ndarray  # (face_ptr[-1],)
    face_block: np.ndarray  # (nf,)
    tri: np.ndarray  # (nt, 3)
    tri_face: np.ndarray  # (nt,)
    tri_block: np.ndarray  # (nt,)
    tri_ptr: np.ndarray  # (nb + 1,)

    @property
    def n_blocks(self) -> int:
        return len(self.block_ptr) - 1

    @classmethod
    def from_blocks(cls, blocks: Sequence[tuple[object, object]], labels: Sequence[str] | None = None
                    ) -> PolyhedronMesh:
        """Validate every (vertices, faces) block (:func:`normalize_polyhedron`) and lay them out flat."""
        if len(blocks) == 0:
            raise PolyhedronError("a polyhedron mesh needs at least one block")
        if labels is None:
            labels = [str(b) for b in range(len(blocks))]
        if len(labels) != len(blocks):
            raise PolyhedronError(f"got {len(labels)} labels for {len(blocks)} blocks")
        normalized = _normalize_blocks(blocks, labels)
        n_vert = np.array([len(v) for v, _ in normalized])
        block_ptr = np.concatenate([[0], np.cumsum(n_vert)])
        faces = [f + block_ptr[b] for b, (_, fs) in enumerate(normalized) for f in fs]
        face_block = np.repeat(np.arange(len(normalized)), [len(fs) for _, fs in normalized])
        face_len = np.array([len(f) for f in faces])
        face_ptr = np.concatenate([[0], np.cumsum(face_len)])
        face_vertex = np.concatenate(faces)
        tri, tri_face = _fan(face_ptr, face_vertex)
        tri_block = face_block[tri_face]
        tri_ptr = np.concatenate([[0], np.cumsum(np.bincount(tri_block, minlength=len(normalized)))])
        return cls(
            vertices=np.concatenate([v for v, _ in normalized]),
            block_ptr=block_ptr,
            vertex_block=np.repeat(np.arange(len(normalized)), n_vert),
            face_ptr=face_ptr,
            face_vertex=face_vertex,
            face_block=face_block,
            tri=tri,
            tri_face=tri_face,
            tri_block=tri_block,
            tri_ptr=tri_ptr,
        )


def polyhedron_moments(vertices: np.ndarray, mesh: PolyhedronMesh) -> PolyhedronMoments:
    """Exact volume, centroid and central second moments of every block at ``vertices`` (nv, 3).

    Signed tetrahedra (block reference point, fan triangle) summed per block
    (Tonon 2005; see the module docstring). Vertices are shifted per block by
    their mean first, so blocks far from the origin keep full precision.
    """
    starts = mesh.block_ptr[:-1]
    counts = np.diff(mesh.block_ptr)
    ref = np.add.reduceat(vertices, starts, axis=0) / counts[:, None]
    p = np.ascontiguousarray((vertices - ref[mesh.vertex_block]).T)  # (3, nv): rows keep the sums contiguous
    a, b, c = p[:, mesh.tri[:, 0]], p[:, mesh.tri[:, 1]], p[:, mesh.tri[:, 2]]
    s = a + b + c
    rows = np.empty((10, len(mesh.tri)))  # per tetrahedron: 6V, 6∫x dV·4, 6∫x_i x_j dV·20
    vol6 = rows[0]
    vol6[:] = a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) + a[2] * (b[0] * c[1] - b[1] * c[0])
    np.multiply(vol6, s, out=rows[1:4])
    for k, (i, j) in enumerate(zip(_I, _J)):  # the six distinct second moments (Tonon 2005)
        rows[4 + k] = vol6 * (a[i] * a[j] + b[i] * b[j] + c[i] * c[j] + s[i] * s[j])
    sums = np.add.reduceat(rows, mesh.tri_ptr[:-1], axis=1)
    volume = sums[0] / 6.0
    centre = (sums[1:4] / 24.0 / volume).T  # about ref
    central = sums[4:].T / 120.0 - volume[:, None] * centre[:, _I] * centre[:, _J]
    second = np.empty((len(volume), 3, 3))
    second[:, _I, _J] = central
    second[:, _J, _I] = central
    return PolyhedronMoments(volume=volume, centroid=centre + ref, second=second)


_I, _J = np.triu_indices(3)  # the six distinct entries of a symmetric 3x3 tensor
_BOX_FACES = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]


def box(lo: Sequence[float] | np.ndarray, hi: Sequence[float] | np.ndarray, label: str = "box") -> Block3D:
    """The axis-aligned box [lo, hi]: 8 vertices, 6 outward quadrilateral faces."""
    lo_a, hi_a = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    if lo_a.shape != (3,) or hi_a.shape != (3,):
        raise PolyhedronError(f"block '{label}': box corners must be [x, y, z] triples")
    if not (np.all(np.isfinite(lo_a)) and np.all(np.isfinite(hi_a))) or np.any(hi_a <= lo_a):
        raise PolyhedronError(f"block '{label}': box needs finite corners with hi > lo on every axis, "
                              f"got lo={lo_a.tolist()}, hi={hi_a.tolist()}")
    x = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
    v = lo_a + x * (hi_a - lo_a)
    return v, [np.array(f) for f in _BOX_FACES]


def prism(polygon_2d: ArrayLike, z0: float, z1: float, label: str = "prism") -> Block3D:
    """Extrusion of a simple 2D polygon (concave allowed) from z0 to z1.

    Bottom and top are one polygon face each, the sides quadrilaterals.
    """
    try:
        base = normalize_polygon(polygon_2d, name=f"block '{label}'")  # counter-clockwise
    except PolygonError as exc:
        raise PolyhedronError(str(exc)) from None
    if not (np.isfinite(z0) and np.isfinite(z1) and z1 > z0):
        raise PolyhedronError(f"block '{label}': prism needs finite z0 < z1, got z0={z0}, z1={z1}")
    n = len(base)
    v = np.vstack([np.column_stack([base, np.full(n, z0)]), np.column_stack([base, np.full(n, z1)])])
    i = np.arange(n)
    j = (i + 1) % n
    sides = np.column_stack([i, j, n + j, n + i])
    faces = [np.arange(n)[::-1].copy(), np.arange(n, 2 * n), *sides]
    return normalize_polyhedron(v, faces, label)


_SURFACE_CELLS = ("triangle", "quad", "polygon")


def polyhedra_from_meshio(mesh: meshio.Mesh, label: str = "mesh") -> list[Block3D]:
    """One block per connected closed surface of a meshio surface mesh (triangles, quads, polygons).

    Surfaces are connected through shared point indices (meshio's STL reader
    merges coincident points); touching blocks must therefore not share mesh
    points. Vertex and line cells are ignored; any other cell type (volume or
    higher-order cells) is an error. Blocks are labelled
    ``f"{label} surface {k}"`` in order of their first face, and validated as
    :func:`normalize_polyhedron` does.
    """
    points = np.asarray(mesh.points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise PolyhedronError(f"{label}: mesh points must be 3D coordinates (x, y, z)")
    faces: list[np.ndarray] = []
    for cells in mesh.cells:
        kind = cells.type
        if kind in _SURFACE_CELLS or kind.startswith("polygon"):
            faces.extend(np.asarray(cells.data, dtype=np.int64))
        elif not (kind == "vertex" or kind.startswith("line")):
            raise PolyhedronError(f"{label}: cells of type '{kind}' are not surface polygons; give the blocks' "
                                  f"surfaces as triangle, quad or polygon cells")
    if not faces:
        raise PolyhedronError(f"{label}: the mesh has no triangle, quad or polygon cells")
    rings = _FaceRings.of(faces)
    n_pts, n_faces = len(points), len(faces)
    # points and faces in one graph (face k is node n_pts + k); each component is one surface
    graph = coo_matrix((np.ones(len(rings.vertex)), (rings.vertex, n_pts + rings.owner)),
                       shape=(n_pts + n_faces,) * 2)
    _, comp = connected_components(graph, directed=False)
    _, first_face, face_comp = np.unique(comp[n_pts:], return_index=True, return_inverse=True)
    surface_rank = np.argsort(np.argsort(first_face))  # surfaces numbered in order of their first face
    face_surface = surface_rank[face_comp.ravel()]
    n_surfaces = len(first_face)
    # the points of each surface, numbered locally in order of their global index
    used = np.unique(rings.vertex)
    point_surface = np.full(n_pts, -1)
    point_surface[rings.vertex] = face_surface[rings.owner]
    order = used[np.lexsort((used, point_surface[used]))]
    point_ptr = np.concatenate([[0], np.cumsum(np.bincount(point_surface[order], minlength=n_surfaces))])
    local = np.empty(n_pts, dtype=np.int64)
    local[order] = np.arange(len(order)) - point_ptr[point_surface[order]]
    face_order = np.argsort(face_surface, kind="stable")
    face_ptr = np.concatenate([[0], np.cumsum(np.bincount(face_surface, minlength=n_surfaces))])
    blocks = [(points[order[point_ptr[k]:point_ptr[k + 1]]],
               [local[faces[m]] for m in face_order[face_ptr[k]:face_ptr[k + 1]]]) for k in range(n_surfaces)]
    return _normalize_blocks(blocks, [f"{label} surface {k}" for k in range(n_surfaces)])


def polyhedron_covers(vertices: np.ndarray, faces: Sequence[np.ndarray], point: np.ndarray,
                      tolerance: float = 1e-9) -> bool:
    """True if ``point`` lies inside the closed polyhedron or on its surface (within ``tolerance`` × size).

    Inside: the generalized winding number, the sum of the solid angles of the
    fan triangles seen from the point over 4π (Van Oosterom & Strackee 1983),
    is 1 (0 outside); exact for concave blocks. On the surface: the point lies
    in the plane of a fan triangle and inside it.
    """
    tri = np.array([(f[0], f[i], f[i + 1]) for f in faces for i in range(1, len(f) - 1)])
    size = float(np.linalg.norm(np.ptp(vertices, axis=0)))
    eps = tolerance * size
    a, b, c = (vertices[tri[:, k]] - point for k in range(3))
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    if min(la.min(), lb.min(), lc.min()) <= eps:
        return True  # at a vertex
    normal = np.cross(b - a, c - a)
    area2 = np.linalg.norm(normal, axis=1)
    height = np.abs(np.einsum("ij,ij->i", a, normal)) / area2  # distance to each triangle's plane
    coplanar = height <= eps
    if np.any(coplanar):  # barycentric test of the point in its coplanar triangles (edges included)
        n = normal[coplanar]
        w = np.stack([np.einsum("ij,ij->i", np.cross(u, v), n) for u, v in
                      ((b[coplanar], c[coplanar]), (c[coplanar], a[coplanar]), (a[coplanar], b[coplanar]))], -1)
        if np.any(np.all(w >= -eps * np.linalg.norm(n, axis=1)[:, None] * size, axis=1)):
            return True
    num = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", a, c) * lb \
        + np.einsum("ij,ij->i", b, c) * la
    winding = np.sum(2.0 * np.arctan2(num, den)) / (4.0 * np.pi)
    return bool(winding > 0.5)
