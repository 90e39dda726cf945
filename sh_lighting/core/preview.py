"""Small numpy images for the lighting panel: the 9 basis functions and the current irradiance.

RGBA float32, rows top to bottom, display-ready sRGB values in [0, 1]. The sphere is seen
orthographically from Blender's front view (−Y toward +Y, +Z up): pixel (r, c) has
sx = 2(c + ½)/size − 1, sz = 1 − 2(r + ½)/size and normal n = (sx, −√(1 − sx² − sz²), sz);
alpha is the disc's coverage. Normals and basis values are cached per size, so an irradiance
preview is one (size², 9) × (9, 3) product and the sRGB encoding.
"""

from functools import lru_cache

import numpy as np

from .equirect import texel_directions
from .irradiance import check_coefficients, irradiance_coefficients
from .sh import lambert_band_factors, sh_basis

NEGATIVE_COLOUR = (1.0, 0.0, 1.0)  # magenta: where the 9-term irradiance is below zero
BASIS_POSITIVE = np.array([0.0, 1.0, 0.0])  # green, as in the paper's figure 4
BASIS_NEGATIVE = np.array([0.0, 0.0, 1.0])  # blue
CACHED_SIZES = 8


def _read_only(*arrays):
    for a in arrays:
        a.flags.writeable = False
    return arrays


@lru_cache(maxsize=CACHED_SIZES)
def sphere_normals(size):
    """(normals (size, size, 3), alpha (size, size)) of the sphere view (module docstring)."""
    if int(size) != size or size < 1:
        raise ValueError(f"size must be a whole number ≥ 1, got {size!r}")
    centres = (np.arange(size) + 0.5) * (2.0 / size) - 1.0
    sx = centres[None, :]
    sz = -centres[:, None]
    rho = np.sqrt(sx * sx + sz * sz)
    # coverage of a pixel (width 2/size) by the disc, linear across the rim
    alpha = np.clip((1.0 - rho) * (size / 2.0) + 0.5, 0.0, 1.0)
    scale = np.minimum(1.0, 1.0 / np.maximum(rho, 1e-300))  # outside: pull onto the rim
    x, z = np.broadcast_arrays(sx * scale, sz * scale)
    y = -np.sqrt(np.maximum(0.0, 1.0 - x * x - z * z))
    normals = np.stack([x, y, z], axis=-1)
    return _read_only(normals, alpha)


@lru_cache(maxsize=CACHED_SIZES)
def _sphere_basis(size):
    normals, _ = sphere_normals(size)
    return _read_only(sh_basis(normals.reshape(-1, 3), 2))[0]


@lru_cache(maxsize=CACHED_SIZES)
def _equirect_basis(height, width):
    return _read_only(sh_basis(texel_directions(height, width).reshape(-1, 3), 2))[0]


def linear_to_srgb(values):
    """IEC 61966-2-1 sRGB encoding of linear values clipped to [0, 1]."""
    v = np.clip(values, 0.0, 1.0)
    encoded = np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1.0 / 2.4) - 0.055)
    return np.minimum(encoded, 1.0)  # 1.055 − 0.055 rounds above 1


def basis_sphere_images(size=128):
    """The 9 Y_lm drawn on the sphere view as in the paper's figure 4: (9, size, size, 4).

    Index k = l(l+1) + m. Green where Y_lm > 0, blue where < 0, brightness
    |Â_l Y_lm(n)| / max over all l, m, n of |Â_l Y_lm| (each function's contribution to the
    irradiance per unit L_lm, eq. 6), so the l = 2 row is dimmer (Â_2 = π/4 < Â_1 = 2π/3).
    Values are display values; alpha is the disc mask.
    """
    normals, alpha = sphere_normals(size)
    a = lambert_band_factors(2)[[0, 1, 1, 1, 2, 2, 2, 2, 2]]
    weighted = sh_basis(normals, 2) * a  # (size, size, 9)
    peak = a[1] * sh_basis(np.array([0.0, 0.0, 1.0]), 2)[2]  # Â_1 Y10 at the pole: the max
    value = np.moveaxis(weighted, -1, 0) / peak  # (9, size, size)
    v = value[..., None]
    colour = np.where(v >= 0.0, BASIS_POSITIVE * v, BASIS_NEGATIVE * -v)
    out = np.empty((9, size, size, 4), dtype=np.float32)
    out[..., :3] = colour
    out[..., 3] = alpha
    return out


def _encode(radiance, exposure, alpha, show_negative):
    """RGBA float32 of linear radiance (..., 3): × 2^exposure, sRGB-encoded, alpha appended."""
    rgba = np.empty(radiance.shape[:-1] + (4,), dtype=np.float32)
    rgba[..., :3] = linear_to_srgb(radiance * 2.0**exposure)
    if show_negative:
        rgba[(radiance < 0.0).any(axis=-1), :3] = NEGATIVE_COLOUR
    rgba[..., 3] = alpha
    return rgba


def _sphere_radiance(c, size):
    """E(n)/π (albedo 1) of every pixel of the sphere view: (size, size, 3)."""
    return (_sphere_basis(size) @ irradiance_coefficients(c)).reshape(size, size, 3) / np.pi


def _order_two(coeffs):
    c, order = check_coefficients(coeffs)
    if order != 2:
        raise ValueError(f"the preview takes the 9 coefficients of order 2, got order {order}")
    return c


def fit_exposure(coeffs, size=128):
    """The exposure (stops) at which the sphere view's brightest pixel shows exactly white:
    −log₂ of the largest E(n)/π of any channel over the disc, so the sphere reads whatever
    the lighting's level (a sun-lit HDRI at exposure 0 turns half the disc white). 0 when no
    pixel is lit (E ≤ 0 everywhere)."""
    _, alpha = sphere_normals(size)
    peak = _sphere_radiance(_order_two(coeffs), size)[alpha > 0.0].max()
    return float(-np.log2(peak)) if peak > 0.0 else 0.0


def irradiance_sphere_image(coeffs, size=128, exposure=0.0, show_negative=False):
    """A white diffuse sphere under the lighting, as seen in the sphere view: (size, size, 4).

    Shows the reflected radiance E(n)/π (eq. 6, albedo 1) × 2^exposure, sRGB-encoded and
    clipped to [0, 1] (``fit_exposure`` gives the exposure that puts the brightest pixel at
    1); negative irradiance shows black, or ``NEGATIVE_COLOUR`` when ``show_negative``.
    Alpha is the disc mask.
    """
    c = _order_two(coeffs)
    _, alpha = sphere_normals(size)
    return _encode(_sphere_radiance(c, size), exposure, alpha, show_negative)


def irradiance_equirect_image(coeffs, width, height, exposure=0.0, show_negative=False):
    """E(n)/π of every normal as an equirect image (height, width, 4), Blender's mapping.

    Texel (row, column) holds the normal of its centre (``equirect.texel_directions``, rows
    top to bottom, the centre column facing +X); same encoding as ``irradiance_sphere_image``,
    alpha 1.
    """
    c = _order_two(coeffs)
    e = _equirect_basis(int(height), int(width)) @ irradiance_coefficients(c)
    return _encode(e.reshape(height, width, 3) / np.pi, exposure, 1.0, show_negative)
