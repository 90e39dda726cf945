"""Splitting the sun off an HDRI: a directional light for the sun, 9 SH terms for the rest.

Nine terms blur a small, very bright source into a broad lobe and ring behind it (docs/reference.md
§2); a real sun holds up to half of an outdoor map's power. Taking it out as a Blender Sun light
and projecting only the rest keeps its sharp cosine falloff (and gives it shadows).

Detection (``detect_sun``), on the luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of an
equirect map (rows top to bottom, Blender's mapping, see ``equirect``):

1. the background level b is the solid-angle-weighted median of Y over the sphere;
2. the peak is the brightest texel; there is no sun unless Y_peak ≥ ``contrast`` × b;
3. the sun region is the set of texels connected to the peak (8-neighbours, wrapping around in
   longitude and across the poles) with Y > max(``contrast`` × b, ``peak_fraction`` × Y_peak);
4. it is a sun only if every region texel lies within ``max_radius`` of the region's centre
   (its power-weighted mean direction: a small source, not a window or a softbox; suns clipped
   flat in the HDRI have their peak anywhere in the disc) and its power is at least
   ``min_power_fraction`` of the map's total power Σ Y dΩ (it matters for the lighting).

The removed texels are replaced by the background around them, B = the per-channel median of
the texels bordering the region (``Sun.background``); a channel already below B is left as it
is, so a region texel becomes min(L, B) per channel. The sun gets exactly the power taken out:
its irradiance (what a surface facing it receives) is Σ_region (L − min(L, B)) dΩ per channel,
never negative, and sun + remaining map have exactly the map's power.

A Blender Sun of strength S and colour C gives irradiance S·C on a surface facing it (a white
diffuse surface then shows S·C/π): ``strength`` and ``colour`` are set so that S·C is that
irradiance, with max(C) = 1.

``sun_split_error`` measures what the split buys against brute force (eq. 1), next to an
imitation of EEVEE's own world sun extraction (``eevee_style_split``: every texel clamped to
``World.sun_threshold`` in its largest channel, the excess as one sun, order-1 SH for the rest).
On Blender's 8 bundled HDRIs (tests/blender/test_sun_split.py) the split cuts the mean error of
the sunrise map from 2.0 % to 0.35 % of the total power and never makes it worse.
"""

from dataclasses import dataclass
from math import pi

import numpy as np

from .edits import LUMINANCE
from .equirect import (
    check_finite_pixels,
    check_pixels,
    row_edges,
    texel_directions,
    texel_solid_angles,
)
from .irradiance import irradiance, reference_irradiance, relative_error, total_power
from .projection import project_equirect

CONTRAST = 100.0  # peak and region: this many times the background level
PEAK_FRACTION = 0.01  # region texels are also above this fraction of the peak
MAX_RADIUS = np.radians(5.0)  # a sun fits within this angle of its peak
MIN_POWER_FRACTION = 0.02  # and carries at least this share of the map's power
EEVEE_SUN_THRESHOLD = 10.0  # Blender's default World.sun_threshold


@dataclass(frozen=True, eq=False)
class Sun:
    """A sun found in an equirect map (see the module docstring).

    direction: (3,) unit vector toward the sun, Blender world axes (power-weighted mean of the
        region's texel directions, weights the luminance above the background).
    angular_diameter: radians, of the disc with the region's solid angle Ω: 2 arccos(1 − Ω/2π).
    colour: (3,) linear RGB with max 1. strength: W/m², Blender Sun strength; irradiance:
        (3,) strength × colour = Σ_region (L − min(L, background)) dΩ per channel.
    mask: (H, W) bool, the texels taken out. background: (3,) RGB B they are replaced with
        (min(L, B) per channel).
    power_fraction: the sun's share of the map's total luminance power.
    """

    direction: np.ndarray
    angular_diameter: float
    colour: np.ndarray
    strength: float
    irradiance: np.ndarray
    mask: np.ndarray
    background: np.ndarray
    power_fraction: float


def weighted_median(values, weights):
    """The value at which the cumulative weight reaches half the total."""
    order = np.argsort(values, axis=None)
    cumulative = np.cumsum(np.broadcast_to(weights, values.shape).ravel()[order])
    return float(values.ravel()[order][np.searchsorted(cumulative, 0.5 * cumulative[-1])])


