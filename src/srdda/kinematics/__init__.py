"""Kinematics (the dimension-dependent seam): shape function, S-R decomposition, updates."""
from .shape2d import NDOF, block_mass_matrix, rotation_matrix, shape_function, strain_selector
from .sr import chen_strain, mean_rotation, sr_decomposition, sr_decomposition_3d
from .update2d import KINEMATICS, point_displacement, rotate_symmetric_components, secant_shape_function

__all__ = [
    "NDOF", "KINEMATICS", "block_mass_matrix", "chen_strain", "mean_rotation", "point_displacement",
    "rotate_symmetric_components", "rotation_matrix", "secant_shape_function", "shape_function",
    "sr_decomposition", "sr_decomposition_3d", "strain_selector",
]
from .shape3d import (NDOF_3D, block_mass_matrix_3d, compose_rotations, elasticity_matrix_3d,
                      rodrigues_coefficients, rotation_matrix_3d, shape_function_3d, skew, strain_selector_3d)
from .update3d import point_displacement_3d, rotate_symmetric_components_3d, secant_shape_function_3d

__all__ += [
    "NDOF_3D", "block_mass_matrix_3d", "compose_rotations", "elasticity_matrix_3d", "point_displacement_3d",
    "rodrigues_coefficients", "rotate_symmetric_components_3d", "rotation_matrix_3d", "secant_shape_function_3d",
    "shape_function_3d", "skew", "strain_selector_3d",
]
