"""Closed forms of the 3D rock-slope checks (srdda.apps.verify.cases.slope3d) against independent computations."""
from __future__ import annotations

import numpy as np
import pytest

from srdda.apps.verify.cases.slope3d import (G, SLIDE_TOPPLE_CASES, WEDGE_PLANES, block_on_incline_model, incline_acceleration,
                                 slide_topple_mode, slide_topple_model, toppling_angular_acceleration,
                                 wedge_friction_for, wedge_model, wedge_solution)
from srdda.geometry.jointsets3d import plane_normal
from srdda.geometry.polyhedron import polyhedron_covers


@pytest.mark.parametrize("psi, phi", [(30.0, 20.0), (30.0, 30.0), (25.0, 40.0), (60.0, 10.0)])
def test_incline_acceleration_is_newtons_law_along_the_plane(psi: float, phi: float):
    # vectors: gravity split along the plane's normal; friction tan φ x the normal force opposes sliding
    n = plane_normal(psi, 90.0)
    g = np.array([0.0, 0.0, -G])
    tangential = np.linalg.norm(g - (g @ n) * n)
    expected = max(0.0, tangential - np.tan(np.radians(phi)) * -(g @ n))
    assert incline_acceleration(psi, phi) == pytest.approx(expected, rel=1e-14, abs=1e-14)


def test_slide_topple_chart_regions_and_boundaries():
    assert [c.mode for c in SLIDE_TOPPLE_CASES] == [c.name for c in SLIDE_TOPPLE_CASES]
    assert len({c.mode for c in SLIDE_TOPPLE_CASES}) == 4
    assert slide_topple_mode(30.0, 30.0, 1.0, 1.0) == "stable"  # tan φ = tan ψ: at rest (limit equilibrium)
    t = np.tan(np.radians(30.0))
    assert slide_topple_mode(30.0, 40.0, t * (1 + 1e-9), 1.0) == "stable"
    assert slide_topple_mode(30.0, 40.0, t * (1 - 1e-9), 1.0) == "topples"


@pytest.mark.parametrize("case", SLIDE_TOPPLE_CASES, ids=lambda c: c.name)
def test_toppling_acceleration_against_the_model_geometry(case):
    # independent: the moment of gravity about the block's down-dip base edge and the block's inertia about
    # that edge, both from the built polyhedron (exact moments, parallel-axis theorem)
    model = slide_topple_model(case)
    arrays = model.arrays()
    mom = arrays.moments(arrays.vertex_position)
    volume, centroid, second = mom.volume[0], mom.centroid[0], mom.second[0]
    block = model.blocks[0].vertices
    p = np.radians(case.psi)
    dip = np.array([np.cos(p), 0.0, -np.sin(p)])
    pivot = block[np.argmax(block @ dip - 1e-6 * (block @ plane_normal(case.psi, 90.0)))]  # lowest down-dip vertex
    axis = np.array([0.0, 1.0, 0.0])
    r = centroid - pivot
    torque = np.cross(r, volume * np.array([0.0, 0.0, -G])) @ axis
    j_centroid = axis @ (np.trace(second) * np.eye(3) - second) @ axis
    j_edge = j_centroid + volume * (r @ r - (r @ axis) ** 2)
    assert toppling_angular_acceleration(case.psi, case.base, case.height) == pytest.approx(torque / j_edge,
                                                                                             rel=1e-12)
    assert (torque > 0) == ("topples" in case.mode)


def _direct_wedge(plane_a, plane_b, phi):
    """Equilibrium by one 3 x 3 solve: N_A n_A + N_B n_B + T l = -W, T the force needed along the line l."""
    na, nb = plane_normal(*plane_a), plane_normal(*plane_b)
    line = np.cross(na, nb)
    line = line / np.linalg.norm(line) * (-1 if line[2] > 0 else 1)
    n_a, n_b, t = np.linalg.solve(np.column_stack([na, nb, line]), -np.array([0.0, 0.0, -1.0]))
    return n_a, n_b, -t, (n_a + n_b) * np.tan(np.radians(phi)) / -t  # T < 0: it must hold the wedge up


@pytest.mark.parametrize("plane_a, plane_b", [WEDGE_PLANES, ((45.0, 105.0), (70.0, 235.0)),
                                              ((50.0, 150.0), (55.0, 210.0)), ((35.0, 100.0), (80.0, 250.0))])
def test_wedge_solution_against_a_direct_vector_equilibrium(plane_a, plane_b):
    s = wedge_solution(plane_a, plane_b, 30.0)
    n_a, n_b, drive, fs = _direct_wedge(plane_a, plane_b, 30.0)
    assert s.is_wedge
    # rounding only: both are a few dozen floating-point operations on unit vectors
    assert (s.normal_a, s.normal_b) == pytest.approx((n_a, n_b), rel=1e-12)
    assert np.sin(np.radians(s.plunge)) == pytest.approx(drive, rel=1e-12)
    assert s.factor_of_safety == pytest.approx(fs, rel=1e-12)


