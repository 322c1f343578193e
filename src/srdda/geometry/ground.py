"""The ground below a point: the fixed blocks' boundary cast along the vertical (the last axis).

Used for the bounce height of an ensemble's collectors (docs/ensembles.md):
in 2D the fixed blocks' edges, in 3D the fan triangles of their faces, are
intersected by the vertical through the point, whole-array.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..modeldata.arrays import ModelArrays

__all__ = ["Ground"]


class Ground:
    """The fixed blocks' boundary, to find the ground height straight below a point (the last axis is up)."""

    def __init__(self, arrays: ModelArrays) -> None:
        fixed = arrays.block_fixed
        if arrays.mesh is None:  # 2D: the edges of fixed blocks
            keep = fixed[arrays.vertex_block]
            vertices = arrays.vertex_position
            self.facets = np.stack([vertices[keep], vertices[arrays.vertex_next[keep]]], axis=1)
        else:  # 3D: the fan triangles of the fixed blocks' faces
            tri = arrays.mesh.tri[fixed[arrays.mesh.tri_block]]
            self.facets = arrays.vertex_position[tri]

    def height_below(self, point: np.ndarray) -> float:
        """Height of the highest ground surface at or below ``point`` on its vertical; NaN if there is none."""
        f = self.facets
        if len(f) == 0:
            return math.nan
        if f.shape[-1] == 2:
            x0, x1 = f[:, 0, 0], f[:, 1, 0]
            span = x1 - x0
            with np.errstate(divide="ignore", invalid="ignore"):
                s = (point[0] - x0) / span
            hit = (span != 0) & (s >= 0) & (s <= 1)
            heights = f[hit, 0, 1] + s[hit] * (f[hit, 1, 1] - f[hit, 0, 1])
        else:  # barycentric coordinates of the point's plan position in each triangle's plan
            a, b, c = f[:, 0], f[:, 1], f[:, 2]
            e1, e2, d = b[:, :2] - a[:, :2], c[:, :2] - a[:, :2], point[:2] - a[:, :2]
            det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
            with np.errstate(divide="ignore", invalid="ignore"):  # vertical triangles (det = 0) never hit
                u = (d[:, 0] * e2[:, 1] - d[:, 1] * e2[:, 0]) / det
                v = (e1[:, 0] * d[:, 1] - e1[:, 1] * d[:, 0]) / det
                hit = (det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1)
            heights = a[hit, 2] + u[hit] * (b[hit, 2] - a[hit, 2]) + v[hit] * (c[hit, 2] - a[hit, 2])
        below = heights[heights <= point[-1] + 1e-9]
        return float(below.max()) if len(below) else math.nan
