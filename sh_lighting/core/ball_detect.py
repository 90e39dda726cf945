"""Where the ball is in a photo: a suggested circle (cx, cy, r) for Match Photo to offer.

Never required, never used unasked. A gradient Hough transform for circles on the √ luminance
(box-averaged to at most ``WORK_SIDE`` pixels; edges vote both ways along their gradient), then
rim points along ``RAYS`` rays at full resolution, a Kåsa fit (x² + y² + D x + E y + F = 0 by
least squares) with outliers dropped, refined once on the unblurred luminance. ``score``: the
fraction of rays on the circle; below ``MIN_SCORE`` or ``MIN_CONTRAST`` nothing is suggested.
Pixel conventions are ``ball_camera``'s. Steps: docs/modules.md.
"""

from dataclasses import dataclass

import numpy as np

WORK_SIDE = 256  # pixels on the longer side for the vote
EDGE_FRACTION = 0.06  # of the pixels: the strongest gradients vote
MIN_FRACTION, MAX_FRACTION = 0.03, 0.5  # radius range, of the shorter side
POOL = 2  # cells either side pooled in the vote
RAYS = 180
SEARCH = 2.0  # coarse pixels either side of the guessed radius searched along a ray
INLIER_PX = 1.5  # full-resolution pixels: a rim point this near the circle is on it
EDGE_SHARE = 0.25  # of the median rim jump: a ray with less found no edge
MIN_SCORE = 0.5  # of the rays: at least half the rim is seen
# The rim's jump (median over the rays on the circle) over the typical change along the rays
# from half the radius to 1.5 times it:
# measured 36-2500 on synthetic balls over textured backgrounds with 2 % noise, 22 on a Cycles
# render under courtyard (10 % noise), 2.7 for a circle found in uniform noise.
MIN_CONTRAST = 5.0
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


@dataclass(frozen=True)
class BallGuess:
    """A suggested circle: centre (cx, cy) and radius r in pixels, and ``score``, the fraction
    of the rim found on it (1: the whole outline; a ball partly hidden scores less)."""

    cx: float
    cy: float
    r: float
    score: float

    @property
    def circle(self):
        return (self.cx, self.cy, self.r)

    def summary(self):
        return (f"ball found at ({self.cx:.1f}, {self.cy:.1f}), radius {self.r:.1f} px "
                f"({100.0 * self.score:.0f} % of its rim seen)")


def _brightness(pixels):
    """√ of the luminance of (H, W, 3+) linear ``pixels``, float64, non-finite as 0."""
    a = np.asarray(pixels, dtype=np.float64)[..., :3]
    y = np.where(np.isfinite(a), a, 0.0) @ LUMINANCE
    return np.sqrt(np.maximum(y, 0.0))


