"""Polygons and their integrals (the dimension-dependent geometry seam)."""
from .polygon import BlockMoments, PolygonError, block_moments, next_vertex_index, normalize_polygon

__all__ = ["BlockMoments", "PolygonError", "block_moments", "next_vertex_index", "normalize_polygon"]
