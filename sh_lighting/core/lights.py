"""Extracting lights from an HDRI: up to k compact bright sources as distant lights, 9 SH
terms for the rest (generalising ``sun``'s single-sun split).

Nine terms blur every small bright source into a broad lobe (docs/reference.md §2); a sun, a
window or a softbox is better rendered as a real light (sharp falloff, shadows). The
extraction is greedy: find the brightest compact source of what is left (``sun.detect_sun``:
the region connected to the brightest texel above max(contrast × background, a fraction of
the peak), within ``max_radius`` of its centre, carrying at least ``min_power_fraction`` of the
map's power), take it out (its texels become min(L, B), B the median of the texels around
it), and repeat, until ``count`` sources are out, none is left, or the error of SH + lights
against brute force (eq. 1) is at most ``error_target``.

Each source becomes a distant light: a Blender Sun of angular diameter 2 arccos(1 − Ω/2π)
(Ω the region's solid angle). What it carries is exactly what was taken out of the map,
the excess texels X = L − min(L, B). Their irradiance at a normal n that sees the whole source
is Σ X (n·ω) dΩ = n·m with m = Σ X ω dΩ (per channel), so the light points along
s = m_Y/|m_Y| (luminance) and its irradiance facing it is S·C = m·s per channel, which makes
rest + light equal to the map's irradiance wherever the source is fully above the horizon
(near its horizon the light's disc and the texels' shape differ; a 10° source spreads over
±5° there). The SH coefficients are those of the remaining map, so nothing is counted twice:
E(n) ≈ E_9(rest) + Σ_k S_k C_k max(n·s_k, 0).

Large sources are Sun lights too (a distant disc is what the world is: an area light would
give a position-dependent irradiance and so not equal the world's).
"""

from dataclasses import dataclass
from math import pi

import numpy as np

from .edits import LUMINANCE
from .equirect import check_finite_pixels, check_pixels, texel_directions, texel_solid_angles
from .irradiance import irradiance, relative_error, total_power
from .projection import project_equirect
from .sh import spread_normals
from .sun import detect_sun, remove_sun, weighted_median
from .world_map import equirect_irradiance

MAX_COUNT = 8  # lights an extraction may make at most
CONTRAST = 20.0  # a source's peak: this many times the map's (median) background level
PEAK_FRACTION = 0.05  # its region: texels above this fraction of its peak
MAX_RADIUS = np.radians(12.0)  # it fits within this angle of its centre
MIN_POWER_FRACTION = 0.01  # and carries at least this share of the map's power
ERROR_NORMALS = 512  # normals at which the error target is checked (Fibonacci lattice)


@dataclass(frozen=True, eq=False)
class Light:
    """A distant light taken out of the map (module docstring), Blender world axes of the map.

    direction: (3,) unit vector toward it; angular_diameter: radians; colour: (3,) max 1;
    strength: W/m² (Sun strength: irradiance facing it); irradiance: (3,) strength × colour;
    power: (3,) Σ X dΩ (what the map lost); power_fraction: its share of the map's luminance
    power; mask: (H, W) texels taken out; background: (3,) B.
    """

    direction: np.ndarray
    angular_diameter: float
    colour: np.ndarray
    strength: float
    irradiance: np.ndarray
    power: np.ndarray
    power_fraction: float
    mask: np.ndarray
    background: np.ndarray


@dataclass(frozen=True, eq=False)
class Extraction:
    """lights: list of ``Light``, brightest first; rest: the map without them (H, W, C);
    coefficients: (9, 3) L_lm of ``rest``; errors: [(mean, max)] of SH + the first i lights
    vs brute force for i = 0 .. len(lights), fractions of the map's power (``relative_error``).
    """

    lights: list
    rest: np.ndarray
    coefficients: np.ndarray
    errors: list


def light_irradiance(lights, normals):
    """Σ_k S_k C_k max(n·s_k, 0) at unit ``normals`` (N, 3) → (N, 3)."""
    n = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    total = np.zeros((n.shape[0], 3))
    for light in lights:
        total += np.maximum(n @ light.direction, 0.0)[:, None] * light.irradiance
    return total


