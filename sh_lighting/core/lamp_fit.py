"""A luminaire's intensity I(ω) approximated by a few native lamps (Granier et al. 2003).

Each lamp is Blender's: a point light (the same intensity every way) or a spot light aimed
along a (light axes) with cone half-angle α and blend β, whose intensity is its on-axis value
c times Blender's cone mask (Cycles ``spot_light_attenuation``; EEVEE's is the same)

    S(ω) = smoothstep((ẑ − cos α) / ((1 − cos α) β)),   smoothstep(x) = 3x² − 2x³ on [0, 1],
    ẑ = z / |(x / s_x, y / s_y, z)|

with (x, y, z) = (ω·e_x, ω·e_y, ω·a) in the spot's frame and (s_x, s_y) the spot object's
scale (1, 1: a round cone, ẑ = ω·a; otherwise an elliptical one, as Blender scales spots).

The fit: candidates are spots on a set of axes (a sphere of directions plus the brightest
samples) × half-angles × blends, and the point light; greedy selection (the candidate that
alone lowers the residual most), then non-negative least squares (``nnls``) on the selected
set, weighted by solid angle; repeated until the relative error is at most ``error_target``
or ``max_lamps`` are in, then each lamp in turn is swapped for the best other candidate while
that lowers the error. The greedy path depends on the candidates, so it runs on a coarse and
a fine grid of half-angles and blends; coordinate descent refines each result's spots (axis,
roll, scale, angle, blend) and the better one is kept. Four rounds then weight each surface of
the room by its error (towards the worst surface's, a minimax, rather than the mean), each
followed by a joint refinement of all spots' parameters (Levenberg–Marquardt, the powers by
NNLS: variable projection), and a last refinement (coordinate descent, then joint) runs on
twice as fine a sampling. Directions are the light's local axes (nadir −Z), intensities in
any unit (candela in, candela out).
"""

from dataclasses import dataclass

import numpy as np

from .nnls import nnls

HALF_ANGLES_DEG = (4.0, 8.0, 12.0, 16.0, 22.0, 30.0, 40.0, 52.0, 66.0, 80.0, 90.0)
BLENDS = (0.15, 0.4, 0.7, 1.0)
FINE_HALF_ANGLES_DEG = (3.0, 4.0, 6.0, 8.0, 10.0, 12.0, 14.0, 16.0, 19.0, 22.0, 26.0, 30.0,
                        35.0, 40.0, 46.0, 52.0, 59.0, 66.0, 73.0, 80.0, 85.0, 90.0)
FINE_BLENDS = (0.05, 0.15, 0.25, 0.4, 0.55, 0.7, 0.85, 1.0)
CANDIDATE_GRIDS = ((HALF_ANGLES_DEG, BLENDS), (FINE_HALF_ANGLES_DEG, FINE_BLENDS))
REWEIGHTS = 4  # rounds of weighting each surface by its error before the fine refinement
JOINT_ITERATIONS = (15, 40)  # Levenberg–Marquardt steps per round and in the fine refinement


@dataclass(frozen=True)
class Lamp:
    """One native lamp: ``kind`` "POINT" or "SPOT"; ``candela`` its on-axis intensity."""

    kind: str
    axis: tuple
    half_angle: float  # radians; π for a point light
    blend: float
    candela: float
    x_axis: tuple = None  # the spot's local +X (⊥ axis); None: any (a round cone)
    scale: tuple = (1.0, 1.0)  # the spot object's X and Y scale (an elliptical cone)


@dataclass(frozen=True)
class LampFit:
    lamps: tuple
    intensity_error: float  # relative RMSE of I over the sphere (solid-angle weighted)


def smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def spot_mask(directions, axis, half_angle, blend, x_axis=None, scale=(1.0, 1.0)):
    """Blender's spot cone mask toward unit ``directions`` (…, 3)."""
    cos_half = np.cos(half_angle)
    width = (1.0 - cos_half) * max(blend, 1e-6)
    d = np.asarray(directions)
    z = d @ np.asarray(axis)
    if x_axis is not None and (scale[0] != 1.0 or scale[1] != 1.0):
        x = d @ np.asarray(x_axis)
        y = d @ np.cross(np.asarray(axis), np.asarray(x_axis))
        z = z / np.sqrt((x / scale[0]) ** 2 + (y / scale[1]) ** 2 + z * z)
    return smoothstep((z - cos_half) / width)


