"""Lighting from a photo of a grey (diffuse) ball: the nine L_lm by linear least squares.

A Lambertian ball of albedo ρ shows ρ E(n) / π at normal n (eq. 1), and the 9-term
E(n) = Σ Â_l L_lm Y_lm(n) (eq. 6-7) is linear in L_lm: each pixel is one equation per channel.
One photo sees only the normals facing the camera, so the unseen side comes from a prior the
user chooses (mirror, ambient, a chrome ball, a second photo, none), weighted to move the seen
picture by at most a fraction of the nine-term misfit; negative light is then removed at the
exact minimum of E. ``PhotoFit`` reports residual, condition, weak terms and clipped pixels.
The priors and the report in detail: docs/modules.md.
"""

from dataclasses import dataclass

import numpy as np

from .ball_camera import PhotoCamera, PhotoError, ball_normals, check_circle
from .irradiance import C4, irradiance
from .minimum import irradiance_minimum, mean_irradiance, negative_light_warning
from .sh import COEFFICIENT_NAMES, band_of_each_coefficient, lambert_band_factors, sh_basis
from .sh import spread_normals

# choices.PHOTO_PRIORS (the CLI's, without numpy); the first is the default
PRIORS = ("mirror", "ambient", "chrome", "photo", "none")
DEFAULT_ALBEDO = 0.18
DEFAULT_MARGIN = 0.05  # of the radius: the rim pixels mix ball and background
DEFAULT_PRIOR_WEIGHT = 1.0  # the most: as much as all the pixels together
MIN_RADIUS = 4.0  # pixels: below it the ball has too few pixels for nine terms
MIN_PIXELS = 30  # used pixels: a few per unknown
# A matte ball's picture is within a few % of the best nine-term picture (3.1 % under a
# sunlit window probe, measured); above this, it is not a diffuse ball's.
MAX_RESIDUAL = 0.1
# ... and the nine terms explain less than half of how the pixels vary: a ball under a single
# hard sun has a larger residual (38 % of its mean, the terminator) but the nine terms
# explain 90 % of its variation; noise or a background explains almost nothing.
MAX_UNEXPLAINED = 0.5
# Texels inside the circle with alpha below 1 (a cut-out's background): left out up to this
# share of the circle's (its anti-aliased edge), refused above (the circle is off).
MAX_TRANSPARENT = 0.05
WEAK_SINGULAR = 0.1  # σ / σ_max below which a direction of the nine terms is poorly fixed
WEAK_LOADING = 0.3  # |component| of such a singular vector that names a term
PRIOR_NORMALS = 400  # lattice normals the prior may be placed on (``sh.spread_normals``)
# The prior may move the seen picture by this fraction of the nine-term misfit (RMS; at least
# RESIDUAL_FLOOR of the mean): the seen side's error then grows by at most ~6 % (the change is
# orthogonal to the residual, √(1 + 0.35²) = 1.06), within the goal of 1.25× even when the
# misfit is overestimated twice (noise the second differences miss).
PRIOR_HEADROOM = 0.35
# A measured prior (a chrome ball, a second photo) is data about the unseen side, not a
# guess: it may move the seen picture further, √(1 + 0.5²) = 1.12 < 1.25. Measured (chrome
# prior, headroom 0.35 / 0.5 / 0.6): a synthetic 8-bit ball under a sunny world, all normals
# 4.1 / 0.68 / 0.55 %, the seen side 1.05 / 1.12 / 1.15× the nine-term limit; a Cycles
# render under courtyard as a chrome-ball world (10 % render noise), all normals
# 6.6 % at 0.6 and 9.4 % at 0.5, the seen side 1.20× and 1.13×: 0.6 is too close to 1.25.
MEASURED_HEADROOM = 0.5
RESIDUAL_FLOOR = 0.005
PRIOR_STEPS = 40  # halvings of the prior's weight
NEGATIVE_STEPS = 24
NEGATIVE_TOLERANCE = 1e-4  # of the channel's mean irradiance
MEASURED_PRIORS = {"chrome": "chrome ball", "photo": "second photo"}  # summary's names


