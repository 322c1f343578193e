"""3D block cutting (srdda.geometry.cutting3d) and joint sets (srdda.geometry.jointsets3d)."""
from __future__ import annotations

import numpy as np
import pytest

from srdda.geometry.cutting2d import NO_JOINT, CuttingError
from srdda.geometry.cutting3d import convex_hull_polyhedron, cut_polyhedra
from srdda.geometry.jointsets3d import (JointPlanes, JointSet3D, dip_and_direction, fisher_directions,
                                        joint_planes, plane_normal)
from srdda.geometry.polyhedron import (PolyhedronError, PolyhedronMesh, box, normalize_polyhedron,
                                      polyhedron_moments)


def _volume(blocks: list) -> float:
    mesh = PolyhedronMesh.from_blocks(blocks)
    return float(polyhedron_moments(mesh.vertices, mesh).volume.sum())


def _slope_parts() -> list:
    """A 60° slope 20 m high (convex part above z = 0) on a 5 m base slab: a non-convex domain in two parts."""
    run = 20.0 / np.tan(np.radians(60.0))
    upper = convex_hull_polyhedron([[10, 0, 0], [40, 0, 0], [40, 20, 0], [10, 20, 0], [10 + run, 0, 20],
                                    [40, 0, 20], [40, 20, 20], [10 + run, 20, 20]])
    return [upper, box((0, 0, -5), (40, 20, 0))]


def _inside_count(cut, points: np.ndarray, tol: float) -> np.ndarray:
    """How many blocks hold each point strictly inside (every face plane at more than ``tol``)."""
    count = np.zeros(len(points), dtype=int)
    for b in range(cut.n_blocks):
        v, faces, _ = cut.block(b)
        inside = np.ones(len(points), dtype=bool)
        for f in faces:
            p = v[f]
            n = 0.5 * np.cross(p - p.mean(0), np.roll(p, -1, 0) - p.mean(0)).sum(0)
            inside &= (points - p.mean(0)) @ (n / np.linalg.norm(n)) < -tol
        count += inside
    return count


def _assert_valid_convex(cut, tol: float = 1e-9) -> None:
    """Every block passes the polyhedron validation and lies behind each of its face planes (convex)."""
    for b in range(cut.n_blocks):
        v, faces, _ = cut.block(b)
        v, faces = normalize_polyhedron(v, faces, f"fragment {b}")
        size = np.linalg.norm(np.ptp(v, axis=0))
        for f in faces:
            p = v[f]
            n = 0.5 * np.cross(p - p.mean(0), np.roll(p, -1, 0) - p.mean(0)).sum(0)
            # the validation's planarity tolerance (1e-9 x size) bounds how far a vertex may stick out
            assert ((v - p.mean(0)) @ (n / np.linalg.norm(n))).max() <= tol * size


def test_orthogonal_sets_give_the_product_of_the_plane_counts():
    dom = box((0, 0, 0), (10, 6, 4))
    sets = [JointSet3D(90, 90, 2.0, origin=(1, 1, 1), joint_type=1),  # x = 1, 3, ..., 9: 6 slices
            JointSet3D(90, 0, 2.0, origin=(1, 1, 1), joint_type=2),  # y = 1, 3, 5: 4
            JointSet3D(0, 0, 2.0, origin=(1, 1, 1), joint_type=3)]  # z = 1, 3: 3
    cut = cut_polyhedra(dom, joint_planes(dom[0], sets))
    assert cut.n_blocks == 6 * 4 * 3 and not cut.skipped and not cut.rejected
    # every block is a box: 8 vertices, 6 faces; volumes 1 (corners), 2, 4 or 8 m³
    assert all(len(cut.block(b)[0]) == 8 and len(cut.block(b)[1]) == 6 for b in range(cut.n_blocks))
    assert set(np.round(cut.volumes(), 12)) == {1.0, 2.0, 4.0, 8.0}
    # faces on each set's planes: 2 per block side on an inner plane; domain faces keep NO_JOINT
    assert np.sum(cut.face_joint == 1) == 2 * 5 * 4 * 3 and np.sum(cut.face_joint == 2) == 2 * 3 * 6 * 3
    assert np.sum(cut.face_joint == 3) == 2 * 2 * 6 * 4 and np.sum(cut.face_joint == NO_JOINT) == 2 * (
        4 * 3 + 6 * 3 + 6 * 4)


