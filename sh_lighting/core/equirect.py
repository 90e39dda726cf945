"""Blender's equirectangular (latitude-longitude) mapping and the exact geometry of its texels.

A direction d = (x, y, z) (Blender axes) reads u = 0.5 − atan2(y, x) / 2π, v = 1 − acos(z) / π
from the bottom (docs/reference.md §3): the centre faces +X, u = 0.25 faces +Y. Arrays are
(H, W, C), rows top to bottom; texel (i, j) covers θ ∈ [iπ/H, (i+1)π/H],
φ ∈ [π − 2π(j+1)/W, π − 2πj/W], solid angle (2π/W)(cos θ_i − cos θ_(i+1)).
"""

from math import pi

import numpy as np


def check_pixels(pixels):
    """Validate an equirectangular radiance map and return it as an ndarray (no copy).

    Accepts any H×W (not only 2:1) with 3 (RGB) or 4 (RGBA, alpha ignored) float channels.
    Raises ValueError naming the problem and the fix.
    """
    a = np.asarray(pixels)
    if a.ndim != 3 or a.shape[2] not in (3, 4):
        raise ValueError(
            f"pixels must have shape (H, W, 3) or (H, W, 4), got {a.shape}: pass an "
            "equirectangular RGB or RGBA image, rows top to bottom"
        )
    if a.shape[0] == 0 or a.shape[1] == 0:
        raise ValueError(f"pixels has zero size {a.shape}: the image has no texels")
    if not np.issubdtype(a.dtype, np.floating):
        raise ValueError(
            f"pixels has dtype {a.dtype}, but the core takes linear float radiance: "
            "convert to float (and from sRGB to linear) before projecting"
        )
    return a


def describe_nonfinite(pixels, limit=5):
    """Count the NaN/Inf RGB texels of ``pixels`` and name where the first few are."""
    bad = ~np.isfinite(pixels[..., :3]).all(axis=-1)
    rows, cols = np.nonzero(bad)
    where = ", ".join(f"(row {r}, column {c})" for r, c in zip(rows[:limit], cols[:limit]))
    more = f" and {len(rows) - limit} more" if len(rows) > limit else ""
    return len(rows), f"{len(rows)} non-finite (NaN or Inf) texels at {where}{more}"


class NonFiniteError(ValueError):
    """An image with NaN or infinite texels; ``description`` counts and locates them
    (``describe_nonfinite``), so that each caller can say how to get past it."""

    def __init__(self, description, advice="repair the image first"):
        super().__init__(f"pixels contain {description}: {advice}")
        self.description = description


def check_finite_pixels(pixels):
    """``pixels`` unchanged, or a ValueError counting and locating its NaN/Inf RGB texels.

    A finite sum of all the values (one pass, no temporary) means every one is finite; only
    otherwise (a NaN or Inf somewhere, alpha included, or an overflowing sum) is each RGB
    value tested."""
    with np.errstate(over="ignore", invalid="ignore"):
        if np.isfinite(np.sum(pixels)):
            return pixels
    if not np.isfinite(pixels[..., :3]).all():
        raise NonFiniteError(describe_nonfinite(pixels)[1])
    return pixels


def zero_nonfinite(pixels):
    """``pixels`` with every NaN or infinite value set to 0 (black): a new float32 array when
    there are any, else ``pixels`` itself (what ``nonfinite="zero"`` means everywhere)."""
    a = np.asarray(pixels)
    if np.isfinite(a).all():
        return a
    return np.where(np.isfinite(a), a, 0.0).astype(np.float32)


def row_edges(height):
    """θ at the H + 1 row boundaries, top (θ = 0) to bottom (θ = π)."""
    return np.linspace(0.0, pi, height + 1)


def row_centres(height):
    """θ at the centre of each of the H rows, top to bottom."""
    return (np.arange(height) + 0.5) * (pi / height)


def column_centres(width):
    """φ at the centre of each of the W columns: φ_j = π - 2π(j + ½)/W."""
    return pi - (np.arange(width) + 0.5) * (2.0 * pi / width)


def texel_solid_angles(height, width):
    """Exact solid angle of one texel in each row, shape (H,); they sum to 4π over the image.

    (2π/W)(cos θ_i - cos θ_(i+1)), written as (2π/W) · 2 sin θ_c sin(Δθ/2) so that thin rows
    lose no digits to cancellation.
    """
    half = 0.5 * pi / height
    return (2.0 * pi / width) * 2.0 * np.sin(row_centres(height)) * np.sin(half)


def texel_directions(height, width, rows=slice(None), at=None):
    """Unit direction of each texel centre, shape (H, W, 3), rows top to bottom.

    ``rows``: a slice of the rows to compute, e.g. ``slice(r0, r1)`` gives
    ``texel_directions(height, width)[r0:r1]`` without computing the other rows. ``at``:
    (row, column) index arrays into those rows: only these texels' directions, (N, 3), the
    same values as ``texel_directions(height, width, rows)[at]``.
    """
    theta = row_centres(height)[rows, None]
    phi = column_centres(width)[None, :]
    sin_t = np.sin(theta)
    if at is not None:
        r, c = at
        return np.stack([sin_t[r, 0] * np.cos(phi)[0, c], sin_t[r, 0] * np.sin(phi)[0, c],
                         np.cos(theta)[r, 0]], axis=-1)
    return np.stack(
        np.broadcast_arrays(sin_t * np.cos(phi), sin_t * np.sin(phi), np.cos(theta)), axis=-1
    )


def direction_to_uv(directions):
    """Blender's (u, v) of unit ``directions`` (..., 3): u in [0, 1), v in [0, 1] from the bottom."""
    d = np.asarray(directions, dtype=np.float64)
    u = np.mod(0.5 - np.arctan2(d[..., 1], d[..., 0]) / (2.0 * pi), 1.0)
    v = 1.0 - np.arccos(np.clip(d[..., 2], -1.0, 1.0)) / pi
    return u, v


def uv_to_direction(u, v):
    """Unit direction (..., 3) that Blender's Environment Texture looks up at (u, v)."""
    phi = pi - 2.0 * pi * np.asarray(u, dtype=np.float64)
    theta = pi * (1.0 - np.asarray(v, dtype=np.float64))
    return np.stack(
        [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1
    )


def direction_to_texel(directions, height, width):
    """(row, column) of the texel that holds each direction; rows counted top to bottom."""
    u, v = direction_to_uv(directions)
    col = np.minimum((u * width).astype(np.int64), width - 1)
    row = np.minimum(((1.0 - v) * height).astype(np.int64), height - 1)
    return row, col