@dataclass(frozen=True)
class PhotoFit:
    """The nine RGB L_lm recovered from a photo and how far to trust them.

    coefficients: (9, 3) L_lm with the prior and the no-negative-light check (what to store).
    plain: (9, 3) the data-only least-squares L_lm (the best nine-term picture).
    residual: RMS over used pixels and channels of photo − plain picture, / their mean.
    noise: the pixels' own noise (``pixel_noise``), / their mean: the part of the residual
        no lighting explains.
    condition: condition number of the equilibrated design matrix of the used pixels.
    weak_terms: names of the terms in its poorly constrained directions (may be empty).
    used, clipped, invalid: pixels fitted; left out as clipped; left out as non-finite or
        masked. prior: its name; prior_weight: its total weight used, / the pixels'.
    prior_scale: (3,) the chrome ball's scale per channel (prior "chrome"), else None.
    negative: ``negative_light_warning`` or None.
    normals: (N, 3) world normals of the used pixels; values: (N, 3) their pixels;
    towards: the view axis (to the camera).
    """

    coefficients: np.ndarray
    plain: np.ndarray
    residual: float
    noise: float
    condition: float
    weak_terms: tuple
    used: int
    clipped: int
    invalid: int
    prior: str
    prior_weight: float
    prior_scale: object
    negative: object
    normals: np.ndarray
    values: np.ndarray
    towards: np.ndarray
    second_residual: object = None

    def warning(self):
        """``poor_fit_warning`` of this fit (and of the second photo's, prior "photo"): the
        line to show first, or None."""
        own = poor_fit_warning(self.residual)
        second = (None if self.second_residual is None
                  else poor_fit_warning(self.second_residual))
        if second is not None:
            second = f"second photo: {second}"
        return "; ".join(line for line in (own, second) if line) or None

    def summary(self):
        """One line for the user: residual, condition, poorly constrained terms, pixels."""
        weak = ", ".join(self.weak_terms) if self.weak_terms else "none"
        scale = ("" if self.prior_scale is None else
                 ", scaled × " + " / ".join(f"{v:.3g}" for v in self.prior_scale))
        return (
            f"residual {100.0 * self.residual:.2f} % of the mean (noise {100.0 * self.noise:.2f} %)"
            f", condition {self.condition:.0f}"
            f", poorly constrained: {weak}; {self.used} pixels used, {self.clipped} clipped and "
            f"{self.invalid} unusable left out; unseen side: "
            f"{MEASURED_PRIORS.get(self.prior, self.prior)}"
            + (f" (weight {self.prior_weight:.2g} of the pixels'{scale})"
               if self.prior != "none" else "")
        )


def poor_fit_warning(residual):
    """The line to show first (None if fine) for a fit whose ``residual`` is above
    ``MAX_RESIDUAL`` yet was not refused (the nine terms explain much of how its pixels vary):
    most often a wrong circle (centred on the rim, twice the ball: 37 % and 33 % measured,
    L00 0.5× and 2.3× the right one), or a ball that is not matte grey; a single hard light
    on the right circle also gives this much (38 %)."""
    if not residual > MAX_RESIDUAL:
        return None
    return (f"poor fit: the pixels in the circle are {100.0 * residual:.0f} % (RMS) from the "
            "best nine-term picture (a matte ball: a few %): check that the circle sits on the "
            "ball's outline (its centre and radius) and that the ball is matte grey and not "
            "clipped (a single hard light, a sun, can do this too)")


def design_matrix(normals, albedo=1.0):
    """(N, 9) A with A L = albedo · E(n) / π for one channel (eq. 6-7: Â_l Y_lm(n))."""
    factors = lambert_band_factors(2)[band_of_each_coefficient(2)]
    return sh_basis(normals, 2) * (factors * (albedo / np.pi))


def ball_picture(coeffs, height, width, circle, camera, albedo=DEFAULT_ALBEDO, background=0.0):
    """The (H, W, 3) picture of a grey ball of ``albedo`` lit by ``coeffs``: albedo · E / π
    at each pixel centre inside the circle (no rim margin), ``background`` elsewhere."""
    rows, cols, normals, _ = ball_normals(height, width, tuple(map(float, circle)),
                                          camera.checked())
    picture = np.full((height, width, 3), float(background))
    picture[rows, cols] = albedo * irradiance(coeffs, normals) / np.pi
    return picture


