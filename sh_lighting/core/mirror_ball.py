"""Blender's mirror-ball environment mapping and the lighting coefficients of a mirror-ball image.

Cycles' "Mirror Ball": a chrome ball seen from −Y along +Y, z up. With x = 2u − 1, z = 2v − 1
(v from the bottom), the disk point is the normal n = (x, −s, z), s = √(1 − x² − z²), and shows
the reflected direction d = (2 s x, 1 − 2 s², 2 s z): the centre −Y, the rim +Y. The map is
equal-area, dΩ = 4 dA. Rows top to bottom; texels outside the disk carry no light.
"""

import numpy as np

from .equirect import NonFiniteError, check_pixels, describe_nonfinite, direction_to_texel
from .sh import num_coefficients, sh_basis

# Texels within this many texel sizes of the rim are integrated on a sub-grid: there the
# direction changes fastest and the texels are only partly inside the disk.
RIM_TEXELS = 3.0
RIM_SUBSAMPLES = 8
# Rows per block when evaluating the basis, to bound temporary memory.
BLOCK_TEXELS = 1 << 18


def mirror_ball_to_direction(u, v):
    """The direction shown at (u, v) of a mirror-ball image, (..., 3); NaN outside the disk."""
    x = 2.0 * np.asarray(u, dtype=np.float64) - 1.0
    z = 2.0 * np.asarray(v, dtype=np.float64) - 1.0
    r2 = x * x + z * z
    s = np.sqrt(np.where(r2 <= 1.0, 1.0 - r2, np.nan))
    return np.stack(np.broadcast_arrays(2.0 * s * x, 1.0 - 2.0 * s * s, 2.0 * s * z), axis=-1)


def direction_to_mirror_ball(directions):
    """(u, v) of unit ``directions`` (..., 3) in a mirror-ball image (v from the bottom).

    +Y (straight behind the ball) is the whole rim; it is returned as the rim's top, (0.5, 1).
    """
    d = np.asarray(directions, dtype=np.float64)
    s = np.sqrt(np.maximum(0.5 * (1.0 - d[..., 1]), 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        x = np.where(s > 0.0, d[..., 0] / (2.0 * s), 0.0)
        z = np.where(s > 0.0, d[..., 2] / (2.0 * s), 1.0)
    return 0.5 * (x + 1.0), 0.5 * (z + 1.0)


def _disk_coordinates(height, width):
    """x of each column centre and z of each row centre (rows top to bottom), and texel sizes."""
    dx, dz = 2.0 / width, 2.0 / height
    x = (np.arange(width) + 0.5) * dx - 1.0
    z = 1.0 - (np.arange(height) + 0.5) * dz
    return x, z, dx, dz


def _rim_weights(x, z, dx, dz, max_order, subsamples):
    """∫ Y_lm dΩ over the part of each texel (centres x, z) inside the disk, by a sub-grid."""
    offsets = (np.arange(subsamples) + 0.5) / subsamples - 0.5
    sx = x[:, None, None] + offsets[None, None, :] * dx
    sz = z[:, None, None] + offsets[None, :, None] * dz
    sx, sz = np.broadcast_arrays(sx, sz)
    d = mirror_ball_to_direction(0.5 * (sx + 1.0), 0.5 * (sz + 1.0))
    inside = np.isfinite(d[..., 0])
    basis = sh_basis(np.where(inside[..., None], d, 0.0), max_order)
    basis *= inside[..., None]
    return basis.sum(axis=(1, 2)) * (4.0 * dx * dz / subsamples**2)


def mirror_ball_weights(height, width, max_order=2, rows=None, subsamples=RIM_SUBSAMPLES):
    """Per-texel ∫ Y_lm dΩ over the texel's part of the disk, shape (R, W, (max_order+1)²).

    ``rows``: a slice of the rows (top to bottom) to compute, all of them by default. Texels
    well inside the disk use the midpoint rule (Y at the centre times 4 × area); texels near or
    across the rim are integrated on a ``subsamples``² sub-grid.
    """
    x, z, dx, dz = _disk_coordinates(height, width)
    xx, zz = np.meshgrid(x, z[rows if rows is not None else slice(None)])
    # Distance from the disk centre to the nearest and farthest points of each texel.
    near = np.hypot(np.maximum(np.abs(xx) - dx / 2, 0.0), np.maximum(np.abs(zz) - dz / 2, 0.0))
    far = np.hypot(np.abs(xx) + dx / 2, np.abs(zz) + dz / 2)
    rim = (far > 1.0 - RIM_TEXELS * max(dx, dz)) & (near < 1.0)
    interior = ~rim & (far <= 1.0)
    weights = np.zeros(xx.shape + (num_coefficients(max_order),))
    d = mirror_ball_to_direction(0.5 * (xx[interior] + 1.0), 0.5 * (zz[interior] + 1.0))
    weights[interior] = sh_basis(d, max_order) * (4.0 * dx * dz)
    weights[rim] = _rim_weights(xx[rim], zz[rim], dx, dz, max_order, subsamples)
    return weights


def project_mirror_ball(pixels, max_order=2, nonfinite="raise"):
    """L_lm of a mirror-ball image, shape ((max_order+1)², 3), float64, Blender axes.

    ``pixels``: (H, W, 3 or 4) float radiance, rows top to bottom, the ball filling the image
    (an ellipse if it is not square). The image is taken as piecewise constant over its texels;
    texels are weighted by the solid angle of their part of the disk. ``nonfinite``: "raise"
    or "zero", as for ``project_equirect``; texels outside the disk are never read.
    """
    a = check_pixels(pixels)
    if nonfinite not in ("raise", "zero"):
        raise ValueError(f'nonfinite must be "raise" or "zero", got {nonfinite!r}')
    height, width, _ = a.shape
    rows = max(1, BLOCK_TEXELS // width)
    coeffs = np.zeros((num_coefficients(max_order), 3))
    for r0 in range(0, height, rows):
        w = mirror_ball_weights(height, width, max_order, slice(r0, r0 + rows))
        rgb = a[r0 : r0 + rows, :, :3].astype(np.float64)
        used = (w != 0.0).any(axis=-1)
        bad = used & ~np.isfinite(rgb).all(axis=-1)
        if bad.any():
            if nonfinite == "raise":
                _, message = describe_nonfinite(np.where(used[..., None], a[r0 : r0 + rows], 0))
                raise NonFiniteError(
                    f"{message} (rows counted from {r0})",
                    "repair the image, or pass nonfinite='zero' to treat those texels as black",
                )
            rgb = np.where(bad[..., None], 0.0, rgb)
        rgb = np.where(used[..., None], rgb, 0.0)
        coeffs += np.einsum("hwk,hwc->kc", w, rgb)
    return coeffs


def mirror_ball_image(equirect, size):
    """The ``size``² mirror-ball image (rows top to bottom) of an equirect map (H, W, C): each
    texel inside the disk the equirect texel its centre's direction falls in (nearest, no
    filtering), 0 outside: what a chrome ball photographed from −Y shows of that world."""
    pixels = np.asarray(equirect)
    centres = (np.arange(size) + 0.5) / size
    u, v = np.meshgrid(centres, centres[::-1])  # v from the bottom
    directions = mirror_ball_to_direction(u, v)
    inside = np.isfinite(directions[..., 0])
    image = np.zeros((size, size) + pixels.shape[2:], dtype=pixels.dtype)
    image[inside] = pixels[direction_to_texel(directions[inside], *pixels.shape[:2])]
    return image