def lamp_intensity(lamps, directions):
    """Σ lamps' intensity toward ``directions`` (…, 3)."""
    directions = np.asarray(directions, dtype=np.float64)
    total = np.zeros(directions.shape[:-1])
    for lamp in lamps:
        shape = 1.0 if lamp.kind == "POINT" else spot_mask(
            directions, lamp.axis, lamp.half_angle, lamp.blend, lamp.x_axis, lamp.scale)
        total = total + lamp.candela * shape
    return total


def sphere_samples(n_theta, n_phi):
    """Cell-centred directions on the sphere and their exact solid angles (sum 4π)."""
    edges = np.linspace(0.0, np.pi, n_theta + 1)
    theta = 0.5 * (edges[:-1] + edges[1:])
    phi = (np.arange(n_phi) + 0.5) * (2 * np.pi / n_phi)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    dirs = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), -np.cos(t)], axis=-1)
    weights = np.repeat((np.cos(edges[:-1]) - np.cos(edges[1:])) * (2 * np.pi / n_phi), n_phi)
    return dirs.reshape(-1, 3), weights


def fibonacci_sphere(count):
    i = np.arange(count) + 0.5
    z = 1.0 - 2.0 * i / count
    r = np.sqrt(1.0 - z * z)
    angle = np.pi * (1.0 + 5 ** 0.5) * i
    return np.stack([r * np.cos(angle), r * np.sin(angle), z], axis=-1)


def relative_rmse(fitted, target, weights):
    """sqrt(Σ w (f − t)²) / sqrt(Σ w t²)."""
    norm = np.sqrt(np.sum(weights * target ** 2))
    return float(np.sqrt(np.sum(weights * (fitted - target) ** 2)) / norm) if norm > 0 else 0.0


def fit_lamps(intensity, max_lamps=8, error_target=0.03, room=None, n_theta=48, n_phi=96,
              n_axes=120):
    """Lamps approximating ``intensity`` (a function of unit directions (…, 3) → values ≥ 0).

    The objective is the relative squared error of I over the sphere (solid-angle weighted)
    and, with ``room`` = d metres, that of the illuminance E = I cos/r² on each lit surface
    of a room around the luminaire (the floor d below, |x|, |y| ≤ 2d; walls d away,
    −d ≤ z ≤ 3d), each surface normalised by its own RMS: a dim wall counts as much as the
    bright floor. The ceiling is left out (the sphere's term still covers the light upward):
    a downlight's faint, unfittable ceiling drew the lamps away from the floor and walls. ``error_target`` applies to the RMS of these relative errors.
    Returns a :class:`LampFit` with the fewest lamps (at most ``max_lamps``) meeting it where
    the greedy search finds them, and the intensity error over the sphere on a finer grid.
    """
    if max_lamps < 1:
        raise ValueError("max_lamps must be at least 1")
    dirs, weights = sphere_samples(n_theta, n_phi)
    target = np.asarray(intensity(dirs), dtype=np.float64)
    if not np.isfinite(target).all() or (target < 0).any():
        raise ValueError("the intensity must be finite and non-negative")
    if target.max() <= 0:
        return LampFit((), 0.0)
    rows, row_weight, b, blocks = _objective(intensity, dirs, weights, room, 16)
    row_target = np.asarray(intensity(rows))
    tried = []
    for half_angles, blends in CANDIDATE_GRIDS:  # the greedy path depends on the grid
        params, columns = _candidates(rows, row_target, n_axes, half_angles, blends)
        chosen, x = _greedy(columns * row_weight[None, :].astype(np.float32), b, max_lamps,
                            error_target)
        lamps = tuple(_lamp(params[k], value) for k, value in zip(chosen, x))
        lamps, error = refine(lamps, rows, row_weight, b, sweeps=8, with_error=True)
        tried.append((error, len(lamps), lamps))
    _, _, lamps = min(tried, key=lambda t: (t[0], t[1]))
    scale = np.ones(len(blocks))
    for _ in range(REWEIGHTS):  # towards the worst surface's error (minimax), not the mean
        errors = _block_errors(lamps, rows, row_weight * _per_row(scale, blocks),
                               b * _per_row(scale, blocks), blocks)
        room_errors = errors[1:]  # the surfaces' (block 0 is the sphere's, kept as it is)
        if room_errors.size == 0 or room_errors.max() <= 0:
            break
        scale[1:] *= np.clip(room_errors / np.sqrt(np.mean(room_errors ** 2)), 0.5, 2.0)
        lamps = refine_joint(lamps, rows, row_weight * _per_row(scale, blocks),
                             b * _per_row(scale, blocks), JOINT_ITERATIONS[0])
    # refined on twice as fine a sampling: a narrow spot cannot hide between samples
    fine_dirs, fine_weights = sphere_samples(2 * n_theta, 2 * n_phi)
    rows, row_weight, b, blocks = _objective(intensity, fine_dirs, fine_weights, room, 40)
    lamps = refine(lamps, rows, row_weight * _per_row(scale, blocks),
                   b * _per_row(scale, blocks), sweeps=6)
    lamps = refine_joint(lamps, rows, row_weight * _per_row(scale, blocks),
                         b * _per_row(scale, blocks), JOINT_ITERATIONS[1])
    fine_dirs, fine_weights = sphere_samples(2 * n_theta, 2 * n_phi)
    fine_error = relative_rmse(lamp_intensity(lamps, fine_dirs), intensity(fine_dirs),
                               fine_weights)
    return LampFit(lamps, fine_error)


