"""Where each pixel of a photographed ball points: the ball's world normal per pixel.

A grey ball shows albedo · E(n) / π at the normal n a pixel sees (eq. 1, 13). Pixel (i, j)
has its centre at (j + ½, i + ½) from the top-left; the camera looks down −Z, +Y up.
Orthographic: the normal at (u, v) = ((x − cx)/r, −(y − cy)/r) is (u, v, √(1 − u² − v²)).
Perspective: the ray d = ((x − W/2) s, −(y − H/2) s, −f) meets the ball (centre C at distance
1, radius sin α) at t = d·C − √((d·C)² − cos² α), n = (t d − C) / sin α; rays that miss it are
not ball. Details: docs/modules.md.
"""

from dataclasses import dataclass

import numpy as np

PROJECTIONS = ("ORTHO", "PERSP")
SENSOR_FITS = ("AUTO", "HORIZONTAL", "VERTICAL")


class PhotoError(ValueError):
    """The photo, its circle or its camera cannot give lighting; the message says what to do."""


@dataclass(frozen=True)
class PhotoCamera:
    """How the photo was taken.

    matrix: 3×3 camera-to-world rotation (columns: the camera's right, up and backward axes
        in world coordinates). projection: "ORTHO" or "PERSP". focal_mm, sensor_mm: the lens
        and the sensor size along the side ``sensor_fit`` names ("AUTO": the larger side).
    """

    matrix: tuple = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    projection: str = "ORTHO"
    focal_mm: float = 50.0
    sensor_mm: float = 36.0
    sensor_fit: str = "AUTO"

    def rotation(self):
        """The camera-to-world matrix as a float64 (3, 3) array, checked to be a rotation."""
        m = np.asarray(self.matrix, dtype=np.float64)
        if m.shape != (3, 3) or not np.isfinite(m).all():
            raise PhotoError(f"the camera matrix must be 3×3 finite numbers, got {np.shape(m)}")
        if not np.allclose(m.T @ m, np.eye(3), atol=1e-4) or np.linalg.det(m) < 0.0:
            raise PhotoError(
                "the camera matrix is not a rotation (scaled, sheared or mirrored): pass the "
                "camera's orientation only, e.g. matrix_world.to_3x3().normalized()"
            )
        return m

    def checked(self):
        """Self, or a PhotoError naming the bad field."""
        self.rotation()
        if self.projection not in PROJECTIONS:
            raise PhotoError(f"projection must be one of {', '.join(PROJECTIONS)}, "
                             f"got {self.projection!r}")
        if self.projection == "PERSP":
            if not (np.isfinite(self.focal_mm) and self.focal_mm > 0.0):
                raise PhotoError(f"the focal length must be > 0 mm, got {self.focal_mm!r}")
            if not (np.isfinite(self.sensor_mm) and self.sensor_mm > 0.0):
                raise PhotoError(f"the sensor size must be > 0 mm, got {self.sensor_mm!r}")
            if self.sensor_fit not in SENSOR_FITS:
                raise PhotoError(f"sensor_fit must be one of {', '.join(SENSOR_FITS)}, "
                                 f"got {self.sensor_fit!r}")
        return self


def camera_looking(direction, roll=0.0, projection="ORTHO", focal_mm=50.0, sensor_mm=36.0):
    """A ``PhotoCamera`` looking along world ``direction`` (towards the ball), rolled by
    ``roll`` radians about it; unrolled, its up axis is as close to world +Z as it can be
    (+Y when looking straight up or down)."""
    forward = np.asarray(direction, dtype=np.float64)
    length = float(np.linalg.norm(forward))
    if not np.isfinite(length) or length == 0.0:
        raise PhotoError(f"the view direction must be a non-zero vector, got {direction!r}")
    forward = forward / length
    up_hint = np.array([0.0, 0.0, 1.0]) if abs(forward[2]) < 0.999 else np.array([0.0, 1.0, 0.0])
    right = np.cross(forward, up_hint)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    c, s = np.cos(roll), np.sin(roll)
    right, up = c * right + s * up, -s * right + c * up
    matrix = np.stack([right, up, -forward], axis=1)
    return PhotoCamera(tuple(map(tuple, matrix)), projection, float(focal_mm), float(sensor_mm))


