"""Joint stiffness per unit area (Pa/m) means the same in 2D and 3D (issue 28 item 6).

A block resting on a base whose joint gives k_n (Pa/m) settles by its weight over k_n × its bearing area:
in 2D the bearing length × the unit thickness, in 3D the bearing area. Shi's static analysis
(velocity_ratio = 0: every step starts at rest) reaches that equilibrium without dynamics: the step's inertia
term 2M/Δt² = 1e10 N/m against the joint's 4e9-9e9 N/m leaves 0.7 of the imbalance a step, 1e-15 after 100 steps.
"""
from __future__ import annotations

import numpy as np
import pytest

import srdda
from srdda.contact import ContactModel, ContactParameters
from srdda.io.modelfile import model_from_dict

G = 9.81
KN = 2e9  # Pa/m: a rock joint (tens of GPa/m is typical); soft enough that the settlement is well resolved


def _resting(dim: int, joint: srdda.JointMaterial) -> srdda.Model:
    """A 2 m wide block (2D; 2 × 1.5 m in 3D), 1 m high, density 2500 kg/m³, on a fixed base."""
    m = srdda.Model(gravity=(0.0, -G) if dim == 2 else (0.0, 0.0, -G))
    m.add_material("rock", srdda.Material(2500.0, 1e12, 0.25))  # stiff blocks: the joint alone settles
    m.add_joint_material("joint", joint, between=[("rock", "rock")])
    if dim == 2:
        m.add_block([[-3, -1], [3, -1], [3, 0], [-3, 0]], "rock", fixed=True)
        m.add_block([[0, 0], [2, 0], [2, 1], [0, 1]], "rock")
    else:
        m.add_box([-3, -3, -1], [3, 3, 0], "rock", fixed=True)
        m.add_box([0, 0, 0], [2, 1.5, 1], "rock")
    return m


@pytest.mark.parametrize("dim, area", [(2, 2.0 * 1.0), (3, 2.0 * 1.5)])
def test_a_block_settles_by_its_weight_over_the_joint_stiffness_times_its_area(dim, area):
    model = _resting(dim, srdda.JointMaterial(friction_angle=30.0, normal_stiffness=KN))
    run = srdda.run(model, srdda.RunSettings(dt=1e-3, n_steps=100, velocity_ratio=0.0))
    assert run.completed, run.status
    contacts = run.final_state.contacts
    weight = 2500.0 * area * 1.0 * G  # 2D: per metre of thickness
    # the normal forces carry the weight, and the joint's stiffness over the bearing area sets the settlement;
    # 1e-6 relative: the static steps reach equilibrium to the solve's rounding, the springs to the last step's
    assert contacts.normal_force.sum() == pytest.approx(weight, rel=1e-6)
    closed = contacts.state != 0
    settlement = -np.mean(contacts.gap[closed])
    assert settlement == pytest.approx(weight / (KN * area), rel=1e-6)


@pytest.mark.parametrize("dim", [2, 3])
def test_contacts_stand_for_their_share_of_the_joint_and_take_its_own_shear_stiffness(dim):
    # face to face, the corner contacts' tributary sizes add up to the bearing area; the shear stiffness is the
    # joint's (not shear_ratio × k_n) when it gives one; without stiffnesses the run's penalty is used as it was
    model = _resting(dim, srdda.JointMaterial(normal_stiffness=KN, shear_stiffness=0.1 * KN))
    arrays = model.arrays()
    params = ContactParameters(5e9, 2e9, 0.02, np.radians(3.0), 0.008)
    cm = ContactModel(arrays, params)
    step = cm.prepare(arrays.vertex_position, None, first_step=True)
    area = 2.0 if dim == 2 else 3.0
    on_base = step.record.block_b == 0
    assert step.record.tributary[on_base].sum() == pytest.approx(area, rel=1e-12)
    np.testing.assert_allclose(step.response.normal_stiffness, KN * step.record.tributary, rtol=1e-15)
    np.testing.assert_allclose(step.response.shear_stiffness, 0.1 * KN * step.record.tributary, rtol=1e-15)
    resting = _resting(dim, srdda.JointMaterial()).arrays()
    plain = ContactModel(resting, params).prepare(arrays.vertex_position, None, True)
    assert np.all(plain.response.normal_stiffness == 5e9) and np.all(plain.response.shear_stiffness == 2e9)


def test_a_corner_on_a_face_stands_for_the_smallest_share_at_its_corner():
    # a square tilted 30° touches the base with one corner: no edge lies on the base (no bond), and it
    # stands for half its shorter edge at that corner (0.5 m of a 1 m square) times the unit thickness
    m = srdda.Model(gravity=(0.0, -G))
    m.add_material("rock", srdda.Material(2500.0, 1e10, 0.25))
    m.add_joint_material("joint", srdda.JointMaterial(normal_stiffness=KN), between=[("rock", "rock")])
    m.add_block([[-3, -1], [3, -1], [3, 0], [-3, 0]], "rock", fixed=True)
    c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    m.add_block(np.array([[0, 0], [1, 0], [1, 1], [0, 1]]) @ np.array([[c, -s], [s, c]]).T + [0, 0.001], "rock")
    arrays = m.arrays()
    step = ContactModel(arrays, ContactParameters(1e9, 4e8, 0.02, np.radians(3.0), 0.008)).prepare(
        arrays.vertex_position, None, True)
    assert len(step.record) == 1 and step.record.bond[0] == 0.0
    assert step.record.tributary[0] == pytest.approx(0.5, rel=1e-12)


def test_a_model_file_gives_joint_stiffnesses_with_units():
    spec = {"gravity": [0.0, -9.81], "run": {"dt": 1e-3, "steps": 1},
            "materials": {"rock": {"density": 2500.0, "young": 1e10, "poisson": 0.25}},
            "joint_materials": {"j": {"friction_angle": 30.0, "normal_stiffness": "2 GPa/m",
                                      "shear_stiffness": "200 MPa/m", "between": [["rock", "rock"]]}},
            "blocks": [{"material": "rock", "vertices": [[0, 0], [1, 0], [1, 1], [0, 1]]}]}
    model, _ = model_from_dict(spec, source="test")
    joint = model.joint_materials["j"]
    assert (joint.normal_stiffness, joint.shear_stiffness) == (2e9, 2e8)
    with pytest.raises(srdda.ModelError, match="shear_stiffness needs a normal_stiffness"):
        srdda.JointMaterial(shear_stiffness=1e9)