def _check_inputs(pixels, albedo, margin, prior, prior_weight, reference):
    a = np.asarray(pixels)
    if a.ndim != 3 or a.shape[2] < 3 or not np.issubdtype(a.dtype, np.number):
        raise PhotoError(f"the photo must be an (H, W, 3 or 4) array of numbers, got shape "
                         f"{a.shape}: pass linear RGB, rows top to bottom")
    if not (np.isfinite(albedo) and 0.0 < albedo <= 1.0):
        raise PhotoError(f"the ball's albedo must be in (0, 1], got {albedo!r} (a grey ball: 0.18)")
    if not (np.isfinite(margin) and 0.0 <= margin < 0.9):
        raise PhotoError(f"the rim margin must be a fraction of the radius in [0, 0.9), got "
                         f"{margin!r}")
    if prior not in PRIORS:
        raise PhotoError(f"the prior must be one of {', '.join(PRIORS)}, got {prior!r}")
    if not (np.isfinite(prior_weight) and prior_weight >= 0.0):
        raise PhotoError(f"the prior weight must be ≥ 0, got {prior_weight!r}")
    if prior == "chrome":
        chrome = np.asarray(reference if reference is not None else np.nan, dtype=np.float64)
        if chrome.shape != (9, 3) or not np.isfinite(chrome).all():
            raise PhotoError("the chrome prior needs the chrome ball's nine RGB L_lm (a "
                             "mirror-ball image's): give the chrome ball, or another prior")
    if prior == "photo" and not isinstance(reference, PhotoFit):
        raise PhotoError("the second-photo prior needs the second photo's fit: give the "
                         "second photo, its circle and its camera, or another prior")
    return a


def pixel_noise(pixels, rows, cols):
    """The pixels' noise σ (RMS per pixel and channel) at (rows, cols), from second
    differences along rows: v[j−1] − 2 v[j] + v[j+1] has variance 6σ² for independent noise
    (a render's fireflies included), while a smooth picture's curvature adds almost nothing
    (< 0.1 % of the mean on a 44 px ball less a 5 % rim)."""
    inside = np.zeros(pixels.shape[:2], dtype=bool)
    inside[rows, cols] = True
    within = (cols > 0) & (cols < pixels.shape[1] - 1)
    r, c = rows[within], cols[within]
    both = inside[r, c - 1] & inside[r, c + 1]
    r, c = r[both], c[both]
    if r.size == 0:
        return 0.0
    v = pixels[..., :3].astype(np.float64)
    second = v[r, c - 1] - 2.0 * v[r, c] + v[r, c + 1]
    return float(np.sqrt(np.mean(second**2) / 6.0))


def _weak_terms(matrix):
    """(condition, names): of the column-equilibrated ``matrix``, and the terms loading its
    singular directions with σ/σ_max < ``WEAK_SINGULAR`` (each as "L20" or "L00+L20")."""
    scale = np.linalg.norm(matrix, axis=0)
    _, sigma, vt = np.linalg.svd(matrix / scale, full_matrices=False)
    condition = float(sigma[0] / sigma[-1]) if sigma[-1] > 0.0 else float("inf")
    names = []
    for s, v in zip(sigma, vt):
        if s < WEAK_SINGULAR * sigma[0]:
            loaded = [COEFFICIENT_NAMES[k] for k in np.argsort(-np.abs(v))
                      if abs(v[k]) >= WEAK_LOADING]
            names.append("+".join(loaded))
    return condition, tuple(dict.fromkeys(names))


def _prior_lattice():
    """(the ``PRIOR_NORMALS`` lattice normals a prior may be placed on, 1.5 lattice spacings
    in radians: farther than that from every seen normal is unseen)."""
    return spread_normals(PRIOR_NORMALS), 1.5 * np.sqrt(4.0 * np.pi / PRIOR_NORMALS)