def test_planes_through_domain_faces_and_corners_make_no_slivers():
    dom = box((0, 0, 0), (4, 4, 4))
    # spacing 2 from the origin: planes x, y, z = 0, 2, 4 (0 and 4 lie on the domain's faces)
    sets = [JointSet3D(90, 90, 2.0), JointSet3D(90, 0, 2.0), JointSet3D(0, 0, 2.0)]
    cut = cut_polyhedra(dom, joint_planes(dom[0], sets))
    assert cut.n_blocks == 8 and not cut.skipped
    # diagonal planes x + y = 2, 4, 6 through two vertical edges of every 2 m cube: each cube halved exactly
    diag = JointPlanes.of([[1, 1, 0]] * 3, [[1, 1, 0], [2, 2, 0], [3, 3, 0]])
    cut2 = cut_polyhedra(dom, JointPlanes.concatenate([joint_planes(dom[0], sets), diag]))
    assert cut2.n_blocks == 16 and not cut2.skipped and not cut2.rejected
    assert _volume(cut2.blocks()) == pytest.approx(64.0, rel=1e-12)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_jointed_slope_conserves_volume_and_tiles_the_domain(seed: int):
    parts = _slope_parts()
    sets = [JointSet3D(35, 270, 4.0, kappa=40, joint_type=1),
            JointSet3D(80, 180, 5.0, kappa=30, joint_type=2, spacing_sd=0.5),
            JointSet3D(70, 60, 6.0, kappa=20, persistence=0.6, radius=6.0, joint_type=3)]
    joints = joint_planes(parts[0][0], sets, seed=seed)
    cut = cut_polyhedra(parts, joints, min_thickness=0.05)
    assert cut.n_blocks > 100 and not cut.rejected  # enough blocks to exercise the checks below
    domain = _volume(parts)
    # exact arithmetic would give equality; 1e-12 leaves a few hundred roundings of the summed tetrahedra
    assert _volume(cut.blocks()) == pytest.approx(domain, rel=1e-12)
    _assert_valid_convex(cut)
    # 3,000 random points of the domain (farther than 1e-6 m from its surface): each is in a block (faces
    # included: no gap) and strictly inside at most one (no overlap); 1e-9 m is far above rounding
    rng = np.random.default_rng(seed)
    lo, hi = np.array([0, 0, -5.0]), np.array([40, 20, 20.0])
    pts = lo + rng.random((6000, 3)) * (hi - lo)
    behind_face = (pts[:, 0] - 10.0) * np.sin(np.radians(60)) - pts[:, 2] * np.cos(np.radians(60))
    inside = (pts[:, 2] < -1e-6) | ((pts[:, 2] > 1e-6) & (behind_face > 1e-6))
    pts = pts[inside][:3000]
    assert np.all(_inside_count(cut, pts, -1e-9) >= 1)  # covered (faces included)
    assert np.all(_inside_count(cut, pts, 1e-9) <= 1)  # strict interiors do not overlap
    assert {s.reason for s in cut.skipped} <= {"thinner than min_thickness",
                                               "degenerate (a face or the volume below the validation tolerance)"}
    assert all(s.value < 0.05 for s in cut.skipped if s.reason.startswith("thinner"))


