"""How a block's points move over a step, for each kinematics.

* ``linear`` (DDA0, Shi 1988): Δu(p) = T(p)·Δd. A rotation r0 stretches the
  block by (1 + r0²) per step (the spurious volume growth of Table 1).
* ``exact-rotation`` (DDA1's post-adjustment and SRDDA's F = S + R, Eq. 11):
  p(t+Δt) = c + Δu_c + (S + R(Δθ))(p - c), S the Chen strain of the strain
  unknowns, R the proper rotation by the mean-rotation unknown θ. A rigid
  rotation keeps areas exactly.

The exact-rotation displacement equals ``T_sec(p; Δθ)·Δd`` where the secant
shape function T_sec has rotation column 2 sin(Δθ/2)·J R(Δθ/2)(p - c)
(because R(θ) - I = 2 sin(θ/2)·J·R(θ/2), J the quarter turn). With Δθ = 0 it
is Shi's T. SRDDA linearises loads, springs and constraints with T_sec at the
converged Δθ, so what the equations see is what the update does.
"""
from __future__ import annotations

import numpy as np

from .shape2d import shape_function

__all__ = ["secant_shape_function", "point_displacement", "rotate_symmetric_components", "KINEMATICS"]

KINEMATICS = ("linear", "exact-rotation")


def secant_shape_function(lever: np.ndarray, theta: np.ndarray | None) -> np.ndarray:
    """T_sec for lever arms (n, 2) and rotation increments (n,); (n, 2, 6).

    ``theta is None`` gives Shi's T (paper Eq. 52).
    """
    T = shape_function(lever)
    if theta is None:
        return T
    half = 0.5 * theta
    c, s = np.cos(half), np.sin(half)
    chord = np.where(np.abs(theta) > 1e-300, 2.0 * s / np.where(theta == 0, 1.0, theta), 1.0)
    rx = c * lever[:, 0] - s * lever[:, 1]
    ry = s * lever[:, 0] + c * lever[:, 1]
    T[:, 0, 2] = -chord * ry
    T[:, 1, 2] = chord * rx
    return T


def point_displacement(lever: np.ndarray, dd: np.ndarray, kinematics: str) -> np.ndarray:
    """Displacement of points with levers (n, 2) for their blocks' Δd rows (n, 6)."""
    theta = dd[:, 2] if kinematics == "exact-rotation" else None
    T = secant_shape_function(lever, theta)
    return np.einsum("nij,nj->ni", T, dd)


def rotate_symmetric_components(comp: np.ndarray, theta: np.ndarray, shear_factor: float) -> np.ndarray:
    """Rotate 2D symmetric tensors given as (xx, yy, xy·shear_factor) rows by θ: R·X·Rᵀ.

    ``shear_factor`` is 1 for stress (τxy) and 2 for engineering strain (γxy).
    """
    c, s = np.cos(theta), np.sin(theta)
    xx, yy, xy = comp[:, 0], comp[:, 1], comp[:, 2] / shear_factor
    c2, s2, cs = c * c, s * s, c * s
    nxx = c2 * xx + s2 * yy - 2 * cs * xy
    nyy = s2 * xx + c2 * yy + 2 * cs * xy
    nxy = cs * (xx - yy) + (c2 - s2) * xy
    return np.column_stack([nxx, nyy, nxy * shear_factor])
