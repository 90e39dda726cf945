"""An equirect world map as Blender shows it, and how to aim a Blender Sun light.

Blender's world shader reads an Environment Texture through an optional Mapping node (Point,
XYZ Euler rotation e) and scales it by the Background's Strength s (REFERENCE.md §3). With
R = ``euler_xyz_matrix(e)`` the Mapping node turns the *lookup* direction: the world shows, in
direction d, the image's radiance at R d, times s:

    L_world(d) = s · L_image(R d).

So the lighting is the image's lighting rotated by Rᵀ (``mapping_rotation``); a feature the
image holds at direction ω appears in the world at Rᵀ ω (``to_world_direction``); and the
world's irradiance at a normal n is s · E_image(R n), since
∫ L_image(R ω) max(n·ω, 0) dω = ∫ L_image(ω') max((R n)·ω', 0) dω' (``map_irradiance``).
``euler`` None means no Mapping node (R = I).

``equirect_irradiance`` is that brute-force sum (eq. 1, every texel, nothing downsampled) in
O(texels + rows × normals) instead of O(texels × normals): in row i (polar angle θ_i) the lit
texels of a normal n = (a, b, c) are those with sin θ_i (a cos φ + b sin φ) + c cos θ_i > 0, one
arc of columns |φ − atan2(b, a)| < arccos(−c cos θ_i / (ρ sin θ_i)) with ρ = √(a² + b²) (all or
none of the row when the bound leaves [−1, 1]); over the arc the sum is
sin θ_i (a Σ L cos φ + b Σ L sin φ) + c cos θ_i Σ L, three running sums along the row. The same
terms as ``irradiance.reference_irradiance`` (its slow reference), added in another order;
texels on the arc's ends have n·ω ≈ 0, so whether rounding puts them in or out is invisible.

A Blender light shines along the −Z axis of its object. ``sun_light_rotation(s)`` is an
object rotation that takes +Z to the unit direction s toward the sun, so the light shines
along −s, from the sun toward the scene.

Everything is in Blender world axes (z up); pixels are (H, W, 3 or 4), rows top to bottom.
"""

from math import pi

import numpy as np

from .equirect import (
    check_finite_pixels,
    check_pixels,
    column_centres,
    row_centres,
    texel_solid_angles,
)
from .irradiance import _check_normals
from .projection import project_equirect
from .rotation import euler_xyz_matrix, rotate_coefficients

# A direction this close to ±Z (|x|, |y| below it) gets its object's X axis from +X rather
# than from the horizontal (the cross product with +Z would be too short to normalise).
NEAR_VERTICAL = 1e-9
# Running sums and gathered arc sums are handled in blocks of rows of about this many values.
CHUNK_VALUES = 1 << 22


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

    s · (the image's L_lm rotated by Rᵀ): what ``sh_lighting.blender.world`` computes for
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


def _lit_arcs(normals, theta, width):
    """(first column, number of columns) of the lit arc of each normal in each row: (N, h)."""
    x, y, z = normals[:, 0, None], normals[:, 1, None], normals[:, 2, None]
    rho = np.hypot(x, y)
    with np.errstate(divide="ignore", invalid="ignore"):
        bound = -(z * np.cos(theta)) / (rho * np.sin(theta))  # lit: cos(φ − α) > bound
    half = np.arccos(np.clip(bound, -1.0, 1.0))
    alpha = np.arctan2(y, x)
    step = 2.0 * pi / width
    # column j is lit for (j + ½) step in (π − α − half, π − α + half), modulo 2π
    first = np.floor((pi - alpha - half) / step - 0.5) + 1.0
    last = np.ceil((pi - alpha + half) / step - 0.5) - 1.0
    count = np.clip(last - first + 1.0, 0.0, width)
    count = np.where(bound < -1.0, width, np.where(bound >= 1.0, 0.0, count))
    count = np.where(np.isnan(bound), 0.0, count)  # ρ = 0 and c cos θ = 0: n·ω = 0
    first = np.where(bound < -1.0, 0.0, first)
    return np.mod(first, width).astype(np.intp), count.astype(np.intp)


def equirect_irradiance(pixels, normals):
    """E(n) = Σ over every texel of L · max(n·ω, 0) · dΩ (eq. 1), for unit ``normals`` (..., 3).

    Equal to ``irradiance.reference_irradiance`` (same texel centres ω and exact solid angles
    dΩ) up to rounding, in O(texels + rows × normals) (module docstring). ``pixels``: (H, W, 3
    or 4) linear radiance, rows top to bottom. Returns (..., 3) float64.
    """
    a = check_pixels(pixels)
    n = _check_normals(normals)
    check_finite_pixels(a)
    height, width, _ = a.shape
    flat = n.reshape(-1, 3)
    theta = row_centres(height)
    phi = column_centres(width)
    trig = np.stack([np.ones(width), np.cos(phi), np.sin(phi)], axis=-1)  # (W, 3)
    solid = texel_solid_angles(height, width)
    rows = max(1, CHUNK_VALUES // (9 * max(width + 1, flat.shape[0])))
    result = np.zeros((flat.shape[0], 3))
    for r0 in range(0, height, rows):
        r1 = min(height, r0 + rows)
        radiance = a[r0:r1, :, :3].astype(np.float64) * solid[r0:r1, None, None]
        # running sums along each row of L, L cos φ, L sin φ: (h, W + 1, 3 terms, 3 channels)
        sums = np.zeros((r1 - r0, width + 1, 3, 3))
        np.cumsum(radiance[:, :, None, :] * trig[None, :, :, None], axis=1, out=sums[:, 1:])
        first, count = _lit_arcs(flat, theta[r0:r1], width)
        end = first + count
        row = np.arange(r1 - r0)[None, :]
        wrapped = end > width
        arc = sums[row, np.minimum(end, width)] - sums[row, first]
        arc += np.where(wrapped, 1.0, 0.0)[..., None, None] * sums[row, np.where(wrapped,
                                                                                 end - width, 0)]
        # n·ω = sin θ (a cos φ + b sin φ) + c cos θ, summed over the arc: (N, h, 3 channels)
        st, ct = np.sin(theta[r0:r1])[None, :, None], np.cos(theta[r0:r1])[None, :, None]
        x, y, z = (flat[:, k, None, None] for k in range(3))
        lit = st * (x * arc[:, :, 1] + y * arc[:, :, 2]) + z * ct * arc[:, :, 0]
        result += lit.sum(axis=1)
    return result.reshape(n.shape[:-1] + (3,))


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
