"""Extracting lights from an HDRI: up to k compact bright sources as distant (Sun) lights, the
9 SH terms for the rest (k = 1: the sun as a Sun light).

Greedy on the luminance Y: the brightest texel above ``contrast`` × the median level b, its
8-connected region above max(contrast · b, peak_fraction · Y_peak), taken when compact, strong
enough and lowering the error; its excess X = L − min(L, B) becomes a Sun along
s = m_Y/|m_Y|, m = Σ X ω dΩ, with S·C = m·s and angular diameter 2 arccos(1 − Ω/2π). So
E(n) ≈ E_9(rest) + Σ_k S_k C_k max(n·s_k, 0), nothing counted twice. Steps: docs/modules.md.
"""

import numbers
from dataclasses import dataclass
from math import degrees, pi

import numpy as np

from .edits import LUMINANCE
from .equirect import (
    check_finite_pixels,
    check_pixels,
    row_edges,
    texel_directions,
    texel_solid_angles,
)
from .irradiance import downsampled_reference, irradiance, total_power
from .projection import project_equirect, project_texels
from .sh import spread_normals

MAX_COUNT = 8  # lights an extraction may make at most
CONTRAST = 20.0  # a source's peak: this many times the map's (median) background level
PEAK_FRACTION = 0.05  # its region: texels above this fraction of its peak
MAX_RADIUS = np.radians(30.0)  # it fits within this angle of its centre (bench_texel: 12°
# left sunrise's 27° glow in the SH, whose shadow is soft where Cycles' is sharp)
LARGEST_RADIUS = np.radians(60.0)  # the largest max_radius accepted
MIN_POWER_FRACTION = 0.01  # and carries at least this share of the map's power
MEDIAN_SORT_LIMIT = 1 << 20  # maps with more texels find the background's median by a bracket
ERROR_NORMALS = 512  # normals at which the error target is checked (Fibonacci lattice)

# Why an extraction stopped (``Extraction.stop_kind``)
COUNT, TARGET, DARK, CONTRAST_LOW, TOO_LARGE, TOO_DIM, NO_GAIN = (
    "COUNT", "TARGET", "DARK", "CONTRAST", "TOO_LARGE", "TOO_DIM", "NO_GAIN")


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
    """lights: list of ``Light``, brightest first; rest: the map without them (H, W, C), float32
    (None if not asked for: ``extract_lights``' ``keep_rest``);
    coefficients: (9, 3) L_lm of ``rest``; errors: [(mean, max)] of SH + the first i lights
    vs brute force for i = 0 .. len(lights), fractions of the map's power (module docstring).
    stop_kind: why no further light was taken (``COUNT``, ``TARGET``, ``DARK``,
    ``CONTRAST_LOW``, ``TOO_LARGE``, ``TOO_DIM``, ``NO_GAIN``); stop: the same for the user, one
    phrase with the numbers; max_radius: the size limit used (radians); stop_size: the size
    across (radians) of the source found too large, when known (else 0).
    """

    lights: list
    rest: np.ndarray
    coefficients: np.ndarray
    errors: list
    stop_kind: str
    stop: str
    max_radius: float
    stop_size: float = 0.0


def weighted_median(values, weights):
    """The value at which the cumulative weight reaches half the total.

    Large maps sort only the values between two quantiles of a subsample that bracket the
    median (checked by the exact weights below and inside the bracket; a full sort if they do
    not): the same value, at 8192×4096 a few passes instead of a 33-million-value argsort."""
    full = np.broadcast_to(weights, values.shape)
    if values.size > MEDIAN_SORT_LIMIT:
        found = _bracketed_median(values, full)
        if found is not None:
            return found
    order = np.argsort(values, axis=None)
    cumulative = np.cumsum(full.ravel()[order])
    return float(values.ravel()[order][np.searchsorted(cumulative, 0.5 * cumulative[-1])])


