"""A luminaire's polar diagram: I(γ) in its two main planes, the file's against the fit's.

The photometric convention: γ from the nadir (down), C0–C180 drawn right–left in red,
C90–C270 in blue; the radius is I / I_max of the file, rings at 25 % steps. The file's curve
is thick and saturated, the fitted lamps' thin and light, so where they part shows the fit's
error. ``polar_curves`` samples I (light axes, nadir −Z); ``polar_image`` draws RGBA (rows
top to bottom) for ``bpy.utils.previews``, a pixel lit within w/2 of a segment.
"""

import numpy as np

GAMMA = np.radians(np.arange(0.0, 180.5, 1.0))  # from the nadir
PLANES = ((0.0, 180.0), (90.0, 270.0))  # right, left halves of each drawn plane (degrees C)
COLOURS = (np.array([0.9, 0.2, 0.15]), np.array([0.2, 0.45, 1.0]))
BACKGROUND = np.array([0.12, 0.12, 0.12])
GRID = np.array([0.3, 0.3, 0.3])


def polar_curves(intensity):
    """I at γ 0..180° in C0, C180, C90, C270, shape (2 planes, 2 halves, 181)."""
    out = np.empty((2, 2, GAMMA.size))
    for p, halves in enumerate(PLANES):
        for h, c in enumerate(np.radians(halves)):
            dirs = np.stack([np.sin(GAMMA) * np.cos(c), np.sin(GAMMA) * np.sin(c),
                             -np.cos(GAMMA)], axis=-1)
            out[p, h] = intensity(dirs)
    return out


def _segments(curves, peak, size):
    """Pixel-space polylines (x right, y down) of each plane's curve, both halves joined."""
    centre, radius = 0.5 * size, 0.46 * size
    lines = []
    for p in range(2):
        right, left = curves[p] / peak
        r = np.concatenate([left[::-1], right])
        side = np.concatenate([-np.sin(GAMMA[::-1]), np.sin(GAMMA)])
        down = np.concatenate([np.cos(GAMMA[::-1]), np.cos(GAMMA)])
        lines.append(np.stack([centre + radius * r * side, centre + radius * r * down], -1))
    return lines


def _near(points, line, width):
    """Pixels (N, 2) within width/2 of the polyline (M, 2)."""
    a, b = line[:-1], line[1:]
    ab = b - a
    length2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-12)
    hit = np.zeros(len(points), dtype=bool)
    for start in range(0, len(a), 64):  # bounded memory
        sa, sab, sl = a[start:start + 64], ab[start:start + 64], length2[start:start + 64]
        ap = points[:, None, :] - sa[None]
        t = np.clip(np.einsum("nmk,mk->nm", ap, sab) / sl, 0.0, 1.0)
        d2 = np.sum((ap - t[..., None] * sab) ** 2, axis=-1)
        hit |= (d2 <= (0.5 * width) ** 2).any(axis=1)
    return hit


def polar_image(measured, fitted, size=128):
    """RGBA (size, size, 4) of the curves (``polar_curves``) of the file and of the fit."""
    measured = np.asarray(measured, dtype=np.float64)
    fitted = np.asarray(fitted, dtype=np.float64)
    if measured.shape != (2, 2, GAMMA.size) or fitted.shape != measured.shape:
        raise ValueError(f"polar curves must have shape (2, 2, {GAMMA.size})")
    if not (np.isfinite(measured).all() and np.isfinite(fitted).all()):
        raise ValueError("polar curves must be finite")
    image = np.ones((size, size, 4))
    image[..., :3] = BACKGROUND
    y, x = np.mgrid[0:size, 0:size] + 0.5
    points = np.stack([x.ravel(), y.ravel()], -1)
    flat = image.reshape(-1, 4)
    distance = np.hypot(x - 0.5 * size, y - 0.5 * size).ravel() / (0.46 * size)
    for ring in (0.25, 0.5, 0.75, 1.0):
        flat[np.abs(distance - ring) * 0.46 * size <= 0.5, :3] = GRID
    peak = measured.max()
    if peak <= 0:
        return image
    for p, line in enumerate(_segments(measured, peak, size)):
        flat[_near(points, line, 2.5), :3] = COLOURS[p]
    for p, line in enumerate(_segments(fitted, peak, size)):
        flat[_near(points, line, 1.0), :3] = 0.45 * COLOURS[p] + 0.55
    return image
