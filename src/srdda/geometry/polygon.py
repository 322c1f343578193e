"""Exact integrals over simple polygons and polygon validation.

All blocks' vertices live in one flat ``(n_vertices, 2)`` array with a CSR-like
pointer ``block_ptr`` (block ``b`` owns ``vertices[block_ptr[b]:block_ptr[b+1]]``).
The integrals are Green's-theorem sums over edges, done for every block at once
with ``np.add.reduceat``: no Python loop over blocks or vertices.

Reference: the exact simplex integration of Shi (1988), ch. 2, written as the
classical edge sums (e.g. Steger 1996, "On the calculation of moments of
polygons").
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import ArrayLike

__all__ = [
    "BlockMoments",
    "PolygonError",
    "block_moments",
    "normalize_polygon",
    "next_vertex_index",
    "previous_vertex_index",
    "polygon_areas",
    "overlapping_pairs",
]


class PolygonError(ValueError):
    """A block polygon is not a simple polygon of positive area."""


@dataclass(frozen=True)
class BlockMoments:
    """Area, centroid and central second moments of every block.

    ``sxx = ∫(x-x0)² dA``, ``syy = ∫(y-y0)² dA``, ``sxy = ∫(x-x0)(y-y0) dA``.
    """

    area: np.ndarray  # (nb,)
    centroid: np.ndarray  # (nb, 2)
    sxx: np.ndarray  # (nb,)
    syy: np.ndarray
    sxy: np.ndarray

    @property
    def volume(self) -> np.ndarray:
        """Volume per metre of thickness (m³/m): the area; the name the dimension-free code uses."""
        return self.area

    @property
    def second(self) -> np.ndarray:
        """Central second moments as tensors (nb, 2, 2): ∫X_i X_j dA."""
        return np.stack([np.stack([self.sxx, self.sxy], -1), np.stack([self.sxy, self.syy], -1)], -2)


def next_vertex_index(block_ptr: np.ndarray) -> np.ndarray:
    """Index of the next vertex (cyclically within its block) for every vertex."""
    n = int(block_ptr[-1])
    nxt = np.arange(1, n + 1)
    nxt[block_ptr[1:] - 1] = block_ptr[:-1]
    return nxt


def previous_vertex_index(block_ptr: np.ndarray) -> np.ndarray:
    """Index of the previous vertex (cyclically within its block) for every vertex."""
    n = int(block_ptr[-1])
    prv = np.arange(-1, n - 1)
    prv[block_ptr[:-1]] = block_ptr[1:] - 1
    return prv


def _edges(vertices: np.ndarray, block_ptr: np.ndarray, owner: np.ndarray | None,
           nxt: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Edge start p and end q relative to their block's vertex mean ``ref``, and p × q (Green's sums)."""
    counts = np.diff(block_ptr)
    ref = np.add.reduceat(vertices, block_ptr[:-1], axis=0) / counts[:, None]
    if owner is None:
        owner = np.repeat(np.arange(len(counts)), counts)
    if nxt is None:
        nxt = next_vertex_index(block_ptr)
    p = vertices - ref[owner]
    q = p[nxt]
    return p, q, p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1], ref


def polygon_areas(vertices: np.ndarray, block_ptr: np.ndarray) -> np.ndarray:
    """Exact signed areas (positive: counter-clockwise) of all polygons (Green's theorem edge sums)."""
    return np.add.reduceat(_edges(vertices, block_ptr, None, None)[2], block_ptr[:-1]) / 2.0


