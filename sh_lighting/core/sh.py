"""Real spherical harmonics Y_lm in the paper's convention (Ramamoorthi and Hanrahan 2001, eq. 3).

Real SH without the Condon-Shortley phase (Y_11 = +√(3/4π) x), index l(l+1) + m, m > 0 with
cos(mφ), m < 0 with sin(|m|φ), φ = atan2(y, x), z = cos θ, Blender world axes
(docs/reference.md §1). ``sh_basis`` uses the paper's closed forms for bands 0-2 and the
associated-Legendre recurrence above; ``sh_basis_recurrence`` is the slow reference.
"""

from math import factorial, pi, sqrt

import numpy as np

# Closed forms of the paper's constants (eq. 3).
Y00 = 0.5 * sqrt(1.0 / pi)  # 0.282095
Y1 = sqrt(3.0 / (4.0 * pi))  # 0.488603: y, z, x
Y2_XY = 0.5 * sqrt(15.0 / pi)  # 1.092548: xy, yz, xz
Y20 = 0.25 * sqrt(5.0 / pi)  # 0.315392: (3z² - 1)
Y22 = 0.25 * sqrt(15.0 / pi)  # 0.546274: (x² - y²)

COEFFICIENT_NAMES = ("L00", "L1-1", "L10", "L11", "L2-2", "L2-1", "L20", "L21", "L22")
# What each coefficient does, in Blender world axes (docs/reference.md §1: Y1-1 ∝ y, Y10 ∝ z,
# Y11 ∝ x, Y2-2 ∝ xy, Y2-1 ∝ yz, Y20 ∝ 3z² - 1, Y21 ∝ xz, Y22 ∝ x² - y²): the one wording of
# the nine terms (panel, tooltips, command line).
COEFFICIENT_PHRASES = (
    "ambient (overall brightness)",
    "light from +Y vs −Y",
    "light from above vs below",
    "light from +X vs −X",
    "xy diagonal",
    "yz diagonal",
    "top/bottom vs horizon",
    "xz diagonal",
    "x vs y axis",
)



def coefficient_table(coeffs):
    """Text lines of a (9, 3) coefficient table: name, R, G, B and what each coefficient does."""
    lines = [f"{'':5} {'R':>11} {'G':>11} {'B':>11}   what it does"]
    for name, rgb, phrase in zip(COEFFICIENT_NAMES, coeffs, COEFFICIENT_PHRASES):
        lines.append(f"{name:5} {rgb[0]:11.5f} {rgb[1]:11.5f} {rgb[2]:11.5f}   {phrase}")
    return lines

def sh_index(l, m):
    """Position of Y_lm in a coefficient array: l(l+1) + m."""
    return l * (l + 1) + m


def num_coefficients(max_order):
    """(max_order + 1)², the number of Y_lm with l <= max_order."""
    return (max_order + 1) ** 2


def order_of(num):
    """Inverse of ``num_coefficients``; a ValueError if ``num`` is not a square."""
    order = int(round(sqrt(num))) - 1
    if order < 0 or num_coefficients(order) != num:
        raise ValueError(
            f"{num} SH coefficients is not (order + 1)² for any order: "
            "pass 1, 4, 9, 16, ... coefficients"
        )
    return order


def spread_normals(count):
    """``count`` near-uniform unit vectors (a Fibonacci lattice in z, golden angle in φ).

    Deterministic: the same ``count`` always gives the same normals. Point k has
    z = 1 − 2(k + ½)/count, so each covers the same area 4π/count of the sphere. The one
    lattice of the package: the SH rotation fit, the error estimates and the tests use it.
    """
    if int(count) != count or count < 1:
        raise ValueError(f"count must be a whole number ≥ 1, got {count!r}")
    k = np.arange(int(count)) + 0.5
    z = 1.0 - 2.0 * k / count
    phi = np.pi * (3.0 - np.sqrt(5.0)) * k  # the golden angle, 2π(1 − 1/φ)
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def band_of_each_coefficient(max_order):
    """The band l of each of the (max_order + 1)² coefficients, as an int array."""
    return np.repeat(np.arange(max_order + 1), 2 * np.arange(max_order + 1) + 1)


def normalisation(l, m):
    """K_lm of the real basis: sqrt((2l+1)/4π · (l-|m|)!/(l+|m|)!), times sqrt(2) for m != 0."""
    m = abs(m)
    k = sqrt((2 * l + 1) / (4.0 * pi) * factorial(l - m) / factorial(l + m))
    return k if m == 0 else sqrt(2.0) * k


