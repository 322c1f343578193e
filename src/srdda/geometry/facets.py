"""The blocks' boundary as simplices: 2D edges, 3D fan triangles of the faces, with their area vectors.

Loads spread over block faces (the water in a tension crack,
:mod:`srdda.constraints.water`) integrate over these simplices: a polygon's
edge i runs from vertex i to the next (counter-clockwise, so its outward
normal is the edge turned clockwise); a polyhedron's face is the fan
(v0, vi, vi+1) of :class:`~srdda.geometry.polyhedron.PolyhedronMesh`, exact
for integrals over the face (a concave face's fan triangles of opposite
orientation subtract).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..modeldata.arrays import ModelArrays

__all__ = ["boundary_simplices", "area_vectors"]


def boundary_simplices(arrays: ModelArrays) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(vertex indices (n, m) of every boundary simplex, its face (n,), its block (n,)): m = 2 in 2D (a face is
    an edge, named by its start vertex), 3 in 3D (a face's fan triangle, the face a mesh face)."""
    if arrays.mesh is None:
        starts = np.arange(len(arrays.vertex_position))
        return np.stack([starts, arrays.vertex_next], axis=1), starts, arrays.vertex_block
    return arrays.mesh.tri, arrays.mesh.tri_face, arrays.mesh.tri_block


def area_vectors(points: np.ndarray) -> np.ndarray:
    """Outward area vectors (n, dim) of simplices ``points`` (n, m, dim): length (2D, per m of thickness) or
    area (3D) times the outward unit normal."""
    if points.shape[1] == 2:
        d = points[:, 1] - points[:, 0]
        return np.stack([d[:, 1], -d[:, 0]], axis=1)
    return 0.5 * np.cross(points[:, 1] - points[:, 0], points[:, 2] - points[:, 0])
