"""Kinematics (the dimension-dependent seam): shape function, S-R decomposition, updates."""
from .shape import NDOF, block_mass_matrix, rotation_matrix, shape_function, strain_selector
from .sr import chen_strain, mean_rotation, sr_decomposition, sr_decomposition_3d
from .update import KINEMATICS, point_displacement, rotate_symmetric_components, secant_shape_function

__all__ = [
    "NDOF", "KINEMATICS", "block_mass_matrix", "chen_strain", "mean_rotation", "point_displacement",
    "rotate_symmetric_components", "rotation_matrix", "secant_shape_function", "shape_function",
    "sr_decomposition", "sr_decomposition_3d", "strain_selector",
]