def _ray_scale(camera, height, width):
    """mm of sensor per pixel."""
    side = {"AUTO": max(width, height), "HORIZONTAL": width, "VERTICAL": height}
    return camera.sensor_mm / side[camera.sensor_fit]


def _rays(camera, height, width, x, y):
    """Unit camera-space rays through image points (x, y) (pixel units), (..., 3)."""
    s = _ray_scale(camera, height, width)
    d = np.stack(np.broadcast_arrays((x - 0.5 * width) * s, -(y - 0.5 * height) * s,
                                     -float(camera.focal_mm)), axis=-1).astype(np.float64)
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def check_circle(circle, height, width, min_radius):
    """(cx, cy, r) as floats, or a PhotoError: not three finite numbers, a radius below
    ``min_radius`` pixels, or a circle with no pixel of the ``width`` × ``height`` image."""
    try:
        cx, cy, r = (float(v) for v in circle)
    except (TypeError, ValueError):
        raise PhotoError(f"the circle must be three numbers (cx, cy, r) in pixels, "
                         f"got {circle!r}") from None
    if not np.isfinite([cx, cy, r]).all():
        raise PhotoError(f"the circle ({cx}, {cy}, {r}) has a value that is not a number")
    if r < min_radius:
        raise PhotoError(
            f"the circle's radius is {r:g} px: at least {min_radius:g} px are needed to fit "
            "nine terms; check the circle's radius (in pixels), or for a ball that small in "
            "the photo, a photo where it is larger"
        )
    if cx + r <= 0.0 or cy + r <= 0.0 or cx - r >= width or cy - r >= height:
        raise PhotoError(
            f"the circle (centre {cx:g}, {cy:g}, radius {r:g} px) lies outside the {width}×"
            f"{height} image: give the centre in pixels from the top-left corner"
        )
    return cx, cy, r


def ball_normals(height, width, circle, camera, margin=0.0):
    """The ball's pixels and their world normals.

    ``circle``: (cx, cy, r) pixels; ``margin``: the fraction of the radius left out at the
    rim (where pixels mix ball and background and normals graze). Returns (rows, columns,
    normals (N, 3) in world axes, towards (3,): the unit world direction from the ball to
    the camera, the view axis the unseen side is defined by).
    """
    camera = camera.checked()
    cx, cy, r = circle
    keep = r * (1.0 - margin)
    i0, i1 = max(0, int(np.floor(cy - keep))), min(height, int(np.ceil(cy + keep)) + 1)
    j0, j1 = max(0, int(np.floor(cx - keep))), min(width, int(np.ceil(cx + keep)) + 1)
    rows, cols = np.mgrid[i0:i1, j0:j1]
    rows, cols = rows.ravel(), cols.ravel()
    x, y = cols + 0.5, rows + 0.5
    inside = np.hypot(x - cx, y - cy) <= keep
    rows, cols, x, y = rows[inside], cols[inside], x[inside], y[inside]
    m = camera.rotation()
    if camera.projection == "ORTHO":
        u, v = (x - cx) / r, -(y - cy) / r
        n = np.stack([u, v, np.sqrt(np.maximum(0.0, 1.0 - u * u - v * v))], axis=-1)
        return rows, cols, n @ m.T, m[:, 2].copy()
    centre = _rays(camera, height, width, np.float64(cx), np.float64(cy))
    rim = _rays(camera, height, width, cx + np.array([r, -r, 0.0, 0.0]),
                cy + np.array([0.0, 0.0, r, -r]))
    alpha = float(np.mean(np.arccos(np.clip(rim @ centre, -1.0, 1.0))))
    radius = np.sin(alpha)
    d = _rays(camera, height, width, x, y)
    b = d @ centre
    disc = b * b - (1.0 - radius * radius)
    hit = disc >= 0.0
    t = b[hit] - np.sqrt(disc[hit])
    n = (t[:, None] * d[hit] - centre) / radius
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return rows[hit], cols[hit], n @ m.T, -(m @ centre)