def test_same_seed_same_blocks_other_seed_other_blocks():
    parts = _slope_parts()
    sets = [JointSet3D(40, 250, 5.0, kappa=25), JointSet3D(75, 150, 5.0, kappa=25, persistence=0.5, radius=5.0)]
    a = cut_polyhedra(parts, joint_planes(parts[0][0], sets, seed=11))
    b = cut_polyhedra(parts, joint_planes(parts[0][0], sets, seed=11))
    c = cut_polyhedra(parts, joint_planes(parts[0][0], sets, seed=12))
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.face_vertex, b.face_vertex)
    assert not (a.vertices.shape == c.vertices.shape and np.array_equal(a.vertices, c.vertices))


def test_a_disc_cuts_only_the_fragments_it_crosses_completely():
    dom = box((0, 0, 0), (10, 4, 4))
    # a disc on x = 2, radius 3.5 about (2, 2, 2): covers the 4 x 4 section (half-diagonal 2.83)
    full = JointPlanes.of([[1, 0, 0]], [[2, 2, 2]], radius=3.5)
    assert cut_polyhedra(dom, full).n_blocks == 2
    # radius 2.5 < 2.83: the corners of the section stick out; the box stays whole
    part = JointPlanes.of([[1, 0, 0]], [[2, 2, 2]], radius=2.5)
    assert cut_polyhedra(dom, part).n_blocks == 1
    # after the plane y = 2 halves the box, a disc about (2, 1, 2) of radius 2.5 covers the lower half's
    # section (farthest corner at 2.24) but not the whole box's (3.6) nor the upper half's (it ends inside)
    halves = JointPlanes.of([[0, 1, 0]], [[0, 2, 0]])
    disc = JointPlanes.of([[1, 0, 0]], [[2, 1, 2]], radius=2.5)
    assert cut_polyhedra(dom, disc).n_blocks == 1
    for order in ([halves, disc], [disc, halves]):  # the same result whatever the order of the joints
        cut = cut_polyhedra(dom, JointPlanes.concatenate(order))
        assert cut.n_blocks == 3
        assert sorted(np.round(cut.volumes(), 12)) == [16.0, 64.0, 80.0]


def test_cuts_leaving_thin_or_degenerate_pieces_are_skipped_and_reported():
    dom = box((0, 0, 0), (1, 1, 1))
    thin = JointPlanes.of([[1, 0, 0]], [[0.01, 0, 0]], joint_type=4)
    assert cut_polyhedra(dom, thin).n_blocks == 2
    cut = cut_polyhedra(dom, thin, min_thickness=0.05)
    assert cut.n_blocks == 1 and len(cut.skipped) == 1
    s = cut.skipped[0]
    assert s.joint == 0 and s.reason == "thinner than min_thickness" and s.value == pytest.approx(0.01)
    assert s.point == pytest.approx((0.01, 0.5, 0.5))
    cut = cut_polyhedra(dom, thin, min_volume=0.02)
    assert cut.n_blocks == 1 and cut.skipped[0].reason == "smaller than min_volume"
    # a plane 1e-7 m below a corner cuts off a tip of 1e-21 m³: its faces are below the validation tolerance
    tip = JointPlanes.of([[1, 1, 1]], [[1 - 1e-7, 1, 1]])
    cut = cut_polyhedra(dom, tip)
    assert cut.n_blocks == 1 and cut.skipped[0].reason.startswith("degenerate")
    # a plane within rounding (1e-14 m) of a corner touches it: no cut, nothing to report
    touch = JointPlanes.of([[1, 1, 1]], [[1 + 1e-14, 1, 1]])
    cut = cut_polyhedra(dom, touch)
    assert cut.n_blocks == 1 and not cut.skipped