def _dilate(region, touches_top, touches_bottom):
    """8-neighbour dilation on an equirect band of rows, wrapping in longitude and at the poles."""
    out = region.copy()
    out[1:] |= region[:-1]
    out[:-1] |= region[1:]
    rows = out.copy()
    out |= np.roll(rows, 1, axis=1) | np.roll(rows, -1, axis=1)
    half = region.shape[1] // 2
    if touches_top:  # across the north pole: the texel half a turn away
        out[0] |= np.roll(region[0], half)
    if touches_bottom:
        out[-1] |= np.roll(region[-1], half)
    return out


def _connected(mask, seed, touches_top, touches_bottom):
    """The 8-connected component of ``mask`` that contains ``seed`` (row, column)."""
    region = np.zeros_like(mask)
    region[seed] = True
    while True:
        grown = _dilate(region, touches_top, touches_bottom) & mask
        if np.array_equal(grown, region):
            return region
        region = grown


def detect_sun(
    pixels,
    contrast=CONTRAST,
    peak_fraction=PEAK_FRACTION,
    max_radius=MAX_RADIUS,
    min_power_fraction=MIN_POWER_FRACTION,
    luminance=LUMINANCE,
):
    """The dominant small bright source of an equirect map as a ``Sun``, or None if there is none.

    ``pixels``: (H, W, 3 or 4) linear radiance, rows top to bottom. Criteria and the meaning of
    each parameter: module docstring; ``luminance``: the RGB weights of Y in the pixels' space
    (``core.colour.luminance_weights``; default Rec.709's).
    """
    luminance = np.asarray(luminance, dtype=np.float64)
    a = check_finite_pixels(check_pixels(pixels))
    height, width, _ = a.shape
    rgb = a[..., :3].astype(np.float64)
    lum = rgb @ luminance
    solid = texel_solid_angles(height, width)
    background = weighted_median(lum, solid[:, None])
    total = float((lum * solid[:, None]).sum())
    seed = np.unravel_index(np.argmax(lum), lum.shape)
    peak = lum[seed]
    if total <= 0.0 or peak <= 0.0 or peak < contrast * max(background, 0.0):
        return None

    # Only rows that can hold texels within 2 max_radius of the peak are searched: a region cut
    # off there spans more than 2 max_radius, so no centre has it within max_radius.
    edges = row_edges(height)
    theta = 0.5 * (edges[seed[0]] + edges[seed[0] + 1])
    reach = 2.0 * max_radius + pi / height
    r0 = int(np.searchsorted(edges, theta - reach, side="right")) - 1
    r1 = int(np.searchsorted(edges, theta + reach, side="left"))
    r0, r1 = max(r0, 0), min(r1, height)
    band = slice(r0, r1)
    threshold = max(contrast * background, peak_fraction * peak)
    local_seed = (seed[0] - r0, seed[1])
    region = _connected(lum[band] > threshold, local_seed, r0 == 0, r1 == height)

    if (r0 > 0 and region[0].any()) or (r1 < height and region[-1].any()):
        return None  # cut off by the search band: too large
    ring = _dilate(_dilate(region, r0 == 0, r1 == height), r0 == 0, r1 == height) & ~region
    fill = np.median(rgb[band][ring], axis=0) if ring.any() else np.zeros(3)

    weights = np.broadcast_to(solid[band, None], region.shape)[region]
    inside = rgb[band][region]
    excess = (inside - np.minimum(inside, fill)) * weights[:, None]  # (N, 3) radiance × dΩ
    sun_irradiance = excess.sum(axis=0)
    sun_power = float(sun_irradiance @ luminance)
    if sun_power < min_power_fraction * total:
        return None
    directions = texel_directions(height, width, band)[region]
    direction = (excess @ luminance) @ directions
    direction /= np.linalg.norm(direction)
    if np.arccos(np.clip(directions @ direction, -1.0, 1.0)).max() >= max_radius:
        return None
    omega = float(weights.sum())
    strength = float(sun_irradiance.max())
    mask = np.zeros((height, width), dtype=bool)
    mask[band] = region
    return Sun(
        direction=direction,
        angular_diameter=float(2.0 * np.arccos(1.0 - omega / (2.0 * pi))),
        colour=sun_irradiance / strength,
        strength=strength,
        irradiance=sun_irradiance,
        mask=mask,
        background=fill,
        power_fraction=sun_power / total,
    )


