"""Block cutting: blocks from a boundary and joint traces (Shi's "DC" step).

The arrangement of all line segments (boundary, joints, opening rings) is
built by GEOS through shapely 2: ``unary_union`` nodes the linework (every
crossing becomes a node, overlaps are dissolved) and ``polygonize`` returns
the faces of the planar graph, ignoring dangling edges. Nothing here
intersects segments by hand; everything else is array work on all blocks at
once (numpy, shapely's vectorised predicates, an STRtree, a k-d tree for node
merging).

Steps (details and choices in ``docs/cutting.md``):

1. free joint ends (touching no other segment) are extended by the edge-node
   distance ``d``, so a joint stopping short of another by less than ``d``
   meets it (Shi's tolerance); overshoots become dangles;
2. node the linework; merge nodes closer than ``d`` and split edges passing
   closer than ``d`` to a node (boundary vertices and nodes never move, so
   the domain keeps its shape); re-node and repeat while anything changed;
3. polygonize; dangling edges drop out; a face with holes (an opening no
   joint reaches) is split by a horizontal cut through each hole;
4. drop faces outside the boundary, inside openings, or holding hole points;
5. orient counter-clockwise, label every edge with the joint type of the
   segment it lies on, remove collinear vertices whose two edges carry the
   same joint type;
6. block materials from material lines (a block whose interior a line
   crosses takes its type; later lines win) and material points.
"""
from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from .polygon import next_vertex_index, polygon_areas, previous_vertex_index

__all__ = ["NO_JOINT", "BlockCut", "CuttingError", "cut_blocks"]

NodeFunction = Callable[[np.ndarray], np.ndarray]

NO_JOINT = -1  # edge label of edges lying on no input segment (hole splits)
_JUNCTION_ULPS = 4.0  # a T-junction vertex this many ulps off its chord is rounding, hence collinear


class CuttingError(ValueError):
    """The cutting input is unusable (the message names the item and the problem)."""


@dataclass(frozen=True)
class BlockCut:
    """Blocks cut from joint traces, as flat arrays.

    ``vertices[block_ptr[b]:block_ptr[b+1]]`` is block ``b``, counter-clockwise,
    not closed. ``edge_joint[i]`` is the joint type (the integer label given
    with the segments) of the edge from vertex ``i`` to the next vertex of the
    same block; ``NO_JOINT`` (-1) for edges on no input segment.
    """

    vertices: np.ndarray
    block_ptr: np.ndarray
    edge_joint: np.ndarray
    block_material: np.ndarray
    polygons: np.ndarray  # shapely Polygons, one per block

    @property
    def n_blocks(self) -> int:
        return len(self.block_ptr) - 1

    def block(self, b: int) -> tuple[np.ndarray, np.ndarray]:
        """Vertices and edge joint types of block ``b``."""
        s, e = self.block_ptr[b], self.block_ptr[b + 1]
        return self.vertices[s:e], self.edge_joint[s:e]

    def areas(self) -> np.ndarray:
        """Exact signed areas (positive: counter-clockwise) of all blocks."""
        return polygon_areas(self.vertices, self.block_ptr)

    def locate(self, points: np.ndarray, what: str = "point") -> np.ndarray:
        """Block index of each point; a point inside a block wins over one on a block's edge.

        Raises :class:`CuttingError` naming the first point that lies in no block.
        """
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        found = np.full(len(pts), -1, dtype=np.int64)
        if len(pts) == 0:
            return found
        geoms = shapely.points(pts)
        tree = shapely.STRtree(self.polygons)
        ip, ib = tree.query(geoms, predicate="intersects")
        inside = shapely.contains_properly(self.polygons[ib], geoms[ip])
        order = np.lexsort((ib, ~inside, ip))  # per point: interior hits first, then lowest block
        ip, ib = ip[order], ib[order]
        first = np.ones(len(ip), dtype=bool)
        first[1:] = ip[1:] != ip[:-1]
        found[ip[first]] = ib[first]
        missing = np.flatnonzero(found < 0)
        if len(missing):
            k = int(missing[0])
            raise CuttingError(f"{what} {k} at ({pts[k, 0]:g}, {pts[k, 1]:g}) lies in no block")
        return found

    def line_points(self, lines: np.ndarray, what: str = "fixed line") -> tuple[np.ndarray, np.ndarray]:
        """Points and blocks standing for lines (x1, y1, x2, y2) drawn across blocks.

        Each line is clipped by every block whose interior it crosses; both ends
        of every clipped piece become a point of that block (a degenerate line,
        x1 = x2 and y1 = y2, is a single point located like :meth:`locate`).
        This is how fixed lines are turned into fixed points: two points per
        block crossed, so each such block is pinned against translation and
        rotation.
        """
        segs = np.asarray(lines, dtype=float).reshape(-1, 4)
        if len(segs) == 0:
            return np.zeros((0, 2)), np.zeros(0, dtype=np.int64)
        degenerate = np.all(segs[:, :2] == segs[:, 2:], axis=1)
        pts_single = segs[degenerate, :2]
        blocks_single = self.locate(pts_single, what) if len(pts_single) else np.zeros(0, dtype=np.int64)
        if np.all(degenerate):
            return pts_single, blocks_single
        geoms = shapely.linestrings(segs[~degenerate].reshape(-1, 2, 2))
        tree = shapely.STRtree(self.polygons)
        il, ib = tree.query(geoms, predicate="intersects")
        keep = ~shapely.touches(geoms[il], self.polygons[ib])
        il, ib = il[keep], ib[keep]
        unused = np.setdiff1d(np.arange(len(geoms)), il)
        if len(unused):
            k = int(np.flatnonzero(~degenerate)[unused[0]])
            raise CuttingError(f"{what} {k} crosses no block")
        pieces = shapely.intersection(geoms[il], self.polygons[ib])
        parts, part_of = shapely.get_parts(pieces, return_index=True)
        coords, cidx = shapely.get_coordinates(parts, return_index=True)
        starts = np.flatnonzero(np.r_[True, cidx[1:] != cidx[:-1]])
        ends = np.r_[starts[1:], len(cidx)] - 1
        ends_pts = np.concatenate([coords[starts], coords[ends]])
        ends_blocks = np.concatenate([ib[part_of[cidx[starts]]], ib[part_of[cidx[ends]]]])
        return (np.concatenate([pts_single, ends_pts]),
                np.concatenate([blocks_single, ends_blocks]).astype(np.int64))


