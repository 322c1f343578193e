"""3D contact detection: the broad phase against all pairs, vertex-face and edge-edge contacts of convex and
concave polyhedra, the angle criterion, the contact geometry and the transfer keys."""
import numpy as np
import pytest

import srdda
from srdda.contact import ContactModel, ContactParameters
from srdda.contact.broadphase3d import candidate_pairs_3d
from srdda.contact.candidates import block_boxes
from srdda.contact.detect3d import surface_geometry
from srdda.contact.narrowphase3d import EDGE_EDGE, VERTEX_FACE
from srdda.geometry.polyhedron import box, prism
from srdda.kinematics.shape3d import rotation_matrix_3d

D0 = 0.05
# along x, the apex of a triangular section up (ridge) or down; extruded along another axis
TO_X = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]])  # (u, v, w) -> (w, u, v): section in y-z, length along x
TO_Y = np.array([[1, 0, 0], [0, 0, 1], [0, 1, 0]])  # (u, v, w) -> (u, w, v): section in x-z, length along y


def _arrays(*blocks, fixed=()):
    m = srdda.Model(gravity=(0.0, 0.0, -9.81))
    m.add_material("rock", srdda.Material(2500.0, 1e9, 0.25))
    for k, (v, f) in enumerate(blocks):
        m.add_polyhedron(v, f, "rock", fixed=k in fixed)
    return m.arrays()


def _model(arrays, d0=D0):
    return ContactModel(arrays, ContactParameters(1e9, 4e8, d0, np.radians(3.0), 0.4 * d0))


def _detect(arrays, d0=D0):
    """The detected features (k, 5) and the contact record (None when there are none)."""
    record = _model(arrays, d0).detector.detect(arrays.vertex_position)
    return (np.empty((0, 5), dtype=np.int64) if record is None else record.features), record


def _bar(section, lo, hi, turn, shift):
    v, f = prism(section, lo, hi)
    return v @ turn.T + shift, f


def test_broad_phase_equals_all_pairs():
    rng = np.random.default_rng(3)
    lo = rng.uniform(0, 5, (400, 3))
    boxes = np.hstack([lo, lo + rng.lognormal(-1, 0.8, (400, 3))])  # sizes over two orders of magnitude
    movable = rng.random(400) > 0.2
    grown = boxes + 0.5 * D0 * np.repeat([-1.0, 1.0], 3)
    overlap = np.all((grown[:, None, :3] <= grown[None, :, 3:]) & (grown[None, :, :3] <= grown[:, None, 3:]), axis=2)
    i, j = np.nonzero(np.triu(overlap, 1))
    keep = movable[i] | movable[j]
    assert np.array_equal(candidate_pairs_3d(boxes, D0, movable), np.column_stack([i[keep], j[keep]]))


def test_broad_phase_finds_the_26_neighbours_of_a_cube_in_a_grid():
    g = np.stack(np.meshgrid(*[np.arange(4.0)] * 3, indexing="ij"), -1).reshape(-1, 3)
    pairs = candidate_pairs_3d(np.hstack([g, g + 1.0]), 0.01)
    degree = np.bincount(pairs.ravel(), minlength=len(g))
    assert degree[np.flatnonzero(np.all(g == 1.0, axis=1))[0]] == 26  # an inner cube touches 26 others
    assert degree.min() == 7  # a corner cube touches 7


def test_cube_resting_on_a_base_has_one_vertex_face_contact_per_bottom_corner():
    arr = _arrays(box((-2, -2, -1), (2, 2, 0)), box((0, 0, 0.01), (1, 1, 1)), fixed=(0,))
    found, geom = _detect(arr)
    assert sorted(found[:, 1].tolist()) == [8, 9, 10, 11]  # the cube's bottom vertices
    assert np.all(found[:, 0] == VERTEX_FACE) and np.all(found[:, 3] == 1) and np.all(found[:, 4] == 0)
    np.testing.assert_allclose(geom.normal, [[0, 0, 1]] * 4, atol=1e-15)
    np.testing.assert_allclose(geom.gap, 0.01, rtol=1e-12)


@pytest.mark.parametrize("lift", [0.0, 0.01, -0.002])
def test_cubes_face_to_face_have_one_contact_per_corner_pair(lift):
    """Two cubes stacked corner on corner (cut blocks): each of the 4 corner pairs finds itself from both
    sides, a corner of each block on the other's face; one contact is kept (the lower block's corner, the
    smaller index), so the joint has 4 springs, not 8, and its bond area is the face's 1 m², not 2."""
    arr = _arrays(box((0, 0, -1), (1, 1, 0)), box((0, 0, lift), (1, 1, 1 + lift)), fixed=(0,))
    found, geom = _detect(arr)
    assert len(found) == 4 and np.all(found[:, 0] == VERTEX_FACE)
    assert np.all(found[:, 3] == 0) and np.all(found[:, 4] == 1)  # a corner of block 0 on block 1's face
    assert sorted(found[:, 1].tolist()) == [4, 5, 6, 7]  # block 0's top corners
    np.testing.assert_allclose(geom.gap, lift, atol=1e-15)
    assert geom.bond.sum() == pytest.approx(1.0, rel=1e-12)  # the joint's area, once


