"""GGX-prefiltered specular radiance from an equirectangular image (glTF environment export).

With the split sum and n = v = R (Karis 2013, eq. 4), the radiance prefiltered at GGX α is
P_α(R) = ∫ L(ω) D_α(h) max(R·ω, 0) dω / ∫ D_α(h) max(R·ω, 0) dω, h = (R + ω)/|R + ω|,
D_α = α² / (π ((R·h)² (α² − 1) + 1)²), (R·h)² = (1 + R·ω)/2: a deterministic sum over the image
box-downsampled to ``SOURCE_TEXELS_PER_TEXEL`` × the output. For α within a texel of the output
it is the mean of the image over each output texel (``scatter_average``, ``bilinear_lookup``).
Blender world axes; rows top to bottom.
"""

from math import pi

import numpy as np

from .equirect import check_pixels, direction_to_uv, texel_directions, texel_solid_angles

# Columns of the downsampled source per output texel along a great circle: a cube face of size
# s spans π/2, so 4s columns over 2π give the source texel the output texel's angular size.
SOURCE_TEXELS_PER_TEXEL = 4
# Fewest source texels the prefilter sums over (``split_texels``): 8 × 16 centres leave none of
# the sphere's hemispheres empty.
MIN_SOURCE_ROWS, MIN_SOURCE_COLUMNS = 8, 16
_BLOCK = 1 << 16  # output directions × source texels per block of weights (256 KB of float32)


def ggx_distribution(alpha, cos_h_squared):
    """GGX / Trowbridge-Reitz D(h) = α² / (π ((n·h)²(α² − 1) + 1)²), given (n·h)² as a
    float array (the result has its dtype: float32 in ``prefilter``)."""
    c = np.asarray(cos_h_squared)
    a2 = c.dtype.type(float(alpha) ** 2)
    return a2 / (c.dtype.type(pi) * (c * (a2 - 1) + 1) ** 2)


def downsample(pixels, height, width):
    """The image box-averaged to (height, width) texels, each texel weighted by its solid angle.

    ``pixels``: (H, W, 3) with H ≥ height, W ≥ width; returns (height, width, 3) float64.
    """
    p = np.asarray(pixels, dtype=np.float64)[..., :3]
    h, w = p.shape[:2]
    if height > h or width > w:
        return p.copy()
    weights = texel_solid_angles(h, w)[:, None, None]
    rows = (np.arange(height) * h) // height
    cols = (np.arange(width) * w) // width
    summed = np.add.reduceat(np.add.reduceat(p * weights, rows, axis=0), cols, axis=1)
    area = np.add.reduceat(np.broadcast_to(weights, (h, 1, 1)), rows, axis=0)
    counts = np.diff(np.append(cols, w))[None, :, None]
    return summed / (area * counts)