def remove_sun(pixels, sun):
    """A copy of ``pixels`` with the sun's texels set to min(L, ``sun.background``) (alpha kept)."""
    a = check_pixels(pixels)
    if a.shape[:2] != sun.mask.shape:
        raise ValueError(f"the sun was found in a {sun.mask.shape} map, not {a.shape[:2]}")
    out = np.array(a, copy=True)
    out[sun.mask, :3] = np.minimum(out[sun.mask, :3], sun.background)
    return out


def sun_irradiance(sun, normals):
    """Irradiance (..., 3) of the sun as a directional light: irradiance_rgb · max(n·s, 0)."""
    cosine = np.maximum(np.asarray(normals, dtype=np.float64) @ sun.direction, 0.0)
    return cosine[..., None] * sun.irradiance


def eevee_style_split(pixels, threshold=EEVEE_SUN_THRESHOLD):
    """An imitation of EEVEE's world sun extraction: (sun irradiance (3,), direction, coeffs).

    Each texel is clamped so that its largest channel is at most ``threshold`` (keeping its
    hue); what is clamped off goes into one sun whose irradiance is Σ (L − L_clamped) dΩ and
    whose direction is the mean texel direction weighted by |L − L_clamped| dΩ (the Euclidean
    length of the RGB excess); the clamped map becomes order-1 SH (l ≤ 1, 4 coefficients),
    which is what EEVEE keeps for world diffuse light. Returns (zeros, None, coeffs) when no
    texel exceeds the threshold.
    """
    a = check_pixels(pixels)
    height, width, _ = a.shape
    rgb = a[..., :3].astype(np.float64)
    peak = np.abs(rgb).max(axis=-1)
    scale = np.minimum(1.0, threshold / np.maximum(peak, 1e-300))
    clamped = rgb * scale[..., None]
    excess = (rgb - clamped) * texel_solid_angles(height, width)[:, None, None]
    coeffs = project_equirect(clamped, max_order=1)
    if not excess.any():
        return np.zeros(3), None, coeffs
    direction = np.linalg.norm(excess, axis=-1).ravel() @ texel_directions(height, width).reshape(
        -1, 3
    )
    return excess.sum(axis=(0, 1)), direction / np.linalg.norm(direction), coeffs


@dataclass(frozen=True, eq=False)
class SunSplitErrors:
    """Errors of three approximations of a map's irradiance, vs brute force (eq. 1).

    Each is |E − E_ref| over the normals as a fraction of the map's total power P = ∫ L dω, the
    largest over the channels: plain 9-term SH; the detected sun as a directional light plus
    9-term SH of the rest (equal to plain when there is no sun); the EEVEE-style split (sun
    above the threshold plus order-1 SH). ``sun``: the detected ``Sun`` or None.
    """

    plain_mean: float
    plain_max: float
    sun_mean: float
    sun_max: float
    eevee_mean: float
    eevee_max: float
    sun: "Sun | None"


def sun_split_error(pixels, normals, sun=None, eevee_threshold=EEVEE_SUN_THRESHOLD, **detect):
    """Compare plain SH9, sun + SH9 and the EEVEE-style split on one map at unit ``normals``.

    ``sun``: a ``Sun`` found earlier, else ``detect_sun(pixels, **detect)`` is called.
    Costs one brute-force ``reference_irradiance``: O(texels × normals).
    """
    a = check_pixels(pixels)
    n = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    reference = reference_irradiance(a, n)
    coeffs = project_equirect(a)
    power = total_power(coeffs)
    plain = relative_error(irradiance(coeffs, n), reference, power)
    if sun is None:
        sun = detect_sun(a, **detect)
    if sun is None:
        split = plain
    else:
        rest = project_equirect(remove_sun(a, sun))
        split = relative_error(irradiance(rest, n) + sun_irradiance(sun, n), reference, power)
    eevee_rgb, eevee_dir, eevee_coeffs = eevee_style_split(a, eevee_threshold)
    e = irradiance(eevee_coeffs, n)
    if eevee_dir is not None:
        e = e + np.maximum(n @ eevee_dir, 0.0)[:, None] * eevee_rgb
    eevee = relative_error(e, reference, power)
    return SunSplitErrors(*plain, *split, *eevee, sun)
