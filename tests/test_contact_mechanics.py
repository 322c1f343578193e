"""Contact mechanics against closed forms: sliding on an incline, a block at rest,
cohesion and tensile strength, joint material per edge."""
import numpy as np
import pytest

import srdda
from srdda.model import JointMaterial

METHODS = ("dda0", "dda1", "srdda")
G = 10.0
ALPHA = np.radians(30.0)


def _rotate(points, angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.asarray(points, dtype=float) @ np.array([[c, -s], [s, c]]).T


def _incline_model(phi=0.0, cohesion=0.0, edge_phi=None):
    """A 1 x 0.5 m block (1250 kg) on a fixed 30° incline, touching it at t = 0."""
    m = srdda.Model(gravity=(0.0, -G))
    m.add_material("rock", srdda.Material(density=2500.0, young=1e9, poisson=0.25))
    m.add_joint_material("joint", JointMaterial(friction_angle=phi, cohesion=cohesion), between=[("rock", "rock")])
    edge_joints = None
    if edge_phi is not None:
        m.add_joint_material("rough", JointMaterial(friction_angle=edge_phi))
        edge_joints = [None, None, "rough", None]  # edge 2 = the top face (6, 0) -> (-6, 0)
    m.add_block(_rotate([[-6, -1], [6, -1], [6, 0], [-6, 0]], ALPHA), "rock", fixed=True, edge_joints=edge_joints)
    m.add_block(_rotate([[0, 0], [1, 0], [1, 0.5], [0, 0.5]], ALPHA), "rock")
    return m


def _travel(model, method, t_end=1.0, dt=1e-3):
    res = srdda.run(model, srdda.RunSettings(dt=dt, n_steps=int(round(t_end / dt)), method=method, penalty=1e10))
    assert res.completed, res.status
    c = res.array("centroid")[:, 1]
    return float(np.linalg.norm(c[-1] - c[0])), res


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("phi", [0.0, 10.0, 20.0])
def test_block_slides_down_incline_as_coulomb_says(method, phi):
    # Acceptance: within 0.5% of ½ g (sin α - cos α tan φ) t² after 1 s. The friction force uses
    # the normal force of the previous solve (Shi), which is constant on a steady incline, so the
    # error is the one-step lag at the start and the contact springs' elastic settling (~1e-3).
    d, res = _travel(_incline_model(phi), method)
    t = res.time[-1]
    exact = 0.5 * G * (np.sin(ALPHA) - np.cos(ALPHA) * np.tan(np.radians(phi))) * t**2
    assert abs(d / exact - 1) < 5e-3


@pytest.mark.parametrize("method", METHODS)
def test_block_sticks_on_incline_above_friction_angle(method):
    # Acceptance: φ = 35° > 30°: moves less than 1e-4 m in 1 s (only the shear springs' elastic
    # deflection, m g sin α / (2 k_s) = 1.6e-6 m, and its oscillation).
    d, _ = _travel(_incline_model(35.0), method)
    assert d < 1e-4


@pytest.mark.parametrize("method", METHODS)
def test_block_resting_on_fixed_base(method):
    # Acceptance: 1000 steps at rest: drift < 1e-5 m, rotation < 1e-6 rad. Static settling of the
    # contact springs is m g / (2 k_n) = 6e-7 m (x2 dynamic overshoot from the release).
    m = srdda.Model(gravity=(0.0, -G))
    m.add_material("rock", srdda.Material(density=2500.0, young=1e9, poisson=0.25))
    m.add_joint_material("joint", JointMaterial(friction_angle=30.0), between=[("rock", "rock")])
    m.add_block([[-2, -1], [2, -1], [2, 0], [-2, 0]], "rock", fixed=True)
    m.add_block([[0, 0], [1, 0], [1, 0.5], [0, 0.5]], "rock")
    res = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=1000, method=method, penalty=1e10))
    assert res.completed
    c = res.array("centroid")[:, 1]
    assert np.max(np.linalg.norm(c - c[0], axis=1)) < 1e-5
    assert np.max(np.abs(res.array("rotation")[:, 1])) < 1e-6
    base = res.array("centroid")[:, 0]
    assert np.array_equal(base, np.broadcast_to(base[0], base.shape))  # the fixed block never moves


@pytest.mark.parametrize("cohesion, holds", [(10e3, True), (5e3, False)])
def test_cohesion_holds_until_exceeded_then_is_lost(cohesion, holds):
    # Two corner contacts share the 1 m base: bond length 0.5 m each, shear load m g sin α / 2
    # = 3125 N each; strength c·0.5 m = 5000 N (holds) or 2500 N (breaks). Once broken the joint
    # has φ = 0 and no cohesion left: the block slides as if frictionless.
    d, res = _travel(_incline_model(0.0, cohesion), "srdda")
    if holds:
        assert d < 1e-4
    else:
        t = res.time[-1]
        assert abs(d / (0.5 * G * np.sin(ALPHA) * t**2) - 1) < 5e-3