def _greedy(matrix, b, max_lamps, error_target):
    """Greedy selection of columns of ``matrix`` (candidates × rows), NNLS powers, then swaps
    of each chosen one for a better while that lowers the error (see the module's text)."""
    norms = np.einsum("ij,ij->i", matrix, matrix, dtype=np.float64)

    def solve(chosen):
        x, _ = nnls(matrix[chosen].T.astype(np.float64), b)
        keep = [k for k, value in zip(chosen, x) if value > 0]
        x = x[x > 0]
        error = float(np.linalg.norm(matrix[keep].T.astype(np.float64) @ x - b) /
                      np.linalg.norm(b)) if keep else 1.0
        return keep, x, error

    def best(residual, exclude):
        score = matrix @ residual.astype(np.float32)
        gain = np.where(score > 0, score.astype(np.float64) ** 2 / np.maximum(norms, 1e-30), 0)
        gain[list(exclude)] = -1.0
        return int(np.argmax(gain))

    chosen, x, error = [], np.zeros(0), 1.0
    while len(chosen) < max_lamps and error > error_target:
        residual = b - (matrix[chosen].T.astype(np.float64) @ x if chosen else 0.0)
        pick = best(residual, chosen)
        trial, trial_x, trial_error = solve(chosen + [pick])
        if trial_error >= error - 1e-9:
            break
        chosen, x, error = trial, trial_x, trial_error
    improved = True
    while improved and len(chosen) > 1:
        improved = False
        for i in range(len(chosen)):
            others = chosen[:i] + chosen[i + 1:]
            rest, rest_x, _ = solve(others)
            residual = b - (matrix[rest].T.astype(np.float64) @ rest_x if rest else 0.0)
            pick = best(residual, chosen)
            trial, trial_x, trial_error = solve(rest + [pick])
            if trial_error < error - 1e-4:
                chosen, x, error = trial, trial_x, trial_error
                improved = True
                break
    return chosen, x


def _objective(intensity, dirs, weights, room, room_samples):
    """Sample directions, row weights, weighted targets of the fit's blocks (see fit) and
    each block's row count."""
    blocks = [(dirs, np.sqrt(weights))]
    if room is not None:
        floor, _ceiling, *walls = _room_blocks(room, room_samples)
        blocks += [floor] + walls
    rows, row_weight, b = [], [], []
    for block_dirs, factor in blocks:
        t = np.asarray(intensity(block_dirs), dtype=np.float64) * factor
        norm = np.linalg.norm(t)
        if norm <= 0:
            continue
        rows.append(block_dirs)
        row_weight.append(factor / norm)
        b.append(t / norm)
    scale = 1.0 / np.sqrt(len(rows))  # the RMS over blocks of each block's relative error
    return (np.concatenate(rows), np.concatenate(row_weight) * scale,
            np.concatenate(b) * scale, [len(r) for r in rows])


