"""Pure numpy helpers of `python -m benchmarks.report` (no bpy; tested in tests/benchmarks).

``fibonacci_normals`` (the error sample), ``downsample2`` (a mip level), the brute-force
irradiance map of the standard method (``build_irradiance_map``, eq. 1 at texel centres, read
by ``lookup_bilinear``), ``error_stats`` (errors / P = ∫L dω and relative to the local value),
``synthetic_map`` (the synthetic extremes, built in row blocks) and ``samples_to_reach``.
"""

from math import pi, sqrt

import numpy as np

from sh_lighting.core.equirect import (
    direction_to_texel,
    direction_to_uv,
    row_centres,
    column_centres,
    texel_directions,
    texel_solid_angles,
)
from sh_lighting.core.irradiance import reference_irradiance

ROWS_PER_BLOCK = 256


def fibonacci_normals(count):
    """``count`` unit vectors (count, 3) on the Fibonacci spiral: deterministic, ~uniform."""
    i = np.arange(count) + 0.5
    z = 1.0 - 2.0 * i / count
    phi = pi * (3.0 - sqrt(5.0)) * i
    r = np.sqrt(np.clip(1.0 - z * z, 0.0, None))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def downsample2(pixels, weighting="texel"):
    """One mip level of an (H, W, C) map: (H/2, W/2, 3) float64, RGB only.

    ``weighting="texel"``: plain 2×2 box averages in texel space (what a GPU mip chain does);
    the four texels of a block are weighted equally although the upper and lower pair cover
    different solid angles, so the integral of the map is not exactly kept.
    ``weighting="solid_angle"``: the two rows of each block weighted by their exact solid
    angles, which keeps ∫L dω (and so L00) exact.
    H and W must be even. Works in blocks of rows, casting each to float64.
    """
    height, width = pixels.shape[:2]
    if height % 2 or width % 2:
        raise ValueError(f"downsample2 needs an even height and width, got {height}×{width}")
    if weighting not in ("texel", "solid_angle"):
        raise ValueError(f"weighting must be 'texel' or 'solid_angle', got {weighting!r}")
    omega = texel_solid_angles(height, width)
    out = np.empty((height // 2, width // 2, 3))
    step = 2 * ROWS_PER_BLOCK
    for r0 in range(0, height, step):
        block = np.asarray(pixels[r0 : r0 + step, :, :3], dtype=np.float64)
        pairs = block[:, 0::2] + block[:, 1::2]  # (rows, W/2, 3): horizontal pairs
        top, bottom = pairs[0::2], pairs[1::2]
        if weighting == "texel":
            level = 0.25 * (top + bottom)
        else:
            w_top = omega[r0 : r0 + step : 2][:, None, None]
            w_bottom = omega[r0 + 1 : r0 + step : 2][:, None, None]
            level = 0.5 * (w_top * top + w_bottom * bottom) / (w_top + w_bottom)
        out[r0 // 2 : r0 // 2 + level.shape[0]] = level
    return out


def irradiance_map_shape(texels):
    """(height, width) of a 2:1 equirect map with about ``texels`` texels: h = round(√(S/2))."""
    height = max(1, int(round(sqrt(texels / 2.0))))
    return height, 2 * height


def build_irradiance_map(pixels, height, width):
    """Brute-force irradiance environment map (height, width, 3): eq. 1 at each texel centre."""
    return reference_irradiance(pixels, texel_directions(height, width))


def lookup_bilinear(emap, normals):
    """Bilinear lookup of an equirect map (h, w, 3) at unit ``normals`` (N, 3) → (N, 3).

    Texel centres sit at u = (j + ½)/w, 1 − v = (i + ½)/h (Blender's mapping, rows top to
    bottom). Columns wrap around in longitude; rows are clamped at the poles.
    """
    height, width = emap.shape[:2]
    u, v = direction_to_uv(normals)
    x = u * width - 0.5
    y = (1.0 - v) * height - 0.5
    x0 = np.floor(x)
    fx = (x - x0)[:, None]
    j0 = x0.astype(np.int64) % width
    j1 = (j0 + 1) % width
    y = np.clip(y, 0.0, height - 1.0)
    i0 = np.minimum(np.floor(y).astype(np.int64), max(height - 2, 0))
    i1 = np.minimum(i0 + 1, height - 1)
    fy = (y - i0)[:, None]
    top = (1.0 - fx) * emap[i0, j0] + fx * emap[i0, j1]
    bottom = (1.0 - fx) * emap[i1, j0] + fx * emap[i1, j1]
    return (1.0 - fy) * top + fy * bottom


RELATIVE_FLOOR = 0.01  # relative errors only where E_ref >= 1 % of its channel's maximum


def error_stats(estimate, reference, power):
    """Errors of ``estimate`` (N, 3) against ``reference`` (N, 3); ``power`` (3,) = ∫L dω.

    Returns a dict of floats, pooled over normals and channels:
    ``mean``, ``p95``, ``max``: |E − E_ref| / P; ``rel_mean``, ``rel_p95``, ``rel_max``:
    |E − E_ref| / E_ref over the normals where E_ref is at least ``RELATIVE_FLOOR`` of its
    channel's maximum (``rel_excluded``: the fraction of values left out); ``min``: the
    lowest E / P (negative = the approximation goes below zero).
    """
    est = np.asarray(estimate, dtype=np.float64)
    ref = np.asarray(reference, dtype=np.float64)
    power = np.asarray(power, dtype=np.float64)
    diff = np.abs(est - ref)
    frac = diff / power
    keep = ref >= RELATIVE_FLOOR * ref.max(axis=0)
    rel = diff[keep] / ref[keep]
    return {
        "mean": float(frac.mean()),
        "p95": float(np.percentile(frac, 95)),
        "max": float(frac.max()),
        "rel_mean": float(rel.mean()) if rel.size else float("nan"),
        "rel_p95": float(np.percentile(rel, 95)) if rel.size else float("nan"),
        "rel_max": float(rel.max()) if rel.size else float("nan"),
        "rel_excluded": float(1.0 - keep.mean()),
        "min": float((est / power).min()),
    }


def _unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def _disc_mask_rows(r0, r1, height, width, centre, radius):
    """Boolean (r1 − r0, W): texel centres within ``radius`` (radians) of ``centre``, and
    always the texel that holds ``centre``."""
    theta = row_centres(height)[r0:r1, None]
    phi = column_centres(width)[None, :]
    c = _unit(centre)
    cosine = np.sin(theta) * (np.cos(phi) * c[0] + np.sin(phi) * c[1]) + np.cos(theta) * c[2]
    mask = cosine >= np.cos(radius)
    row, col = direction_to_texel(c, height, width)  # never empty, even on coarse maps
    if r0 <= row < r1:
        mask[row - r0, col] = True
    return mask


def _disc_solid_angle(height, width, centre, radius):
    """Exact solid angle of the texels ``_disc_mask_rows`` selects."""
    omega = texel_solid_angles(height, width)
    total = 0.0
    for r0 in range(0, height, ROWS_PER_BLOCK):
        r1 = min(height, r0 + ROWS_PER_BLOCK)
        total += float(_disc_mask_rows(r0, r1, height, width, centre, radius).sum(axis=1)
                       @ omega[r0:r1])
    return total


# The synthetic extremes: (direction, angular radius, RGB power ∫L dω of the disc).
SUN = (_unit([0.45, 0.3, 0.64]), np.radians(0.5), np.array([12.0, 11.0, 9.5]))
POINTS = (
    (_unit([1.0, 0.2, 0.5]), np.radians(1.0), np.array([3.0, 1.0, 0.4])),
    (_unit([-0.6, 0.7, 0.3]), np.radians(1.0), np.array([0.5, 1.2, 3.0])),
    (_unit([0.1, -0.9, -0.4]), np.radians(1.0), np.array([1.0, 1.0, 1.0])),
)
SYNTHETIC_NAMES = ("sun", "step", "constant", "points")


def synthetic_map(name, height, width):
    """A synthetic equirect map, float32 (height, width, 4), rows top to bottom.

    * ``sun``: a 0.5°-radius disc holding ~90 % of the power over a dim sky that brightens
      towards the zenith (0.05 … 0.12);
    * ``step``: 1 over the upper hemisphere, 0 below (height must be even);
    * ``constant``: 1 everywhere;
    * ``points``: three 1°-radius coloured discs, one below the horizon, on black.
    The discs' radiance is set from their exact texel solid angle so that their power is the
    same at every resolution.
    """
    if name not in SYNTHETIC_NAMES:
        raise ValueError(f"unknown synthetic map {name!r}; choose from {SYNTHETIC_NAMES}")
    pixels = np.zeros((height, width, 4), dtype=np.float32)
    pixels[..., 3] = 1.0
    if name == "constant":
        pixels[..., :3] = 1.0
        return pixels
    if name == "step":
        if height % 2:
            raise ValueError("the step map needs an even height (the horizon on a row edge)")
        pixels[: height // 2, :, :3] = 1.0
        return pixels
    discs = (SUN,) if name == "sun" else POINTS
    radiances = [power / _disc_solid_angle(height, width, c, r) for c, r, power in discs]
    for r0 in range(0, height, ROWS_PER_BLOCK):
        r1 = min(height, r0 + ROWS_PER_BLOCK)
        block = pixels[r0:r1, :, :3]
        if name == "sun":
            z = np.cos(row_centres(height)[r0:r1])
            sky = 0.05 + 0.07 * np.clip(z, 0.0, None)
            block[...] = (sky[:, None, None] * np.array([0.8, 0.9, 1.2])).astype(np.float32)
        for (centre, radius, _), radiance in zip(discs, radiances):
            mask = _disc_mask_rows(r0, r1, height, width, centre, radius)
            block[mask] = radiance.astype(np.float32)
    return pixels


def samples_to_reach(samples, errors, target):
    """The first sample count whose error is ≤ ``target`` (samples ascending), else None."""
    for count, error in zip(samples, errors):
        if error <= target:
            return count
    return None


def power_law_samples(samples, errors, target):
    """Samples at which a least-squares fit error = a·samples^(−b) reaches ``target``.

    Returns (samples needed, b). Fitted on all given points (log-log); None if b ≤ 0.
    """
    logs, loge = np.log(np.asarray(samples, float)), np.log(np.asarray(errors, float))
    slope, intercept = np.polyfit(logs, loge, 1)
    if slope >= 0:
        return None, -slope
    return float(np.exp((np.log(target) - intercept) / slope)), float(-slope)