@pytest.mark.parametrize("tensile, holds", [(20e3, True), (10e3, False)])
def test_tensile_strength_holds_a_hanging_block(tensile, holds):
    # A 1 x 0.5 m block (12500 N) hangs under a fixed ceiling: 6250 N of tension at each of the
    # two corner contacts (bond length 0.5 m): strength 10000 N holds, 5000 N fails and the block
    # then falls freely (tension is lost once the contact opens). The glue has some cohesion too:
    # a joint without shear strength slides under any shear, however small, and so breaks.
    m = srdda.Model(gravity=(0.0, -G))
    m.add_material("rock", srdda.Material(density=2500.0, young=1e9, poisson=0.25))
    m.add_joint_material("glue", JointMaterial(cohesion=1e4, tensile_strength=tensile), between=[("rock", "rock")])
    m.add_block([[-2, 0], [2, 0], [2, 1], [-2, 1]], "rock", fixed=True)
    m.add_block([[0, -0.5], [1, -0.5], [1, 0], [0, 0]], "rock")
    res = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=300, method="srdda", penalty=1e10))
    assert res.completed
    drop = res.array("centroid")[0, 1, 1] - res.array("centroid")[-1, 1, 1]
    if holds:
        assert drop < 1e-4
    else:
        t = res.time[-1]
        assert abs(drop / (0.5 * G * t**2) - 1) < 1e-2  # the first step's release costs < 1%


def test_joint_material_chosen_per_edge():
    # The materials map says φ = 0, but the incline's top face carries a 35° joint: it sticks.
    d, _ = _travel(_incline_model(0.0, edge_phi=35.0), "srdda", t_end=0.5)
    assert d < 1e-4
    d_free, res = _travel(_incline_model(0.0), "srdda", t_end=0.5)
    assert abs(d_free / (0.5 * G * np.sin(ALPHA) * res.time[-1] ** 2) - 1) < 5e-3


def _spinning_corner_impact():
    """A 1 x 0.5 m block tilted 20°, its lowest corner on a fixed base, spinning into it at 8 rad/s."""
    m = srdda.Model(gravity=(0.0, -G))
    m.add_material("rock", srdda.Material(density=2500.0, young=1e10, poisson=0.25))
    m.add_joint_material("joint", JointMaterial(friction_angle=30.0), between=[("rock", "rock")])
    m.add_block([[-3, -1], [3, -1], [3, 0], [-3, 0]], "rock", fixed=True)
    m.add_block(_rotate([[0, 0], [1, 0], [1, 0.5], [0, 0.5]], np.radians(20.0)), "rock", velocity=(0.5, -0.5),
                angular_velocity=8.0)
    return m


@pytest.mark.parametrize("method, bound", [("srdda", 1e-12), ("dda0", 1e-12)])
def test_contact_sees_the_displacement_the_update_makes(method, bound):
    # The end-of-step gap the contact springs were solved for (linear in Δd through the method's
    # shape function) against the gap of the vertex where the update actually put it. Under
    # srdda the contact uses T_sec at the converged rotation increment, so the two agree to
    # rounding (the secant loop stops at |Δθ|·|δθ| < 1e-13); dda0 moves vertices by T·Δd itself.
    # Under dda1 (Shi's T, exact-rotation update) they differ by about r·Δθ²/2 = 2e-6 m.
    model = _spinning_corner_impact()
    res = srdda.run(model, srdda.RunSettings(dt=2e-3, n_steps=1, method=method, penalty=1e10))
    state, c = res.final_state, res.final_state.contacts
    arrays = model.arrays()
    vertex, edge = c.features[:, 0], c.features[:, 1]  # the 2D detector's [vertex, edge start, kind]
    p0 = state.vertices[edge]
    d = state.vertices[arrays.vertex_next[edge]] - p0
    normal = np.column_stack([d[:, 1], -d[:, 0]]) / np.linalg.norm(d, axis=1)[:, None]
    actual = np.einsum("nk,nk->n", state.vertices[vertex] - p0, normal)
    assert np.all(c.closed) and np.all(c.gap < 0)  # the corner was driven into the base
    assert np.max(np.abs(c.gap - actual)) < bound
    if method == "srdda":
        dda1 = srdda.run(model, srdda.RunSettings(dt=2e-3, n_steps=1, method="dda1", penalty=1e10)).final_state
        actual1 = np.einsum("nk,nk->n", dda1.vertices[dda1.contacts.features[:, 0]] - p0, normal)
        assert np.max(np.abs(dda1.contacts.gap - actual1)) > 1e-7  # the test can tell the difference