def block_moments(vertices: np.ndarray, block_ptr: np.ndarray, owner: np.ndarray | None = None,
                  nxt: np.ndarray | None = None) -> BlockMoments:
    """Exact area, centroid and central second moments of all polygons.

    Vertices are shifted per block by their mean before summing, so blocks far
    from the origin keep full precision. ``owner`` (block of each vertex) and
    ``nxt`` (:func:`next_vertex_index`) may be passed to save recomputing them.
    """
    starts = block_ptr[:-1]
    p, q, cross, ref = _edges(vertices, block_ptr, owner, nxt)
    x0, y0, x1, y1 = p[:, 0], p[:, 1], q[:, 0], q[:, 1]

    def edge_sum(terms: np.ndarray) -> np.ndarray:
        return np.add.reduceat(terms, starts)

    area = edge_sum(cross) / 2.0
    mx = edge_sum((x0 + x1) * cross) / 6.0  # ∫x dA
    my = edge_sum((y0 + y1) * cross) / 6.0
    ixx = edge_sum((x0 * x0 + x0 * x1 + x1 * x1) * cross) / 12.0  # ∫x² dA
    iyy = edge_sum((y0 * y0 + y0 * y1 + y1 * y1) * cross) / 12.0
    ixy = edge_sum((x0 * y1 + 2 * x0 * y0 + 2 * x1 * y1 + x1 * y0) * cross) / 24.0
    cx = mx / area
    cy = my / area
    return BlockMoments(
        area=area,
        centroid=np.column_stack([cx, cy]) + ref,
        sxx=ixx - area * cx * cx,
        syy=iyy - area * cy * cy,
        sxy=ixy - area * cx * cy,
    )


def normalize_polygon(vertices: ArrayLike, name: str = "polygon") -> np.ndarray:
    """Validate a block polygon and return it counter-clockwise, unclosed.

    Rejects (with :class:`PolygonError` naming ``name``) fewer than three
    vertices, non-finite coordinates, zero or negative area, repeated
    vertices, and self-intersection. Validity is decided by shapely (GEOS).
    """
    v = np.asarray(vertices, dtype=float)
    if v.ndim != 2 or v.shape[1] != 2:
        raise PolygonError(f"{name}: vertices must be a list of [x, y] pairs")
    if len(v) > 1 and np.array_equal(v[0], v[-1]):
        v = v[:-1]
    if len(v) < 3:
        raise PolygonError(f"{name}: a polygon needs at least 3 vertices, got {len(v)}")
    if not np.all(np.isfinite(v)):
        raise PolygonError(f"{name}: vertex coordinates must be finite numbers")
    poly = shapely.Polygon(v)
    if np.linalg.matrix_rank(v - v.mean(axis=0)) < 2:
        raise PolygonError(f"{name}: polygon has zero area (degenerate)")
    if not shapely.is_valid(poly):
        reason = shapely.is_valid_reason(poly)
        raise PolygonError(f"{name}: polygon is not simple ({reason})")
    if len(np.unique(v, axis=0)) != len(v):
        raise PolygonError(f"{name}: polygon repeats a vertex")
    if poly.area <= 0.0:
        raise PolygonError(f"{name}: polygon has zero area (degenerate)")
    if polygon_areas(v, np.array([0, len(v)]))[0] < 0:
        v = v[::-1].copy()
    return v


def overlapping_pairs(vertices: np.ndarray, block_ptr: np.ndarray, tolerance: float = 1e-6
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Block pairs (k, 2) whose interiors overlap by more than ``tolerance`` × the smaller area, and the areas.

    Blocks that only touch (a shared edge, a vertex on an edge) overlap by zero
    up to rounding. Candidate pairs come from shapely's STRtree (intersecting
    envelopes); the overlap areas, one vectorised intersection, only of the pairs
    whose interiors meet (the DE-9IM pattern ``T********``; a 10,000-brick wall's
    compile took 0.60 s intersecting every touching pair, 0.21-0.25 s so).
    """
    counts = np.diff(block_ptr)
    owner = np.repeat(np.arange(len(counts)), counts)
    polygons = shapely.polygons(shapely.linearrings(vertices, indices=owner))
    i, j = shapely.STRtree(polygons).query(polygons, predicate="intersects")
    keep = i < j
    i, j = i[keep], j[keep]
    inside = shapely.relate_pattern(polygons[i], polygons[j], "T********")
    i, j = i[inside], j[inside]
    area = shapely.area(shapely.intersection(polygons[i], polygons[j]))
    smaller = np.minimum(shapely.area(polygons[i]), shapely.area(polygons[j]))
    over = area > tolerance * smaller
    return np.column_stack([i[over], j[over]]), area[over]
