"""Exact lighting edits on the 9 (or any (order+1)²) RGB coefficients L_lm.

Each edit is linear in L(ω), so exact on the coefficients; each returns new float64 ones.
``rotate``: L'(ω) = L(Rᵀω) by yaw, pitch, roll (the band-wise rotation of ``rotation``);
``exposure``: L' = 2^stops L; ``saturation``: each RGB row blended toward its luminance;
``band_gains``: one gain per band l = 0, 1, 2 (eq. 13's terms); ``flip_vertical``: z → −z;
``describe_coefficients``: what each coefficient does in the current lighting.
"""

import numpy as np

from .colour import luminance_weights
from .irradiance import C4, TERM_PEAKS, check_coefficients
from .rotation import rotate_coefficients
from .sh import COEFFICIENT_NAMES, band_of_each_coefficient

# Luminance weights of linear Rec.709 RGB (``core.colour.luminance_weights``; they sum to 1, so
# grey keeps the luminance); callers in another working space pass that space's weights.
LUMINANCE = luminance_weights()


def _axis_rotation(axis, angle):
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]  # the plane turned: x → (y, z), y → (z, x), z → (x, y)
    r = np.eye(3)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def yaw_pitch_roll_matrix(yaw, pitch, roll):
    """R = Rz(yaw) · Rx(pitch) · Ry(roll), angles in radians.

    Applied to the lighting, a light in direction s moves to R s: first ``roll`` about +Y (the
    line of sight of Blender's front view), then ``pitch`` about +X, then ``yaw`` about the
    vertical +Z. Each turn is right-handed (counter-clockwise seen from the axis' positive
    end): yaw +90° takes +X to +Y, pitch +90° takes +Y to +Z, roll +90° takes +Z to +X.
    """
    return _axis_rotation(2, yaw) @ _axis_rotation(0, pitch) @ _axis_rotation(1, roll)


def rotate(coeffs, yaw=0.0, pitch=0.0, roll=0.0):
    """The lighting rotated by R = ``yaw_pitch_roll_matrix(yaw, pitch, roll)``: L'(ω) = L(Rᵀω).

    Exact: each band l is multiplied by its (2l+1)×(2l+1) rotation matrix D_l(R).
    """
    c, _ = check_coefficients(coeffs)
    return rotate_coefficients(c, yaw_pitch_roll_matrix(yaw, pitch, roll))


def exposure(coeffs, stops):
    """L' = 2^stops · L (so E' = 2^stops · E): ``stops`` photographic stops brighter."""
    c, _ = check_coefficients(coeffs)
    return c * 2.0**stops


def _bands_mask(order, bands):
    band = band_of_each_coefficient(order)
    if bands is None:
        return np.ones(band.size, dtype=bool)
    return np.isin(band, list(bands))


def saturation(coeffs, amount, bands=None, luminance=LUMINANCE):
    """Each coefficient's RGB blended with its grey: grey + amount · (L_lm − grey).

    grey = ``luminance`` · RGB of that coefficient (default Rec.709's 0.2126 R + 0.7152 G +
    0.0722 B; ``core.colour.luminance_weights`` of the working space), so the luminance of the
    lighting, and of the irradiance, is unchanged. ``amount``: 0 grey, 1 unchanged, > 1 more
    saturated. ``bands``: the bands l to change (default all), e.g. (1, 2) to grey out only
    the directional colour and keep the ambient tint.
    """
    c, order = check_coefficients(coeffs)
    grey = (c @ np.asarray(luminance, dtype=np.float64))[:, None]
    out = c.copy()
    mask = _bands_mask(order, bands)
    out[mask] += (amount - 1.0) * (c[mask] - grey[mask])  # amount 1: exactly unchanged
    return out


def band_gains(coeffs, ambient=1.0, directional=1.0, quadratic=1.0):
    """Scale band l = 0 by ``ambient``, l = 1 by ``directional``, l = 2 by ``quadratic``.

    In eq. 13 these are the constant term c4 L00 − c5 L20 (ambient gain on L00), the linear
    terms in x, y, z, and the quadratic ones. Bands above 2, if any, are left unchanged.
    """
    c, order = check_coefficients(coeffs)
    gains = np.ones(order + 1)
    gains[: min(3, order + 1)] = [ambient, directional, quadratic][: min(3, order + 1)]
    return c * gains[band_of_each_coefficient(order)][:, None]