def test_bad_domains_and_joints_are_one_clear_error():
    with pytest.raises(CuttingError, match="not convex"):
        cut_polyhedra((np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [1, 0.5, 0], [0, 2, 0],
                                 [0, 0, 1], [2, 0, 1], [2, 2, 1], [1, 0.5, 1], [0, 2, 1]], float),
                       [[0, 4, 3, 2, 1], [5, 6, 7, 8, 9], [0, 1, 6, 5], [1, 2, 7, 6], [2, 3, 8, 7], [3, 4, 9, 8],
                        [4, 0, 5, 9]]), JointPlanes.of([[1, 0, 0]], [[1, 0, 0]]))
    with pytest.raises(CuttingError, match="zero normal"):
        JointPlanes.of([[0, 0, 0]], [[1, 0, 0]])
    with pytest.raises(CuttingError, match="radius"):
        JointSet3D(30, 10, 1.0, persistence=0.5)
    with pytest.raises(CuttingError, match="dip must be"):
        JointSet3D(95, 10, 1.0)
    with pytest.raises(CuttingError, match="coplanar"):
        convex_hull_polyhedron([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])


def test_convex_hull_merges_coplanar_facets():
    v, faces = convex_hull_polyhedron(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1],
                                                [1, 1, 1], [0, 1, 1], [0.5, 0.5, 0.5]]) * 2.0)
    assert len(v) == 8 and len(faces) == 6 and _volume([(v, faces)]) == pytest.approx(8.0, rel=1e-14)


def test_dip_and_dip_direction_convention():
    # x east, y north, z up: a plane dipping 30° east has its upward normal tilted east
    assert plane_normal(30.0, 90.0) == pytest.approx([0.5, 0.0, np.cos(np.radians(30))], abs=1e-15)
    assert plane_normal(90.0, 0.0) == pytest.approx([0.0, 1.0, 0.0], abs=1e-15)  # a vertical E-W plane
    dip, direction = dip_and_direction(-plane_normal([40.0, 60.0], [130.0, 220.0]))  # either sense
    assert dip == pytest.approx([40.0, 60.0]) and direction == pytest.approx([130.0, 220.0])


@pytest.mark.parametrize("kappa", [5.0, 50.0, 500.0])
def test_fisher_samples_have_the_closed_form_mean_resultant_length(kappa: float):
    n = 20_000
    mean = plane_normal(40.0, 130.0)
    x = fisher_directions(mean, kappa, n, np.random.default_rng(3))
    assert np.allclose(np.linalg.norm(x, axis=1), 1.0, atol=1e-14)
    w = x @ mean
    # E[cos θ] = coth κ - 1/κ (the Langevin function), Var = 1 - 2 E/κ - E² (Fisher, Lewis & Embleton 1987)
    e = 1.0 / np.tanh(kappa) - 1.0 / kappa
    sd = np.sqrt(1.0 - 2.0 * e / kappa - e * e)
    assert abs(w.mean() - e) < 5.0 * sd / np.sqrt(n)  # 5 standard errors: fails by chance with p < 1e-6
    # the sample's mean direction lies on the mean: the perpendicular part of the mean vector is noise,
    # Rayleigh-distributed with variance (1 - E[w²]) / 2n per axis; beyond 5 x its RMS with p = exp(-25)
    perp = x.mean(axis=0) - w.mean() * mean
    assert np.linalg.norm(perp) < 5.0 * np.sqrt((1.0 - (sd ** 2 + e ** 2)) / n)
    again = fisher_directions(mean, kappa, n, np.random.default_rng(3))
    assert np.array_equal(x, again)


def test_finite_discs_follow_the_boolean_model_count():
    rng_seed = 5
    js = JointSet3D(0.0, 0.0, 10.0, persistence=0.4, radius=1.0, origin=(0, 0, 5))  # one plane z = 5 in the box
    joints = joint_planes(box((0, 0, 0), (100, 100, 9))[0], [js], seed=rng_seed)
    assert np.all(joints.radius == 1.0) and np.allclose(joints.point[:, 2], 5.0)
    # Poisson count with mean λA, λ = -ln(1 - p)/(π r²) over the section grown by r: 102 x 102 m²
    expected = -np.log(0.6) / np.pi * 102 * 102
    assert abs(len(joints) - expected) < 5 * np.sqrt(expected)