def test_the_issue_wedge_and_its_friction_angles():
    s = wedge_solution(*WEDGE_PLANES, 30.0)
    assert s.plunge == pytest.approx(37.058, abs=1e-3) and s.trend == pytest.approx(155.848, abs=1e-3)
    for fs in (1.2, 0.8):
        phi = wedge_friction_for(fs)
        sol = wedge_solution(*WEDGE_PLANES, phi)
        assert sol.factor_of_safety == pytest.approx(fs, rel=1e-12)
        # sliding along the line with both planes in contact: a = g sin ψ_i (1 - FS), zero when it holds
        expected = G * np.sin(np.radians(sol.plunge)) * (1 - fs) if fs < 1 else 0.0
        assert sol.acceleration == pytest.approx(expected, rel=1e-12, abs=1e-15)
    assert wedge_friction_for(1.2) == pytest.approx(38.31, abs=0.01)
    assert wedge_friction_for(0.8) == pytest.approx(27.77, abs=0.01)


def test_wedge_limits_planar_sliding_and_symmetric_wedge_factor():
    # a vertical release plane along A's dip direction: all the weight on A, planar sliding on A
    s = wedge_solution((35.0, 120.0), (90.0, 210.0), 25.0)
    assert s.plunge == pytest.approx(35.0, abs=1e-12) and s.trend == pytest.approx(120.0, abs=1e-12)
    assert s.normal_b == pytest.approx(0.0, abs=1e-15)
    assert s.factor_of_safety == pytest.approx(np.tan(np.radians(25)) / np.tan(np.radians(35)), rel=1e-12)
    assert s.acceleration == pytest.approx(incline_acceleration(35.0, 25.0), rel=1e-12)
    # two planes of the same strike (dipping the same way): their line is horizontal, nothing drives it
    s = wedge_solution((30.0, 90.0), (60.0, 90.0), 10.0)
    assert s.plunge == pytest.approx(0.0, abs=1e-12) and s.acceleration == 0.0
    # a symmetric wedge: N_A + N_B = K W cos ψ_i with Hoek & Bray's wedge factor K = sin β / sin(ξ/2),
    # β = 90° (the bisecting plane is vertical) and ξ = 180° - the angle between the normals
    for dip, half in ((50.0, 30.0), (60.0, 45.0), (45.0, 10.0)):
        s = wedge_solution((dip, 180.0 - half), (dip, 180.0 + half), 20.0)
        xi = np.pi - np.arccos(plane_normal(dip, 180.0 - half) @ plane_normal(dip, 180.0 + half))
        k = 1.0 / np.sin(xi / 2)
        assert s.normal_a == pytest.approx(s.normal_b, rel=1e-12)
        assert s.normal_a + s.normal_b == pytest.approx(k * np.cos(np.radians(s.plunge)), rel=1e-12)


def test_wedge_model_geometry():
    model = wedge_model(wedge_friction_for(1.2))
    assert [b.name for b in model.blocks] == ["wedge", "plane A", "plane B"]
    wedge, slab_a, slab_b = model.blocks
    na, nb = plane_normal(*WEDGE_PLANES[0]), plane_normal(*WEDGE_PLANES[1])
    tol = 1e-9 * 6.0  # the validation's planarity tolerance at the wedge's size
    # separated: the wedge above both planes, each slab below its plane, the slabs on either side of the
    # vertical plane through the line of intersection
    assert np.all(wedge.vertices @ na > -tol) and np.all(wedge.vertices @ nb > -tol)
    assert np.all(slab_a.vertices @ na < tol) and np.all(slab_b.vertices @ nb < tol)
    side = np.cross(wedge_solution(*WEDGE_PLANES, 30.0).line, [0.0, 0.0, 1.0])
    sa, sb = slab_a.vertices @ side, slab_b.vertices @ side
    assert (sa.min() > -tol and sb.max() < tol) or (sa.max() < tol and sb.min() > -tol)
    # the wedge's faces on A and B rest on the slabs: every wedge vertex on a plane lies on that slab
    on_a = np.abs(wedge.vertices @ na) < tol
    on_b = np.abs(wedge.vertices @ nb) < tol
    assert on_a.sum() == 3 and on_b.sum() == 3
    assert all(polyhedron_covers(slab_a.vertices, slab_a.faces, p) for p in wedge.vertices[on_a])
    assert all(polyhedron_covers(slab_b.vertices, slab_b.faces, p) for p in wedge.vertices[on_b])
    # a tetrahedron: apex at the origin, three vertices on the top z = 6; volume by the determinant
    v = wedge.vertices[np.argsort(wedge.vertices[:, 2])]
    assert v[0] == pytest.approx([0, 0, 0], abs=tol) and v[1:, 2] == pytest.approx([6.0] * 3)
    arrays = model.arrays()
    assert arrays.moments(arrays.vertex_position).volume[0] == pytest.approx(
        abs(np.linalg.det(v[1:] - v[0])) / 6.0, rel=1e-12)
    assert arrays.block_fixed.tolist() == [False, True, True]


def test_block_on_incline_model_rests_on_its_slab():
    model = block_on_incline_model(30.0, 20.0, base=1.0, height=2.0, width=1.5)
    block, slab = model.blocks
    n = plane_normal(30.0, 90.0)
    assert np.sort(block.vertices @ n) == pytest.approx([0.0] * 4 + [2.0] * 4, abs=1e-14)
    assert np.max(slab.vertices @ n) == pytest.approx(0.0, abs=1e-14)
    arrays = model.arrays()
    assert arrays.moments(arrays.vertex_position).volume[0] == pytest.approx(3.0, rel=1e-14)
    assert arrays.block_fixed.tolist() == [False, True]
    assert model.joint_materials["joint"].friction_angle == 20.0
