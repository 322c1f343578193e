"""Property-based runs (hypothesis): random valid models run without error and conserve what they must.

Random convex blocks (a random number of vertices on a randomly stretched
circle), random initial velocities and spins, random methods:

* in free flight under gravity, mass is kept exactly and linear momentum
  follows m(v0 + g t) to round-off, and exact-rotation methods keep the area;
* dropped on a fixed base, the total energy (kinetic + potential + strain +
  springs + contacts) never rises above its initial value by more than 1e-6 of
  the block's weight × its drop height (contacts dissipate or store energy;
  they never create it).
"""
from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

import srdda
from srdda.assembly.blocks import mass_matrices

G = -9.81


@st.composite
def convex_block(draw):
    n = draw(st.integers(3, 9))
    angles = np.sort(np.array(draw(st.lists(st.floats(0, 2 * np.pi, exclude_max=True), min_size=n, max_size=n,
                                            unique=True))))
    assume(np.min(np.diff(np.append(angles, angles[0] + 2 * np.pi))) > 0.05)  # distinct, well-shaped corners
    stretch = draw(st.floats(0.3, 1.0))
    size = draw(st.floats(0.2, 2.0))
    points = size * np.column_stack([np.cos(angles), stretch * np.sin(angles)])
    area = 0.5 * abs(np.sum(points[:, 0] * np.roll(points[:, 1], -1) - np.roll(points[:, 0], -1) * points[:, 1]))
    assume(area > 1e-2 * size**2)
    return points


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(block=convex_block(), v=st.tuples(st.floats(-5, 5), st.floats(-5, 5)), omega=st.floats(-5, 5),
       method=st.sampled_from(["dda0", "dda1", "srdda"]))
def test_free_flight_keeps_mass_and_momentum(block, v, omega, method):
    m = srdda.Model(gravity=(0.0, G))
    m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
    m.add_block(block, "rock", velocity=v, angular_velocity=omega)
    arrays = m.arrays()
    result = srdda.run(arrays, srdda.RunSettings(dt=1e-3, n_steps=200, method=method), keep_history=False)
    assert result.completed, result.status
    state = result.final_state
    mass = mass_matrices(arrays, state)[:, 0, 0]
    np.testing.assert_allclose(mass, arrays.block_mass, rtol=1e-12)  # ρ(t)·A(t) returns m to rounding
    momentum = np.einsum("nij,nj->ni", mass_matrices(arrays, state), state.velocity)[0, :2]
    expected = arrays.block_mass[0] * (np.array(v) + np.array([0.0, G]) * state.time)
    # 1e-12 of the largest momentum (plus 1e-9 kg·m/s for a block thrown at rest): 200 exact steps, rounding
    np.testing.assert_allclose(momentum, expected, rtol=0, atol=1e-12 * np.abs(expected).max() + 1e-9)
    if method != "dda0":  # exact rotation: the area stays (elastic strain under no load: rounding)
        np.testing.assert_allclose(state.moments.area, arrays.moments(arrays.vertex_position).area, rtol=1e-10)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(block=convex_block(), height=st.floats(0.05, 0.5), vx=st.floats(-2, 2), omega=st.floats(-3, 3),
       turn=st.floats(0, 2 * np.pi), method=st.sampled_from(["dda1", "srdda"]))
# found by a random search: a glancing impact whose friction was extrapolated past the step's normal
# force and then held against a reversed slip (fixed in srdda.contact.term; 11.7 kJ created before)
@example(block=np.array([[1.46337774, 0.68163876], [-1.05253267, 0.85031979], [0.56732437, -0.95892427]]),
         height=0.25, vx=-1.0, omega=0.0, turn=3.65625, method="dda1")
def test_a_dropped_block_never_creates_energy(block, height, vx, omega, turn, method):
    c, s = np.cos(turn), np.sin(turn)
    shape = block @ np.array([[c, s], [-s, c]])
    shape = shape - [0.0, shape[:, 1].min() - height]  # lowest vertex `height` above the base
    m = srdda.Model(gravity=(0.0, G))
    m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
    m.add_joint_material("j", srdda.JointMaterial(friction_angle=30.0), between=[("rock", "rock")])
    m.add_block([[-10, -1], [10, -1], [10, 0], [-10, 0]], "rock", fixed=True)
    m.add_block(shape, "rock", velocity=(vx, 0.0), angular_velocity=omega)
    result = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=600, method=method, penalty=1e11))
    assert result.completed, result.status
    energy = result.array("energy")
    total = energy[:, list(result.energy[0]).index("total")]
    weight = abs(G) * m.arrays().block_mass[1]
    assert np.max(total - total[0]) <= 1e-6 * weight * (height + np.ptp(shape[:, 1]))
