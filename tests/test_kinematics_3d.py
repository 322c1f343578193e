"""3D kinematics (paper Appendix, Eqs. A1-A10): shape function, mass matrix, elasticity, Rodrigues
rotations, the secant shape function, point updates and their S-R decomposition."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial import Delaunay

from srdda.geometry import PolyhedronMesh, box, polyhedron_moments, prism
from srdda.kinematics import (
    NDOF_3D,
    block_mass_matrix,
    block_mass_matrix_3d,
    compose_rotations,
    elasticity_matrix_3d,
    point_displacement_3d,
    rotate_symmetric_components,
    rotate_symmetric_components_3d,
    rotation_matrix,
    rotation_matrix_3d,
    secant_shape_function,
    secant_shape_function_3d,
    shape_function_3d,
    sr_decomposition_3d,
    strain_selector_3d,
)

RNG = np.random.default_rng(12)
L_SHAPE = [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]
vectors = arrays(np.float64, 3, elements=st.floats(-1.5, 1.5))


def _skew(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def test_shape_function_is_eq_a1():
    X, Y, Z = 0.3, -1.2, 2.5
    T = shape_function_3d(np.array([[X, Y, Z]]))[0]
    # Eq. A1 written out, d = (u0, v0, w0, rx, ry, rz, εx, εy, εz, γyz, γzx, γxy)
    expected = np.array([[1, 0, 0, 0, Z, -Y, X, 0, 0, 0, Z / 2, Y / 2],
                         [0, 1, 0, -Z, 0, X, 0, Y, 0, Z / 2, 0, X / 2],
                         [0, 0, 1, Y, -X, 0, 0, 0, Z, Y / 2, X / 2, 0]])
    assert T.shape == (3, NDOF_3D)
    assert np.array_equal(T, expected)


def test_shape_function_is_translation_rotation_and_strain():
    # T·d = u0 + r × lever + ε·lever, ε the symmetric tensor of the strain unknowns (engineering shears)
    lever = RNG.normal(size=(20, 3))
    d = RNG.normal(size=(20, 12))
    eps = np.zeros((20, 3, 3))
    eps[:, [0, 1, 2], [0, 1, 2]] = d[:, 6:9]
    eps[:, 1, 2] = eps[:, 2, 1] = d[:, 9] / 2
    eps[:, 2, 0] = eps[:, 0, 2] = d[:, 10] / 2
    eps[:, 0, 1] = eps[:, 1, 0] = d[:, 11] / 2
    expected = d[:, :3] + np.cross(d[:, 3:6], lever) + np.einsum("nij,nj->ni", eps, lever)
    got = np.einsum("nij,nj->ni", shape_function_3d(lever), d)
    assert np.allclose(got, expected, rtol=0, atol=1e-14)  # round-off on entries of order one


def test_strain_selector_gives_the_voigt_strain_of_the_displacement_gradient():
    # u = T(lever)·d is linear in the lever: ∇u column a is T(e_a)·d - T(0)·d. Its symmetric part in
    # Voigt order with engineering shears (Eq. A3) must be B_b·d (Eq. A4).
    d = RNG.normal(size=12)
    levers = np.vstack([np.zeros(3), np.eye(3)])
    u = shape_function_3d(levers) @ d
    grad = (u[1:] - u[0]).T
    sym = 0.5 * (grad + grad.T)
    voigt = [sym[0, 0], sym[1, 1], sym[2, 2], 2 * sym[1, 2], 2 * sym[2, 0], 2 * sym[0, 1]]
    assert np.allclose(strain_selector_3d() @ d, voigt, rtol=0, atol=1e-15)


def _tet_quadrature(points):
    """Delaunay tetrahedra of a convex point set with the 4-point rule exact for degree-2 polynomials
    (Keast 1986): nodes α v_i + β Σ_{j≠i} v_j, α = 0.5854101966249685, β = 0.1381966011250105, weights V/4."""
    tets = points[Delaunay(points).simplices]  # (nt, 4, 3)
    vol = np.abs(np.linalg.det(tets[:, 1:] - tets[:, :1])) / 6
    alpha, beta = 0.5854101966249685, 0.1381966011250105
    weights = beta * np.ones((4, 4)) + (alpha - beta) * np.eye(4)
    nodes = np.einsum("qk,tkx->tqx", weights, tets).reshape(-1, 3)
    return nodes, np.repeat(vol / 4, 4)


def _quadrature_mass(convex_parts):
    nodes, w = map(np.concatenate, zip(*[_tet_quadrature(np.asarray(p, float)) for p in convex_parts]))
    centroid = w @ nodes / w.sum()
    T = shape_function_3d(nodes - centroid)
    return np.einsum("q,qia,qib->ab", w, T, T), w.sum()


def _cuboid_corners(lo, hi):
    return box(lo, hi)[0]


@pytest.mark.parametrize("block, parts", [
    (box([1, -2, 0.5], [2.5, 0, 1.25]), [_cuboid_corners([1, -2, 0.5], [2.5, 0, 1.25])]),
    (prism(L_SHAPE, 0.0, 0.75), [_cuboid_corners([0, 0, 0], [2, 1, 0.75]), _cuboid_corners([0, 1, 0], [1, 2, 0.75])]),
])
def test_mass_matrix_matches_quadrature(block, parts):
    # ∫TᵀT dV: the integrand is quadratic, so the degree-2 tetrahedron rule over a split into convex
    # boxes is exact; the two computations share nothing but T.
    mesh = PolyhedronMesh.from_blocks([block])
    m = polyhedron_moments(mesh.vertices, mesh)
    M = block_mass_matrix_3d(m.volume, m.second)[0]
    Mq, volume = _quadrature_mass(parts)
    assert volume == pytest.approx(m.volume[0], rel=1e-14)
    assert np.allclose(M, Mq, rtol=0, atol=1e-13 * np.abs(Mq).max())  # round-off of two different sums
    assert np.allclose(M, M.T, rtol=0, atol=0)
    assert np.all(np.linalg.eigvalsh(M) > 0)


def test_mass_matrix_rotation_block_is_the_inertia_tensor():
    # columns e_k × r: ∫ (e_k × r)·(e_l × r) dV = tr(S) δ_kl - S_kl, the inertia tensor per unit density;
    # rotation-strain coupling of the εx column: ∫ (e_k × r)_x X dV = (0, S_xz, -S_xy)_k
    mesh = PolyhedronMesh.from_blocks([prism(L_SHAPE, 0.0, 0.3)])
    m = polyhedron_moments(mesh.vertices, mesh)
    S = m.second[0]
    M = block_mass_matrix_3d(m.volume, m.second)[0]
    assert np.allclose(M[3:6, 3:6], np.trace(S) * np.eye(3) - S, rtol=0, atol=1e-15)
    assert np.allclose(M[3:6, 6], [0, S[0, 2], -S[0, 1]], rtol=0, atol=1e-15)
    assert np.allclose(M[:3, :3], m.volume[0] * np.eye(3), rtol=0, atol=0)
    assert np.array_equal(M[:3, 3:], np.zeros((3, 9)))  # ∫X = 0 about the centroid


def test_mass_matrix_of_a_prism_contains_the_2d_one():
    # For in-plane unknowns (u0, v0, rz, εx, εy, γxy) of an extruded polygon, T is the 2D T (Eq. 52) and
    # the w row is zero, so that block of the 3D mass matrix is the 2D one times the thickness.
    h = 0.4
    mesh = PolyhedronMesh.from_blocks([prism(L_SHAPE, 1.0, 1.0 + h)])
    m = polyhedron_moments(mesh.vertices, mesh)
    M3 = block_mass_matrix_3d(m.volume, m.second)[0]
    s = m.second[0] / h  # the 2D central moments ∫X² dA, ∫Y² dA, ∫XY dA
    M2 = block_mass_matrix(m.volume / h, s[[0]][:, 0], s[[1]][:, 1], s[[0]][:, 1])[0]
    in_plane = [0, 1, 5, 6, 7, 11]
    assert np.allclose(M3[np.ix_(in_plane, in_plane)], h * M2, rtol=0, atol=1e-14)


def test_elasticity_uniaxial_stress():
    # σx alone: εx = σ/E, εy = εz = -νσ/E, no shear; pure shear τyz: γyz = τ/G, G = E/(2(1+ν)).
    E, nu, sigma = 3.0e10, 0.25, 2.0e6
    D = elasticity_matrix_3d(E, nu)
    strain = np.linalg.solve(D, [sigma, 0, 0, 0, 0, 0])
    # D is well conditioned (ν = 0.25): the solve loses only a few ulps
    assert np.allclose(strain, [sigma / E, -nu * sigma / E, -nu * sigma / E, 0, 0, 0], rtol=1e-14, atol=1e-25)
    G = E / (2 * (1 + nu))
    assert np.allclose(np.linalg.solve(D, [0, 0, 0, 1e5, 0, 0]), [0, 0, 0, 1e5 / G, 0, 0], rtol=1e-14, atol=1e-25)
    assert np.array_equal(D, D.T)


@pytest.mark.parametrize("young, poisson, message", [(0.0, 0.2, "Young's modulus"), (1e9, 0.5, "Poisson's ratio"),
                                                      (np.nan, 0.2, "Young's modulus")])
def test_elasticity_rejects_bad_constants(young, poisson, message):
    with pytest.raises(ValueError, match=message):
        elasticity_matrix_3d(young, poisson)


def _rodrigues(theta):
    """R = I + sin t K + (1 - cos t) K², K the unit skew of θ/|θ| (reference, one vector)."""
    t = np.linalg.norm(theta)
    K = _skew(theta / t)
    return np.eye(3) + np.sin(t) * K + (1 - np.cos(t)) * K @ K


@given(vectors)
def test_rotation_matrix_is_rodrigues_and_proper(theta):
    if np.linalg.norm(theta) < 1e-3:
        return  # the reference divides by |θ|; small angles are tested against the series below
    R = rotation_matrix_3d(theta[None])[0]
    # entries of order one built from sums of a few products, and det by LU: a few ulps each
    tol = 1e-14
    assert np.allclose(R, _rodrigues(theta), rtol=0, atol=tol)
    assert np.allclose(R @ R.T, np.eye(3), rtol=0, atol=tol)
    assert abs(np.linalg.det(R) - 1) < tol
    # rotating by θ then by -θ is the identity
    assert np.allclose(compose_rotations(R, rotation_matrix_3d(-theta[None])[0]), np.eye(3), rtol=0, atol=tol)


def test_small_rotation_is_smooth():
    # below ~1e-8 the series I + [θ]× + [θ]×²/2 is exact in double precision; θ = 0 gives I exactly
    theta = np.array([[3e-9, -1e-9, 2e-9], [0.0, 0.0, 0.0]])
    R = rotation_matrix_3d(theta)
    K = _skew(theta[0])
    assert np.allclose(R[0], np.eye(3) + K + K @ K / 2, rtol=0, atol=1e-24)
    assert np.array_equal(R[1], np.eye(3))


def test_rotation_about_z_is_the_2d_rotation():
    angles = np.array([-2.0, 0.3, 1e-7, 3.0])
    R = rotation_matrix_3d(np.column_stack([np.zeros(4), np.zeros(4), angles]))
    # sin/cos of |θ| against sin/cos of θ, and Rodrigues' sum: a few ulps of entries of order one
    assert np.allclose(R[:, :2, :2], rotation_matrix(angles), rtol=0, atol=1e-15)
    assert np.array_equal(R[:, 2, 2], np.ones(4))


def test_compose_rotations_applies_the_increment_after():
    axis = np.array([1.0, 2.0, -2.0]) / 3
    a, b = 0.4, 1.1
    Ra, Rb = rotation_matrix_3d(np.array([a * axis, b * axis]))
    # about one axis angles add (1e-15: round-off of one product)
    assert np.allclose(compose_rotations(Ra, Rb), rotation_matrix_3d((a + b) * axis[None])[0], atol=1e-15)
    Rx, Ry = rotation_matrix_3d(np.array([[0.5, 0, 0], [0, 0.5, 0]]))
    x = np.array([0.2, -0.7, 1.3])
    assert np.allclose(compose_rotations(Rx, Ry) @ x, Ry @ (Rx @ x), rtol=0, atol=1e-15)
    assert not np.allclose(compose_rotations(Rx, Ry), compose_rotations(Ry, Rx))  # order matters in 3D


@settings(max_examples=200)
@given(vectors, vectors)
def test_secant_rotation_columns_give_the_exact_rotation(theta, lever):
    # T_sec(θ)·(0, 0, 0, θ, 0, ...) = (R(θ) - I)·lever; 1e-14 allows round-off on entries of order one
    T = secant_shape_function_3d(lever[None], theta[None])[0]
    d = np.zeros(12)
    d[3:6] = theta
    exact = (rotation_matrix_3d(theta[None])[0] - np.eye(3)) @ lever
    assert np.allclose(T @ d, exact, rtol=0, atol=1e-14)
    # translation and strain columns are Shi's T
    shi = shape_function_3d(lever[None])[0]
    keep = [0, 1, 2, *range(6, 12)]
    assert np.array_equal(T[:, keep], shi[:, keep])


def test_secant_shape_function_reduces_to_shi():
    lever = RNG.normal(size=(5, 3))
    shi = shape_function_3d(lever)
    assert np.array_equal(secant_shape_function_3d(lever, None), shi)
    assert np.array_equal(secant_shape_function_3d(lever, np.zeros((5, 3))), shi)
    # and continuously: the rotation columns differ from Shi's by O(|θ|)
    tiny = secant_shape_function_3d(lever, np.full((5, 3), 1e-9))
    assert np.allclose(tiny, shi, rtol=0, atol=1e-8)


def test_secant_about_z_matches_2d():
    lever2 = RNG.normal(size=(6, 2))
    angle = np.array([0.0, 1e-9, 0.2, -1.0, 2.5, 3.1])
    T2 = secant_shape_function(lever2, angle)
    T3 = secant_shape_function_3d(np.column_stack([lever2, np.zeros(6)]),
                                  np.column_stack([np.zeros(6), np.zeros(6), angle]))
    # 2D d = (u0, v0, r0, εx, εy, γxy) are the 3D unknowns (u0, v0, rz, εx, εy, γxy)
    assert np.allclose(T3[:, :2, [0, 1, 5, 6, 7, 11]], T2, rtol=0, atol=1e-15)


def _box_points():
    mesh = PolyhedronMesh.from_blocks([box([0, 0, 0], [1.0, 0.5, 2.0])])
    m = polyhedron_moments(mesh.vertices, mesh)
    return mesh, mesh.vertices - m.centroid[0], m


@given(vectors)
def test_exact_rotation_keeps_distances_and_volume(theta):
    mesh, lever, m = _box_points()
    dd = np.zeros((len(lever), 12))
    dd[:, :3] = [0.3, -0.2, 5.0]
    dd[:, 3:6] = theta
    moved = mesh.vertices + point_displacement_3d(lever, dd, "exact-rotation")
    dist = np.linalg.norm(lever[:, None] - lever[None], axis=-1)
    new_dist = np.linalg.norm(moved[:, None] - moved[None], axis=-1)
    assert np.allclose(new_dist, dist, rtol=0, atol=1e-14)  # lengths up to ~2.3: round-off only
    assert polyhedron_moments(moved, mesh).volume[0] == pytest.approx(m.volume[0], rel=1e-14)


@given(vectors)
def test_linear_update_grows_the_volume_by_one_plus_theta_squared(theta):
    # DDA0: the rotation part of T is I + [θ]×, det(I + [θ]×) = 1 + |θ|²; a linear map scales volume by det
    mesh, lever, m = _box_points()
    dd = np.zeros((len(lever), 12))
    dd[:, 3:6] = theta
    moved = mesh.vertices + point_displacement_3d(lever, dd, "linear")
    assert np.allclose(moved, mesh.vertices + np.cross(theta, lever), rtol=0, atol=1e-15)
    grown = polyhedron_moments(moved, mesh).volume[0]
    assert grown == pytest.approx(m.volume[0] * (1 + theta @ theta), rel=1e-13)  # products up to |θ|³ ~ 6


def test_unknown_kinematics_is_an_error():
    with pytest.raises(ValueError, match="kinematics must be one of"):
        point_displacement_3d(np.zeros((1, 3)), np.zeros((1, 12)), "spline")


def _gradient_of_update(dd_row, kinematics):
    """∇u of the (affine) update of one block: columns u(e_a) - u(0)."""
    levers = np.vstack([np.zeros(3), np.eye(3)])
    u = point_displacement_3d(levers, np.tile(dd_row, (4, 1)), kinematics)
    return (u[1:] - u[0]).T


@settings(max_examples=200)
@given(arrays(np.float64, 3, elements=st.floats(-1, 1)).filter(lambda w: 1e-3 < np.linalg.norm(w) < 1.5),
       arrays(np.float64, 6, elements=st.floats(-0.05, 0.05)))
def test_sr_decomposition_of_the_exact_update(theta, strain):
    # Exact update with rotation θ (|θ| < π/2, Chen's principal branch) and strains e: F = I + ∇u = R(θ) + E,
    # so sr_decomposition_3d (Eqs. A8-A10) gives back R(θ), the angle |θ| and S = E (S = 0 without strain).
    dd = np.zeros(12)
    dd[3:6] = theta
    R = rotation_matrix_3d(theta[None])[0]
    S, R_sr, angle = sr_decomposition_3d(_gradient_of_update(dd, "exact-rotation"))
    assert np.allclose(S, 0, atol=1e-14)
    assert np.allclose(R_sr, R, rtol=0, atol=1e-12)  # arcsin near π/2 loses digits, as in the 2D test
    assert abs(angle - np.linalg.norm(theta)) < 1e-10
    dd[6:] = strain
    E = np.diag(strain[:3])
    E[1, 2] = E[2, 1] = strain[3] / 2
    E[2, 0] = E[0, 2] = strain[4] / 2
    E[0, 1] = E[1, 0] = strain[5] / 2
    S, R_sr, _ = sr_decomposition_3d(_gradient_of_update(dd, "exact-rotation"))
    assert np.allclose(S, E, rtol=0, atol=1e-14)
    assert np.allclose(R_sr, R, rtol=0, atol=1e-12)


def _voigt_tensor(comp, shear_factor):
    X = np.diag(comp[:3]).astype(float)
    X[1, 2] = X[2, 1] = comp[3] / shear_factor
    X[2, 0] = X[0, 2] = comp[4] / shear_factor
    X[0, 1] = X[1, 0] = comp[5] / shear_factor
    return X


@given(vectors, arrays(np.float64, 6, elements=st.floats(-10, 10)), st.sampled_from([1.0, 2.0]))
def test_rotate_symmetric_components_3d(theta, comp, shear_factor):
    R = rotation_matrix_3d(theta[None])
    out = rotate_symmetric_components_3d(comp[None], R, shear_factor)[0]
    X, Y = _voigt_tensor(comp, shear_factor), _voigt_tensor(out, shear_factor)
    scale = 1e-13 * max(1.0, np.abs(comp).max())  # round-off of two 3x3 products, entries up to 10
    assert np.allclose(Y, R[0] @ X @ R[0].T, rtol=0, atol=scale)
    assert abs(np.trace(Y) - np.trace(X)) < scale
    # det as a triple product (LU warns on the singular tensors hypothesis likes): entries³ ~ 1e3
    assert abs(Y[0] @ np.cross(Y[1], Y[2]) - X[0] @ np.cross(X[1], X[2])) < scale * 100
    back = rotate_symmetric_components_3d(out[None], rotation_matrix_3d(-theta[None]), shear_factor)[0]
    assert np.allclose(back, comp, rtol=0, atol=scale)


def test_rotate_symmetric_components_about_z_matches_2d():
    comp = RNG.normal(size=(5, 6))
    angle = np.array([0.0, 0.1, -0.7, 2.0, 3.0])
    R = rotation_matrix_3d(np.column_stack([np.zeros(5), np.zeros(5), angle]))
    tol = 1e-14  # two different formulas for the same products of entries up to ~3: a few ulps
    for shear_factor in (1.0, 2.0):
        out = rotate_symmetric_components_3d(comp, R, shear_factor)
        two_d = rotate_symmetric_components(comp[:, [0, 1, 5]], angle, shear_factor)
        assert np.allclose(out[:, [0, 1, 5]], two_d, rtol=0, atol=tol)
        assert np.allclose(out[:, 2], comp[:, 2], rtol=0, atol=tol)  # zz is untouched
        # (τzx, τyz) turns as the vector (x, y): rows zx, yz of R X Rᵀ are R_2D (X_zx, X_yz)
        c, s = np.cos(angle), np.sin(angle)
        assert np.allclose(out[:, 4], c * comp[:, 4] - s * comp[:, 3], rtol=0, atol=tol)
        assert np.allclose(out[:, 3], s * comp[:, 4] + c * comp[:, 3], rtol=0, atol=tol)
