"""The pure-numpy core of sh_lighting: all the math, no bpy.

Ramamoorthi and Hanrahan, "An Efficient Representation for Irradiance Environment Maps",
SIGGRAPH 2001. Coefficients are raw radiance L_lm in Blender world axes (z up), shape
((order+1)², 3), ordered by l(l+1)+m; see docs/reference.md for every convention.
"""

from .equirect import direction_to_uv, texel_directions, texel_solid_angles, uv_to_direction
from .frames import blender_to_y_up, paper_to_blender, y_up_to_blender
from .irradiance import (
    irradiance,
    irradiance_coefficients,
    irradiance_matrices,
    reference_irradiance,
)
from .projection import project_equirect
from .rotation import euler_xyz_matrix, rotate_coefficients, sh_rotation_matrix
from .sh import COEFFICIENT_NAMES, lambert_band_factors, sh_basis, sh_index

__all__ = [
    "COEFFICIENT_NAMES",
    "blender_to_y_up",
    "direction_to_uv",
    "euler_xyz_matrix",
    "irradiance",
    "irradiance_coefficients",
    "irradiance_matrices",
    "lambert_band_factors",
    "paper_to_blender",
    "project_equirect",
    "reference_irradiance",
    "rotate_coefficients",
    "sh_basis",
    "sh_index",
    "sh_rotation_matrix",
    "texel_directions",
    "texel_solid_angles",
    "uv_to_direction",
    "y_up_to_blender",
]