def _as_segments(segments: object, what: str) -> np.ndarray:
    segs = np.asarray(segments, dtype=float)
    if segs.size == 0:
        return np.zeros((0, 4))
    if segs.ndim != 2 or segs.shape[1] != 4:
        raise CuttingError(f"{what}: expected rows of (x1, y1, x2, y2), got shape {segs.shape}")
    if not np.all(np.isfinite(segs)):
        raise CuttingError(f"{what}: coordinates must be finite numbers")
    return segs


def _as_polygon(poly: object, what: str) -> shapely.Polygon:
    if isinstance(poly, shapely.Polygon):
        geom = poly
    elif isinstance(poly, shapely.Geometry):
        raise CuttingError(f"{what}: expected one polygon, got a {poly.geom_type}")
    else:
        v = np.asarray(poly, dtype=float)
        if v.ndim != 2 or v.shape[1] != 2 or len(v) < 3:
            raise CuttingError(f"{what}: a polygon is a list of at least three [x, y] vertices")
        geom = shapely.Polygon(v)
    if not geom.is_valid or geom.area <= 0:
        raise CuttingError(f"{what}: not a simple polygon of positive area ({shapely.is_valid_reason(geom)})")
    return geom


def _ring_segments(poly: shapely.Polygon) -> np.ndarray:
    rings = [poly.exterior, *poly.interiors]
    out = []
    for ring in rings:
        c = np.asarray(ring.coords)
        out.append(np.hstack([c[:-1], c[1:]]))
    return np.vstack(out)


