"""An equirect world map as Blender shows it, and how to aim a Blender Sun light.

With the Mapping node's R = ``euler_xyz_matrix(e)`` and the Background's Strength s, the world
shows L_world(d) = s · L_image(R d) (docs/reference.md §3): the lighting is the image's rotated
by Rᵀ (``mapping_rotation``), a feature at ω appears at Rᵀ ω (``to_world_direction``), and the
irradiance is s · E_image(R n) (``map_irradiance``; ``equirect_irradiance`` the brute-force sum
of eq. 1). ``sun_light_rotation(s)`` takes the light's +Z to s, so it shines along −s. Blender
world axes; pixels (H, W, 3 or 4), rows top to bottom.
"""

import numpy as np

from .irradiance import reference_irradiance
from .projection import project_equirect
from .rotation import euler_xyz_matrix, rotate_coefficients

# A direction this close to ±Z (|x|, |y| below it) gets its object's X axis from +X rather
# than from the horizontal (the cross product with +Z would be too short to normalise).
NEAR_VERTICAL = 1e-9


def mapping_rotation(euler):
    """The rotation applied to the image's lighting by a Mapping node of XYZ Euler ``euler``.

    Rᵀ with R = ``euler_xyz_matrix(euler)`` (radians); the identity for ``euler`` None.
    """
    if euler is None:
        return np.eye(3)
    return euler_xyz_matrix(np.asarray(euler, dtype=np.float64)).T


def to_world_direction(direction, euler):
    """Where a direction ω of the image (..., 3) appears in the world: Rᵀ ω."""
    return np.asarray(direction, dtype=np.float64) @ mapping_rotation(euler).T


def map_coefficients(pixels, strength=1.0, euler=None, max_order=2):
    """L_lm of the world showing equirect ``pixels`` at ``strength`` through ``euler``.

    s · (the image's L_lm rotated by Rᵀ): what ``sh_lighting.blender.world.reader`` computes for
    such a world, for any pixels (e.g. a map with its sun taken out).
    """
    return apply_mapping(project_equirect(pixels, max_order=max_order), strength, euler)


def apply_mapping(coeffs, strength=1.0, euler=None):
    """L_lm of the world showing an image whose own L_lm are ``coeffs``, at ``strength``
    through ``euler``: s · (``coeffs`` rotated by Rᵀ), a new float64 array.

    The step after the projection, whatever the image's layout (equirect or mirror ball).
    """
    coeffs = np.asarray(coeffs, dtype=np.float64) * float(strength)
    if euler is None:
        return coeffs
    return rotate_coefficients(coeffs, mapping_rotation(euler))


def map_irradiance(pixels, normals, strength=1.0, euler=None):
    """Brute-force E(n) (eq. 1) of that world at unit world ``normals`` (..., 3) → (..., 3).

    s · E_image(R n), each over every texel (``equirect_irradiance``).
    """
    n = np.asarray(normals, dtype=np.float64)
    # rows are normals: (R n)ᵀ = nᵀ Rᵀ, and Rᵀ = mapping_rotation(euler)
    return equirect_irradiance(pixels, n @ mapping_rotation(euler)) * float(strength)


def equirect_irradiance(pixels, normals):
    """E(n) = Σ over every texel of L · ∫_texel max(n·ω, 0) dω (eq. 1), for unit ``normals``
    (..., 3): ``irradiance.reference_irradiance``. ``pixels``: (H, W, 3 or 4) linear radiance,
    rows top to bottom. Returns (..., 3) float64.
    """
    return reference_irradiance(pixels, normals)


def sun_light_rotation(direction):
    """A 3×3 rotation (columns: the object's X, Y, Z axes in world axes) with Z = ``direction``.

    ``direction``: (3,) toward the sun (normalised here). The object's −Z, along which a Blender
    light shines, is then −direction. Its X axis is horizontal (Z × the direction, normalised),
    so the light does not roll; for a direction straight up or down it is (nearly) +X.
    """
    z = np.asarray(direction, dtype=np.float64)
    length = np.linalg.norm(z)
    if z.shape != (3,) or not np.isfinite(z).all() or length == 0.0:
        raise ValueError(f"a sun direction must be a finite non-zero 3-vector, got {direction!r}")
    z = z / length
    x = np.array([-z[1], z[0], 0.0])  # (0, 0, 1) × z
    if np.linalg.norm(x) < NEAR_VERTICAL:
        x = np.array([1.0, 0.0, 0.0]) - z[0] * z  # +X made exactly perpendicular to z
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=-1)