def _bracketed_median(values, weights):
    """``weighted_median`` from the values inside a subsample's 0.5 ± 0.01 weighted quantiles,
    or None when the median is not inside that bracket."""
    step = max(1, int(np.sqrt(values.size / MEDIAN_SORT_LIMIT * 16)))
    sample, sample_w = values[::step, ::step].ravel(), weights[::step, ::step].ravel()
    order = np.argsort(sample)
    cumulative = np.cumsum(sample_w[order])
    at = [min(len(order) - 1, int(np.searchsorted(cumulative, q * cumulative[-1])))
          for q in (0.49, 0.51)]
    lo, hi = (float(sample[order][i]) for i in at)
    below, total, inside_v, inside_w = 0.0, 0.0, [], []
    for r0 in range(0, values.shape[0], 256):
        v, w = values[r0 : r0 + 256], weights[r0 : r0 + 256]
        below += float(np.sum(w, where=v < lo, dtype=np.float64))
        total += float(np.sum(w, dtype=np.float64))
        inside = (v >= lo) & (v <= hi)
        inside_v.append(v[inside])
        inside_w.append(w[inside])
    inside_v, inside_w = np.concatenate(inside_v), np.concatenate(inside_w)
    half = 0.5 * total
    if not below < half <= below + float(inside_w.sum(dtype=np.float64)):
        return None
    order = np.argsort(inside_v)
    cumulative = below + np.cumsum(inside_w[order], dtype=np.float64)
    index = min(len(order) - 1, int(np.searchsorted(cumulative, half)))
    return float(inside_v[order][index])


LUMINANCE_ROWS = 256  # rows of Y computed at a time
CAST_ROWS = 32  # rows cast to float64 at a time within them (8 MB at 8192 wide)


def _luminance(pixels, luminance, out=None, rows=slice(None)):
    """Y = RGB · ``luminance`` of every texel, float64 (H, W), in blocks of rows (no float64
    copy of the whole image). ``out``, ``rows``: recompute in ``out`` only the blocks that
    hold those rows (the same blocks, so the same values, as a whole new Y)."""
    height = pixels.shape[0]
    out = np.empty(pixels.shape[:2]) if out is None else out
    first, last, _ = rows.indices(height)
    start = first // LUMINANCE_ROWS * LUMINANCE_ROWS
    cast = np.empty((min(CAST_ROWS, height),) + pixels.shape[1:])
    for r0 in range(start, last, LUMINANCE_ROWS):
        _block_luminance(pixels, luminance, out, r0, min(height, r0 + LUMINANCE_ROWS), cast)
    return out


def _block_luminance(pixels, luminance, out, r0, r1, cast):
    """out[r0:r1] = RGB · ``luminance``: the rows cast whole (all channels, a contiguous
    cast, 2.5x faster at 8K than one of the RGB view), then the product reads RGB of it."""
    for c0 in range(r0, r1, cast.shape[0]):
        c1 = min(r1, c0 + cast.shape[0])
        block = cast[: c1 - c0]
        block[...] = pixels[c0:c1]
        out[c0:c1] = block[..., :3] @ luminance


def relative_errors(estimate, reference, power):
    """(mean, max) of |E − E_ref| / P over the channels with light (P > 0): the worst
    channel's mean over the normals and the largest value (Ramamoorthi and Hanrahan's
    measure); (0, 0) when no channel has light."""
    p = np.asarray(power, dtype=np.float64)
    lit = p > 0.0
    if not lit.any():
        return 0.0, 0.0
    err = np.abs(np.asarray(estimate, float) - reference)[:, lit] / p[lit]
    return float(err.mean(axis=0).max()), float(err.max())


def light_irradiance(lights, normals):
    """Σ_k S_k C_k max(n·s_k, 0) at unit ``normals`` (N, 3) → (N, 3)."""
    n = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    total = np.zeros((n.shape[0], 3))
    for light in lights:
        total += np.maximum(n @ light.direction, 0.0)[:, None] * light.irradiance
    return total


NEIGHBOUR_ROWS = np.array([-1, -1, -1, 0, 0, 1, 1, 1])
NEIGHBOUR_COLUMNS = np.array([-1, 0, 1, -1, 1, -1, 0, 1])


