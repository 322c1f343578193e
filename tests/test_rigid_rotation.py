"""A freely spinning block: exact identities of the three kinematics."""
import numpy as np
import pytest

import srdda


def _spinner(method, n_steps, dt=1e-3, omega=1.0, shape=None):
    m = srdda.Model()
    m.add_material("rock", srdda.Material(density=2500.0, young=2e16, poisson=0.25))
    verts = shape if shape is not None else [[-0.5, -0.25], [0.5, -0.25], [0.5, 0.25], [-0.5, 0.25]]
    m.add_block(verts, "rock", angular_velocity=omega)
    return srdda.run(m, srdda.RunSettings(dt=dt, n_steps=n_steps, method=method))


def test_srdda_free_spinning_block_keeps_omega_and_area():
    # Acceptance: E = 2e16 Pa, ω0 = 1 rad/s, Δt = 1 ms, 10,000 steps, ω and area to 1e-10.
    r = _spinner("srdda", 10_000)
    w = r.array("velocity")[:, 0, 2]
    a = r.array("area")[:, 0]
    assert np.max(np.abs(w - 1.0)) <= 1e-10
    assert np.max(np.abs(a / a[0] - 1.0)) <= 1e-10
    # and it turned by ω·t = 10 rad (exactly, up to round-off of 1e4 additions)
    assert r.array("rotation")[-1, 0] == pytest.approx(10.0, rel=1e-12)


def test_dda1_spinning_block_keeps_area():
    r = _spinner("dda1", 2000)
    a = r.array("area")[:, 0]
    assert np.max(np.abs(a / a[0] - 1.0)) <= 1e-12


def test_dda0_area_grows_by_one_plus_dr_squared_per_step():
    # Shi's linear update maps the block by I + Δr·J (J the quarter turn): det = 1 + Δr².
    # With no forces Δr = ω Δt exactly each step, so A_n = A_0 (1 + (ωΔt)²)^n.
    dt, omega, n = 1e-2, 2.0, 500
    concave = [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]  # L-shape: the identity holds for any polygon
    r = _spinner("dda0", n, dt=dt, omega=omega, shape=concave)
    a = r.array("area")[:, 0]
    expected = a[0] * (1 + (omega * dt) ** 2) ** np.arange(n + 1)
    # round-off only: 1e-12 relative over 500 steps
    assert np.max(np.abs(a / expected - 1)) <= 1e-12


def test_objective_rotation_of_stress_and_strain_components():
    # srdda writes the co-moving stress (Eq. 50) back in global components as R σ Rᵀ;
    # strain-type components carry γ = 2 ε_xy. Exact identity up to round-off.
    from srdda.kinematics import rotate_symmetric_components, rotation_matrix

    rng = np.random.default_rng(0)
    comp = rng.normal(size=(20, 3))
    theta = rng.uniform(-3, 3, 20)
    R = rotation_matrix(theta)
    for factor in (1.0, 2.0):
        tensor = np.stack([np.stack([comp[:, 0], comp[:, 2] / factor], -1),
                           np.stack([comp[:, 2] / factor, comp[:, 1]], -1)], -2)
        expected = R @ tensor @ np.swapaxes(R, 1, 2)
        got = rotate_symmetric_components(comp, theta, factor)
        assert np.allclose(got[:, 0], expected[:, 0, 0], atol=1e-14)
        assert np.allclose(got[:, 1], expected[:, 1, 1], atol=1e-14)
        assert np.allclose(got[:, 2], factor * expected[:, 0, 1], atol=1e-14)