def scatter_average(pixels, texel_index, count):
    """Solid-angle-weighted mean of the image texels inside each of ``count`` output texels.

    Each image texel goes, with its exact solid angle, to the output texel
    ``texel_index(directions)`` (flat indices) that holds its centre, so no texel is skipped;
    meant for images whose texels are at most half an output texel (else some output texels
    get none and are 0: use ``bilinear_lookup``). Returns (count, 3) float64.
    """
    p = np.asarray(pixels, dtype=np.float64)[..., :3]
    h, w = p.shape[:2]
    total = np.zeros((count, 3))
    weight = np.zeros(count)
    rows_per_chunk = max(1, (1 << 20) // w)
    for r0 in range(0, h, rows_per_chunk):
        r1 = min(h, r0 + rows_per_chunk)
        index = texel_index(texel_directions(h, w, rows=slice(r0, r1)).reshape(-1, 3))
        solid = np.repeat(texel_solid_angles(h, w)[r0:r1], w)
        weight += np.bincount(index, solid, minlength=count)
        radiance = p[r0:r1].reshape(-1, 3)
        for c in range(3):
            total[:, c] += np.bincount(index, radiance[:, c] * solid, minlength=count)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(weight[:, None] > 0, total / weight[:, None], 0.0)


def bilinear_lookup(pixels, directions):
    """The image bilinearly interpolated at unit Blender ``directions`` (..., 3) → (..., 3).

    Texel centres as in ``equirect``; columns wrap around, rows are clamped at the poles.
    """
    p = np.asarray(pixels, dtype=np.float64)[..., :3]
    h, w = p.shape[:2]
    u, v = direction_to_uv(directions)
    x = u * w - 0.5
    y = np.clip((1.0 - v) * h - 0.5, 0.0, h - 1.0)
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    x0, x1 = x0 % w, (x0 + 1) % w
    y1 = np.minimum(y0 + 1, h - 1)
    top = p[y0, x0] * (1.0 - fx) + p[y0, x1] * fx
    bottom = p[y1, x0] * (1.0 - fx) + p[y1, x1] * fx
    return top * (1.0 - fy) + bottom * fy


def split_texels(pixels, rows=MIN_SOURCE_ROWS, columns=MIN_SOURCE_COLUMNS):
    """``pixels`` with each texel split into k × m equal ones, so that it has at least
    ``rows`` × ``columns`` texels (the same piecewise-constant map, the same light): the
    prefilter's sum over texel centres then finds texels in every direction's hemisphere (a
    map one texel wide has all its centres at φ = 0). Returns ``pixels`` itself when large
    enough."""
    h, w = pixels.shape[:2]
    k, m = -(-rows // h), -(-columns // w)
    if k == 1 and m == 1:
        return pixels
    return np.repeat(np.repeat(pixels, k, axis=0), m, axis=1)


def prefilter(pixels, directions, alpha, source_width):
    """P_α (module docstring) at unit Blender ``directions`` (..., 3) → (..., 3) float64.

    The sum runs over the image downsampled to ``source_width`` × ``source_width``/2 texels
    (the image itself if it is not larger, its texels split if it has fewer than
    ``MIN_SOURCE_ROWS`` × ``MIN_SOURCE_COLUMNS``: ``split_texels``). With c = R·ω, D_α is
    a2 / (π (A + B c)²), A = (α² + 1)/2, B = (α² − 1)/2; the constant a2/π cancels in the ratio, so each weight is
    max(c, 0) / (A + B c)², formed in place in float32 blocks small enough for the cache, and
    one product with [L Ω, Ω] per block gives numerator and denominator together.
    """
    check_pixels(pixels)
    source = split_texels(downsample(pixels, max(1, source_width // 2), source_width))
    h, w = source.shape[:2]
    omega = texel_directions(h, w).reshape(-1, 3).T.astype(np.float32)  # (3, N)
    solid = np.repeat(texel_solid_angles(h, w), w)
    weighted = np.concatenate([source.reshape(-1, 3) * solid[:, None], solid[:, None]],
                              axis=1).astype(np.float32)  # (N, 4): L Ω and Ω
    d = np.asarray(directions, dtype=np.float64)
    flat = d.reshape(-1, 3).astype(np.float32)
    a2 = float(alpha) ** 2
    big_a, big_b = np.float32(0.5 * (a2 + 1.0)), np.float32(0.5 * (a2 - 1.0))
    out = np.empty((flat.shape[0], 3))
    step = max(1, _BLOCK // omega.shape[1])
    cos_rl = np.empty((step, omega.shape[1]), dtype=np.float32)
    denominator = np.empty_like(cos_rl)
    for start in range(0, flat.shape[0], step):  # float32 weights: 1e-7 of a sum of them
        rows = flat[start : start + step]
        c, t = cos_rl[: len(rows)], denominator[: len(rows)]
        np.matmul(rows, omega, out=c)
        np.multiply(c, big_b, out=t)
        t += big_a
        t *= t
        np.maximum(c, np.float32(0.0), out=c)
        c /= t
        sums = (c @ weighted).astype(np.float64)
        out[start : start + step] = sums[:, :3] / sums[:, 3:]
    return out.reshape(d.shape)
