"""The first-order block shape function of Shi's DDA (paper Eq. 52).

A point (x, y) of a block with centroid (x0, y0) moves by ``T(x, y) @ d`` with
``d = (u0, v0, r0, εx, εy, γxy)``:

    T = [[1, 0, -(y-y0), (x-x0), 0,      (y-y0)/2],
         [0, 1,  (x-x0), 0,      (y-y0), (x-x0)/2]]

Functions take the lever arm ``r = p - centroid`` for many points at once.
"""
from __future__ import annotations

import numpy as np

__all__ = ["NDOF", "shape_function", "strain_selector", "block_mass_matrix", "rotation_matrix"]

NDOF = 6  # generalized unknowns per 2D block


def shape_function(lever: np.ndarray) -> np.ndarray:
    """T for lever arms ``lever`` of shape (n, 2); returns (n, 2, 6)."""
    X = lever[:, 0]
    Y = lever[:, 1]
    n = len(lever)
    T = np.zeros((n, 2, NDOF))
    T[:, 0, 0] = 1.0
    T[:, 1, 1] = 1.0
    T[:, 0, 2] = -Y
    T[:, 1, 2] = X
    T[:, 0, 3] = X
    T[:, 1, 4] = Y
    T[:, 0, 5] = 0.5 * Y
    T[:, 1, 5] = 0.5 * X
    return T


def strain_selector() -> np.ndarray:
    """B_b of paper Eq. 58: picks the strain (rate) components out of d."""
    B = np.zeros((3, NDOF))
    B[0, 3] = B[1, 4] = B[2, 5] = 1.0
    return B


def block_mass_matrix(area: np.ndarray, sxx: np.ndarray, syy: np.ndarray, sxy: np.ndarray) -> np.ndarray:
    """∫ TᵀT dA for every block (per unit density), exact; shape (nb, 6, 6).

    With central moments ∫X = ∫Y = 0, so translation decouples from the rest.
    """
    nb = len(area)
    M = np.zeros((nb, NDOF, NDOF))
    M[:, 0, 0] = M[:, 1, 1] = area
    M[:, 2, 2] = sxx + syy
    M[:, 2, 3] = -sxy
    M[:, 2, 4] = sxy
    M[:, 2, 5] = 0.5 * (sxx - syy)
    M[:, 3, 3] = sxx
    M[:, 3, 5] = 0.5 * sxy
    M[:, 4, 4] = syy
    M[:, 4, 5] = 0.5 * sxy
    M[:, 5, 5] = 0.25 * (sxx + syy)
    iu = np.triu_indices(NDOF, 1)
    M[:, iu[1], iu[0]] = M[:, iu[0], iu[1]]
    return M


def rotation_matrix(theta: np.ndarray) -> np.ndarray:
    """Proper 2D rotations by angles ``theta`` (counter-clockwise); (n, 2, 2)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)
