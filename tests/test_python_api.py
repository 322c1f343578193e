"""The Python API for common models (issue 31 item 10): boxes, moving and turning a model or a group of blocks,
vertex and measured-point histories in the in-memory Result, block masses, named energy columns."""
from __future__ import annotations

from operator import attrgetter

import numpy as np
import pytest

import srdda
from srdda.geometry.polyhedron import box
from srdda.ledger import ENERGY_NAMES
from srdda.model import RENAMED_FIELDS, ModelError

G = 9.81


def _rock(dim: int = 2) -> srdda.Model:
    m = srdda.Model(gravity=(0.0, -G) if dim == 2 else (0.0, 0.0, -G))
    m.add_material("rock", srdda.Material(2500.0, 1e10, 0.25))
    return m


def test_add_box_is_the_box_polyhedron_and_its_mass_is_density_times_volume() -> None:
    a, b = _rock(3), _rock(3)
    a.add_box((0, 0, 0), (1, 2, 3), "rock", name="b")
    b.add_polyhedron(*box((0, 0, 0), (1, 2, 3)), "rock", name="b")
    np.testing.assert_array_equal(a.arrays().vertex_position, b.arrays().vertex_position)
    np.testing.assert_allclose(a.block_masses(), [2500.0 * 6.0], rtol=1e-12)
    with pytest.raises(ModelError, match="hi > lo"):
        a.add_box((0, 0, 0), (1, -1, 1), "rock")


def test_turning_a_2d_model_turns_vertices_velocities_stresses_and_points() -> None:
    m = _rock()
    m.add_block([[0, 0], [2, 0], [2, 1], [0, 1]], "rock", velocity=(1.0, 0.0), stress=(1e6, 0.0, 0.0), name="a")
    m.add_block([[3, 0], [4, 0], [4, 1], [3, 1]], "rock", name="b")
    m.add_measured_point([2.0, 1.0])
    m.add_fixed_point([3.5, 0.5])
    m.rotate(90.0, about=(0.0, 0.0), blocks=["a"])
    np.testing.assert_allclose(m.blocks[0].vertices[:, 0].min(), -1.0, atol=1e-15)
    np.testing.assert_allclose(m.blocks[0].velocity[:2], [0.0, 1.0], atol=1e-15)
    np.testing.assert_allclose(m.blocks[0].stress, [0.0, 1e6, 0.0], atol=1e-9)  # σx along the turned axis
    np.testing.assert_allclose(m.measured_points[0][1], [-1.0, 2.0], atol=1e-15)
    np.testing.assert_array_equal(m.fixed_points[0][1], [3.5, 0.5])  # on block b, which stays
    m.translate((10.0, 0.0))
    assert m.blocks[1].vertices[:, 0].min() == 13.0 and m.fixed_points[0][1][0] == 13.5
    np.testing.assert_allclose(m.block_masses(), [5000.0, 2500.0], rtol=1e-12)


def test_a_turned_model_is_an_incline_with_the_closed_form_acceleration() -> None:
    # a block on a flat base, the whole model turned by ψ = 30°: it slides with a = g (sin ψ − cos ψ tan φ)
    # (φ = 20°). Measured 4e-8 relative from the velocity between 0.1 s and 0.3 s (the springs settle first);
    # 1e-6 is 25 times that
    psi, phi = 30.0, 20.0
    m = _rock()
    m.add_joint_material("j", srdda.JointMaterial(friction_angle=phi), between=[("rock", "rock")])
    m.add_block([[-1, -1], [10, -1], [10, 0], [-1, 0]], "rock", fixed=True)
    m.add_block([[0, 0], [1, 0], [1, 0.5], [0, 0.5]], "rock")
    m.rotate(-psi)  # clockwise: the block slides towards +x, down the slope
    res = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=300, method="srdda", penalty=1e10))
    speed = np.linalg.norm(res.array("velocity")[:, 1, :2], axis=1)
    t = res.array("time")
    a = (speed[300] - speed[100]) / (t[300] - t[100])
    expected = G * (np.sin(np.radians(psi)) - np.cos(np.radians(psi)) * np.tan(np.radians(phi)))
    assert a == pytest.approx(expected, rel=1e-6)