def legendre_q(max_order, z):
    """Q_l^m(z) for 0 <= m <= l <= max_order, with P_l^m(z) = (1 - z²)^(m/2) Q_l^m(z).

    Without the Condon-Shortley phase. Standard three-term recurrence in l:
    Q_m^m = (2m-1)!!, Q_(m+1)^m = (2m+1) z Q_m^m,
    (l-m) Q_l^m = (2l-1) z Q_(l-1)^m - (l+m-1) Q_(l-2)^m.
    Returns a dict {(l, m): array shaped like z}.
    """
    z = np.asarray(z, dtype=np.float64)
    q = {}
    double_factorial = 1.0
    for m in range(max_order + 1):
        if m > 0:
            double_factorial *= 2 * m - 1
        q[m, m] = np.full_like(z, double_factorial)
        if m + 1 <= max_order:
            q[m + 1, m] = (2 * m + 1) * z * q[m, m]
        for l in range(m + 2, max_order + 1):
            q[l, m] = ((2 * l - 1) * z * q[l - 1, m] - (l + m - 1) * q[l - 2, m]) / (l - m)
    return q


def _check_directions(directions):
    d = np.asarray(directions, dtype=np.float64)
    if d.ndim < 1 or d.shape[-1] != 3:
        raise ValueError(
            f"directions must have shape (..., 3), got {np.shape(directions)}: "
            "pass unit vectors (x, y, z) in Blender world axes"
        )
    return d


def _check_order(max_order):
    if int(max_order) != max_order or max_order < 0:
        raise ValueError(f"max_order must be a whole number >= 0, got {max_order!r}")
    return int(max_order)


def sh_basis_recurrence(directions, max_order=2):
    """All Y_lm (l <= max_order) at unit ``directions`` by the recurrence (the slow reference).

    Uses sin^m θ cos mφ = Re (x + iy)^m and sin^m θ sin mφ = Im (x + iy)^m, so nothing
    divides by sin θ and the poles are exact. Returns shape (..., (max_order+1)²).
    """
    d = _check_directions(directions)
    max_order = _check_order(max_order)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    q = legendre_q(max_order, z)
    out = np.empty(d.shape[:-1] + (num_coefficients(max_order),))
    c_m, s_m = np.ones_like(x), np.zeros_like(x)  # Re and Im of (x + iy)^m
    for m in range(max_order + 1):
        for l in range(m, max_order + 1):
            k = normalisation(l, m)
            out[..., sh_index(l, m)] = k * q[l, m] * c_m
            if m > 0:
                out[..., sh_index(l, -m)] = k * q[l, m] * s_m
        c_m, s_m = c_m * x - s_m * y, c_m * y + s_m * x
    return out


def sh_basis(directions, max_order=2):
    """Real SH Y_lm (l <= max_order) at unit ``directions``, shape (..., (max_order+1)²).

    Bands 0-2 use the paper's closed forms (eq. 3); higher bands come from the recurrence.
    """
    d = _check_directions(directions)
    max_order = _check_order(max_order)
    if max_order > 2:
        out = sh_basis_recurrence(d, max_order)
        out[..., :9] = sh_basis(d, 2)
        return out
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    out = np.empty(d.shape[:-1] + (9,))
    out[..., 0] = Y00
    out[..., 1] = Y1 * y
    out[..., 2] = Y1 * z
    out[..., 3] = Y1 * x
    out[..., 4] = Y2_XY * x * y
    out[..., 5] = Y2_XY * y * z
    out[..., 6] = Y20 * (3.0 * z * z - 1.0)
    out[..., 7] = Y2_XY * x * z
    out[..., 8] = Y22 * (x * x - y * y)
    return out[..., : num_coefficients(max_order)]


def lambert_band_factors(max_order):
    """Â_l for l = 0..max_order: the clamped-cosine kernel's SH transfer (eq. 8).

    Â_0 = π, Â_1 = 2π/3, Â_l = 0 for odd l > 1, and for even l
    Â_l = 2π (-1)^(l/2 - 1) / ((l + 2)(l - 1)) · l! / (2^l ((l/2)!)²).
    """
    a = np.zeros(_check_order(max_order) + 1)
    for l in range(max_order + 1):
        if l == 0:
            a[l] = pi
        elif l == 1:
            a[l] = 2.0 * pi / 3.0
        elif l % 2 == 0:
            h = l // 2
            a[l] = (
                2.0 * pi * (-1) ** (h - 1) / ((l + 2) * (l - 1))
                * factorial(l) / (2**l * factorial(h) ** 2)
            )
    return a