def _as_light(sun, pixels, total_luminance, luminance):
    """The ``Light`` carrying exactly the texels ``sun`` takes out of ``pixels``."""
    height, width = sun.mask.shape
    rgb = pixels[..., :3].astype(np.float64)[sun.mask]
    excess = (rgb - np.minimum(rgb, sun.background)) * texel_solid_angles(height, width)[
        np.nonzero(sun.mask)[0], None]
    directions = texel_directions(height, width)[sun.mask]
    moment = excess.T @ directions  # (3 channels, 3): m per channel
    luminance_moment = luminance @ moment
    direction = luminance_moment / np.linalg.norm(luminance_moment)
    rgb_irradiance = np.maximum(moment @ direction, 0.0)
    strength = float(rgb_irradiance.max())
    power = excess.sum(axis=0)
    return Light(direction, sun.angular_diameter, rgb_irradiance / strength, strength,
                 rgb_irradiance, power, float(power @ luminance) / total_luminance,
                 sun.mask, sun.background)


def extract_lights(pixels, count=MAX_COUNT, error_target=None, contrast=CONTRAST,
                   peak_fraction=PEAK_FRACTION, max_radius=MAX_RADIUS,
                   min_power_fraction=MIN_POWER_FRACTION, normals=None, luminance=LUMINANCE):
    """Take up to ``count`` compact bright sources out of equirect ``pixels`` (module
    docstring); stop early once the mean error of SH + lights is ≤ ``error_target`` (a
    fraction of the map's power, None: no target). Returns an ``Extraction``.

    ``pixels``: (H, W, 3 or 4) linear radiance, rows top to bottom. ``normals``: where the
    errors are measured (default ``ERROR_NORMALS`` of a Fibonacci lattice). ``luminance``:
    the RGB weights of Y in the pixels' space (``core.colour.luminance_weights``; default
    Rec.709's).
    """
    luminance = np.asarray(luminance, dtype=np.float64)
    a = check_finite_pixels(check_pixels(pixels))
    if not 0 <= int(count) <= MAX_COUNT or int(count) != count:
        raise ValueError(f"the number of lights must be a whole number from 0 to {MAX_COUNT}, "
                         f"got {count!r}")
    if error_target is not None and not error_target > 0.0:
        raise ValueError(f"the error target must be a fraction above 0, got {error_target!r}")
    n = spread_normals(ERROR_NORMALS) if normals is None else np.asarray(normals, float)
    height, width, _ = a.shape
    solid = texel_solid_angles(height, width)
    lum = a[..., :3].astype(np.float64) @ luminance
    total_luminance = float((lum * solid[:, None]).sum())
    background = weighted_median(lum, solid[:, None])
    reference = equirect_irradiance(a, n)
    rest = np.array(a, dtype=np.float32, copy=True)
    coeffs = project_equirect(rest)
    power = total_power(coeffs)
    lights = []
    errors = [relative_error(irradiance(coeffs, n), reference, power)]
    while len(lights) < count and (error_target is None or errors[-1][0] > error_target):
        peak = float((rest[..., :3].astype(np.float64) @ luminance).max())
        if peak < contrast * max(background, 0.0) or total_luminance <= 0.0:
            break
        # the peak-fraction threshold is relative to this source; the contrast to the map's
        # background (and the power share to the whole map's power), not to what is left
        sun = detect_sun(rest, contrast=contrast * background
                         / max(_median(rest, solid, luminance), 1e-300),
                         peak_fraction=peak_fraction, max_radius=max_radius,
                         min_power_fraction=min_power_fraction * total_luminance
                         / max(_luminance_power(rest, solid, luminance), 1e-300),
                         luminance=luminance)
        if sun is None:
            break
        light = _as_light(sun, rest, total_luminance, luminance)
        trial_rest = remove_sun(rest, sun)
        trial = project_equirect(trial_rest)
        estimate = irradiance(trial, n) + light_irradiance([*lights, light], n)
        error = relative_error(estimate, reference, power)
        if error[0] >= errors[-1][0]:
            break  # this source is better left to the SH (e.g. the halo around a sun)
        lights.append(light)
        rest, coeffs = trial_rest, trial
        errors.append(error)
    return Extraction(lights, rest, coeffs, errors)


def _median(pixels, solid, luminance):
    return weighted_median(pixels[..., :3].astype(np.float64) @ luminance, solid[:, None])


def _luminance_power(pixels, solid, luminance):
    return float(((pixels[..., :3].astype(np.float64) @ luminance) * solid[:, None]).sum())


def angular_diameter_of(solid_angle):
    """The angular diameter of a disc of ``solid_angle`` steradians: 2 arccos(1 − Ω/2π)."""
    return float(2.0 * np.arccos(np.clip(1.0 - solid_angle / (2.0 * pi), -1.0, 1.0)))