def test_cut_blocks_go_straight_into_a_model():
    from srdda.cutmodel import add_cut_polyhedra
    from srdda.model import Material, Model, ModelError

    parts = _slope_parts()
    cut = cut_polyhedra(parts, joint_planes(parts[0][0], [JointSet3D(45, 270, 6.0), JointSet3D(90, 0, 7.0)]))
    model = Model(gravity=(0.0, 0.0, -9.81))
    model.add_material("rock", Material(2600.0, 1e10, 0.25))
    model.add_material("base", Material(2600.0, 1e10, 0.25))
    fixed = cut.block_part == 1
    idx = add_cut_polyhedra(model, cut, {0: "rock", 1: "base"}, fixed=fixed)
    assert idx == list(range(cut.n_blocks))
    arrays = model.arrays()
    volume = arrays.moments(arrays.vertex_position).volume
    assert volume == pytest.approx(cut.volumes(), rel=1e-12)  # the same blocks, renumbered faces at most
    assert np.array_equal(arrays.block_fixed, fixed) and np.array_equal(arrays.block_material, cut.block_part)
    with pytest.raises(ModelError, match=r"part\(s\) \[1\]"):
        add_cut_polyhedra(Model(), cut, {0: "rock"})


_CUT_FILE = """
gravity = [0, 0, -9.81]
[run]
dt = 1e-3
steps = 1
contacts = false
[materials.rock]
density = 2600
young = "10 GPa"
poisson = 0.25
[cutting]
seed = 4
fixed_box = [[-1, -1, -6], [41, 21, 0]]
[[cutting.domain]]
material = "rock"
vertices = [[10, 0, 0], [40, 0, 0], [40, 20, 0], [10, 20, 0], [21.547, 0, 20], [40, 0, 20], [40, 20, 20],
            [21.547, 20, 20]]
[[cutting.domain]]
material = "rock"
box = [[0, 0, -5], [40, 20, 0]]
[[cutting.joint_sets]]
dip = 35
dip_direction = 270
spacing = "300 cm"
kappa = 40
[[cutting.joints]]
point = [20, 10, 10]
dip = 60
dip_direction = 90
radius = 30
[[measured_points]]
at = [30, 10, 10]
block = "cut 3"
"""


def test_the_cutting_section_of_a_model_file_builds_the_cut_blocks():
    import tomllib

    from srdda.io.modelfile import ModelFileError, model_from_dict

    data = tomllib.loads(_CUT_FILE)
    parts = [convex_hull_polyhedron(data["cutting"]["domain"][0]["vertices"]), box((0, 0, -5), (40, 20, 0))]
    sets = [JointSet3D(35, 270, 3.0, kappa=40)]
    points = np.concatenate([p[0] for p in parts])
    disc = JointPlanes.of(plane_normal(60, 90), [20, 10, 10], 30.0)
    cut = cut_polyhedra(parts, JointPlanes.concatenate([joint_planes(points, sets, seed=4), disc]))
    data["measured_points"][0]["at"] = cut.centroids()[3].tolist()  # a point of the block it names (issue 32)
    model, _ = model_from_dict(data, "cut.toml")
    assert len(model.blocks) == cut.n_blocks > 10
    assert [b.name for b in model.blocks[:2]] == ["cut 0", "cut 1"]
    assert np.array_equal(np.concatenate([b.vertices for b in model.blocks]), cut.vertices)
    # the base slab's blocks (centroid below z = 0) are the fixed ones
    assert [b.fixed for b in model.blocks] == (cut.centroids()[:, 2] < 0).tolist()
    assert model.measured_points[0][0] == 3
    bad = tomllib.loads(_CUT_FILE)
    bad["cutting"]["domain"][1]["vertices"] = [[0, 0, 0]] * 4
    with pytest.raises(ModelFileError, match=r"cutting: domain\[1\]: give 'box', or 'vertices'"):
        model_from_dict(bad, "cut.toml")
    bad = tomllib.loads(_CUT_FILE)
    bad["cutting"]["domain"][0]["material"] = "granite"
    with pytest.raises(ModelFileError, match=r"domain\[0\].material: unknown material 'granite'"):
        model_from_dict(bad, "cut.toml")
    bad = tomllib.loads(_CUT_FILE)
    bad["cutting"]["joint_sets"][0]["dipp"] = 3
    with pytest.raises(ModelFileError, match=r"cutting.joint_sets\[0\].dipp: unknown field"):
        model_from_dict(bad, "cut.toml")
    del bad["cutting"]
    with pytest.raises(ModelFileError, match="no blocks"):
        model_from_dict(bad, "cut.toml")