def _rows_in(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Which rows of ``a`` (float (n, 2)) occur exactly in ``b``."""
    if len(b) == 0 or len(a) == 0:
        return np.zeros(len(a), dtype=bool)
    dt = np.dtype((np.void, a.dtype.itemsize * 2))
    av = np.ascontiguousarray(a).view(dt).ravel()
    bv = np.ascontiguousarray(b).view(dt).ravel()
    return np.isin(av, bv)


def _extend_free_ends(segs: np.ndarray, others: np.ndarray, distance: float) -> np.ndarray:
    """Extend ends of ``segs`` touching no other segment (of ``segs`` or ``others``) by ``distance``."""
    if distance <= 0 or len(segs) == 0:
        return segs
    lines = shapely.linestrings(np.vstack([segs, others]).reshape(-1, 2, 2))
    ends = shapely.points(segs.reshape(-1, 2))  # 2k = start, 2k+1 = end of segment k
    ip, il = shapely.STRtree(lines).query(ends, predicate="intersects")
    other = il != ip // 2
    touching = np.zeros(len(ends), dtype=bool)
    touching[ip[other]] = True
    d = segs[:, 2:] - segs[:, :2]
    u = d / np.linalg.norm(d, axis=1)[:, None]
    out = segs.copy()
    out[:, :2] -= np.where(touching[0::2, None], 0.0, distance * u)
    out[:, 2:] += np.where(touching[1::2, None], 0.0, distance * u)
    return out


def _explode_edges(geom: shapely.Geometry) -> np.ndarray:
    """All 2-point edges (m, 2, 2) of a (multi)line geometry."""
    parts = shapely.get_parts(geom)
    parts = parts[shapely.get_type_id(parts) == 1]
    coords, idx = shapely.get_coordinates(parts, return_index=True)
    same = idx[1:] == idx[:-1]
    edges = np.stack([coords[:-1][same], coords[1:][same]], axis=1)
    return edges[np.any(edges[:, 0] != edges[:, 1], axis=1)]


def _merge_close_nodes(edges: np.ndarray, distance: float, rank_of: NodeFunction,
                       ring_edge_of: NodeFunction) -> tuple[np.ndarray, bool]:
    """Merge every cluster of nodes closer than ``distance`` (chained) into its highest-ranked node.

    Ranks: 3 boundary vertex, 2 node on the boundary, 1 input end point, 0 other.
    A cluster whose best rank is 0 or 1 collapses to one node; in a cluster
    touching the boundary (best rank >= 2) the best-ranked nodes lying on the
    same boundary edge (``ring_edge_of``) merge into one, and every
    lower-ranked node moves to the nearest best-ranked node, so the boundary
    never moves.
    """
    nodes, inverse = np.unique(edges.reshape(-1, 2), axis=0, return_inverse=True)
    inverse = inverse.ravel()
    pairs = cKDTree(nodes).query_pairs(distance, output_type="ndarray")
    if len(pairs) == 0:
        return edges, False
    n = len(nodes)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    rank = rank_of(nodes)
    best = np.zeros(label.max() + 1, dtype=np.int64)
    np.maximum.at(best, label, rank)
    order = np.lexsort((np.arange(n), -rank, label))
    first = np.ones(n, dtype=bool)
    first[1:] = label[order][1:] != label[order][:-1]
    rep = np.empty(label.max() + 1, dtype=np.int64)
    rep[label[order][first]] = order[first]
    target = rep[label]
    on_boundary = best[label] >= 2
    top = rank == best[label]
    keep_top = np.flatnonzero(on_boundary & top)
    if len(keep_top):
        group = np.column_stack([label[keep_top], ring_edge_of(nodes[keep_top])])
        _, gidx = np.unique(group, axis=0, return_inverse=True)
        gidx = gidx.ravel()
        grep = np.full(gidx.max() + 1, -1, dtype=np.int64)
        grep[gidx[::-1]] = keep_top[::-1]  # first node of each (cluster, boundary edge) group
        target[keep_top] = grep[gidx]
    movers = np.flatnonzero(on_boundary & ~top)
    if len(movers):
        tops = np.flatnonzero(on_boundary & top)
        k = min(16, len(tops))
        _, near = cKDTree(nodes[tops]).query(nodes[movers], k=k)
        near = tops[np.asarray(near).reshape(len(movers), k)]
        same = label[near] == label[movers][:, None]
        pick = np.where(same.any(axis=1), near[np.arange(len(movers)), same.argmax(axis=1)], rep[label[movers]])
        target[movers] = target[pick]
    if np.all(target == np.arange(n)):
        return edges, False
    moved = nodes[target][inverse].reshape(-1, 2, 2)
    moved = moved[np.any(moved[:, 0] != moved[:, 1], axis=1)]
    return moved, True


def _snap_nodes_to_edges(edges: np.ndarray, distance: float, fixed_edge: NodeFunction,
                         rank_of: NodeFunction) -> tuple[np.ndarray, bool]:
    """Split every edge passing closer than ``distance`` to a node not its own at that node.

    A node near a boundary edge (``fixed_edge`` true) moves onto the edge (its
    projection) so the domain keeps its shape, unless the node is itself on
    the boundary (rank >= 2: it stays, the boundary edge is left alone); near
    any other edge the edge is split at the node itself. Each node snaps to
    its nearest such edge.
    """
    nodes, inverse = np.unique(edges.reshape(-1, 2), axis=0, return_inverse=True)
    ends = inverse.reshape(-1, 2)
    lines = shapely.linestrings(edges)
    inode, iedge = shapely.STRtree(lines).query(shapely.points(nodes), predicate="dwithin", distance=distance)
    own = (ends[iedge, 0] == inode) | (ends[iedge, 1] == inode)
    inode, iedge = inode[~own], iedge[~own]
    if len(inode) == 0:
        return edges, False
    boundary_node = rank_of(nodes)[inode] >= 2
    movable = ~(boundary_node & fixed_edge(edges[iedge]))
    inode, iedge = inode[movable], iedge[movable]
    if len(inode) == 0:
        return edges, False
    a, b = edges[iedge, 0], edges[iedge, 1]
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", nodes[inode] - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
    foot = a + t[:, None] * ab
    dist = np.linalg.norm(nodes[inode] - foot, axis=1)
    order = np.lexsort((dist, inode))
    first = np.ones(len(order), dtype=bool)
    first[1:] = inode[order][1:] != inode[order][:-1]
    pick = order[first]
    inode, iedge, t, foot = inode[pick], iedge[pick], t[pick], foot[pick]
    interior = (t > 0.0) & (t < 1.0)
    inode, iedge, t, foot = inode[interior], iedge[interior], t[interior], foot[interior]
    if len(inode) == 0:
        return edges, False
    on_fixed = fixed_edge(edges[iedge])
    moved = nodes.copy()
    moved[inode[on_fixed]] = foot[on_fixed]  # a node near the boundary moves onto it
    split_at = moved[inode]
    # chains: every edge from its start through its split points (sorted along it) to its end
    m = len(edges)
    all_edge = np.concatenate([np.arange(m), iedge, np.arange(m)])
    all_t = np.concatenate([np.zeros(m), t, np.ones(m)])
    all_pt = np.concatenate([moved[ends[:, 0]], split_at, moved[ends[:, 1]]])
    order = np.lexsort((all_t, all_edge))
    all_edge, all_pt = all_edge[order], all_pt[order]
    same = all_edge[1:] == all_edge[:-1]
    out = np.stack([all_pt[:-1][same], all_pt[1:][same]], axis=1)
    return out[np.any(out[:, 0] != out[:, 1], axis=1)], True


def _warn_tight_boundary(ring_segs: np.ndarray, distance: float) -> None:
    """Warn when a boundary/opening vertex lies within ``distance`` of a boundary edge not its own."""
    if distance <= 0 or len(ring_segs) == 0:
        return
    verts = np.unique(ring_segs[:, :2], axis=0)
    lines = shapely.linestrings(ring_segs.reshape(-1, 2, 2))
    iv, ie = shapely.STRtree(lines).query(shapely.points(verts), predicate="dwithin", distance=distance)
    own = np.all(ring_segs[ie, :2] == verts[iv], axis=1) | np.all(ring_segs[ie, 2:] == verts[iv], axis=1)
    close = iv[~own]
    if len(close):
        x, y = verts[close[0]]
        warnings.warn(f"edge_node_distance {distance:g} exceeds the gap between boundary features near "
                      f"({x:g}, {y:g}); nodes there may merge and move the boundary", stacklevel=3)


def _split_holes(poly: shapely.Polygon) -> list[shapely.Polygon]:
    """Split a polygon with holes by horizontal cuts through its holes until none is left."""
    todo, done = [poly], []
    while todo:
        p = todo.pop()
        if not p.interiors:
            done.append(p)
            continue
        y = p.interiors[0].centroid.y
        x0, _, x1, _ = p.bounds
        cut = shapely.LineString([(x0 - 1.0, y), (x1 + 1.0, y)])
        pieces = shapely.get_parts(shapely.polygonize(shapely.get_parts(shapely.unary_union([p.boundary, cut]))))
        inside = shapely.within(shapely.point_on_surface(pieces), p)
        todo.extend(pieces[inside])
    return done


def cut_blocks(
    joints: object,
    joint_types: Sequence[int] | np.ndarray | None = None,
    *,
    edge_node_distance: float,
    boundary: object | None = None,
    boundary_type: int = 0,
    openings: Sequence[object] = (),
    opening_type: int | None = None,
    hole_points: object = (),
    material_lines: object = (),
    material_line_types: Sequence[int] | np.ndarray = (),
    material_points: object = (),
    material_point_types: Sequence[int] = (),
    default_material: int = 0,
    collinear_tolerance: float = 1e-10,
) -> BlockCut:
    """Cut blocks from joint segments ``(x1, y1, x2, y2)`` (see the module docstring).

    ``joint_types`` labels each segment (default 0). ``boundary`` (polygon
    vertices or a shapely Polygon) is optional: without it, every closed loop
    of the segments is a block (Shi's legacy files draw the boundary as
    joints). ``openings`` are polygons removed from the domain (tunnels); their
    edges carry ``opening_type`` (default ``boundary_type``). Blocks holding a
    ``hole_points`` point are removed. ``collinear_tolerance`` is the largest
    |sin| of the turn at a vertex that is still removed as collinear.
    """
    segs = _as_segments(joints, "joints")
    types = np.zeros(len(segs), dtype=np.int64) if joint_types is None else np.asarray(joint_types, dtype=np.int64)
    if types.shape != (len(segs),):
        raise CuttingError(f"joint_types: expected {len(segs)} labels, got {types.shape}")
    if not edge_node_distance >= 0:
        raise CuttingError(f"edge_node_distance must be >= 0, got {edge_node_distance}")
    lengths = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1])
    long_enough = lengths > edge_node_distance  # shorter joints would collapse into one node
    segs, types = segs[long_enough & (lengths > 0)], types[long_enough & (lengths > 0)]

    ring_segs, ring_types = [np.zeros((0, 4))], [np.zeros(0, dtype=np.int64)]
    domain = None
    if boundary is not None:
        domain = _as_polygon(boundary, "boundary")
        ring_segs.append(_ring_segments(domain))
        ring_types.append(np.full(len(ring_segs[-1]), boundary_type))
    opening_polys = [_as_polygon(o, f"opening {i}") for i, o in enumerate(openings)]
    for o in opening_polys:
        ring_segs.append(_ring_segments(o))
        ring_types.append(np.full(len(ring_segs[-1]), boundary_type if opening_type is None else opening_type))
    ring_all = np.vstack(ring_segs)
    ring_vertices = ring_all[:, :2]
    all_segs = np.vstack([ring_all, segs])
    all_types = np.concatenate([*ring_types, types])
    if len(all_segs) < 3:
        raise CuttingError("joints: at least three segments are needed to close a block")
    scale = float(np.ptp(all_segs.reshape(-1, 2), axis=0).max())
    d = float(edge_node_distance)

    ring_lines = shapely.multilinestrings(ring_all.reshape(-1, 2, 2)) if len(ring_all) else None
    on_ring_tol = 1e-12 * scale
    originals = all_segs.reshape(-1, 2)

    def rank_of(nodes: np.ndarray) -> np.ndarray:
        rank = _rows_in(nodes, originals).astype(np.int64)
        if ring_lines is not None:
            rank = np.where(shapely.dwithin(ring_lines, shapely.points(nodes), on_ring_tol), 2, rank)
            rank = np.where(_rows_in(nodes, ring_vertices), 3, rank)
        return rank

    _warn_tight_boundary(ring_all, d)
    extended = np.vstack([ring_all, _extend_free_ends(segs, ring_all, d)])
    edges = _explode_edges(shapely.unary_union(shapely.linestrings(extended.reshape(-1, 2, 2))))
    ring_tree = shapely.STRtree(shapely.linestrings(ring_all.reshape(-1, 2, 2))) if len(ring_all) else None

    def ring_edge_of(nodes: np.ndarray) -> np.ndarray:
        """Nearest boundary edge of each node; a boundary vertex is its own group."""
        out = np.full(len(nodes), -1, dtype=np.int64)
        if ring_tree is not None:
            inode, iedge = ring_tree.query_nearest(shapely.points(nodes), all_matches=False)
            out[inode] = iedge
            vertex = _rows_in(nodes, ring_vertices)
            out[vertex] = -2 - np.flatnonzero(vertex)
        return out

    def on_ring(e: np.ndarray) -> np.ndarray:
        if ring_lines is None:
            return np.zeros(len(e), dtype=bool)
        return shapely.dwithin(ring_lines, shapely.points(0.5 * (e[:, 0] + e[:, 1])), on_ring_tol)

    for _ in range(6):
        if d <= 0:
            break
        edges, merged = _merge_close_nodes(edges, d, rank_of, ring_edge_of)
        edges, snapped = _snap_nodes_to_edges(edges, d, on_ring, rank_of)
        if not (merged or snapped):
            break
        edges = _explode_edges(shapely.unary_union(shapely.linestrings(edges)))

    faces = shapely.get_parts(shapely.polygonize(shapely.linestrings(edges)))
    faces = faces[shapely.area(faces) > 0]
    if len(faces) == 0:
        raise CuttingError("joints: the segments close no block")
    keep = np.ones(len(faces), dtype=bool)
    probe = shapely.point_on_surface(faces)
    if domain is not None:
        keep &= shapely.within(probe, domain)
    for o in opening_polys:
        keep &= ~shapely.within(probe, o)
    holes = np.asarray(hole_points, dtype=float).reshape(-1, 2)
    if len(holes):
        hit = shapely.STRtree(faces).query(shapely.points(holes), predicate="within")[1]
        keep[hit] = False
    faces = faces[keep]
    holed = shapely.get_num_interior_rings(faces) > 0
    if np.any(holed):
        warnings.warn(f"{int(holed.sum())} block(s) enclosed an opening that no joint reaches; split by "
                      "horizontal cuts (edges with no joint type)", stacklevel=2)
        split = [q for p in faces[holed] for q in _split_holes(p)]
        faces = np.concatenate([faces[~holed], np.array(split, dtype=object)])
    if len(faces) == 0:
        raise CuttingError("joints: no block is left after removing openings and hole points")

    vertices, block_ptr = _ccw_rings(faces)
    edge_joint = _edge_labels(vertices, block_ptr, all_segs, all_types, tol=max(d, 1e-9 * scale) * 1.5)
    vertices, block_ptr, edge_joint = _remove_collinear(vertices, block_ptr, edge_joint, collinear_tolerance,
                                                           _JUNCTION_ULPS * np.spacing(np.abs(all_segs).max()))
    polygons = _polygons_from(vertices, block_ptr)
    material = _materials(polygons, default_material, material_lines, material_line_types,
                          material_points, material_point_types)
    return BlockCut(vertices, block_ptr, edge_joint, material, polygons)


def _polygons_from(vertices: np.ndarray, block_ptr: np.ndarray) -> np.ndarray:
    counts = np.diff(block_ptr)
    owner = np.repeat(np.arange(len(counts)), counts)
    rings = shapely.linearrings(vertices, indices=owner)
    return shapely.polygons(rings)


def _ccw_rings(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exterior rings of all faces as flat counter-clockwise vertex arrays (not closed)."""
    coords, idx = shapely.get_coordinates(shapely.get_exterior_ring(faces), return_index=True)
    last = np.r_[idx[1:] != idx[:-1], True]
    coords, idx = coords[~last], idx[~last]
    counts = np.bincount(idx, minlength=len(faces))
    block_ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    start = block_ptr[:-1][idx]
    k = np.arange(len(idx)) - start
    flip = (polygon_areas(coords, block_ptr) < 0)[idx]
    src = np.where(flip, start + counts[idx] - 1 - k, np.arange(len(idx)))
    return coords[src], block_ptr


def _edge_labels(vertices: np.ndarray, block_ptr: np.ndarray, segs: np.ndarray, types: np.ndarray,
                 tol: float) -> np.ndarray:
    """Joint type of the input segment each block edge lies on (later segments win ties)."""
    mid = 0.5 * (vertices + vertices[next_vertex_index(block_ptr)])
    tree = shapely.STRtree(shapely.linestrings(segs.reshape(-1, 2, 2)))
    ie, iseg = tree.query_nearest(shapely.points(mid), max_distance=tol, all_matches=True)
    best = np.full(len(mid), -1, dtype=np.int64)
    np.maximum.at(best, ie, iseg)
    return np.where(best >= 0, types[np.maximum(best, 0)], NO_JOINT)


def _remove_collinear(vertices: np.ndarray, block_ptr: np.ndarray, edge_joint: np.ndarray,
                      tol: float, junction_tol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Drop vertices where a block's boundary runs straight on and keeps its joint type.

    A vertex where only its two edges meet (node degree 2) goes when the |sin|
    of the turn is at most ``tol``: the block on the other side sees the same
    two edges and drops it too, so the tiling stays exact. A vertex where a
    third edge ends (a T-junction) stays in the neighbours, so it is dropped
    only when it lies within ``junction_tol`` (a length: rounding level) of
    the chord of its two neighbours.
    """
    nxt = next_vertex_index(block_ptr)
    prev = previous_vertex_index(block_ptr)
    _, node = np.unique(vertices, axis=0, return_inverse=True)
    node = node.ravel()
    pairs = np.unique(np.sort(np.column_stack([node, node[nxt]]), axis=1), axis=0)
    degree = np.bincount(pairs.ravel(), minlength=node.max() + 1)[node]
    a = vertices - vertices[prev]
    b = vertices[nxt] - vertices
    cross = np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    dot = np.einsum("ij,ij->i", a, b)
    la, lb = np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1)
    chord = np.linalg.norm(a + b, axis=1)
    straight = np.where(degree <= 2, cross <= tol * la * lb, cross <= junction_tol * chord) & (dot > 0)
    drop = straight & (edge_joint[prev] == edge_joint)
    counts = np.diff(block_ptr)
    owner = np.repeat(np.arange(len(counts)), counts)
    left = counts - np.bincount(owner, weights=drop, minlength=len(counts)).astype(np.int64)
    collapsed = left < 3  # a sliver whose straightened neighbour now covers it
    if np.any(collapsed):
        warnings.warn(f"{int(collapsed.sum())} sliver block(s) thinner than rounding merged into their "
                      "neighbours", stacklevel=3)
    keep = ~drop & ~collapsed[owner]
    left = left[~collapsed]
    new_ptr = np.concatenate([[0], np.cumsum(left)]).astype(np.int64)
    return vertices[keep], new_ptr, edge_joint[keep]


def _materials(polygons: np.ndarray, default: int, lines: object, line_types: Sequence[int] | np.ndarray,
               points: object, point_types: Sequence[int]) -> np.ndarray:
    """Block material labels: default, then material lines (later win), then material points."""
    material = np.full(len(polygons), default, dtype=np.int64)
    tree = shapely.STRtree(polygons)
    segs = _as_segments(lines, "material lines")
    if len(segs):
        lt = np.asarray(line_types, dtype=np.int64)
        if lt.shape != (len(segs),):
            raise CuttingError(f"material_line_types: expected {len(segs)} labels, got {lt.shape}")
        geoms = shapely.linestrings(segs.reshape(-1, 2, 2))
        il, ib = tree.query(geoms, predicate="intersects")
        inner = ~shapely.touches(geoms[il], polygons[ib])
        best = np.full(len(polygons), -1, dtype=np.int64)
        np.maximum.at(best, ib[inner], il[inner])
        material = np.where(best >= 0, lt[np.maximum(best, 0)], material)
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(pts):
        pt = np.asarray(point_types, dtype=np.int64)
        if pt.shape != (len(pts),):
            raise CuttingError(f"material_point_types: expected {len(pts)} labels, got {pt.shape}")
        ip, ib = tree.query(shapely.points(pts), predicate="within")
        best = np.full(len(polygons), -1, dtype=np.int64)
        np.maximum.at(best, ib, ip)
        material = np.where(best >= 0, pt[np.maximum(best, 0)], material)
    return material
