"""The block type: everything about a block that depends on the dimension.

The step, the terms, the assembly and the constraints see blocks only through
a :class:`BlockType`: how many unknowns a block has and where its
translation, rotation and strain sit among them, its shape function (plain
or secant), its mass matrix, how its points move over a step, how its
accumulated rotation is composed and how its stresses are rotated. ``PLANE``
is Shi's 2D block (6 unknowns, paper Eq. 52); a 3D block (12 unknowns,
Eq. A1) is a second instance of the same interface.

The accumulated rotation is composed by the block type: in 2D the rotation
angle is the exact coordinate of SO(2), whose composition is the sum of the
angles (it also keeps the number of turns, which a matrix forgets); in 3D it
is the product of rotation matrices.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .shape2d import NDOF, block_mass_matrix
from .shape3d import block_mass_matrix_3d, compose_rotations, rotation_matrix_3d
from .update2d import point_displacement, rotate_symmetric_components, secant_shape_function
from .update3d import point_displacement_3d, rotate_symmetric_components_3d, secant_shape_function_3d

__all__ = ["BlockType", "PlaneBlocks", "SolidBlocks", "PLANE", "SOLID", "block_type_of_dimension"]


@dataclass(frozen=True)
class BlockType:
    """What a block of one dimension is made of (see the module doc); Shi's 2D block by default."""

    name: str
    dim: int  # coordinates of a point
    ndof: int  # generalized unknowns per block
    n_strain: int  # independent strain (and stress) components
    translation: slice  # of the unknowns
    rotation: slice
    strain: slice

    # -- shape functions ----------------------------------------------------
    def shape(self, lever: np.ndarray, rotation_increment: np.ndarray | None = None) -> np.ndarray:
        """T (n, dim, ndof) at lever arms ``lever``: Shi's T, or T_sec at a rotation increment."""
        return secant_shape_function(lever, rotation_increment)

    def mass_matrix(self, volume: np.ndarray, second: np.ndarray) -> np.ndarray:
        """∫TᵀT per unit density (nb, ndof, ndof) from the volume and central second moments."""
        return block_mass_matrix(volume, second[:, 0, 0], second[:, 1, 1], second[:, 0, 1])

    # -- the update of a step ----------------------------------------------
    def rotation_increment(self, dd: np.ndarray) -> np.ndarray:
        """The rotation unknowns of step increments ``dd`` (n, ndof), as the secant shape takes them."""
        return dd[:, self.rotation.start]

    def point_displacement(self, lever: np.ndarray, dd: np.ndarray, kinematics: str) -> np.ndarray:
        """Displacement (n, dim) of points at ``lever`` of blocks moving by ``dd`` (n, ndof)."""
        return point_displacement(lever, dd, kinematics)

    def initial_rotation(self, n_blocks: int) -> np.ndarray:
        """The accumulated rotation of blocks that have not turned."""
        return np.zeros(n_blocks)

    def compose_rotation(self, rotation: np.ndarray, dd: np.ndarray) -> np.ndarray:
        """Accumulated rotation after a step with increments ``dd``."""
        return rotation + self.rotation_increment(dd)

    def rotate_symmetric(self, components: np.ndarray, dd: np.ndarray, shear_factor: float) -> np.ndarray:
        """Symmetric tensors (n, n_strain) turned by the step's rotation: R·X·Rᵀ (objective update)."""
        return rotate_symmetric_components(components, self.rotation_increment(dd), shear_factor)

    def secant_mismatch(self, increment: np.ndarray, previous: np.ndarray) -> float:
        """max |θ|·|θ - θ_prev|: how far the last linearisation's rotation was from the solved one."""
        return float(np.max(np.abs(increment - previous) * np.abs(increment))) if len(increment) else 0.0


@dataclass(frozen=True)
class PlaneBlocks(BlockType):
    """2D blocks: (u0, v0, r0, εx, εy, γxy), paper Eq. 52; the rotation is an angle."""


@dataclass(frozen=True)
class SolidBlocks(BlockType):
    """3D blocks: (u0, v0, w0, rx, ry, rz, εx, εy, εz, γyz, γzx, γxy), paper Eq. A1-A2.

    The rotation increment is a rotation vector; the accumulated rotation is a
    matrix composed by products (Rodrigues), never a sum of vectors.
    """

    def shape(self, lever: np.ndarray, rotation_increment: np.ndarray | None = None) -> np.ndarray:
        return secant_shape_function_3d(lever, rotation_increment)

    def mass_matrix(self, volume: np.ndarray, second: np.ndarray) -> np.ndarray:
        return block_mass_matrix_3d(volume, second)

    def rotation_increment(self, dd: np.ndarray) -> np.ndarray:
        return dd[:, self.rotation]

    def point_displacement(self, lever: np.ndarray, dd: np.ndarray, kinematics: str) -> np.ndarray:
        return point_displacement_3d(lever, dd, kinematics)

    def initial_rotation(self, n_blocks: int) -> np.ndarray:
        return np.tile(np.eye(self.dim), (n_blocks, 1, 1))

    def compose_rotation(self, rotation: np.ndarray, dd: np.ndarray) -> np.ndarray:
        return compose_rotations(rotation, rotation_matrix_3d(self.rotation_increment(dd)))

    def rotate_symmetric(self, components: np.ndarray, dd: np.ndarray, shear_factor: float) -> np.ndarray:
        return rotate_symmetric_components_3d(components, rotation_matrix_3d(self.rotation_increment(dd)),
                                              shear_factor)

    def secant_mismatch(self, increment: np.ndarray, previous: np.ndarray) -> float:
        if not len(increment):
            return 0.0
        return float(np.max(np.linalg.norm(increment - previous, axis=1) * np.linalg.norm(increment, axis=1)))


PLANE = PlaneBlocks("plane", dim=2, ndof=NDOF, n_strain=3, translation=slice(0, 2), rotation=slice(2, 3),
                    strain=slice(3, 6))
SOLID = SolidBlocks("solid", dim=3, ndof=12, n_strain=6, translation=slice(0, 3), rotation=slice(3, 6),
                    strain=slice(6, 12))

_BY_DIMENSION = {2: PLANE, 3: SOLID}


def block_type_of_dimension(dim: int) -> BlockType:
    """The block type of ``dim``-dimensional models."""
    if dim not in _BY_DIMENSION:
        raise ValueError(f"no block type for {dim}-dimensional models (available: {sorted(_BY_DIMENSION)})")
    return _BY_DIMENSION[dim]
