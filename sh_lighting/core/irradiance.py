"""Irradiance from lighting coefficients (eq. 5-13) and its brute-force ground truth (eq. 1).

* ``irradiance_coefficients``: E_lm = Â_l L_lm (eq. 7, Â_l from eq. 8);
* ``irradiance``: E(n) by the paper's quadratic polynomial (eq. 13) for 9 coefficients, by the
  general sum Σ Â_l L_lm Y_lm(n) (eq. 6) for any other order;
* ``irradiance_matrices``: the 4×4 M of eq. 12 per colour channel, E(n) = nᵀ M n, n = (x, y, z, 1);
* ``reference_irradiance``: eq. 1 summed over every texel of an equirectangular map with exact
  solid angles and the clamped cosine at the texel centre (the ground truth the paper's
  error claims are measured against).

All coefficients are raw radiance L_lm (not pre-convolved), shape ((order+1)², 3), Blender axes.
"""

from math import pi, sqrt

import numpy as np

from .coefficients import check_coefficients as checked_coefficients
from .equirect import check_finite_pixels, check_pixels, texel_directions, texel_solid_angles
from .sh import band_of_each_coefficient, lambert_band_factors, order_of, sh_basis, spread_normals

# Eq. 13's constants, in closed form (the paper prints them rounded to 6 digits).
A0, A1, A2 = lambert_band_factors(2)
C1 = A2 * 0.25 * sqrt(15.0 / pi)  # 0.429043
C2 = 0.5 * A1 * sqrt(3.0 / (4.0 * pi))  # 0.511664
C3 = 3.0 * A2 * 0.25 * sqrt(5.0 / pi)  # 0.743125
C4 = A0 * 0.5 * sqrt(1.0 / pi)  # 0.886227
C5 = A2 * 0.25 * sqrt(5.0 / pi)  # 0.247708

# Largest |constant × polynomial| over the unit sphere of each term of eq. 13 (c4; 2 c2 for
# y, z, x; c1 for 2xy, 2yz, 2xz and x² − y²; c3 − c5 = 2 c5 for c3 z² − c5):
# TERM_PEAKS[i] · |L_i| is the most term i adds to or removes from E(n) anywhere.
TERM_PEAKS = np.array(
    [C4, 2.0 * C2, 2.0 * C2, 2.0 * C2, C1, C1, max(abs(-C5), abs(C3 - C5)), C1, C1]
)

# Texel directions times normals are computed in chunks of about this many float64 values.
CHUNK_VALUES = 1 << 22


def check_coefficients(coeffs):
    """Validate an ((order+1)², 3) coefficient array; returns (float64 array, order).

    The project's one coefficient check (``coefficients.check_coefficients``) for any order.
    """
    c = checked_coefficients(coeffs, count=None)
    return c, order_of(c.shape[0])


def irradiance_coefficients(coeffs):
    """E_lm = Â_l L_lm (eq. 7), same shape as ``coeffs``."""
    c, order = check_coefficients(coeffs)
    return c * lambert_band_factors(order)[band_of_each_coefficient(order)][:, None]


def _check_normals(normals):
    n = np.asarray(normals, dtype=np.float64)
    if n.ndim < 1 or n.shape[-1] != 3:
        raise ValueError(f"normals must have shape (..., 3), got {np.shape(normals)}")
    return n


def irradiance(coeffs, normals):
    """E(n) at unit ``normals`` (..., 3) → (..., 3) RGB: eq. 13 for 9 coefficients, else eq. 6."""
    c, order = check_coefficients(coeffs)
    n = _check_normals(normals)
    if order != 2:
        return sh_basis(n, order) @ irradiance_coefficients(c)
    x, y, z = (n[..., i, None] for i in range(3))
    L00, L1m1, L10, L11, L2m2, L2m1, L20, L21, L22 = c
    return (
        C1 * L22 * (x * x - y * y)
        + C3 * L20 * z * z
        + C4 * L00
        - C5 * L20
        + 2.0 * C1 * (L2m2 * x * y + L21 * x * z + L2m1 * y * z)
        + 2.0 * C2 * (L11 * x + L1m1 * y + L10 * z)
    )


