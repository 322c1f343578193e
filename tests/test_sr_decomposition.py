"""Exact identities of Chen's S-R decomposition (paper Eqs. 11-16, A8-A10)."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from srdda.kinematics import chen_strain, mean_rotation, rotation_matrix, sr_decomposition, sr_decomposition_3d

# Tolerances: every identity below is exact in real arithmetic; 1e-14 allows
# a few ulps of round-off on entries of order one.
TOL = 1e-14

grads2 = arrays(np.float64, (2, 2), elements=st.floats(-0.4, 0.4))
grads3 = arrays(np.float64, (3, 3), elements=st.floats(-0.3, 0.3))


@given(grads2)
def test_2d_s_plus_r_is_f(g):
    S, R, _ = sr_decomposition(g)
    assert np.allclose(S + R, np.eye(2) + g, rtol=0, atol=TOL)
    assert np.allclose(S, S.T, rtol=0, atol=TOL)
    assert np.allclose(R @ R.T, np.eye(2), rtol=0, atol=TOL)
    assert abs(np.linalg.det(R) - 1) < TOL


@settings(max_examples=200)
@given(grads3)
def test_3d_s_plus_r_is_f(g):
    S, R, theta = sr_decomposition_3d(g)
    assert np.allclose(S + R, np.eye(3) + g, rtol=0, atol=1e-13)
    assert np.allclose(S, S.T, rtol=0, atol=TOL)
    assert np.allclose(R @ R.T, np.eye(3), rtol=0, atol=1e-13)
    assert abs(np.linalg.det(R) - 1) < 1e-13


@given(st.floats(-1.5, 1.5))
def test_2d_pure_rotation_has_zero_strain(theta):
    g = rotation_matrix(np.array([theta]))[0] - np.eye(2)
    S, _, th = sr_decomposition(g)
    assert np.allclose(S, 0, atol=TOL)
    assert abs(th - theta) < 1e-12  # arcsin near ±π/2 loses a few digits
    assert np.allclose(chen_strain(g), 0, atol=TOL)


@given(st.floats(0.0, 1.5), arrays(np.float64, 3, elements=st.floats(-1, 1)))
def test_3d_pure_rotation_has_zero_strain(theta, axis):
    n = np.linalg.norm(axis)
    if n < 1e-3:
        return
    k = axis / n
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    Rtrue = np.eye(3) + np.sin(theta) * K + (1 - np.cos(theta)) * K @ K  # Rodrigues
    S, R, th = sr_decomposition_3d(Rtrue - np.eye(3))
    assert np.allclose(S, 0, atol=1e-13)
    assert np.allclose(R, Rtrue, atol=1e-12)
    assert abs(th - theta) < 1e-10


def test_2d_formula_matches_3d_for_in_plane_gradients():
    rng = np.random.default_rng(3)
    for _ in range(50):
        g2 = rng.uniform(-0.3, 0.3, (2, 2))
        g3 = np.zeros((3, 3))
        g3[:2, :2] = g2
        S2, R2, t2 = sr_decomposition(g2)
        S3, R3, t3 = sr_decomposition_3d(g3)
        assert abs(abs(t2) - t3) < TOL
        assert np.allclose(R3[:2, :2], R2, atol=TOL)
        assert np.allclose(S3[:2, :2], S2, atol=TOL)


def test_mean_rotation_sign_is_counter_clockwise():
    th = mean_rotation(rotation_matrix(np.array([0.3]))[0] - np.eye(2))
    assert th > 0