def _unseen(normals, lattice, spacing):
    """Which ``lattice`` normals are farther than ``spacing`` radians from every seen one."""
    step = max(1, normals.shape[0] // 4000)
    nearest = np.max(lattice @ normals[::step].T, axis=1)
    return nearest < np.cos(spacing)


def chrome_scale(chrome, normals, values, albedo):
    """(3,) per channel s minimising |s · albedo E_chrome(n) / π − v| over the seen normals
    and their pixels ``values``: the chrome ball's L_lm in the grey ball's units."""
    picture = design_matrix(normals, albedo) @ np.asarray(chrome, dtype=np.float64)
    scale = np.sum(picture * values, axis=0) / np.maximum(np.sum(picture**2, axis=0),
                                                          np.finfo(float).tiny)
    if not (scale > 0.0).all():
        raise PhotoError("the chrome ball's light does not match the grey ball's (a channel "
                         "comes out negative or zero): check that both balls are of one place")
    return scale


def joint_fit(normals, values, second, albedo):
    """(9, 3) least-squares L_lm of two photos' pixels together: this photo's ``normals`` and
    ``values`` and a ``second`` ``PhotoFit``'s (the same ball, albedo and exposure)."""
    matrix = design_matrix(np.vstack([normals, second.normals]), albedo)
    return np.linalg.lstsq(matrix, np.vstack([values, second.values]), rcond=None)[0]


def prior_observations(prior, plain, normals, towards, values_mean, albedo, reference=None):
    """(unseen lattice normals (M, 3), targets (M, 3) in pixel units) of ``prior``;
    ``reference``: for "chrome" and "photo", the (9, 3) L_lm whose picture is the target."""
    lattice, spacing = _prior_lattice()
    unseen = _unseen(normals, lattice, spacing)
    where = lattice[unseen]
    targets = np.broadcast_to(values_mean, where.shape).copy()
    if prior == "mirror" and where.size:
        mirrored = where - 2.0 * (where @ towards)[:, None] * towards
        seen = ~_unseen(normals, mirrored, spacing)
        targets[seen] = albedo * irradiance(plain, mirrored[seen]) / np.pi
    elif prior in ("chrome", "photo"):
        targets = albedo * irradiance(reference, where) / np.pi
    return where, targets


def fit_photo(pixels, circle, camera=PhotoCamera(), *, albedo=DEFAULT_ALBEDO,
              margin=DEFAULT_MARGIN, clip=None, prior="mirror",
              prior_weight=DEFAULT_PRIOR_WEIGHT, mask=None, max_residual=MAX_RESIDUAL,
              reference=None, opaque=None):
    """The nine RGB L_lm of the world lighting a grey ball in a photo (module docstring).

    ``pixels``: (H, W, 3 or 4) linear RGB, rows top to bottom (alpha ignored); ``circle``:
    (cx, cy, r) of the ball in pixels; ``camera``: a ``PhotoCamera``; ``clip``: pixels with a
    channel ≥ it are left out (an 8-bit photo decoded to linear: 1.0), or an (H, W) bool
    array of the clipped pixels (e.g. a byte of 255 in the file), None for none;
    ``mask``: (H, W) bool, False where the ball is hidden; ``max_residual``: above it the
    pixels are not a diffuse ball's and a PhotoError is raised (None: never); ``reference``:
    for prior "chrome" the chrome ball's (9, 3) L_lm, for "photo" the second photo's
    ``PhotoFit`` (fitted with prior "none"); ``opaque``: (H, W) bool, False where a photo
    with alpha is transparent (a cut-out's background): such texels inside the circle are
    left out, and refused above ``MAX_TRANSPARENT`` of them (the circle is off the ball).
    Returns a ``PhotoFit``; raises PhotoError with one line saying what to do.
    """
    a = _check_inputs(pixels, albedo, margin, prior, prior_weight, reference)
    height, width = a.shape[:2]
    cx, cy, r = check_circle(circle, height, width, MIN_RADIUS)
    rows, cols, normals, towards = ball_normals(height, width, (cx, cy, r), camera, margin)
    values = a[rows, cols, :3].astype(np.float64)
    usable = np.isfinite(values).all(axis=1)
    if mask is not None:
        usable &= np.asarray(mask, dtype=bool)[rows, cols]
    if opaque is not None:
        seen = np.asarray(opaque, dtype=bool)[rows, cols]
        transparent = int((~seen).sum())
        if transparent > MAX_TRANSPARENT * seen.size:
            raise PhotoError(
                f"{transparent} of the {seen.size} pixels inside the circle are transparent "
                "(alpha below 1: a cut-out's background): check the circle, it reaches past "
                "the ball"
            )
        usable &= seen
    if clip is None:
        clipped = np.zeros_like(usable)
    elif np.ndim(clip) == 2:
        clipped = usable & np.asarray(clip, dtype=bool)[rows, cols]
    else:
        clipped = usable & (values >= clip).any(axis=1)
    used = usable & ~clipped
    count, n_clipped = int(used.sum()), int(clipped.sum())
    if count < MIN_PIXELS:
        if n_clipped and n_clipped >= usable.sum() // 2:
            raise PhotoError(
                f"{n_clipped} of the ball's {int(usable.sum())} pixels are clipped (a channel "
                f"at the file's top value or above the threshold), {count} are left: "
                "photograph the ball darker, or raise the clip threshold for a linear image"
            )
        raise PhotoError(
            f"only {count} usable pixels inside the circle (at least {MIN_PIXELS} are needed): "
            "check the circle, enlarge it, or lower the rim margin"
        )
    normals, values = normals[used], values[used]
    mean = values.mean(axis=0)
    if not (mean.max() > 0.0):
        raise PhotoError(
            "the ball is black (its pixels average 0 or less): check the exposure and that "
            "the circle is on the ball"
        )
    matrix = design_matrix(normals, albedo)
    plain = np.linalg.lstsq(matrix, values, rcond=None)[0]
    residual = float(np.sqrt(np.mean((matrix @ plain - values) ** 2)) / np.mean(mean))
    unexplained = float(np.sum((matrix @ plain - values) ** 2)
                        / max(np.sum((values - mean) ** 2), np.finfo(float).tiny))
    if max_residual is not None and residual > max_residual and unexplained > MAX_UNEXPLAINED:
        raise PhotoError(
            f"the pixels in the circle are {100.0 * residual:.0f} % (RMS) away from any "
            "diffuse ball's picture (a matte ball: a few %): the circle is off, there is no "
            "ball there, or the ball is shiny or clipped"
        )
    condition, weak = _weak_terms(matrix)
    noise = pixel_noise(a, rows[used], cols[used]) / float(np.mean(mean))
    coeffs, weight, share, gain, second_residual = plain, 0.0, 0.0, None, None
    seen_values = values
    if prior == "chrome":
        gain = chrome_scale(reference, normals, values, albedo)
        reference = np.asarray(reference, dtype=np.float64) * gain
    elif prior == "photo":
        _check_second_photo(normals, reference)
        second_residual = reference.residual
        reference = joint_fit(normals, values, reference, albedo)
    if prior != "none" and prior_weight > 0.0:
        where, targets = prior_observations(prior, plain, normals, towards, mean, albedo,
                                            reference)
        if where.size:
            prior_matrix = design_matrix(where, albedo)
            misfit = np.sqrt(max(residual**2 - noise**2, 0.0))
            headroom = MEASURED_HEADROOM if prior in MEASURED_PRIORS else PRIOR_HEADROOM
            allowed = headroom * max(misfit, RESIDUAL_FLOOR) * float(np.mean(mean))
            coeffs, weight = _prior_fit(matrix, values, plain, prior_matrix, targets,
                                        prior_weight * count / where.shape[0], allowed)
            share = weight * where.shape[0] / count
            scale = np.sqrt(weight)
            matrix = np.vstack([matrix, scale * prior_matrix])
            values = np.vstack([values, scale * targets])
    coeffs = _never_negative(coeffs, matrix, values, albedo, count)
    return PhotoFit(coeffs, plain, residual, noise, condition, weak, count, n_clipped,
                    int((~usable).sum()), prior, float(share), gain,
                    negative_light_warning(coeffs), normals, seen_values, np.asarray(towards),
                    second_residual)


def _check_second_photo(normals, second):
    """A PhotoError when the ``second`` photo sees no lattice normal the first leaves unseen."""
    lattice, spacing = _prior_lattice()
    if not (_unseen(normals, lattice, spacing) & ~_unseen(second.normals, lattice, spacing)).any():
        raise PhotoError("the second photo sees only what the first sees: take it from "
                         "another side of the ball (e.g. opposite the first)")


def _prior_fit(matrix, values, plain, prior_matrix, targets, most, allowed):
    """(L_lm, w) of the data plus the prior observations with per-row weight w ≤ ``most``:
    the largest w (halved from ``most``) that moves the seen picture, RMS over pixels and
    channels, by at most ``allowed`` (pixel units): the prior decides only what the photo
    leaves open. Normal equations: (AᵀA + w PᵀP) L = Aᵀv + w Pᵀt."""
    ata, atv = matrix.T @ matrix, matrix.T @ values
    ptp, ptt = prior_matrix.T @ prior_matrix, prior_matrix.T @ targets
    count = matrix.shape[0]
    weight = most
    for _ in range(PRIOR_STEPS):
        coeffs = np.linalg.solve(ata + weight * ptp, atv + weight * ptt)
        change = coeffs - plain
        moved = np.sqrt(np.einsum("kc,kj,jc->", change, ata, change) / (3 * count))
        if moved <= allowed:
            return coeffs, weight
        weight *= 0.5
    return plain, 0.0


def _never_negative(coeffs, matrix, values, albedo, count):
    """``coeffs`` refitted per channel with E = 0 observations at the minimum's normal while
    the 9-term E goes below −``NEGATIVE_TOLERANCE`` × its mean (see the module docstring)."""
    coeffs = np.array(coeffs)
    weight = np.sqrt(float(count))  # each zero observation weighs as much as all the pixels
    for channel in range(3):
        rows_a, rows_b = [matrix], [values[:, channel]]
        for _ in range(NEGATIVE_STEPS):
            minimum = irradiance_minimum(coeffs)
            mean = mean_irradiance(coeffs)[channel]
            if mean <= 0.0 or minimum.value[channel] >= -NEGATIVE_TOLERANCE * mean:
                break
            rows_a.append(weight * design_matrix(minimum.direction[channel][None], albedo))
            rows_b.append(np.zeros(1))
            coeffs[:, channel] = np.linalg.lstsq(np.vstack(rows_a), np.concatenate(rows_b),
                                                 rcond=None)[0]
    # What the steps leave (the minimum moves as the fit changes) is lifted: E + deficit
    # everywhere, i.e. L00 + deficit / c4 (eq. 13's constant term).
    deficit = np.maximum(-irradiance_minimum(coeffs).value, 0.0)
    coeffs[0] += deficit / C4
    return coeffs


def relative_rms(estimate, reference):
    """RMS of estimate − reference over normals and channels, / the mean of ``reference``."""
    e, ref = np.asarray(estimate, dtype=np.float64), np.asarray(reference, dtype=np.float64)
    return float(np.sqrt(np.mean((e - ref) ** 2)) / np.mean(ref))


def best_nine_term_error(normals, reference):
    """The nine-term limit on ``normals``: ``relative_rms`` of the least-squares nine-term
    E(n) fit to the irradiance ``reference`` (N, 3) there, against it."""
    matrix = design_matrix(normals, np.pi)  # A L = E(n)
    fit = np.linalg.lstsq(matrix, reference, rcond=None)[0]
    return relative_rms(matrix @ fit, reference)


def scaled_error(estimate, reference):
    """``relative_rms`` after the one scale s minimising |s estimate − reference| (albedo ×
    exposure unknown), and s."""
    e, ref = np.asarray(estimate, dtype=np.float64), np.asarray(reference, dtype=np.float64)
    s = float(np.sum(e * ref) / np.sum(e * e))
    return relative_rms(s * e, ref), s


@dataclass(frozen=True)
class ExposureMatch:
    """The grey ball calibrated to the chrome ball.

    scale: × grey L_lm gives the chrome ball's L00 (luminance): the L00 calibration.
    seen_scale: × grey E(n) best matches the chrome ball's on the grey ball's seen normals
        (least squares, luminance): better conditioned, since one photo fixes L00 poorly
        (it trades with the moment along the view axis, ``PhotoFit.weak_terms``).
    l00_colour: per channel relative difference of the scaled L00 left (white balance).
    seen, everywhere: ``relative_rms`` of scale × grey vs chrome E(n) (luminance weighted
        channels) on the seen normals and over the whole sphere."""

    scale: float
    seen_scale: float
    l00_colour: np.ndarray
    seen: float
    everywhere: float

    def summary(self):
        return (
            f"exposure × {self.scale:.4g} to match the chrome ball's L00 (× "
            f"{self.seen_scale:.4g} to match it on the seen side); then they differ by "
            f"{100.0 * self.seen:.1f} % on the seen side and {100.0 * self.everywhere:.1f} % "
            "over all normals"
        )


def match_exposure(grey, chrome, seen_normals=None, weights=(0.2126, 0.7152, 0.0722)):
    """``ExposureMatch`` of grey-ball ``grey`` (9, 3) against chrome-ball ``chrome`` (9, 3)
    L_lm: s = (w · chrome L00) / (w · grey L00), w the luminance ``weights`` (Rec.709)."""
    g, c = np.asarray(grey, dtype=np.float64), np.asarray(chrome, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    if not (g[0] @ w > 0.0 and c[0] @ w > 0.0):
        raise PhotoError("an L00 is zero or negative: both balls need light to be compared")
    scale = float((c[0] @ w) / (g[0] @ w))
    everywhere_normals = spread_normals(1024)
    seen = everywhere_normals if seen_normals is None else np.asarray(seen_normals)
    grey_seen, chrome_seen = irradiance(g, seen) @ w, irradiance(c, seen) @ w
    seen_scale = float(grey_seen @ chrome_seen / (grey_seen @ grey_seen))
    return ExposureMatch(
        scale, seen_scale, scale * g[0] / c[0] - 1.0,
        relative_rms(scale * grey_seen, chrome_seen),
        relative_rms(scale * irradiance(g, everywhere_normals) @ w,
                     irradiance(c, everywhere_normals) @ w),
    )