def test_a_cube_on_a_larger_face_keeps_its_four_corners():
    """Corners that do not meet corners of the other block are no pair: a cube on a wider base keeps the
    four contacts of its own corners (the same as without the pairing)."""
    arr = _arrays(box((-2, -2, -1), (2, 2, 0)), box((0, 0, 0.0), (1, 1, 1)), fixed=(0,))
    found, geom = _detect(arr)
    assert sorted(found[:, 1].tolist()) == [8, 9, 10, 11] and np.all(found[:, 3] == 1)
    assert geom.bond.sum() == pytest.approx(1.0, rel=1e-12)


def test_far_cube_is_not_a_contact():
    arr = _arrays(box((-2, -2, -1), (2, 2, 0)), box((0, 0, 2 * D0), (1, 1, 1)))
    assert len(_detect(arr)[0]) == 0


def test_cube_on_its_corner_touches_with_that_corner_only():
    turn = rotation_matrix_3d(np.array([[np.arctan(np.sqrt(2.0)), 0, 0]]))[0] \
        @ rotation_matrix_3d(np.array([[0, 0, np.pi / 4]]))[0]  # a body diagonal vertical
    v, f = box((-0.5, -0.5, -0.5), (0.5, 0.5, 0.5))
    v = v @ turn.T
    v[:, 2] -= v[:, 2].min() - 0.01
    arr = _arrays(box((-2, -2, -1), (2, 2, 0)), (v, f))
    found, geom = _detect(arr)
    assert found.tolist() == [[VERTEX_FACE, 8 + int(np.argmin(v[:, 2])), 1, 1, 0]]
    np.testing.assert_allclose(geom.gap, [0.01], rtol=1e-9)


def test_angle_criterion_rejects_a_vertex_whose_edge_dips_below_the_face():
    # A cube tilted 20° about y: its edges along x go down towards +x. Its highest bottom vertex v sits
    # 0.01 m above the base's top face near the base's edge x = 2, and its edge along x dips below the
    # face's plane beyond that edge: v's cone cannot touch the face without overlapping the base first.
    turn = rotation_matrix_3d(np.array([[0.0, np.radians(20.0), 0.0]]))[0]
    v, f = box((0, 0, 0), (1, 1, 1))
    v = v @ turn.T
    v += np.array([1.9, 0.0, 0.01]) - v[0]
    found, _ = _detect(_arrays(box((-2, -2, -1), (2, 2, 0)), (v, f)))
    assert not np.any((found[:, 0] == VERTEX_FACE) & (found[:, 1] == 8))
    flat = box((1.9, 0, 0.01), (2.9, 1, 1.01))  # the same vertex with its edges level: a contact
    found, _ = _detect(_arrays(box((-2, -2, -1), (2, 2, 0)), flat))
    assert np.any((found[:, 0] == VERTEX_FACE) & (found[:, 1] == 8))