def _neighbours(rows, columns, shape, touches_top, touches_bottom):
    """(rows, columns) of the 8-neighbours of texels (``rows``, ``columns``) in an equirect
    band of rows of ``shape``, wrapping in longitude, and across a pole (the texel half a turn
    away in the same row) where the band ``touches_top`` or ``touches_bottom`` of the map.
    Repeats are kept."""
    height, width = shape
    r = (rows[:, None] + NEIGHBOUR_ROWS).ravel()
    c = ((columns[:, None] + NEIGHBOUR_COLUMNS) % width).ravel()
    inside = (r >= 0) & (r < height)
    r, c = [r[inside]], [c[inside]]
    for touches, row in ((touches_top, 0), (touches_bottom, height - 1)):
        at_pole = rows == row
        if touches and at_pole.any():
            r.append(rows[at_pole])
            c.append((columns[at_pole] + width // 2) % width)
    return np.concatenate(r), np.concatenate(c)


def _dilate(region, touches_top, touches_bottom):
    """8-neighbour dilation on an equirect band of rows, wrapping in longitude and at the poles."""
    out = region.copy()
    out[_neighbours(*np.nonzero(region), region.shape, touches_top, touches_bottom)] = True
    return out


def _connected(mask, seed, touches_top, touches_bottom):
    """The 8-connected component of ``mask`` that contains ``seed`` (row, column), grown from
    its newest texels only (the work is that of the component, not of the band per step)."""
    region = np.zeros_like(mask)
    region[seed] = True
    rows, columns = np.array([seed[0]]), np.array([seed[1]])
    while rows.size:
        r, c = _neighbours(rows, columns, mask.shape, touches_top, touches_bottom)
        new = mask[r, c] & ~region[r, c]
        region[r[new], c[new]] = True
        rows, columns = np.divmod(np.unique(r[new] * mask.shape[1] + c[new]), mask.shape[1])
    return region


def _find_source(texels, lum, solid, contrast, background, min_power, total, peak_fraction,
                 max_radius, luminance):
    """The brightest compact source of the map whose RGB at (rows, columns) is
    ``texels(rows, columns)`` (N, 3) float (any), luminance ``lum`` (H, W), as
    ((direction, moment (3, 3), power (3,), mask, background, Ω), None), or (None, (stop kind,
    phrase)): steps 1-4 of the module docstring, ``background`` the map's level b,
    ``min_power`` the least power (fraction × ``total``, the map's P_Y)."""
    height, width = lum.shape
    seed = np.unravel_index(np.argmax(lum), lum.shape)
    peak = float(lum[seed])
    floor = contrast * max(background, 0.0)
    if not peak >= floor or peak <= 0.0:
        ratio = f"{peak / background:.3g} ×" if background > 0.0 else "no brighter than"
        return None, (CONTRAST_LOW, f"the brightest texel left is {ratio} the background "
                      f"level, less than {contrast:g} ×")
    # Only rows that can hold texels within 2 max_radius of the peak are searched: a region cut
    # off there spans more than 2 max_radius, so no centre has it within max_radius.
    edges = row_edges(height)
    theta = 0.5 * (edges[seed[0]] + edges[seed[0] + 1])
    reach = 2.0 * max_radius + pi / height
    r0 = int(np.searchsorted(edges, theta - reach, side="right")) - 1
    r1 = int(np.searchsorted(edges, theta + reach, side="left"))
    r0, r1 = max(r0, 0), min(r1, height)
    band = slice(r0, r1)
    limit = f"the size limit of {degrees(2.0 * max_radius):.0f}°"
    region = _connected(lum[band] > max(floor, peak_fraction * peak), (seed[0] - r0, seed[1]),
                        r0 == 0, r1 == height)
    if (r0 > 0 and region[0].any()) or (r1 < height and region[-1].any()):
        return None, (TOO_LARGE, f"the brightest source left is wider than {limit}")
    ring = _dilate(_dilate(region, r0 == 0, r1 == height), r0 == 0, r1 == height) & ~region
    # only the texels of the region and its ring are read (row-major, as boolean indexing)
    around = np.nonzero(ring)
    fill = (np.median(texels(around[0] + r0, around[1]).astype(np.float64), axis=0)
            if around[0].size else np.zeros(3))
    at = np.nonzero(region)
    weights = solid[band][at[0]]
    inside = texels(at[0] + r0, at[1]).astype(np.float64)
    excess = (inside - np.minimum(inside, fill)) * weights[:, None]  # (N, 3) radiance × dΩ
    power = excess.sum(axis=0)
    share = float(power @ luminance) / total
    if float(power @ luminance) < min_power or not share > 0.0:
        return None, (TOO_DIM, f"the brightest source left carries {100 * share:.2g} % of the "
                      f"light, less than {100 * min_power / total:.2g} %")
    directions = texel_directions(height, width, band, at)
    moment = excess.T @ directions  # (3 channels, 3): m per channel
    toward = luminance @ moment
    toward = toward / np.linalg.norm(toward)
    spread = float(np.arccos(np.clip(directions @ toward, -1.0, 1.0)).max())
    if spread >= max_radius:
        return None, (TOO_LARGE, f"the brightest source left is {degrees(2 * spread):.3g}° "
                      f"across, wider than {limit}", 2.0 * spread)
    mask = np.zeros((height, width), dtype=bool)
    mask[band] = region
    return (toward, moment, power, mask, fill, float(weights.sum())), None


def _as_light(found, total, luminance):
    """The ``Light`` carrying exactly the excess texels of the source ``found``."""
    direction, moment, power, mask, background, omega = found
    rgb_irradiance = np.maximum(moment @ direction, 0.0)
    strength = float(rgb_irradiance.max())
    return Light(direction, float(2.0 * np.arccos(np.clip(1.0 - omega / (2.0 * pi), -1, 1))),
                 rgb_irradiance / strength, strength, rgb_irradiance, power,
                 float(power @ luminance) / total, mask, background)


def remove_light(pixels, light):
    """A copy of ``pixels`` with the light's texels set to min(L, ``light.background``), alpha
    kept."""
    a = check_pixels(pixels)
    if a.shape[:2] != light.mask.shape:
        raise ValueError(f"the light was found in a {light.mask.shape} map, not {a.shape[:2]}")
    out = np.array(a, copy=True)
    _take_out(out, light)
    return out


def _rest_texels(pixels, taken, rows, columns):
    """RGB (N, 3), ``pixels``' dtype, of the rest at texels (``rows``, ``columns``):
    ``pixels`` there with the lights of ``taken`` taken out in order, the values
    ``_take_out`` would leave in a copy, read without one."""
    values = pixels[rows, columns, :3]
    for light in taken:
        hit = light.mask[rows, columns]
        if hit.any():
            values[hit] = np.minimum(values[hit], light.background)
    return values


def _update_luminance(pixels, taken, luminance, lum, rows):
    """``_luminance(rest, luminance, lum, rows)`` of the rest (``pixels`` with the lights of
    ``taken`` taken out), each block of rows copied (RGB only) while its Y is computed."""
    height = pixels.shape[0]
    first, last, _ = rows.indices(height)
    cast = np.empty((min(CAST_ROWS, height),) + pixels.shape[1:])
    for r0 in range(first // LUMINANCE_ROWS * LUMINANCE_ROWS, last, LUMINANCE_ROWS):
        r1 = min(height, r0 + LUMINANCE_ROWS)
        block = np.array(pixels[r0:r1], copy=True)
        for light in taken:
            mask = light.mask[r0:r1]
            block[mask, :3] = np.minimum(block[mask, :3], light.background)
        _block_luminance(block, luminance, lum[r0:r1], 0, r1 - r0, cast)


def _mask_rows(mask):
    """The slice of the rows from the first to the last that ``mask`` (H, W) touches."""
    rows = np.flatnonzero(mask.any(axis=1))
    return slice(int(rows[0]), int(rows[-1]) + 1) if rows.size else slice(0, 0)


def _take_out(pixels, light):
    """``remove_light`` in place, on the rows of the light's mask only."""
    band = _mask_rows(light.mask)
    view, mask = pixels[band], light.mask[band]
    view[mask, :3] = np.minimum(view[mask, :3], light.background)


def real_number(value):
    """Whether ``value`` is a finite real number (not a bool, a string or None)."""
    return (isinstance(value, numbers.Real) and not isinstance(value, bool)
            and np.isfinite(value))


def extract_lights(pixels, count=MAX_COUNT, error_target=None, contrast=CONTRAST,
                   peak_fraction=PEAK_FRACTION, max_radius=MAX_RADIUS,
                   min_power_fraction=MIN_POWER_FRACTION, normals=None, luminance=LUMINANCE,
                   coefficients=None, keep_rest=True, downsample=None):
    """Take up to ``count`` compact bright sources out of equirect ``pixels`` (module
    docstring); stop early once the mean error of SH + lights is ≤ ``error_target`` (a
    fraction of the map's power, None: no target). Returns an ``Extraction``.

    ``pixels``: (H, W, 3 or 4) linear radiance, rows top to bottom. ``max_radius``: the size
    limit, radians from the source's centre (up to ``LARGEST_RADIUS``). ``normals``: where the
    errors are measured (default ``ERROR_NORMALS`` of a Fibonacci lattice). ``luminance``:
    the RGB weights of Y in the pixels' space (``core.colour.luminance_weights``; default
    Rec.709's).

    Work that a caller may already have done, and a copy it may not need: ``coefficients``,
    ``project_equirect(pixels)`` of float32 ``pixels`` (else projected here); ``downsample``,
    the (map, bound) of ``irradiance.downsampled_reference``'s downsample of ``pixels``
    (``irradiance.bounded_error_estimate``'s "downsample"); ``keep_rest`` False: no copy of
    the map for ``Extraction.rest`` (None). The map is never copied while the lights are
    tried: the rest's texels are read through the lights taken so far (``_rest_texels``) and
    its coefficients are updated by the change at the light's texels (``project_texels``:
    linear, so equal to a new projection to rounding).
    """
    luminance = np.asarray(luminance, dtype=np.float64)
    a = check_finite_pixels(check_pixels(pixels))
    if not (real_number(count) and count == int(count) and 0 <= count <= MAX_COUNT):
        raise ValueError(f"the number of lights must be a whole number from 0 to {MAX_COUNT}, "
                         f"got {count!r}")
    if error_target is not None and not (real_number(error_target) and error_target > 0.0):
        raise ValueError(f"the error target must be a fraction above 0, got {error_target!r}")
    if not (real_number(max_radius) and 0.0 < max_radius <= LARGEST_RADIUS):
        got = f"{degrees(2 * max_radius):g}°" if real_number(max_radius) else repr(max_radius)
        raise ValueError(f"the size limit must be above 0° and at most "
                         f"{degrees(2 * LARGEST_RADIUS):.0f}° across, got {got}")
    n = spread_normals(ERROR_NORMALS) if normals is None else np.asarray(normals, float)
    height, width, _ = a.shape
    solid = texel_solid_angles(height, width)
    lum = _luminance(a, luminance)
    total = float(lum.sum(axis=1) @ solid)  # Σ Y dΩ without an (H, W) temporary
    background = weighted_median(lum, solid[:, None])
    # within 1e-3 of the power at 8K (bench_sizes)
    reference = downsampled_reference(a, n, downsample=downsample)[0]
    private = a.dtype != np.float32
    if private:  # the rest is float32 (what Blender stores), with its own Y
        a = a.astype(np.float32)
        lum = _luminance(a, luminance)  # the rest's Y, updated where a light is taken out
    coeffs = (project_equirect(a) if coefficients is None or private
              else np.array(coefficients, dtype=np.float64))
    power = total_power(coeffs)
    lights = []
    errors = [relative_errors(irradiance(coeffs, n), reference, power)]
    stop = (COUNT, f"{count} light(s) asked for")
    while True:
        if len(lights) >= count:
            break
        if error_target is not None and errors[-1][0] <= error_target:
            stop = (TARGET, f"the error target of {100 * error_target:.2g} % was reached")
            break
        if not total > 0.0:
            stop = (DARK, "the image has no light")
            break
        found, why = _find_source(lambda r, c, taken=tuple(lights): _rest_texels(a, taken, r, c),
                                  lum, solid, contrast, background,
                                  min_power_fraction * total, total, peak_fraction,
                                  max_radius, luminance)
        if found is None:
            stop = why
            break
        light = _as_light(found, total, luminance)
        # the rest's coefficients with the light taken out: + those of the change (float32
        # values as the rest stores them, their difference exact in float64)
        band = _mask_rows(light.mask)
        at = np.nonzero(light.mask[band])
        at = (at[0] + band.start, at[1])
        before = _rest_texels(a, lights, *at)
        after = np.minimum(before, light.background).astype(before.dtype)
        trial = coeffs + project_texels(after.astype(np.float64) - before, *at, height, width)
        estimate = irradiance(trial, n) + light_irradiance([*lights, light], n)
        error = relative_errors(estimate, reference, power)
        if error[0] >= errors[-1][0]:  # e.g. the halo around a sun
            stop = (NO_GAIN, f"the next source ({100 * light.power_fraction:.2g} % of the "
                    f"light, {degrees(light.angular_diameter):.0f}° across) would not lower "
                    "the error: it stays in the SH")
            break
        lights.append(light)
        coeffs = trial
        _update_luminance(a, lights, luminance, lum, _mask_rows(light.mask))
        errors.append(error)
    rest = None
    if keep_rest:
        rest = a if private else np.array(a, dtype=np.float32, copy=True)
        for light in lights:
            _take_out(rest, light)
    size = stop[2] if len(stop) > 2 else 0.0
    return Extraction(lights, rest, coeffs, errors, stop[0], stop[1], float(max_radius), size)
