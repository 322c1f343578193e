"""Contact detection: vertex-edge and vertex-vertex contacts of convex and concave blocks,
the entrance line, the broad phase against all pairs, and contact transfer."""
import numpy as np
import pytest

import srdda
from srdda.contact import ContactModel, ContactParameters
from srdda.contact.broadphase2d import candidate_pairs_2d as candidate_pairs
from srdda.contact.candidates import block_boxes
from srdda.contact.narrowphase2d import VERTEX_EDGE, VERTEX_VERTEX
from srdda.contact.record import match_previous

D0 = 0.05


def _model(*blocks):
    m = srdda.Model(allow_overlap=True)  # some cases put a vertex inside the other block on purpose
    m.add_material("rock", srdda.Material(density=2500.0, young=1e9, poisson=0.25))
    for b in blocks:
        m.add_block(b, "rock")
    return m.arrays()


def _detect(arrays, d0=D0):
    cm = ContactModel(arrays, ContactParameters(1e9, 4e8, d0, np.radians(3.0), 0.4 * d0))
    record = cm.detector.detect(arrays.vertex_position)
    found = np.empty((0, 3), dtype=np.int64) if record is None else record.features
    return {(tuple(arrays.vertex_position[v]), tuple(arrays.vertex_position[e]), int(k)) for v, e, k in found}


def test_vertex_on_edge_of_convex_block():
    # A triangle's apex 0.01 m above the middle of a square's top edge: one vertex-edge contact.
    arr = _model([[0, 0], [1, 0], [1, 1], [0, 1]], [[0.5, 1.01], [0.8, 1.5], [0.2, 1.5]])
    found = _detect(arr)
    # The top edge of the square runs (1, 1) -> (0, 1) counter-clockwise.
    assert found == {((0.5, 1.01), (1.0, 1.0), VERTEX_EDGE)}


def test_far_vertex_is_not_a_contact():
    arr = _model([[0, 0], [1, 0], [1, 1], [0, 1]], [[0.5, 1.0 + 2 * D0], [0.8, 1.5], [0.2, 1.5]])
    assert _detect(arr) == set()


def test_angle_criterion_rejects_a_vertex_whose_wedge_overlaps_the_edge():
    # The triangle's vertex (0.5, 1.01) has an edge going down below the square's top line:
    # its wedge cannot touch the top edge without overlapping it first.
    arr = _model([[0, 0], [1, 0], [1, 1], [0, 1]], [[0.5, 1.01], [0.9, 0.8 + 1.0], [0.9, 0.6]])
    found = _detect(arr)
    assert not any(f[0] == (0.5, 1.01) for f in found)


def test_face_to_face_contact_gives_one_contact_per_corner():
    # A square resting on a wider base: its two bottom corners on the base's top edge.
    arr = _model([[-2, -1], [2, -1], [2, 0], [-2, 0]], [[0, 0], [1, 0], [1, 1], [0, 1]])
    found = _detect(arr)
    assert found == {((0.0, 0.0), (2.0, 0.0), VERTEX_EDGE), ((1.0, 0.0), (2.0, 0.0), VERTEX_EDGE)}


def test_stacked_equal_squares_vertex_vertex_once_with_the_right_entrance_line():
    # Corners coincide pairwise: each pair is one vertex-vertex contact (not two) whose edge
    # is the shared horizontal line, never a vertical side.
    arr = _model([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1], [1, 1], [1, 2], [0, 2]])
    found = _detect(arr)
    assert len(found) == 2
    for vertex, edge_start, kind in found:
        assert kind == VERTEX_VERTEX
        v = np.array(vertex)
        e = arr.vertex_position[np.flatnonzero((arr.vertex_position == edge_start).all(axis=1))]
        assert v[1] == 1.0 and all(p[1] == 1.0 for p in e)
    # Each contacted edge is horizontal (both ends at y = 1).
    for _, edge_start, _ in found:
        assert edge_start[1] == 1.0


def test_corner_to_corner_entrance_line_is_the_edge_it_crosses():
    # A diamond's bottom vertex penetrates the top-right corner region of a square, 0.002 m
    # below its top and 0.01 m inside its right side: the shortest way out is the top edge.
    # It projects into both edges at the corner; the right side fails the angle criterion.
    arr = _model([[0.99, 0.998], [1.5, 1.5], [0.99, 2.0], [0.48, 1.5]], [[0, 0], [1, 0], [1, 1], [0, 1]])
    found = _detect(arr)
    assert found == {((0.99, 0.998), (1.0, 1.0), VERTEX_EDGE)}


