"""How a 3D block's points move over a step, for each kinematics (3D twin of :mod:`.update2d`).

* ``linear`` (DDA0): Δu(p) = T(p)·Δd with T of Eq. A1. The rotation part is
  I + [Δr]×, whose determinant is 1 + |Δr|²: a rotating block's volume grows by
  that factor per step.
* ``exact-rotation`` (DDA1's post-adjustment and SRDDA's F = S + R, Eqs. 11,
  A8-A10): p(t+Δt) = c + Δu_c + (S + R(Δθ))(p - c), S the strain tensor of the
  strain unknowns and R the Rodrigues rotation of the rotation unknowns
  Δθ = (rx, ry, rz). A rigid rotation keeps lengths and volume exactly.

The exact-rotation displacement equals ``T_sec(p; Δθ)·Δd`` where the secant
shape function T_sec has rotation columns A = -a [r]× - b [Δθ]×[r]× (r the
lever arm, a = sin t / t, b = (1 - cos t) / t², t = |Δθ|), because
A·Δθ = a Δθ×r + b Δθ×(Δθ×r) = (R(Δθ) - I) r. With Δθ = 0 it is Shi's T.
"""
from __future__ import annotations

import numpy as np

from .shape3d import rodrigues_coefficients, shape_function_3d, skew
from .update2d import KINEMATICS

__all__ = ["point_displacement_3d", "rotate_symmetric_components_3d", "secant_shape_function_3d"]


def secant_shape_function_3d(lever: np.ndarray, rotation_vector: np.ndarray | None) -> np.ndarray:
    """T_sec for lever arms (n, 3) and rotation increments (n, 3); (n, 3, 12).

    ``rotation_vector is None`` gives Shi's T (Eq. A1).
    """
    T = shape_function_3d(lever)
    if rotation_vector is None:
        return T
    a, b = rodrigues_coefficients(np.linalg.norm(rotation_vector, axis=1))
    lever_x = skew(lever)
    T[:, :, 3:6] = -a[:, None, None] * lever_x - b[:, None, None] * (skew(rotation_vector) @ lever_x)
    return T


def point_displacement_3d(lever: np.ndarray, dd: np.ndarray, kinematics: str) -> np.ndarray:
    """Displacement of points with levers (n, 3) for their blocks' Δd rows (n, 12)."""
    if kinematics not in KINEMATICS:
        raise ValueError(f"kinematics must be one of {KINEMATICS}, got {kinematics!r}")
    rotation = dd[:, 3:6] if kinematics == "exact-rotation" else None
    T = secant_shape_function_3d(lever, rotation)
    return np.einsum("nij,nj->ni", T, dd)


_II = np.array([0, 1, 2, 1, 2, 0])  # Voigt order (xx, yy, zz, yz, zx, xy) of Eq. A3
_JJ = np.array([0, 1, 2, 2, 0, 1])


def rotate_symmetric_components_3d(comp: np.ndarray, rotation: np.ndarray, shear_factor: float) -> np.ndarray:
    """Rotate symmetric tensors given as Voigt rows (xx, yy, zz, yz, zx, xy)·(1, 1, 1, f, f, f): R·X·Rᵀ.

    ``rotation`` (n, 3, 3); ``shear_factor`` f is 1 for stress and 2 for
    engineering strain (γ = 2 ε).
    """
    shear = np.array([1.0, 1.0, 1.0, shear_factor, shear_factor, shear_factor])
    X = np.empty((len(comp), 3, 3))
    X[:, _II, _JJ] = comp / shear
    X[:, _JJ, _II] = comp / shear
    Y = rotation @ X @ np.swapaxes(rotation, -1, -2)
    return Y[:, _II, _JJ] * shear
