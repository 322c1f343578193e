"""Polygons and their integrals (the dimension-dependent geometry seam); block cutting and joint sets."""
from .cutting2d import NO_JOINT, BlockCut, CuttingError, cut_blocks
from .jointsets2d import JointSet, circular_opening, joint_traces, polygonal_opening
from .polygon import BlockMoments, PolygonError, block_moments, next_vertex_index, normalize_polygon

__all__ = ["NO_JOINT", "BlockCut", "BlockMoments", "CuttingError", "JointSet", "PolygonError", "block_moments",
           "circular_opening", "cut_blocks", "joint_traces", "next_vertex_index", "normalize_polygon",
           "polygonal_opening"]
from .polyhedron import (PLANARITY_TOLERANCE, PolyhedronError, PolyhedronMesh, PolyhedronMoments, box,
                         normalize_polyhedron, polyhedra_from_meshio, polyhedron_moments, prism)

__all__ += ["PLANARITY_TOLERANCE", "PolyhedronError", "PolyhedronMesh", "PolyhedronMoments", "box",
            "normalize_polyhedron", "polyhedra_from_meshio", "polyhedron_moments", "prism"]
from .cutting3d import PolyhedralCut, convex_hull_polyhedron, cut_polyhedra
from .jointsets3d import JointPlanes, JointSet3D, dip_and_direction, fisher_directions, joint_planes, plane_normal

__all__ += ["JointPlanes", "JointSet3D", "PolyhedralCut", "convex_hull_polyhedron", "cut_polyhedra",
            "dip_and_direction", "fisher_directions", "joint_planes", "plane_normal"]