def test_vertex_vertex_corner_region():
    # The diamond's bottom vertex just outside the square's top-right corner, beyond both edges:
    # a vertex-vertex contact whose entrance line is the square's top edge (the vertex is farther
    # outside it). The square's corner, 0.0035 m from the diamond's lower-left edge, projects into
    # that edge: a vertex-edge contact.
    arr = _model([[0, 0], [1, 0], [1, 1], [0, 1]], [[1.01, 1.005], [1.5, 1.5], [1.01, 2.0], [0.52, 1.5]])
    found = _detect(arr)
    assert found == {((1.01, 1.005), (1.0, 1.0), VERTEX_VERTEX), ((1.0, 1.0), (0.52, 1.5), VERTEX_EDGE)}


def test_vertex_vertex_entrance_line_of_the_other_way_round():
    # Same with the diamond as block 0: the same two contacts (block order does not matter when
    # only one way round is in the other vertex's region).
    arr = _model([[1.01, 1.005], [1.5, 1.5], [1.01, 2.0], [0.52, 1.5]], [[0, 0], [1, 0], [1, 1], [0, 1]])
    found = _detect(arr)
    assert found == {((1.01, 1.005), (1.0, 1.0), VERTEX_VERTEX), ((1.0, 1.0), (0.52, 1.5), VERTEX_EDGE)}


def test_concave_block_notch_gives_two_contacts():
    # An L-shaped (concave) block; a square's corner sits in its inner corner, touching both legs.
    ell = [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]
    square = [[1.01, 1.01], [1.8, 1.01], [1.8, 1.8], [1.01, 1.8]]
    arr = _model(ell, square)
    found = _detect(arr)
    at_corner = {f for f in found if f[0] == (1.01, 1.01)}
    # the square's corner is 0.01 from the leg top (2,1)->(1,1) and from the side (1,1)->(1,2)
    # and projects into both: one vertex-edge contact on each leg
    assert at_corner == {((1.01, 1.01), (2.0, 1.0), VERTEX_EDGE), ((1.01, 1.01), (1.0, 1.0), VERTEX_EDGE)}
    # the square's bottom edge lies on the leg top: its other bottom corner touches it too
    assert ((1.8, 1.01), (2.0, 1.0), VERTEX_EDGE) in found
    # the ell's reflex vertex (1, 1) is never a contact vertex
    assert not any(f[0] == (1.0, 1.0) for f in found)


def test_a_corner_in_a_notch_keeps_both_faces_where_it_projects_beyond_one():
    # The square's corner has slid 1 mm past the notch's corner along the ell's leg top (it projects beyond
    # that edge's end) and pressed 1 mm into the side wall. It touches both faces: the side wall as a
    # vertex-edge contact, the leg top as a notch contact measured to its line (2 mm above it). With the side
    # wall's contact alone the corner could drop onto the leg top unresisted and be found there compressed
    # (the tunnel example gained 4.8 J/m so, docs/dev/contact-solve.md).
    ell = [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]
    square = [[0.999, 1.002], [1.8, 1.002], [1.8, 1.8], [0.999, 1.8]]
    found = _detect(_model(ell, square))
    at_corner = {f for f in found if f[0] == (0.999, 1.002)}
    assert at_corner == {((0.999, 1.002), (2.0, 1.0), VERTEX_VERTEX), ((0.999, 1.002), (1.0, 1.0), VERTEX_EDGE)}


def test_concave_block_vertex_on_inner_edges():
    # A triangle poking into the notch of a U-shaped block touches both inner walls.
    u = [[0, 0], [3, 0], [3, 2], [2, 2], [2, 1], [1, 1], [1, 2], [0, 2]]
    wedge = [[1.5, 1.3], [1.99, 1.6], [1.99, 2.5], [1.01, 2.5], [1.01, 1.6]]
    arr = _model(u, wedge)
    found = _detect(arr)
    vertices = {f[0] for f in found}
    assert (1.99, 1.6) in vertices and (1.01, 1.6) in vertices  # on the two inner walls
    assert (1.5, 1.3) not in vertices  # 0.3 m above the notch floor