def _box(image, factor):
    """``image`` box-averaged by ``factor`` (its edges cropped to a multiple of it)."""
    h, w = (image.shape[0] // factor) * factor, (image.shape[1] // factor) * factor
    return image[:h, :w].reshape(h // factor, factor, w // factor, factor).mean(axis=(1, 3))


def _vote(image):
    """(cx, cy, r) of the best circle of the coarse ``image`` (coarse pixel units), or None."""
    gy, gx = np.gradient(image)
    magnitude = np.hypot(gx, gy)
    threshold = np.quantile(magnitude, 1.0 - EDGE_FRACTION)
    rows, cols = np.nonzero((magnitude > threshold) & (magnitude > 0.0))
    if rows.size == 0:
        return None
    ux, uy = gx[rows, cols] / magnitude[rows, cols], gy[rows, cols] / magnitude[rows, cols]
    h, w = image.shape
    radii = np.arange(max(2, int(MIN_FRACTION * min(h, w))), int(MAX_FRACTION * min(h, w)) + 1)
    best, where = -1.0, None
    for r in radii:
        counts = np.zeros(h * w)
        for sign in (1.0, -1.0):
            x = np.floor(cols + 0.5 + sign * r * ux).astype(np.int64)
            y = np.floor(rows + 0.5 + sign * r * uy).astype(np.int64)
            inside = (x >= 0) & (x < w) & (y >= 0) & (y < h)
            counts += np.bincount(y[inside] * w + x[inside], minlength=h * w)
        # a gradient's direction is off by a few degrees: a circle's votes spread over cells
        pooled = _neighbour_sum(counts.reshape(h, w), POOL, "constant")
        cell = int(np.argmax(pooled))
        if pooled.flat[cell] > best:
            best, where = pooled.flat[cell], (cell % w + 0.5, cell // w + 0.5, r)
    return where[0], where[1], float(where[2])


def _neighbour_sum(a, k, mode):
    """Each cell of ``a`` summed with its neighbours' within ``k`` cells (``np.pad`` mode
    beyond the edges)."""
    padded = np.pad(a, k, mode=mode)
    h, w = a.shape
    return sum(padded[k + i:k + i + h, k + j:k + j + w]
               for i in range(-k, k + 1) for j in range(-k, k + 1))


def _blur(image):
    """``image`` averaged over 3 × 3 pixels: a render's or a sensor's per-pixel noise (10 %
    at 32 spp under courtyard) would otherwise outvote a soft rim."""
    return _neighbour_sum(image, 1, "edge") / 9.0


def _bilinear(image, x, y):
    """``image`` at points (x, y) in pixel units (centres at half-integers), edge-clamped."""
    h, w = image.shape
    fx = np.clip(x - 0.5, 0.0, w - 1.0)
    fy = np.clip(y - 0.5, 0.0, h - 1.0)
    x0, y0 = np.minimum(fx.astype(np.int64), w - 2), np.minimum(fy.astype(np.int64), h - 2)
    tx, ty = fx - x0, fy - y0
    return ((image[y0, x0] * (1 - tx) + image[y0, x0 + 1] * tx) * (1 - ty)
            + (image[y0 + 1, x0] * (1 - tx) + image[y0 + 1, x0 + 1] * tx) * ty)


def _ray_changes(image, cx, cy, start, stop):
    """(|change| of ``image`` per quarter-pixel step along ``RAYS`` rays from (cx, cy), from
    ``start`` to ``stop`` pixels (RAYS, S), the steps' distances (S + 1,), the rays' unit
    directions (RAYS, 2))."""
    angles = np.linspace(0.0, 2.0 * np.pi, RAYS, endpoint=False)
    steps = np.arange(max(start, 1.0), stop, 0.25)
    directions = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    x = cx + directions[:, :1] * steps
    y = cy + directions[:, 1:] * steps
    return np.abs(np.diff(_bilinear(image, x, y), axis=1)), steps, directions


def _rim_points(image, cx, cy, r, search):
    """((RAYS, 2) points where ``image`` changes fastest along rays from (cx, cy) between
    r − search and r + search, and that change per ray)."""
    change, steps, directions = _ray_changes(image, cx, cy, r - search, r + search)
    best = np.argmax(change, axis=1)
    along = 0.5 * (steps[best] + steps[best + 1])
    return (np.array([cx, cy]) + directions * along[:, None]), change[np.arange(RAYS), best]


def _kasa(points):
    """(cx, cy, r) of the circle x² + y² + D x + E y + F = 0 fitted to ``points``."""
    x, y = points[:, 0], points[:, 1]
    design = np.stack([x, y, np.ones_like(x)], axis=1)
    d, e, f = np.linalg.lstsq(design, -(x * x + y * y), rcond=None)[0]
    cx, cy = -d / 2.0, -e / 2.0
    return cx, cy, float(np.sqrt(max(cx * cx + cy * cy - f, 0.0)))


def detect_ball(pixels):
    """The ``BallGuess`` of the most circular outline in (H, W, 3 or 4) linear ``pixels``
    (rows top to bottom), or None when no circle has at least ``MIN_SCORE`` of its rim."""
    image = _brightness(pixels)
    factor = max(1, -(-max(image.shape) // WORK_SIDE))
    coarse = _blur(_box(image, factor))
    images = (_blur(image), image)  # the rim found on the blurred image, then placed
    if min(coarse.shape) < 8 or not np.ptp(coarse) > 0.0:
        return None
    guess = _vote(coarse)
    if guess is None:
        return None
    cx, cy, r = (v * factor for v in guess)
    for search, image in zip((SEARCH * factor, SEARCH), images):
        points, jumps = _rim_points(image, cx, cy, r, search)
        # a ray where nothing changes (a card over the ball) has no rim point
        keep = jumps >= EDGE_SHARE * np.median(jumps)
        for _ in range(3):
            if keep.sum() < 3:
                return None
            cx, cy, r = _kasa(points[keep])
            distance = np.abs(np.hypot(points[:, 0] - cx, points[:, 1] - cy) - r)
            keep &= distance <= max(INLIER_PX, search)
        keep = (distance <= INLIER_PX) & (jumps >= EDGE_SHARE * np.median(jumps))
    score = float(keep.mean())
    typical = np.median(_ray_changes(image, cx, cy, 0.5 * r, 1.5 * r)[0])
    contrast = float(np.median(jumps[keep]) / max(typical, np.finfo(float).tiny)
                     if keep.any() else 0.0)
    if score < MIN_SCORE or contrast < MIN_CONTRAST or not np.isfinite([cx, cy, r]).all():
        return None
    return BallGuess(float(cx), float(cy), float(r), score)
