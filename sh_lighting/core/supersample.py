"""Refining small, very bright features of a rendered equirectangular capture.

A feature much smaller than a pixel but very bright (a Sky Texture's sun: 0.545° wide, ~85 %
of the light) is hit by too few point samples. The Blender layer renders the pixels around it
again, finer; this module finds those pixels and averages the finer render back into them,
each finer row weighted by its exact solid angle, so the map stays the per-texel mean that
``project_equirect`` integrates. Rows top to bottom; columns wrap around, rows do not.
"""

import numpy as np

from .equirect import check_pixels, texel_solid_angles

#: A texel is "hot" when its light (radiance × solid angle) exceeds this share of the total in
#: any channel: about 65 times a texel's share of a uniform 256×128 map.
HOT_FRACTION = 2e-3


def hot_region(pixels, fraction=HOT_FRACTION, margin=1):
    """The smallest block of texels holding every hot texel (plus ``margin`` around), or None.

    Returns (row0, row1, column_start, columns): rows row0..row1−1 and the ``columns`` columns
    starting at ``column_start`` and wrapping around the image's seam. Texels with a
    negative or non-finite total are never hot.
    """
    a = check_pixels(pixels)
    height, width = a.shape[:2]
    light = np.abs(a[..., :3].astype(np.float64)) * texel_solid_angles(height, width)[:, None, None]
    total = light.sum(axis=(0, 1))
    if not np.isfinite(total).all():
        return None
    with np.errstate(invalid="ignore"):
        hot = (light > fraction * np.where(total > 0.0, total, np.inf)).any(axis=-1)
    if not hot.any():
        return None
    rows = np.flatnonzero(hot.any(axis=1))
    row0, row1 = max(0, rows[0] - margin), min(height, rows[-1] + 1 + margin)
    columns = np.flatnonzero(hot.any(axis=0))
    # The shortest arc holding every hot column: the complement of the widest gap between them.
    gaps = np.diff(np.append(columns, columns[0] + width)) - 1
    widest = int(np.argmax(gaps))
    start = int(columns[(widest + 1) % len(columns)])
    count = width - int(gaps[widest])
    start, count = start - margin, min(width, count + 2 * margin)
    return int(row0), int(row1), int(start % width), int(count)


def average_fine_rows(fine, factor, row0, height):
    """Average a ``factor`` times finer render of rows row0.. of an H-row map back to texels.

    ``fine``: (h·factor, w·factor, C) rows top to bottom, covering coarse rows row0..row0+h−1
    of a map of ``height`` rows (so fine rows row0·factor.. of a height·factor-row map).
    Fine rows are weighted by their exact solid angle, fine columns equally. Returns (h, w, C).
    """
    a = check_pixels(fine)
    fine_rows, fine_cols, channels = a.shape
    if fine_rows % factor or fine_cols % factor:
        raise ValueError(f"fine render of shape {a.shape[:2]} is not a multiple of {factor}")
    h, w = fine_rows // factor, fine_cols // factor
    if row0 < 0 or row0 + h > height:
        raise ValueError(f"rows {row0}..{row0 + h - 1} are outside a map of {height} rows")
    weights = texel_solid_angles(height * factor, 1)[row0 * factor : (row0 + h) * factor]
    weights = weights.reshape(h, factor)
    blocks = a.astype(np.float64).reshape(h, factor, w, factor, channels).mean(axis=3)
    summed = np.einsum("hfwc,hf->hwc", blocks, weights)
    return summed / weights.sum(axis=1)[:, None, None]