def _per_row(scale, blocks):
    return np.repeat(scale, blocks)


def _block_errors(lamps, dirs, row_weight, b, blocks):
    """Each block's relative error ‖A x − b‖ / ‖b‖ of the lamps."""
    residual = (row_weight * lamp_intensity(lamps, dirs) - b) ** 2
    edges = np.cumsum([0] + list(blocks))
    return np.array([np.sqrt(residual[i:j].sum() / max((b[i:j] ** 2).sum(), 1e-300))
                     for i, j in zip(edges[:-1], edges[1:])])


def _room_blocks(d, samples):
    """(directions, cos/r²) on the floor, ceiling and four walls of the room of ``fit``."""
    u = (np.arange(samples) + 0.5) / samples * 4 * d - 2 * d
    a, c = np.meshgrid(u, u + d)  # c: −d..3d on the walls
    e, f = np.meshgrid(u, u)
    faces = [
        (np.stack([e, f, np.full_like(e, -d)], -1), np.array([0.0, 0.0, 1.0])),
        (np.stack([e, f, np.full_like(e, d)], -1), np.array([0.0, 0.0, -1.0])),
        (np.stack([np.full_like(a, d), a, c], -1), np.array([-1.0, 0.0, 0.0])),
        (np.stack([np.full_like(a, -d), a, c], -1), np.array([1.0, 0.0, 0.0])),
        (np.stack([a, np.full_like(a, d), c], -1), np.array([0.0, -1.0, 0.0])),
        (np.stack([a, np.full_like(a, -d), c], -1), np.array([0.0, 1.0, 0.0])),
    ]
    out = []
    for points, normal in faces:
        points = points.reshape(-1, 3)
        r = np.linalg.norm(points, axis=-1)
        dirs = points / r[:, None]
        out.append((dirs, np.clip(-(dirs @ normal), 0.0, None) / r ** 2))
    return out


def refine(lamps, dirs, row_weight, b, sweeps=12, with_error=False):
    """Coordinate descent on each spot's axis (two tilts), half-angle and blend, the powers
    by NNLS at every trial (variable projection), with steps halving when nothing improves."""
    norm = np.linalg.norm(b)

    def column(s):
        return row_weight * (1.0 if s is None else spot_mask(dirs, s[0], s[1], s[2], s[3], s[4]))

    def error(matrix):
        x, residual = nnls(matrix, b)
        return residual / norm, x

    spots = [None if lamp.kind == "POINT" else
             (np.array(lamp.axis), lamp.half_angle, lamp.blend,
              np.array(lamp.x_axis) if lamp.x_axis is not None else perpendicular(lamp.axis),
              tuple(lamp.scale)) for lamp in lamps]
    matrix = np.stack([column(s) for s in spots], 1)
    best, x = error(matrix)
    step = np.radians(4.0)
    for _ in range(sweeps):
        improved = False
        for i, spot in enumerate(spots):
            if spot is None:
                continue
            for trial in _neighbours(spot, step):
                trial_matrix = matrix.copy()
                trial_matrix[:, i] = column(trial)  # only the moved lamp's column changes
                value, trial_x = error(trial_matrix)
                if value < best - 1e-6:
                    spots[i], matrix, best, x, spot, improved = (trial, trial_matrix, value,
                                                                 trial_x, trial, True)
        if not improved:
            step *= 0.5
            if step < np.radians(0.25):
                break
    out = []
    for spot, value in zip(spots, x):
        if value <= 0:
            continue
        if spot is None:
            out.append(_lamp(None, value))
        else:
            axis, half, blend, x_axis, scale = spot
            out.append(Lamp("SPOT", tuple(float(a) for a in axis), float(half), float(blend),
                            float(value), tuple(float(a) for a in x_axis),
                            (float(scale[0]), float(scale[1]))))
    return (tuple(out), best) if with_error else tuple(out)


SPOT_LOW = np.array([-np.inf, -np.inf, -np.inf, np.log(0.2), np.log(0.2), np.radians(1.0), 0.02])
SPOT_HIGH = np.array([np.inf, np.inf, np.inf, np.log(5.0), np.log(5.0), np.pi / 2, 1.0])


