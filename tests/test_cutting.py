"""Block cutting: exact tiling identities on random joint configurations and hand-checked cases."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from srdda.geometry.cutting2d import NO_JOINT, CuttingError, cut_blocks
from srdda.geometry.jointsets2d import JointSet, circular_opening, joint_traces

SQUARE = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]


def _check_tiling(cut, expected_area: float, domain=None) -> None:
    """The three acceptance identities of issue 5 on one cut."""
    polys = cut.polygons
    areas = cut.areas()
    # every block simple and counter-clockwise
    assert np.all(shapely.is_valid(polys))
    assert np.all(areas > 0)
    for b in range(cut.n_blocks):
        v, _ = cut.block(b)
        assert len(np.unique(v, axis=0)) == len(v)
    # areas sum to the domain area minus openings: 1e-12 relative (noded crossing
    # points are rounded to doubles, an error of a few ulps of the coordinates)
    assert abs(areas.sum() - expected_area) <= 1e-12 * expected_area
    # no overlap: pairwise intersection area below 1e-12 of the smaller block. GEOS'
    # floating-point overlay can fail on nearly collinear edges (it once returned a whole
    # block as the intersection of two blocks that only share an edge, and a union area
    # contradicting its own point-in-polygon test); such pairs are re-measured with its
    # snap-rounding overlay on a grid of 1e-12 x the domain size.
    i, j = shapely.STRtree(polys).query(polys, predicate="intersects")
    pair = i < j
    i, j = i[pair], j[pair]
    if len(i):
        inter = shapely.area(shapely.intersection(polys[i], polys[j]))
        suspect = inter > 1e-12 * np.minimum(areas[i], areas[j])
        if np.any(suspect):
            grid = 1e-12 * float(np.ptp(cut.vertices, axis=0).max())
            inter[suspect] = shapely.area(shapely.intersection(polys[i[suspect]], polys[j[suspect]],
                                                               grid_size=grid))
        assert np.all(inter <= 1e-12 * np.minimum(areas[i], areas[j]))
    if domain is not None:
        # independent of overlays (GEOS predicates are exact): random points of the domain
        # lie strictly inside exactly one block, or on block edges
        rng = np.random.default_rng(0)
        x0, y0, x1, y1 = domain.bounds
        pts = shapely.points(rng.uniform((x0, y0), (x1, y1), size=(2000, 2)))
        pts = pts[shapely.contains_properly(domain, pts)]
        ip, _ = shapely.STRtree(polys).query(pts, predicate="within")  # a point "within" is strictly inside
        hits = np.bincount(ip, minlength=len(pts))
        assert np.all(hits <= 1)
        on_edge = shapely.STRtree(shapely.boundary(polys)).query(pts, predicate="intersects")[0]
        assert np.all((hits == 1) | np.isin(np.arange(len(pts)), on_edge))


coord = st.floats(-0.3, 1.3, allow_nan=False, allow_infinity=False)
segment = st.tuples(coord, coord, coord, coord).filter(lambda s: (s[0], s[1]) != (s[2], s[3]))


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    joints=st.lists(segment, min_size=0, max_size=14),
    width=st.floats(0.5, 50.0),
    height=st.floats(0.5, 50.0),
    opening=st.sampled_from(["none", "circle", "square"]),
    d_rel=st.sampled_from([1e-6, 1e-3]),  # DDA inputs always give an edge-node distance > 0
)
def test_random_joints_tile_the_domain(joints, width, height, opening, d_rel):
    scale = np.array([width, height, width, height])
    segs = np.array(joints, dtype=float).reshape(-1, 4) * scale
    boundary = np.array(SQUARE) * [width, height]
    openings = []
    if opening == "circle":
        openings = [circular_opening((0.5 * width, 0.5 * height), 0.2 * min(width, height), 24)]
    elif opening == "square":
        openings = [np.array([(0.3, 0.3), (0.6, 0.35), (0.55, 0.7), (0.35, 0.6)]) * [width, height]]
    area = width * height - sum(shapely.Polygon(o).area for o in openings)
    domain = shapely.Polygon(boundary, holes=openings)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the split-opening warning is tested below
        cut = cut_blocks(segs, np.arange(len(segs)) + 1, edge_node_distance=d_rel * max(width, height),
                         boundary=boundary, openings=openings)
    _check_tiling(cut, area, domain)


def test_cross_cuts_four_quarters_with_joint_types():
    segs = [(0.5, -0.2, 0.5, 1.2), (-0.2, 0.5, 1.2, 0.5)]
    cut = cut_blocks(segs, [2, 3], edge_node_distance=1e-3, boundary=SQUARE, boundary_type=7)
    assert cut.n_blocks == 4
    np.testing.assert_allclose(np.sort(cut.areas()), 0.25, rtol=1e-14)
    for b in range(4):
        v, j = cut.block(b)
        assert len(v) == 4
        mid = 0.5 * (v + np.roll(v, -1, axis=0))
        on_x = np.isclose(mid[:, 0], 0.5)
        on_y = np.isclose(mid[:, 1], 0.5)
        np.testing.assert_array_equal(j, np.where(on_x, 2, np.where(on_y, 3, 7)))


def test_dangling_joint_is_dropped_and_collinear_vertex_removed():
    cut = cut_blocks([(0.5, 0.0, 0.5, 0.6)], edge_node_distance=1e-3, boundary=SQUARE)
    assert cut.n_blocks == 1
    v, _ = cut.block(0)
    assert len(v) == 4  # the dangle's foot on the bottom edge is not a vertex


def test_collinear_vertex_kept_where_joint_type_changes():
    # the bottom edge is two joints of different types meeting at (0.5, 0)
    segs = [(0, 0, 0.5, 0), (0.5, 0, 1, 0), (1, 0, 1, 1), (1, 1, 0, 1), (0, 1, 0, 0)]
    cut = cut_blocks(segs, [1, 2, 1, 1, 1], edge_node_distance=0.0)
    v, j = cut.block(0)
    assert len(v) == 5
    assert sorted(j.tolist()) == [1, 1, 1, 1, 2]


def test_undershooting_joint_closer_than_edge_node_distance_cuts():
    segs = [(0.5, 0.0005, 0.5, 0.9995)]  # stops 0.0005 short of both edges
    assert cut_blocks(segs, edge_node_distance=1e-3, boundary=SQUARE).n_blocks == 2
    assert cut_blocks(segs, edge_node_distance=1e-4, boundary=SQUARE).n_blocks == 1


def test_nodes_closer_than_edge_node_distance_merge():
    # two joints meet the bottom edge 0.0004 apart: their feet merge into one node,
    # so the middle block is a triangle; with a smaller distance it keeps a 0.0004 m edge
    segs = [(0.5, 0.0, 0.2, 1.0), (0.5004, 0.0, 0.8, 1.0)]
    merged = cut_blocks(segs, edge_node_distance=1e-3, boundary=SQUARE)
    apart = cut_blocks(segs, edge_node_distance=1e-5, boundary=SQUARE)
    mid_merged = merged.locate([(0.5, 0.5)])[0]
    mid_apart = apart.locate([(0.5, 0.5)])[0]
    assert len(merged.block(mid_merged)[0]) == 3
    assert len(apart.block(mid_apart)[0]) == 4
    assert abs(merged.areas().sum() - 1.0) < 1e-14  # the boundary node stays: the domain is unchanged


def test_node_near_an_edge_splits_it():
    # a joint ends 1e-4 below the top edge of a block (within d): the block is cut
    segs = [(0.5, 0.0, 0.5, 0.5), (0.0, 0.5, 1.0, 0.5), (0.25, 0.5, 0.25, 0.9999)]
    cut = cut_blocks(segs, edge_node_distance=1e-3, boundary=SQUARE)
    assert cut.n_blocks == 4
    assert abs(cut.areas().sum() - 1.0) < 1e-14


def test_hole_points_and_openings_remove_blocks():
    segs = [(0.5, 0, 0.5, 1)]
    cut = cut_blocks(segs, edge_node_distance=1e-3, boundary=SQUARE, hole_points=[(0.25, 0.5)])
    assert cut.n_blocks == 1
    assert abs(cut.areas()[0] - 0.5) < 1e-14


def test_opening_no_joint_reaches_is_split_with_warning():
    hole = circular_opening((0.5, 0.5), 0.2, 16)
    with pytest.warns(UserWarning, match="enclosed an opening"):
        cut = cut_blocks([], edge_node_distance=0.0, boundary=SQUARE, openings=[hole])
    assert cut.n_blocks == 2
    assert np.any(cut.edge_joint == NO_JOINT)
    _check_tiling(cut, 1.0 - shapely.Polygon(hole).area)


def test_materials_by_lines_and_points():
    segs = [(0.5, 0, 0.5, 1), (0, 0.5, 1, 0.5)]
    cut = cut_blocks(segs, edge_node_distance=1e-3, boundary=SQUARE, default_material=1,
                     material_lines=[(0.1, 0.1, 0.9, 0.2)], material_line_types=[2],
                     material_points=[(0.2, 0.9)], material_point_types=[3])
    mats = cut.block_material[cut.locate([(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)])]
    np.testing.assert_array_equal(mats, [2, 2, 3, 1])


def test_locate_and_fixed_lines():
    segs = [(0.5, 0, 0.5, 1)]
    cut = cut_blocks(segs, edge_node_distance=1e-3, boundary=SQUARE)
    left, right = cut.locate([(0.25, 0.5), (0.75, 0.5)])
    assert left != right
    with pytest.raises(CuttingError, match="lies in no block"):
        cut.locate([(2.0, 2.0)], "load point")
    pts, blocks = cut.line_points([(0.1, 0.5, 0.9, 0.5)])
    assert sorted(blocks.tolist()) == sorted([left, left, right, right])
    np.testing.assert_allclose(np.sort(pts[:, 0]), [0.1, 0.5, 0.5, 0.9])
    pts, blocks = cut.line_points([(0.2, 0.2, 0.2, 0.2)])
    assert blocks.tolist() == [left]


def test_bad_input_names_the_field():
    with pytest.raises(CuttingError, match="joints"):
        cut_blocks([(0, 0, 1)], edge_node_distance=0.0)
    with pytest.raises(CuttingError, match="joint_types"):
        cut_blocks([(0, 0, 1, 1)] * 3, [1], edge_node_distance=0.0)
    with pytest.raises(CuttingError, match="boundary"):
        cut_blocks([], edge_node_distance=0.0, boundary=[(0, 0), (1, 1), (1, 0), (0, 1)])
    with pytest.raises(CuttingError, match="close no block"):
        cut_blocks([(0, 0, 1, 0), (0, 1, 1, 1), (0, 2, 1, 2)], edge_node_distance=0.0)


def test_joint_sets_persistent_spacing_and_clipping():
    domain = [(0, 0), (10, 0), (10, 6), (0, 6)]
    segs, types = joint_traces(domain, [JointSet(dip=0.0, spacing=1.0, origin=(0, 0.5), joint_type=4)])
    assert np.all(types == 4)
    np.testing.assert_allclose(np.sort(segs[:, 1]), np.arange(6) + 0.5, atol=1e-12)
    np.testing.assert_allclose(np.abs(segs[:, 2] - segs[:, 0]), 10.0, atol=1e-12)
    cut = cut_blocks(segs, types, edge_node_distance=1e-3, boundary=domain)
    assert cut.n_blocks == 7


def test_joint_sets_trace_length_bridge_and_seed():
    domain = [(0, 0), (100, 0), (100, 100), (0, 100)]
    js = JointSet(dip=30.0, spacing=5.0, trace_length=8.0, bridge=2.0, dip_sd=2.0, spacing_sd=0.5)
    a, _ = joint_traces(domain, [js], seed=3)
    b, _ = joint_traces(domain, [js], seed=3)
    c, _ = joint_traces(domain, [js], seed=4)
    np.testing.assert_array_equal(a, b)
    assert a.shape != c.shape or not np.array_equal(a, c)
    lengths = np.hypot(a[:, 2] - a[:, 0], a[:, 3] - a[:, 1])
    assert lengths.max() <= 8.0 + 1e-9  # clipping only shortens
    # interior traces keep their full length; ~80 % of each line is joint (8 of every 10 m)
    assert np.median(lengths) == pytest.approx(8.0, rel=1e-9)
    inside = shapely.within(shapely.linestrings(a.reshape(-1, 2, 2)), shapely.Polygon(domain))
    assert np.all(shapely.covered_by(shapely.linestrings(a.reshape(-1, 2, 2)), shapely.Polygon(domain)))
    assert inside.sum() > 0


def test_add_cut_blocks_maps_materials_joints_and_fixed():
    import srdda
    from srdda.model import JointMaterial

    cut = cut_blocks([(0.5, 0, 0.5, 1)], [1], edge_node_distance=1e-3, boundary=SQUARE, boundary_type=0,
                     material_points=[(0.75, 0.5)], material_point_types=[2])
    model = srdda.Model()
    model.add_material("a", srdda.Material(1000.0, 1e9, 0.2))
    model.add_material("b", srdda.Material(2000.0, 1e9, 0.2))
    model.add_joint_material("j", JointMaterial(friction_angle=20.0))
    left = int(cut.locate([(0.25, 0.5)])[0])
    fixed = np.arange(cut.n_blocks) == left
    srdda.add_cut_blocks(model, cut, materials={0: "a", 2: "b"}, joints={1: "j"}, fixed=fixed)
    arrays = model.arrays()
    assert arrays.block_fixed.tolist() == fixed.tolist()
    assert sorted(arrays.block_material.tolist()) == [0, 1]
    # exactly one edge of each block lies on the joint x = 0.5 (joint index 1); the others: by materials
    assert np.bincount(arrays.vertex_block[arrays.edge_joint == 1]).tolist() == [1, 1]
    assert np.sum(arrays.edge_joint == -1) == 6
    with pytest.raises(srdda.ModelError, match="material label"):
        srdda.add_cut_blocks(srdda.Model(), cut, materials={0: "a"})


def test_tolerance_larger_than_a_boundary_gap_is_warned():
    opening = [(0.1, 0.005), (0.9, 0.005), (0.9, 0.9), (0.1, 0.9)]  # 5 mm above the bottom edge
    with pytest.warns(UserWarning, match="exceeds the gap between boundary features"):
        cut_blocks([(0.5, 0, 0.5, 1)], edge_node_distance=0.01, boundary=SQUARE, openings=[opening])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cut_blocks([(0.5, 0, 0.5, 1)], edge_node_distance=0.001, boundary=SQUARE, openings=[opening])


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    dips=st.lists(st.floats(0.0, 180.0), min_size=1, max_size=3),
    spacing=st.floats(1.0, 8.0),
    trace=st.one_of(st.none(), st.floats(3.0, 20.0)),
    bridge=st.floats(0.0, 3.0),
    seed=st.integers(0, 2**16),
)
def test_generated_joint_sets_tile_a_slope_with_a_tunnel(dips, spacing, trace, bridge, seed):
    """Joint sets from the generator (with scatter) on a slope with a tunnel: the same identities."""
    slope = np.array([(0, -5), (60, -5), (60, 20), (35, 20), (15, 0), (0, 0)], dtype=float)
    tunnel = circular_opening((45.0, 5.0), 3.0, 32)
    rock = shapely.Polygon(slope, holes=[tunnel])
    sets = [JointSet(dip=a, spacing=spacing, trace_length=trace, bridge=bridge, joint_type=i + 1,
                     spacing_sd=0.1 * spacing, dip_sd=2.0) for i, a in enumerate(dips)]
    segs, types = joint_traces(rock, sets, seed=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cut = cut_blocks(segs, types, edge_node_distance=0.01, boundary=slope, openings=[tunnel])
    _check_tiling(cut, rock.area, rock)


def test_joint_set_and_opening_inputs_are_checked():
    from srdda.geometry.jointsets2d import polygonal_opening

    with pytest.raises(CuttingError, match="spacing"):
        JointSet(dip=10.0, spacing=0.0)
    with pytest.raises(CuttingError, match="trace_length"):
        JointSet(dip=10.0, spacing=1.0, trace_length=-1.0)
    with pytest.raises(CuttingError, match="radius"):
        circular_opening((0, 0), 0.0)
    with pytest.raises(CuttingError, match="not simple"):
        polygonal_opening([(0, 0), (1, 1), (1, 0), (0, 1)])
    hexagon = circular_opening((1.0, 2.0), 2.0, 6)
    np.testing.assert_allclose(np.hypot(hexagon[:, 0] - 1.0, hexagon[:, 1] - 2.0), 2.0, rtol=1e-15)
    # a vertical set (dip 90°) 1 m apart across a 5 m wide box: x = 0.5, 1.5, ..., 4.5
    segs, _ = joint_traces([(0, 0), (5, 0), (5, 2), (0, 2)], [JointSet(dip=90.0, spacing=1.0, origin=(0.5, 0))])
    np.testing.assert_allclose(np.sort(segs[:, 0]), np.arange(5) + 0.5, atol=1e-12)
