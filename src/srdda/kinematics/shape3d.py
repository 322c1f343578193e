"""The first-order shape function of a 3D block (paper Appendix, Eq. A1), its mass matrix, elasticity, rotations.

A point x of a block with centroid x_c moves by ``T(x) @ d`` with the twelve
unknowns of Eq. A2, in the paper's order

    d = (u0, v0, w0, rx, ry, rz, εx, εy, εz, γyz, γzx, γxy)

(translation of the centroid, rotation angles about x, y, z, normal strains,
engineering shear strains). With the lever arm (X, Y, Z) = x - x_c (Eq. A1):

    T = [[1, 0, 0,  0,  Z, -Y,  X, 0, 0,  0,   Z/2, Y/2],
         [0, 1, 0, -Z,  0,  X,  0, Y, 0,  Z/2, 0,   X/2],
         [0, 0, 1,  Y, -X,  0,  0, 0, Z,  Y/2, X/2, 0  ]]

so the rotation columns give r × (X, Y, Z) and the strain columns ε·(X, Y, Z)
with ε the symmetric strain tensor. Every column after the translations is
linear in the lever arm, ``T[:, k] = G_k @ lever``; the constant matrices G_k
give both T and the exact mass matrix ∫TᵀT dV from the central second moments.
Strains and stresses use the Voigt order of Eq. A3: (xx, yy, zz, yz, zx, xy).
"""
from __future__ import annotations

import numpy as np

__all__ = [
    "NDOF_3D",
    "block_mass_matrix_3d",
    "compose_rotations",
    "elasticity_matrix_3d",
    "rodrigues_coefficients",
    "rotation_matrix_3d",
    "shape_function_3d",
    "skew",
    "strain_selector_3d",
]

NDOF_3D = 12  # generalized unknowns per 3D block (Eq. A2)


def skew(vectors: np.ndarray) -> np.ndarray:
    """Cross-product matrices [w]× of vectors (n, 3), so that [w]× r = w × r; (n, 3, 3)."""
    K = np.zeros((len(vectors), 3, 3))
    K[:, _SKEW_ROW, _SKEW_COL] = vectors[:, _SKEW_COMPONENT] * _SKEW_SIGN
    return K


# [w]× = [[0, -z, y], [z, 0, -x], [-y, x, 0]]: (row, column, component of w, sign)
_SKEW_ROW, _SKEW_COL = np.array([0, 0, 1, 1, 2, 2]), np.array([1, 2, 0, 2, 0, 1])
_SKEW_COMPONENT, _SKEW_SIGN = np.array([2, 1, 2, 0, 1, 0]), np.array([-1.0, 1.0, 1.0, -1.0, -1.0, 1.0])


def _linear_columns() -> np.ndarray:
    """G_k (9, 3, 3) with T[:, 3 + k] = G_k @ lever (Eq. A1)."""
    G = np.zeros((9, 3, 3))
    G[0:3] = skew(np.eye(3))  # rx, ry, rz: e_k × lever
    G[3, 0, 0] = G[4, 1, 1] = G[5, 2, 2] = 1.0  # εx, εy, εz
    G[6, 1, 2] = G[6, 2, 1] = 0.5  # γyz
    G[7, 0, 2] = G[7, 2, 0] = 0.5  # γzx
    G[8, 0, 1] = G[8, 1, 0] = 0.5  # γxy
    return G


_G = _linear_columns()
# ∫ T_kᵀ T_l dV = Σ_ab (Σ_i G_k[i,a] G_l[i,b]) S[a,b]: one (81, 9) matrix applied to the flattened S
_MASS_FROM_SECOND = np.einsum("kia,lib->klab", _G, _G).reshape(81, 9)


def shape_function_3d(lever: np.ndarray) -> np.ndarray:
    """T of Eq. A1 for lever arms ``lever`` (n, 3); returns (n, 3, 12)."""
    n = len(lever)
    T = np.zeros((n, 3, NDOF_3D))
    T[:, 0, 0] = T[:, 1, 1] = T[:, 2, 2] = 1.0
    T[:, :, 3:] = np.einsum("kia,na->nik", _G, lever)
    return T


def strain_selector_3d() -> np.ndarray:
    """B_b of Eq. A4: picks the six strain (rate) components (Voigt order of Eq. A3) out of d; (6, 12)."""
    B = np.zeros((6, NDOF_3D))
    B[np.arange(6), 6 + np.arange(6)] = 1.0
    return B


def block_mass_matrix_3d(volume: np.ndarray, second: np.ndarray) -> np.ndarray:
    """∫ TᵀT dV for every block (per unit density), exact; shape (nb, 12, 12).

    ``second`` are the central second moments ∫ X_i X_j dV (nb, 3, 3). About
    the centroid ∫X = 0, so translation decouples: the translation block is
    V·I and the rest is ∫ leverᵀ G_kᵀ G_l lever dV = tr(G_kᵀ G_l S).
    """
    nb = len(volume)
    M = np.zeros((nb, NDOF_3D, NDOF_3D))
    M[:, 0, 0] = M[:, 1, 1] = M[:, 2, 2] = volume
    M[:, 3:, 3:] = (second.reshape(nb, 9) @ _MASS_FROM_SECOND.T).reshape(nb, 9, 9)
    return M


def elasticity_matrix_3d(young: float, poisson: float) -> np.ndarray:
    """Isotropic D (6, 6) relating (σx, σy, σz, τyz, τzx, τxy) to (εx, εy, εz, γyz, γzx, γxy).

    Engineering shear strains, so the shear diagonal is G = E / (2(1 + ν)).
    """
    if not (np.isfinite(young) and young > 0):
        raise ValueError(f"Young's modulus must be a positive number, got {young}")
    if not -1.0 < poisson < 0.5:
        raise ValueError(f"Poisson's ratio must lie in (-1, 0.5) for a 3D solid, got {poisson}")
    lam = young * poisson / ((1 + poisson) * (1 - 2 * poisson))
    shear = young / (2 * (1 + poisson))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[np.arange(3), np.arange(3)] += 2 * shear
    D[np.arange(3, 6), np.arange(3, 6)] = shear
    return D


def rotation_matrix_3d(rotvec: np.ndarray) -> np.ndarray:
    """Proper rotations by rotation vectors θ (n, 3) (Rodrigues); (n, 3, 3).

    R = I + sin|θ| K + (1 - cos|θ|) K², K the unit skew of θ/|θ|, written as
    R = I + a [θ]× + b [θ]×² with a = sin t / t, b = (1 - cos t) / t² (t = |θ|),
    both evaluated without cancellation (b = ½ (sin(t/2) / (t/2))²), so θ → 0
    is smooth and exact (R = I at θ = 0).
    """
    a, b = rodrigues_coefficients(np.linalg.norm(rotvec, axis=1))
    K = skew(rotvec)
    return np.eye(3) + a[:, None, None] * K + b[:, None, None] * (K @ K)


def rodrigues_coefficients(angle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(sin t / t, (1 - cos t) / t²) for angles t ≥ 0, exact and smooth through t = 0."""
    a = np.sinc(angle / np.pi)  # numpy's sinc is sin(πx)/(πx), 1 at 0
    half = np.sinc(angle / (2 * np.pi))
    return a, 0.5 * half * half


def compose_rotations(rotation: np.ndarray, increment: np.ndarray) -> np.ndarray:
    """Accumulated rotation after a step: ``increment @ rotation`` (both (n, 3, 3)).

    The step's rotation increment acts on the current (already rotated)
    configuration in the global frame, so it multiplies from the left. The
    accumulated rotation is kept as a matrix: rotation vectors do not add.
    """
    return increment @ rotation