def test_a_fragment_failing_validation_is_removed_and_reported():
    # the kernel's own checks leave no such fragment, so the reporting path is driven directly: a unit cube
    # and a "cube" squashed flat (zero volume) laid out as the kernel returns them
    from srdda.geometry.cutting3d import _subset, _validate

    cube_v, faces = box((0, 0, 0), (1, 1, 1))
    flat_v = cube_v * [1, 1, 0] + [2, 0, 0]
    vertices = np.vstack([cube_v, flat_v])
    block_ptr, face_first = np.array([0, 8, 16]), np.array([0, 6, 12])
    rings = [f for f in faces] * 2
    face_ptr = np.concatenate([[0], np.cumsum([len(f) for f in rings])])
    face_vertex = np.concatenate(rings)
    keep, rejected = _validate(vertices, block_ptr, face_first, face_ptr, face_vertex, np.array([0, 3]))
    assert keep.tolist() == [True, False] and len(rejected) == 1
    assert rejected[0].part == 3 and "fragment 1" in rejected[0].reason
    assert rejected[0].centroid == pytest.approx((2.5, 0.5, 0.0))
    out = _subset(keep, vertices, block_ptr, face_first, face_ptr, face_vertex, np.arange(12), np.array([0, 3]))
    assert np.array_equal(out[0], cube_v) and out[1].tolist() == [0, 8] and out[2].tolist() == [0, 6]
    assert np.array_equal(out[4], np.concatenate(faces)) and out[5].tolist() == list(range(6))


def test_model_add_polyhedra_checks_its_input_like_add_polyhedron():
    from srdda.model import Material, Model, ModelError

    model = Model(gravity=(0.0, 0.0, -9.81))
    model.add_material("rock", Material(2600.0, 1e10, 0.25))
    cube = box((0, 0, 0), (1, 1, 1))
    assert model.add_polyhedra([], [], [], []) == []
    with pytest.raises(ModelError, match="one material, name and fixed flag per block"):
        model.add_polyhedra([cube], ["rock", "rock"], ["a"], [False])
    with pytest.raises(ModelError, match="b: unknown material 'granite'"):
        model.add_polyhedra([cube, cube], ["rock", "granite"], ["a", "b"], [False, True])
    assert model.add_polyhedra([cube, box((1, 0, 0), (2, 1, 1))], ["rock"] * 2, ["a", "b"], [False, True]) == [0, 1]
    assert [b.fixed for b in model.blocks] == [False, True] and model.blocks[1].name == "b"
    flat = (cube[0] * [1, 1, 0], cube[1])
    with pytest.raises(PolyhedronError, match="block 'c'"):  # as add_polyhedron: the validation's own error
        model.add_polyhedra([flat], ["rock"], ["c"], [False])
    planar = Model()
    planar.add_material("rock", Material(2600.0, 1e10, 0.25))
    planar.add_block([[0, 0], [1, 0], [1, 1]], "rock")
    with pytest.raises(ModelError):
        planar.add_polyhedra([cube], ["rock"], ["d"], [False])