def refine_joint(lamps, dirs, row_weight, b, iterations, step=1e-3):
    """Levenberg–Marquardt on all spots' parameters at once, the powers by NNLS at every
    trial (variable projection: the Jacobian of the masks times the powers, projected off
    the lamps' columns). Each spot's seven parameters: two tilts and a roll of its frame,
    log X and Y scale, half-angle and blend; derivatives by forward differences."""
    norm = np.linalg.norm(b)
    frames = [_frame(lamp) for lamp in lamps if lamp.kind != "POINT"]
    params = [np.array([0.0, 0.0, 0.0, np.log(f[2][0]), np.log(f[2][1]), f[3], f[4]])
              for f in frames]
    point = [lamp for lamp in lamps if lamp.kind == "POINT"][:1]

    def columns(params):
        cols = [row_weight * spot_mask(dirs, *_spot(f, p)) for f, p in zip(frames, params)]
        return np.stack(cols + [row_weight] * len(point), 1)

    matrix = columns(params)
    x, residual = nnls(matrix, b)
    best, damping = residual / norm, 1e-2
    for _ in range(iterations):
        jacobian = np.zeros((len(b), 7 * len(frames)))
        for i, (frame, p) in enumerate(zip(frames, params)):
            for k in range(7 if x[i] > 0 else 0):
                q = p.copy()
                q[k] += step if q[k] + step <= SPOT_HIGH[k] else -step
                moved = row_weight * spot_mask(dirs, *_spot(frame, q))
                jacobian[:, 7 * i + k] = x[i] * (moved - matrix[:, i]) / (q[k] - p[k])
        basis, _ = np.linalg.qr(matrix[:, x > 0])
        jacobian -= basis @ (basis.T @ jacobian)
        gradient = jacobian.T @ (matrix @ x - b)
        normal = jacobian.T @ jacobian
        diagonal = np.where(np.diag(normal) > 0, np.diag(normal), 1.0)
        for _ in range(6):  # raise the damping until a step lowers the error
            delta = np.linalg.lstsq(normal + damping * np.diag(diagonal), -gradient,
                                    rcond=None)[0]
            trial = [np.clip(p + delta[7 * i:7 * i + 7], SPOT_LOW, SPOT_HIGH)
                     for i, p in enumerate(params)]
            trial_matrix = columns(trial)
            trial_x, residual = nnls(trial_matrix, b)
            if residual / norm < best - 1e-7:
                params, matrix, x, best = trial, trial_matrix, trial_x, residual / norm
                damping = max(damping / 3.0, 1e-6)
                break
            damping *= 4.0
        else:
            break
    out = []
    for frame, p, value in zip(frames, params, x):
        if value > 0:
            axis, half, blend, x_axis, scale = _spot(frame, p)
            out.append(Lamp("SPOT", tuple(float(a) for a in axis), float(half), float(blend),
                            float(value), tuple(float(a) for a in x_axis), scale))
    if point and x[-1] > 0:
        out.append(_lamp(None, x[-1]))
    return tuple(out)


def _frame(lamp):
    """A spot's axis, local +X, scale, half-angle and blend."""
    x_axis = perpendicular(lamp.axis) if lamp.x_axis is None else np.array(lamp.x_axis)
    return (np.array(lamp.axis, dtype=np.float64), x_axis, tuple(lamp.scale), lamp.half_angle,
            lamp.blend)


def _spot(frame, p):
    """spot_mask's arguments for ``frame`` moved by the parameters ``p`` of refine_joint."""
    axis, u = frame[0], frame[1]
    tilted = axis + p[0] * u + p[1] * np.cross(axis, u)
    tilted /= np.linalg.norm(tilted)
    u = u - tilted * (u @ tilted)
    u /= np.linalg.norm(u)
    x_axis = np.cos(p[2]) * u + np.sin(p[2]) * np.cross(tilted, u)
    return tilted, p[5], p[6], x_axis, (float(np.exp(p[3])), float(np.exp(p[4])))