@pytest.mark.parametrize("seed", [0, 1])
def test_broad_phase_finds_every_pair_that_all_pairs_finds(seed):
    rng = np.random.default_rng(seed)
    lo = rng.uniform(0, 10, (300, 2))
    boxes = np.hstack([lo, lo + rng.uniform(0.05, 0.5, (300, 2))])
    margin = 0.1
    got = {tuple(p) for p in candidate_pairs(boxes, margin)}
    g = boxes + np.array([-1, -1, 1, 1]) * margin / 2
    overlap = ((g[:, None, 0] <= g[None, :, 2]) & (g[None, :, 0] <= g[:, None, 2])
               & (g[:, None, 1] <= g[None, :, 3]) & (g[None, :, 1] <= g[:, None, 3]))
    i, j = np.nonzero(np.triu(overlap, 1))
    assert got == set(zip(i.tolist(), j.tolist()))


def test_block_boxes():
    arr = _model([[0, 0], [1, 0], [1, 1], [0, 1]], [[2, 3], [4, 3], [3, 5]])
    assert np.array_equal(block_boxes(arr.vertex_position, arr.block_ptr), [[0, 0, 1, 1], [2, 3, 4, 5]])


def test_match_previous():
    assert match_previous(np.array([5, 7, 9]), np.array([9, 1, 5])).tolist() == [2, -1, 0]
    assert match_previous(np.array([5]), np.array([], dtype=np.int64)).tolist() == [-1]


def test_vertex_on_the_far_side_of_a_thin_block_is_not_a_contact():
    # A triangle's apex touches the top of a 0.1 m thin plate. With d0 = 0.3 m the apex is also
    # within d0 of the plate's bottom edge (0.1 behind its line): not a contact (the angle
    # criterion and the plausibility test both reject it); only the top-edge contact is real.
    arr = _model([[0, 0], [2, 0], [2, 0.1], [0, 0.1]], [[1.0, 0.1], [1.3, 0.6], [0.7, 0.6]])
    found = _detect(arr, d0=0.3)
    assert {f for f in found if f[0] == (1.0, 0.1)} == {((1.0, 0.1), (2.0, 0.1), VERTEX_EDGE)}


def test_shallow_penetration_is_a_contact_deep_is_not():
    # A penetrating vertex counts while inside the other block and no deeper than the allowed
    # penetration (0.4 d0 = 0.02 m here); deeper, it can only be a mis-pairing.
    shallow = _model([[0, 0], [2, 0], [2, 1], [0, 1]], [[1.0, 0.99], [1.3, 1.5], [0.7, 1.5]])
    assert ((1.0, 0.99), (2.0, 1.0), VERTEX_EDGE) in _detect(shallow)
    deep = _model([[0, 0], [2, 0], [2, 1], [0, 1]], [[1.0, 0.97], [1.3, 1.5], [0.7, 1.5]])
    assert not any(f[0] == (1.0, 0.97) for f in _detect(deep))


@pytest.mark.parametrize("method", ["dda0", "dda1", "srdda"])
def test_blocks_with_coincident_corners_rest_on_each_other(method):
    # Cut blocks share whole edges with identical end vertices. The corners of the
    # upper block then sit exactly on the lower block's corners, a degenerate
    # vertex-vertex case: the block must rest, not fall through (free fall would
    # be 0.45 m in 0.3 s). Bound: settlement mg/(2k) plus elastic shortening,
    # about 8e-6 m, so 2e-5 m.
    m = srdda.Model(gravity=(0.0, -10.0))
    m.add_material("r", srdda.Material(2500.0, 1e9, 0.25))
    m.add_block([[0, -1], [1, -1], [1, 0], [0, 0]], "r", fixed=True)
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "r")
    r = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=300, method=method, penalty=1e10))
    assert r.completed
    assert abs(r.array("centroid")[-1, 1, 1] - 0.5) < 2e-5
    assert r.closed_contacts[-1] == 2


def test_vertex_beside_an_acute_corner_is_not_a_contact_with_its_other_edge():
    # The jointed-slope explosion: a block's corner sits on the top edge of another block
    # 0.01 m from that block's acute (78°) corner, barely penetrating (1e-5 m). It also
    # projects into the corner's other (right) edge and lies 0.01 m behind that edge's line,
    # well within 0.4 d0 = 0.02 m, and its wedge fits that edge (the upper block's left side
    # is parallel to it). The right edge is not its shortest way out (the top edge is 1e-5 m
    # away): only the top-edge contact is real; the other would be a 0.01 m deep spring
    # created from nothing. The same holds the other way round for the acute corner itself.
    t12 = np.tan(np.radians(12.0))
    lower = [[-1, -1], [-t12, -1], [0, 0], [-1, 0]]
    v = (-0.01, -1e-5)
    upper = [list(v), [1.2, -1e-5], [1.2 + 0.4 * t12, 0.4], [v[0] + 0.4 * t12, 0.4]]
    found = _detect(_model(lower, upper))
    assert {f for f in found if f[0] == v} == {(v, (0.0, 0.0), VERTEX_EDGE)}  # top edge (0,0)->(-1,0)
    corner = {f for f in found if f[0] == (0.0, 0.0)}
    assert corner == {((0.0, 0.0), v, VERTEX_EDGE)}  # the upper block's bottom edge only