def test_turning_a_3d_model_about_an_axis() -> None:
    m = _rock(3)
    m.add_box((0, 0, 0), (1, 1, 1), "rock", angular_velocity=(0.0, 0.0, 2.0))
    m.add_measured_point((1.0, 1.0, 1.0))
    m.rotate(90.0, axis=(1.0, 0.0, 0.0), about=(0.0, 0.0, 0.0))  # z -> -y, y -> z
    np.testing.assert_allclose(m.blocks[0].velocity[3:], [0.0, -2.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(m.measured_points[0][1], [1.0, -1.0, 1.0], atol=1e-15)
    with pytest.raises(ModelError, match="axis"):
        m.rotate(10.0, axis=(0.0, 0.0, 0.0))


def test_blocks_with_hinges_are_turned_before_the_hinges_are_added() -> None:
    m = _rock()
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock")
    m.add_pin([0.0, 0.0])
    with pytest.raises(ModelError, match="before adding hinges"):
        m.rotate(10.0)


def test_the_result_keeps_vertex_and_measured_point_histories_and_energy_names() -> None:
    m = _rock()
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock", velocity=(1.0, 2.0))
    m.add_measured_point([1.0, 1.0])
    res = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=20, method="srdda"))
    verts = res.array("vertices")
    assert verts.shape == (21, 4, 2)
    np.testing.assert_array_equal(verts[-1], res.final_state.vertices)
    position, velocity = res.measured(0)
    np.testing.assert_allclose(position[-1], verts[-1][2], atol=1e-12)  # the corner (1, 1) is vertex 2
    t = res.array("time")
    np.testing.assert_allclose(position[:, 1], 1.0 + 2.0 * t - 0.5 * G * t**2, rtol=1e-9)  # free fall, exact
    np.testing.assert_allclose(velocity[:, 0], 1.0, rtol=1e-12)
    assert res.energy_names == ENERGY_NAMES
    energies = res.energies()
    np.testing.assert_array_equal(energies["kinetic"], res.array("energy")[:, res.energy_names.index("kinetic")])
    no_vertices = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=2, method="srdda"), keep_vertices=False)
    assert no_vertices.array("vertices").shape == (3, 0, 2)


def test_the_model_arrays_names_of_srdda_0_1_still_read_with_a_deprecation_warning() -> None:
    m = _rock()
    m.add_block([[0, 0], [2, 0], [2, 1], [0, 1]], "rock", name="a")
    m.add_block([[3, 0], [4, 0], [4, 1], [3, 1]], "rock", name="b")
    m.add_fixed_point([0.5, 0.5], stiffness=1e9)
    m.add_point_load([1.5, 0.5], [0.0, -1e3])
    m.add_point_spring([1.0, 1.0], [3.5, 1.0], 1e6)
    m.add_measured_point([3.5, 0.5])
    arrays = m.arrays()
    assert len(RENAMED_FIELDS) == 18
    for old, new in RENAMED_FIELDS.items():
        with pytest.warns(DeprecationWarning, match=rf"ModelArrays\.{old} is deprecated .*: use ModelArrays\.{new}$"):
            value = getattr(arrays, old)
        assert value is attrgetter(new)(arrays), old  # the same array, not a copy
    # the point rows as srdda 0.1 laid them out: fixed points, loads, spring ends a, ends b, measured points
    with pytest.warns(DeprecationWarning):
        rows = [arrays.fixed_rows, arrays.load_rows, arrays.spring_rows_a, arrays.spring_rows_b, arrays.measured_rows]
    assert [r.tolist() for r in rows] == [[0], [1], [2], [3], [4]]
    with pytest.raises(AttributeError):
        arrays.vertices = arrays.vertex_position  # read-only