def test_crossing_edges_make_one_edge_edge_contact_with_the_cross_product_normal():
    ridge = _bar([[-0.5, 0], [0.5, 0], [0, 0.5]], -1, 1, TO_X, 0.0)  # apex edge along x at z = 0.5
    upper = _bar([[-0.5, 0.5], [0.5, 0.5], [0, 0]], -1, 1, TO_Y, np.array([0, 0, 0.51]))  # apex along y, z = 0.51
    found, geom = _detect(_arrays(ridge, upper))
    assert found[:, 0].tolist() == [EDGE_EDGE]
    np.testing.assert_allclose(np.abs(geom.normal), [[0, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(geom.gap, [0.01], rtol=1e-12)
    np.testing.assert_allclose(geom.point_a[0, :2], [0, 0], atol=1e-15)  # the crossing point


def test_parallel_edges_make_no_edge_edge_contact():
    ridge = _bar([[-0.5, 0], [0.5, 0], [0, 0.5]], -1, 1, TO_X, 0.0)
    upper = _bar([[-0.5, 0.5], [0.5, 0.5], [0, 0]], -1, 1, TO_X, np.array([0, 0, 0.51]))  # apex along x too
    found, _ = _detect(_arrays(ridge, upper))
    assert not np.any(found[:, 0] == EDGE_EDGE)
    # each end vertex of either apex edge meets the other apex edge (vertex-edge): one V-F contact with an
    # entrance face, here one of the two 45° faces at that edge (both as near)
    assert sorted(found[:, 0].tolist()) == [VERTEX_FACE] * 4
    assert set(found[:, 1].tolist()) == {2, 5, 6, 9}  # the apex edges' end vertices


def test_edge_lying_across_a_face_rim_touches_at_its_inner_end_and_at_the_rim():
    # a bar with a triangular section, apex edge down, lies across the base's edge x = 2
    bar = _bar([[-0.1, 0.3], [0.1, 0.3], [0, 0.01]], 1.5, 2.5, TO_X, 0.0)  # along x, apex edge at z = 0.01
    found, geom = _detect(_arrays(box((-2, -2, -1), (2, 2, 0)), bar))
    kinds = sorted(found[:, 0].tolist())
    assert kinds == [VERTEX_FACE, EDGE_EDGE]
    edge = found[:, 0] == EDGE_EDGE
    ends = np.sort(np.vstack([geom.point_a[edge], geom.point_b[edge]]), axis=0)  # the base's rim, the bar's edge
    np.testing.assert_allclose(ends, [[2.0, 0.0, 0.0], [2.0, 0.0, 0.01]], atol=1e-12)
    np.testing.assert_allclose(geom.point_a[found[:, 0] == VERTEX_FACE][0], [1.5, 0.0, 0.01], atol=1e-12)
    np.testing.assert_allclose(geom.gap, 0.01, rtol=1e-9)


def test_block_with_a_notch_resting_on_a_ridge_touches_on_the_notch_faces():
    # a concave block: a 2 x 1 m box with a 90° V-notch in its bottom, resting on a 90° ridge that fits it
    notched = _bar([[-1, 0], [-0.5, 0], [0, 0.5], [0.5, 0], [1, 0], [1, 1], [-1, 1]], -1, 1, TO_Y,
                   np.array([0, 0, 0.001]))
    ridge = _bar([[-0.5, 0], [0.5, 0], [0, 0.5]], -1, 1, TO_Y, 0.0)
    arr = _arrays(ridge, notched, fixed=(0,))
    found, geom = _detect(arr)
    notch_normals = np.array([[1, 0, -1], [-1, 0, -1]]) / np.sqrt(2)  # outward normals of the notch faces
    assert len(found) > 0
    outward_of_notched = np.where((found[:, 4] == 1)[:, None], geom.normal, -geom.normal)
    on_notch = np.isclose(np.abs(outward_of_notched @ notch_normals.T), 1.0, atol=1e-12).any(axis=1)
    assert np.all(on_notch)  # every contact lies on a notch face
    sides = np.sign(np.round(outward_of_notched[:, 0], 12))
    assert set(sides.tolist()) == {-1.0, 1.0}  # both notch faces carry contacts
    np.testing.assert_allclose(geom.gap, 0.001 / np.sqrt(2), rtol=1e-9)


def test_penetrating_vertex_beyond_a_thin_plate_is_not_a_contact_with_its_far_face():
    plate = box((-2, -2, -0.01), (2, 2, 0))
    cube = box((0, 0, -0.005), (1, 1, 1))  # bottom 5 mm into a 10 mm plate: nearest way out is the top face
    arr = _arrays(plate, cube)
    found, _ = _detect(arr)
    detector = _model(arr).detector
    surface = surface_geometry(arr.vertex_position, detector.mesh, detector.topology, detector.sin_tol)
    cube_on_plate = found[(found[:, 3] == 1) & (found[:, 0] == VERTEX_FACE)]
    assert len(cube_on_plate) == 4
    np.testing.assert_allclose(surface.face_normal[cube_on_plate[:, 2]], [[0, 0, 1]] * 4, atol=1e-15)


@pytest.mark.parametrize("turn", [0.3, 1.1])
def test_detection_does_not_depend_on_the_frame(turn):
    # the same configuration turned about an arbitrary axis gives the same contacts and gaps
    arr = _arrays(box((-2, -2, -1), (2, 2, 0)), box((0, 0, 0.01), (1, 1, 1)))
    R = rotation_matrix_3d(np.array([[turn, -0.4 * turn, 0.7]]))[0]
    moved = _arrays(*[(arr.vertex_position[arr.block_ptr[b]:arr.block_ptr[b + 1]] @ R.T,
                       [f - arr.block_ptr[b] for f in _faces(arr, b)]) for b in range(2)])
    f1, g1 = _detect(arr)
    f2, g2 = _detect(moved)
    assert np.array_equal(f1, f2)
    np.testing.assert_allclose(g2.gap, g1.gap, rtol=1e-9)
    np.testing.assert_allclose(g2.normal, g1.normal @ R.T, atol=1e-12)


def _faces(arr, b):
    m = arr.mesh
    return [m.face_vertex[m.face_ptr[k]:m.face_ptr[k + 1]] for k in np.flatnonzero(m.face_block == b)]


def test_block_boxes_3d():
    arr = _arrays(box((0, 0, 0), (1, 2, 3)), box((5, 5, 5), (6, 6, 6)))
    np.testing.assert_array_equal(block_boxes(arr.vertex_position, arr.block_ptr),
                                  [[0, 0, 0, 1, 2, 3], [5, 5, 5, 6, 6, 6]])


def _deep(arrays):
    """Features and record with d0 = 0.3 m and 0.125 m allowed depth."""
    record = ContactModel(arrays, ContactParameters(1e9, 4e8, 0.3, np.radians(3.0), 0.125)).detector.detect(
        arrays.vertex_position)
    if record is None:
        return np.empty((0, 5), dtype=np.int64), np.empty(0)
    return record.features, record.gap


def test_a_vertex_beside_a_rim_is_no_deep_penetration():
    """A vertex hanging 0.05 m beyond a cube's rim and 0.1 m below its top, its edges reaching back over the top:
    it is beside the cube, not in it (a freshly cut 3D slope had 21 such 'penetrations' of up to 12 cm, which
    blew its first step apart). With d0 = 0.3 m and 0.125 m allowed depth, the band rule alone took it for a
    contact with the top face at gap -0.1 m; outside every face plane but one by more than 1e-3 d0, it is not."""
    from srdda.geometry.cutting3d import convex_hull_polyhedron
    cube = box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    hanging = convex_hull_polyhedron(np.array([[1.05, 0.5, 0.9], [0.95, 0.3, 1.3], [0.95, 0.7, 1.3],
                                               [1.2, 0.5, 1.5]]))
    arrays = _arrays(cube, hanging, fixed=(0,))
    found, gap = _deep(arrays)
    assert not np.any(gap < -1e-3 * 0.3), (found, gap)  # nothing deeper than the slack
    # the same tetrahedron lowered onto the top face (its lowest vertex 0.01 m into it, above the face) is one
    lowered = convex_hull_polyhedron(np.array([[0.9, 0.5, 0.99], [0.8, 0.3, 1.3], [0.8, 0.7, 1.3], [1.05, 0.5, 1.5]]))
    arrays = _arrays(cube, lowered, fixed=(0,))
    found, gap = _deep(arrays)
    deep = (found[:, 0] == VERTEX_FACE) & np.isclose(gap, -0.01)
    assert deep.sum() == 1, (found, gap)


def test_spring_points_are_material_points_when_the_blocks_strain():
    # a shear spring joins material points of the two blocks: after any affine motion of both blocks (a strain,
    # here 1e-3 stretch and 5e-4 shear, as a step's elastic strain in DDA), an unstretched spring stays
    # unstretched. The vertex-face contacts store their face point in the coordinates of the face's edges; in
    # unit axes the point would move by strain × its distance from the face's first vertex (0.5e-3 m here, the
    # 2.7e-5 m a step found on the 3D slope). Rounding: the coordinates are O(1) m, so 1e-13 m is ~500 ulps.
    v, f = box((-0.5, -0.35, 0.0), (0.5, 0.35, 0.6))  # turned 30° about z over the lower block's edge x = 2
    top = (v @ rotation_matrix_3d(np.array([[0.0, 0.0, np.radians(30.0)]]))[0].T + [1.8, 0.7, 1.0], f)
    arrays = _arrays(box((0.0, 0.0, 0.0), (2.0, 1.5, 1.0)), top, fixed=(0,))
    model = _model(arrays)
    start = model.detector.detect(arrays.vertex_position)
    assert np.any(start.features[:, 0] == VERTEX_FACE) and np.any(start.features[:, 0] == EDGE_EDGE)
    strain = np.array([[1.0 + 1e-3, 5e-4, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    moved = model.detector.detect(arrays.vertex_position @ strain.T)
    assert np.array_equal(moved.key, start.key)
    assert np.max(np.abs(start.shear(start.start_reference))) < 1e-13
    assert np.max(np.abs(moved.shear(start.start_reference))) < 1e-13
    # and a reference shift changes the shear by what it was asked for, for every kind of contact
    wanted = np.random.default_rng(0).normal(0.0, 1e-6, start.start_reference.shape)
    shifted = start.start_reference + start.reference_shift(wanted)
    assert np.allclose(start.shear(shifted), wanted, rtol=0.0, atol=1e-13)