def irradiance_matrices(coeffs):
    """M of eq. 12 for each channel, shape (3, 4, 4): E(n) = nᵀ M n with n = (x, y, z, 1)."""
    c, order = check_coefficients(coeffs)
    if order != 2:
        raise ValueError(f"the matrix form needs the 9 coefficients of order 2, got order {order}")
    L00, L1m1, L10, L11, L2m2, L2m1, L20, L21, L22 = c
    m = np.empty((3, 4, 4))
    m[:, 0] = np.stack([C1 * L22, C1 * L2m2, C1 * L21, C2 * L11], axis=-1)
    m[:, 1] = np.stack([C1 * L2m2, -C1 * L22, C1 * L2m1, C2 * L1m1], axis=-1)
    m[:, 2] = np.stack([C1 * L21, C1 * L2m1, C3 * L20, C2 * L10], axis=-1)
    m[:, 3] = np.stack([C2 * L11, C2 * L1m1, C2 * L10, C4 * L00 - C5 * L20], axis=-1)
    return m


def reference_irradiance(pixels, normals):
    """Ground-truth E(n) (eq. 1) of an equirectangular map at ``normals`` (..., 3) → (..., 3).

    Σ over every texel of L · max(n·ω, 0) · dΩ with ω the texel centre and dΩ its exact solid
    angle. Cost O(texels × normals), computed in float64 in chunks of texel rows.
    """
    a = check_pixels(pixels)
    n = _check_normals(normals)
    check_finite_pixels(a)
    height, width, _ = a.shape
    flat_n = n.reshape(-1, 3)
    radiance = a[..., :3].astype(np.float64) * texel_solid_angles(height, width)[:, None, None]
    directions = texel_directions(height, width)
    rows = max(1, CHUNK_VALUES // max(1, flat_n.shape[0] * width))
    result = np.zeros((flat_n.shape[0], 3))
    for r0 in range(0, height, rows):
        cosines = flat_n @ directions[r0 : r0 + rows].reshape(-1, 3).T
        np.maximum(cosines, 0.0, out=cosines)
        result += cosines @ radiance[r0 : r0 + rows].reshape(-1, 3)
    return result.reshape(n.shape[:-1] + (3,))


def total_power(coeffs):
    """P = ∫ L dω of each channel, (3,): L00 / Y00 = 2√π L00."""
    c, _ = check_coefficients(coeffs)
    return 2.0 * sqrt(pi) * c[0]


def error_over_power(estimate, reference, power):
    """|E − E_ref| / P per normal and channel: the paper's error measure.

    Ramamoorthi and Hanrahan (2001) give the 9-term irradiance error as a fraction of the total
    light P = ∫ L dω (``total_power``; REFERENCE.md §2: at most 3/32 anywhere and 0.0307 on
    average for non-negative lighting). ``estimate``, ``reference``: (N, 3) irradiance at the
    same normals; ``power``: (3,). A channel with P ≤ 0 is refused (ValueError).
    """
    p = np.asarray(power, dtype=np.float64)
    if np.any(p <= 0.0):
        raise ValueError("a channel has total power ≤ 0 (L00 ≤ 0): relative errors are undefined")
    return np.abs(np.asarray(estimate, dtype=np.float64) - reference) / p


def relative_error(estimate, reference, power):
    """(mean, max) of ``error_over_power``: the worst channel's mean over the normals, and the
    largest value over normals and channels, as floats (the paper's mean and max error).
    """
    err = error_over_power(estimate, reference, power)
    return float(err.mean(axis=0).max()), float(err.max())


def error_estimate(pixels, coeffs, count=256):
    """{"mean", "max"} 9-term irradiance error / total power ∫L dω of an equirect map, or
    None (a channel without light).

    The paper's measure (``relative_error``): |E9 − E| at ``count`` normals
    (``sh.spread_normals``) against the brute-force ``reference_irradiance`` (eq. 1) of
    ``pixels``, divided per channel by the channel's power 2√π L00; mean is the worst
    channel's mean, max the largest over normals and channels. The command line's and the
    preset builder's estimate.
    """
    power = total_power(coeffs)
    if not (power > 0.0).all():
        return None
    normals = spread_normals(count)
    mean, largest = relative_error(
        irradiance(coeffs, normals), reference_irradiance(pixels, normals), power
    )
    return {"mean": mean, "max": largest}