def perpendicular(axis):
    """A unit vector ⊥ ``axis`` (Blender's to_track_quat('-Z', 'Y') X axis up to sign)."""
    axis = np.asarray(axis, dtype=np.float64)
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(axis, helper)
    return u / np.linalg.norm(u)


def _neighbours(spot, step):
    axis, half, blend, u, scale = spot
    v = np.cross(axis, u)
    for direction in (u, -u, v, -v):  # tilt the axis, carrying the frame along
        tilted = np.cos(step) * axis + np.sin(step) * direction
        tilted /= np.linalg.norm(tilted)
        x_axis = u - tilted * (u @ tilted)
        yield tilted, half, blend, x_axis / np.linalg.norm(x_axis), scale
    for turn in (step, -step):  # roll about the axis
        yield axis, half, blend, np.cos(turn) * u + np.sin(turn) * v, scale
    for factor in (1.0 + 2 * step, 1.0 / (1.0 + 2 * step)):
        yield axis, float(np.clip(half * factor, np.radians(1.0), np.pi / 2)), blend, u, scale
        yield axis, half, float(np.clip(blend * factor, 0.02, 1.0)), u, scale
        for k in (0, 1):
            stretched = list(scale)
            stretched[k] = float(np.clip(stretched[k] * factor, 0.2, 5.0))
            yield axis, half, blend, u, tuple(stretched)


def _candidates(dirs, target, n_axes, half_angles=HALF_ANGLES_DEG, blends=BLENDS):
    """Candidate parameters (axis, half-angle, blend; None for the point) and their masks."""
    peak = target.max()
    brightest = dirs[np.argsort(target)[-24:]]
    axes = np.concatenate([fibonacci_sphere(n_axes), [[0, 0, -1.0], [0, 0, 1.0]], brightest])
    nearest = np.argmax(axes @ dirs.T, axis=1)
    lit = target[nearest] > 0.01 * peak  # a spot aimed into darkness cannot help
    params = [None]
    columns = [np.ones(len(dirs), dtype=np.float32)]
    for axis in axes[lit]:
        cosines = dirs @ axis
        for degrees in half_angles:
            half = np.radians(degrees)
            for blend in blends:
                width = (1.0 - np.cos(half)) * blend
                columns.append(smoothstep((cosines - np.cos(half)) / width).astype(np.float32))
                params.append((tuple(axis), half, blend))
    return params, np.stack(columns)


def _lamp(param, value):
    if param is None:
        return Lamp("POINT", (0.0, 0.0, -1.0), float(np.pi), 0.0, float(value))
    axis, half, blend = param
    return Lamp("SPOT", tuple(float(a) for a in axis), float(half), float(blend), float(value))


def plane_illuminance_error(intensity, lamps, distance=1.0, half_size=2.0, samples=64):
    """Relative RMSE of the illuminance E = I cos θ / r² on the plane ``distance`` below.

    The plane is perpendicular to the light's axis (−Z), sampled at cell centres of the
    square |x|, |y| ≤ ``half_size`` × ``distance``; the lamps against ``intensity``.
    """
    step = 2.0 * half_size / samples
    u = (np.arange(samples) + 0.5) * step - half_size
    x, y = np.meshgrid(u * distance, u * distance)
    points = np.stack([x, y, np.full_like(x, -distance)], axis=-1)
    r = np.linalg.norm(points, axis=-1)
    dirs = points / r[..., None]
    factor = (distance / r) / r ** 2
    exact = np.asarray(intensity(dirs)) * factor
    fitted = lamp_intensity(lamps, dirs) * factor
    return relative_rmse(fitted.ravel(), exact.ravel(), np.ones(exact.size))


def wall_illuminance_error(intensity, lamps, distance=1.0, samples=48):
    """The largest relative RMSE of the illuminance over the four walls ``distance`` from the
    light (|along| ≤ 2 d, −d ≤ z ≤ 3 d: the room of ``fit_lamps``); 0 for unlit walls."""
    worst = 0.0
    for dirs, factor in _room_blocks(distance, samples)[2:]:
        exact = np.asarray(intensity(dirs)) * factor
        if exact.max() <= 0:
            continue
        fitted = lamp_intensity(lamps, dirs) * factor
        worst = max(worst, relative_rmse(fitted, exact, np.ones(exact.size)))
    return worst
