"""Chen's S-R (strain-rotation) decomposition F = S + R (paper Eqs. 11-16, A8-A10).

S is symmetric (the Chen strain), R a proper rotation by the mean rotation
angle θ. With u_{i,j} = ∂u_i/∂x_j and F = I + ∇u:

2D (Eq. 16):  sin θ = (u_{2,1} - u_{1,2}) / 2,
              R = [[cos θ, -sin θ], [sin θ, cos θ]],  S = sym(∇u) + (1 - cos θ) I.
3D (Eqs. 12-15): sin θ = ½ |axial(∇u - ∇uᵀ)|, L = (∇u - ∇uᵀ) / (2 sin θ),
              R = I + sin θ L + (1 - cos θ) L²,  S = sym(∇u) - (1 - cos θ) L².

The decomposition exists for |sin θ| ≤ 1; θ is taken in [-π/2, π/2] (2D) or
[0, π/2] (3D), the principal branch of Chen's theorem.
"""
from __future__ import annotations

import numpy as np

__all__ = ["mean_rotation", "chen_strain", "sr_decomposition", "sr_decomposition_3d"]


def mean_rotation(grad_u: np.ndarray) -> np.ndarray:
    """Mean rotation angle θ of 2D displacement gradients (..., 2, 2) (Eq. 16)."""
    s = 0.5 * (grad_u[..., 1, 0] - grad_u[..., 0, 1])
    if np.any(np.abs(s) > 1.0):
        raise ValueError("S-R decomposition needs |(u2,1 - u1,2)/2| <= 1")
    return np.arcsin(s)


def chen_strain(grad_u: np.ndarray) -> np.ndarray:
    """Chen strain S = sym(∇u) + (1 - cos θ) I of 2D gradients (..., 2, 2) (Eq. 12)."""
    theta = mean_rotation(grad_u)
    sym = 0.5 * (grad_u + np.swapaxes(grad_u, -1, -2))
    return sym + (1.0 - np.cos(theta))[..., None, None] * np.eye(2)


def sr_decomposition(grad_u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """2D S-R decomposition: returns (S, R, θ) with S + R = I + ∇u."""
    theta = mean_rotation(grad_u)
    c, s = np.cos(theta), np.sin(theta)
    R = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)
    sym = 0.5 * (grad_u + np.swapaxes(grad_u, -1, -2))
    S = sym + (1.0 - c)[..., None, None] * np.eye(2)
    return S, R, theta


def sr_decomposition_3d(grad_u: np.ndarray, tiny: float = 1e-300) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """3D S-R decomposition of gradients (..., 3, 3): returns (S, R, θ) (Eqs. 12-15).

    For θ = 0 the axis is undefined; then L² is irrelevant (1 - cos θ = 0) and
    R = I, S = sym(∇u).
    """
    W = 0.5 * (grad_u - np.swapaxes(grad_u, -1, -2))  # = sin θ · L
    axial = np.stack([W[..., 2, 1], W[..., 0, 2], W[..., 1, 0]], -1)
    s = np.linalg.norm(axial, axis=-1)
    if np.any(s > 1.0):
        raise ValueError("S-R decomposition needs sin θ <= 1")
    theta = np.arcsin(s)
    c = np.cos(theta)
    safe = np.where(s > tiny, s, 1.0)
    L = W / safe[..., None, None]
    L2 = L @ L
    eye = np.eye(3)
    R = eye + s[..., None, None] * L + (1.0 - c)[..., None, None] * L2
    sym = 0.5 * (grad_u + np.swapaxes(grad_u, -1, -2))
    S = sym - (1.0 - c)[..., None, None] * L2
    return S, R, theta