@pytest.mark.parametrize("outside", [0.0, 1e-12, 1e-10])
def test_penetrating_corner_is_found_on_either_side_of_rounding(outside):
    # A triangle's apex has penetrated 1e-8 m at the top-right corner of a block whose right
    # face is sheared (obtuse corner). Rounding may put the apex just outside that face
    # (by up to 1e-10 m here, far below 1e-6 of the 1 m edge): the contact must be found
    # whatever side it lands on (issue 15, defect 9: a missed contact lets the penetration
    # grow and the late spring then creates energy).
    shear = 0.3  # the right face runs (1 - 0.3, 0) -> (1, 1)
    normal = np.array([1.0, -shear]) / np.hypot(1.0, shear)  # outward normal of that face
    apex = np.array([1.0, 1.0 - 1e-8]) + (outside + shear * 1e-8 / np.hypot(1.0, shear)) * normal
    arr = _model([[0, 0], [1 - shear, 0], [1, 1], [0, 1]], [apex, apex + [0.3, 0.5], apex + [-0.3, 0.5]])
    found = _detect(arr)
    v = tuple(arr.vertex_position[4])
    assert any(f[0] == v and f[1] == (1.0, 1.0) for f in found), found


@pytest.mark.parametrize("dim", [2, 3])
def test_kept_candidates_are_the_fresh_broad_phase_in_its_order(dim):
    # 200 blocks (as 8 vertices each) wander by random steps of up to 0.3 d0 per axis: at every step the
    # kept list, filtered, must be exactly the broad phase run afresh, pairs and order; and the broad
    # phase runs again only after some vertex moved more than the margin's half (here about every 2-3 steps)
    from srdda.contact.candidates import KeptCandidates
    from srdda.contact.broadphase3d import candidate_pairs_3d
    find = candidate_pairs if dim == 2 else candidate_pairs_3d
    rng = np.random.default_rng(7)
    n, d0 = 200, 0.1
    centres = rng.uniform(0, 4, (n, dim))
    corners = rng.uniform(-0.15, 0.15, (n, 8, dim))
    kept = KeptCandidates(find, d0, d0)
    steps = 40
    for _ in range(steps):
        vertices = (centres[:, None, :] + corners).reshape(-1, dim)
        boxes = np.hstack([vertices.reshape(n, 8, dim).min(axis=1), vertices.reshape(n, 8, dim).max(axis=1)])
        assert np.array_equal(kept(vertices, boxes), find(boxes, d0))
        centres += rng.uniform(-0.3 * d0, 0.3 * d0, (n, dim))
    assert 5 < kept.searches < steps


@pytest.mark.parametrize("room", [0, 4])
def test_parallel_narrow_phase_finds_the_serial_rows_in_their_order(room):
    # the narrow phase of large models shares chunks of pairs among threads; each chunk writes into room for
    # `room` rows a pair, and a chunk that finds more is found again on one thread. With no room every chunk
    # is found again, with room for 4 none (a brick finds fewer than 2 rows a directed pair): both must give
    # the serial rows, row for row, on a brick wall whose corners are jittered within the contact distance
    # (some slightly penetrating)
    from srdda.apps.bench.models import brick_wall
    from srdda.contact.narrowphase2d import narrow_phase_2d, narrow_phase_2d_parallel
    model, _ = brick_wall(24, 12)
    arrays = model.arrays()
    cm = ContactModel(arrays, ContactParameters(1e9, 4e8, 2e-3, np.radians(3.0), 1e-3))
    detector = cm.detector
    jitter = np.random.default_rng(3).uniform(-8e-4, 8e-4, arrays.vertex_position.shape)
    vertices = arrays.vertex_position + jitter
    boxes, pairs = detector.pairs(vertices)
    args = (vertices, arrays.block_ptr, arrays.vertex_block, arrays.vertex_next, detector.previous_vertex, pairs,
            boxes, detector.distance, detector.sin_tol, detector.max_penetration)
    serial = narrow_phase_2d(*args)
    assert 0 < len(serial) < 2 * len(pairs)
    assert np.array_equal(narrow_phase_2d_parallel(*args, room), serial)