def vertical_parity(max_order=2):
    """(−1)^(l+m) for each coefficient: Y_lm(x, y, −z) = (−1)^(l+m) Y_lm(x, y, z).

    Y_lm ∝ P_l^|m|(z) · (x ± iy)^|m| terms, and P_l^|m|(−z) = (−1)^(l+|m|) P_l^|m|(z) (it has
    the parity of l − |m| in z, the rest does not involve z). For l ≤ 2 the odd ones are
    Y10 ∝ z, Y2-1 ∝ yz and Y21 ∝ xz.
    """
    band = band_of_each_coefficient(max_order)
    m = np.concatenate([np.arange(-l, l + 1) for l in range(max_order + 1)])
    return np.where((band + m) % 2 == 0, 1.0, -1.0)


def flip_vertical(coeffs):
    """The lighting mirrored top to bottom, L'(x, y, z) = L(x, y, −z): "lit from below".

    L'_lm = ∫ L(x, y, −z) Y_lm dω = (−1)^(l+m) L_lm (``vertical_parity``): L10, L2-1, L21
    change sign, the rest stay. Exactly what projecting the upside-down equirect map gives.
    """
    c, order = check_coefficients(coeffs)
    return c * vertical_parity(order)[:, None]


_WORDS = (
    None,
    ("lit from +Y", "lit from −Y", "no ±Y difference"),
    ("lit from above", "lit from below", "no above/below difference"),
    ("lit from +X", "lit from −X", "no ±X difference"),
    ("brighter along the +X+Y/−X−Y diagonal", "brighter along the +X−Y/−X+Y diagonal",
     "no diagonal preference"),
    ("brighter toward +Y above and −Y below", "brighter toward −Y above and +Y below",
     "no Y-tilt"),
    ("brighter toward top and bottom than the horizon",
     "brighter around the horizon than top and bottom", "no horizon/pole difference"),
    ("brighter toward +X above and −X below", "brighter toward −X above and +X below",
     "no X-tilt"),
    ("brighter along ±X than ±Y", "brighter along ±Y than ±X", "no X/Y difference"),
)
NEGLIGIBLE = 0.02  # a term moving E by < 2 % of its mean is called negligible
SLIGHT = 0.10  # < 10 %: "slightly"


def describe_coefficients(coeffs, luminance=LUMINANCE):
    """Nine short strings saying what each L_lm does in this lighting, e.g.
    "L10 +0.42: lit from above (±50 % of the mean)".

    Uses the luminance of each RGB coefficient (weights ``luminance``, default Rec.709's). Each term's effect is measured as
    the most it adds to or removes from E(n) (Â_l |L_lm| max|Y_lm| = ``TERM_PEAKS`` · |L_lm|,
    eq. 6 and 13) relative to the mean irradiance c4 L00 = Â_0 L00 Y00: below 2 % it is called
    negligible, below 10 % slight.
    Axes are Blender's: z up; the front view looks along +Y.
    """
    c, order = check_coefficients(coeffs)
    if order != 2:
        raise ValueError(f"descriptions need the 9 coefficients of order 2, got order {order}")
    lum = c @ np.asarray(luminance, dtype=np.float64)
    mean = C4 * lum[0]
    lines = []
    if mean > 0.0:
        lines.append(f"L00 {lum[0]:+.3g}: overall light (mean irradiance {mean:.3g})")
    else:
        lines.append(f"L00 {lum[0]:+.3g}: no net light (mean irradiance ≤ 0, not physical)")
    for k in range(1, 9):
        name = f"{COEFFICIENT_NAMES[k]} {lum[k]:+.3g}"
        positive, negative, neutral = _WORDS[k]
        effect = TERM_PEAKS[k] * abs(lum[k]) / mean if mean > 0.0 else np.inf
        if effect < NEGLIGIBLE:
            lines.append(f"{name}: {neutral}")
            continue
        words = positive if lum[k] > 0 else negative
        if effect < SLIGHT:
            words = "slightly " + words
        share = f"±{100 * effect:.0f} % of the mean" if np.isfinite(effect) else "L00 ≤ 0"
        lines.append(f"{name}: {words} ({share})")
    return lines

