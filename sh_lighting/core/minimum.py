"""The exact minimum and maximum of the 9-term irradiance E(n) over the unit sphere.

E(v) = vᵀ A v + 2 bᵀ v + c on |v| = 1 (eq. 12 split: A the 3×3 block of M, b its last column,
c = c4 L00 − c5 L20), per channel: the trust-region subproblem, solved exactly. In A's
eigenbasis (d₁ ≤ d₂ ≤ d₃, β = Qᵀ b) the multiplier λ < d₁ is the root of
Σ β_i² / (d_i − λ)² = 1, bracketed in [d₁ − |b|, d₁ − |β₁|] (safeguarded Newton); the hard
case β₁ = 0 takes λ = d₁. The dual g(λ) = λ + c − Σ β_i² / (d_i − λ) is a lower bound with
no gap (S-lemma): each result carries both bounds. The maximum is −min(−E). Details:
docs/modules.md.
"""

from dataclasses import dataclass

import numpy as np

from .irradiance import C4, check_coefficients, irradiance, irradiance_matrices
from .sh import spread_normals

# Newton/bisection steps on the secular equation: Newton converges in a handful, bisection
# alone needs ~60 to halve a float64 bracket to its last bit.
MAX_ITERATIONS = 200
# Relative size (to the data's scale) below which b, or its component along the lowest
# eigenvectors, counts as zero; and eigenvalues this close (relatively) count as equal.
ZERO = 1e-13


@dataclass(frozen=True)
class SphereExtremum:
    """Minimum (or maximum) of E(n) over unit normals n, per colour channel.

    value: (3,) E at ``direction``, attained, so an upper bound of the true minimum.
    direction: (3, 3) the unit normal n of each channel (rows R, G, B), Blender world axes.
    bound: (3,) the dual value g(λ), a lower bound of the true minimum (for a maximum: an
        upper bound of the true maximum); ``abs(value - bound)`` bounds the error.
    """

    value: np.ndarray
    direction: np.ndarray
    bound: np.ndarray


def _secular_root(d, beta, lo, hi):
    """λ in [lo, hi] (all < d[0]) with Σ β_i²/(d_i − λ)² = 1, by safeguarded Newton on ψ.

    ψ(λ) = 1/√f(λ) − 1 = 1/|v(λ)| − 1 decreases with λ and is concave and close to linear (the
    Moré–Sorensen choice); a Newton step that leaves the bracket is replaced by bisection.
    """
    lam = hi
    for _ in range(MAX_ITERATIONS):
        gap = d - lam
        if np.any(gap <= 0.0):  # rounding at hi == d[0]: step back inside
            lam = 0.5 * (lo + hi)
            continue
        f = np.sum(beta * beta / (gap * gap))
        if f > 1.0:
            hi = lam
        else:
            lo = lam
        # dψ/dλ = −½ f^(−3/2) f', f' = 2 Σ β²/(d − λ)³
        df = 2.0 * np.sum(beta * beta / gap**3)
        psi = 1.0 / np.sqrt(f) - 1.0
        dpsi = -0.5 * f**-1.5 * df
        step = lam - psi / dpsi if dpsi != 0.0 else 0.5 * (lo + hi)
        if not lo < step < hi:
            step = 0.5 * (lo + hi)
        if step == lam or hi - lo <= 4.0 * np.spacing(max(abs(lo), abs(hi))):
            return lam
        lam = step
    return lam


def minimize_quadratic_on_sphere(a, b, c):
    """min over unit v ∈ R³ of vᵀ a v + 2 bᵀ v + c, exactly (see the module docstring).

    ``a``: symmetric (3, 3); ``b``: (3,); ``c``: scalar. Returns (value, v, lower_bound, λ).
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    d, q = np.linalg.eigh(0.5 * (a + a.T))
    beta = q.T @ b
    norm_b = float(np.linalg.norm(b))
    scale = max(float(np.abs(d).max()), norm_b, np.finfo(float).tiny)
    lowest = d - d[0] <= ZERO * scale  # the eigenvalues equal to d₁
    beta_low = float(np.linalg.norm(beta[lowest]))

    if beta_low <= ZERO * scale:
        # Possibly the hard case: try λ = d₁, v completed along q₁.
        rest = ~lowest
        coef = np.zeros(3)
        coef[rest] = -beta[rest] / (d[rest] - d[0])
        length2 = float(coef @ coef)
        if length2 <= 1.0:
            coef[0] = np.sqrt(1.0 - length2)  # q₁ is d's first eigenvector, in `lowest`
            lam = d[0]
            v = q @ coef
            bound = lam + c - np.sum(beta[rest] ** 2 / (d[rest] - lam))
            return _finish(a, b, c, v, bound, lam)
    lo = d[0] - norm_b
    hi = d[0] - beta_low
    lam = _secular_root(d, beta, lo, hi)
    gap = d - lam
    bound = lam + c - np.sum(beta * beta / gap)
    # v = −(A − λI)⁻¹ b. Near the hard case (β tiny along the lowest eigenvectors, λ just
    # below d₁) the lowest components −β_i/(d₁ − λ) lose digits to the tiny d₁ − λ; their
    # length then follows more accurately from |v| = 1. Both candidates are unit vectors, so
    # the smaller E is still an attained value.
    coef = -beta / gap
    candidates = [q @ (coef / np.linalg.norm(coef))]
    low_length = float(np.linalg.norm(coef[lowest]))
    if low_length > 0.0:
        rest_length2 = float(coef[~lowest] @ coef[~lowest])
        completed = coef.copy()
        completed[lowest] *= np.sqrt(max(0.0, 1.0 - rest_length2)) / low_length
        candidates.append(q @ (completed / np.linalg.norm(completed)))
    values = [float(v @ a @ v + 2.0 * b @ v + c) for v in candidates]
    return _finish(a, b, c, candidates[int(np.argmin(values))], bound, lam)


def _finish(a, b, c, v, bound, lam):
    value = float(v @ a @ v + 2.0 * b @ v + c)
    return value, v, float(min(bound, value)), float(lam)


def _extremum(coeffs, sign):
    m = sign * irradiance_matrices(coeffs)
    values, directions, bounds = np.empty(3), np.empty((3, 3)), np.empty(3)
    for ch in range(3):
        value, v, bound, _ = minimize_quadratic_on_sphere(m[ch, :3, :3], m[ch, :3, 3], m[ch, 3, 3])
        values[ch], directions[ch], bounds[ch] = sign * value, v, sign * bound
    return SphereExtremum(values, directions, bounds)


def irradiance_minimum(coeffs):
    """The exact minimum over unit normals of the 9-term E(n) = nᵀ M n (eq. 12), per channel.

    ``coeffs``: (9, 3) radiance L_lm, Blender axes. Returns a ``SphereExtremum``.
    """
    return _extremum(coeffs, 1.0)


def irradiance_maximum(coeffs):
    """The exact maximum over unit normals of the 9-term E(n) (eq. 12), per channel."""
    return _extremum(coeffs, -1.0)


def mean_irradiance(coeffs):
    """Mean of E(n) over the sphere, per channel: Â₀ L00 Y00 = c4 L00 (bands l ≥ 1 average 0)."""
    c, _ = check_coefficients(coeffs)
    return C4 * c[0]


AXIS_WORDS = (("+X", "−X"), ("+Y", "−Y"), ("above", "below"))


def direction_words(direction):
    """A unit direction in words: its dominant axes, e.g. "below" or "below, toward +X"."""
    d = np.asarray(direction, dtype=np.float64)
    order = np.argsort(-np.abs(d))
    words = []
    for axis in order:
        if abs(d[axis]) >= 0.4 or not words:
            words.append(AXIS_WORDS[axis][0 if d[axis] >= 0 else 1])
    if len(words) == 1:
        return words[0] if words[0] in ("above", "below") else f"toward {words[0]}"
    vertical = [w for w in words if w in ("above", "below")]
    horizontal = [w for w in words if w not in ("above", "below")]
    if vertical:
        return f"{vertical[0]}, toward {' '.join(horizontal)}"
    return f"toward {' '.join(horizontal)}"


# A dip below zero of at most this fraction of the mean irradiance is small: within what nine
# terms get wrong there anyway. Measured: sunrise.exr dips to −4.6 % (blue, facing down, over
# 2.2 % of directions) where the world's own is +3.3 % of the mean: the nine terms miss it by
# 8 % of the mean there, dip or not, and the least smoothing that
# removes the dip raises their mean error over all directions (2.20 % → 2.36 % of the light,
# max 6.5 % → 7.6 %); Grace Cathedral dips −1.2 % over 1.0 %; the deepest a single light can
# make, −15.8 % (docs/reference.md §2), is not small.
SMALL_NEGATIVE = 0.05
SHARE_NORMALS = 4096  # directions at which the share of negative ones is counted


def negative_share(coeffs, count=SHARE_NORMALS):
    """The fraction of directions (a Fibonacci lattice of ``count``) where a channel of the
    9-term irradiance is below zero."""
    return float((irradiance(coeffs, spread_normals(count)) < 0.0).any(axis=1).mean())


def negative_light_is_small(coeffs):
    """True when the irradiance dips below zero, but by at most ``SMALL_NEGATIVE`` of the
    mean in every channel (the panel then says it quietly, not as an error)."""
    mean = mean_irradiance(coeffs)
    if np.any(mean <= 0.0):
        return False
    relative = irradiance_minimum(coeffs).value / mean
    return bool(relative.min() < 0.0 and relative.min() >= -SMALL_NEGATIVE)


def negative_light_warning(coeffs, tolerance=1e-6):
    """None if E(n) ≥ 0 for every normal and channel, else one short sentence for the user.

    The 9-term irradiance goes negative behind a strong small light (docs/reference.md §2: down to
    −0.0396 P for a single light) or after edits. Channels whose exact minimum is below
    −``tolerance`` × their mean irradiance (``mean_irradiance``) are named, with the minimum as
    a percentage of that mean and the direction of the most negative channel.
    """
    minimum = irradiance_minimum(coeffs)
    mean = mean_irradiance(coeffs)
    names = "RGB"
    if np.any(mean <= 0.0):
        bad = ", ".join(names[i] for i in np.nonzero(mean <= 0.0)[0])
        return (
            f"Negative light: channel {bad} has a mean irradiance ≤ 0 "
            "(L00 ≤ 0), so it is dark or negative almost everywhere"
        )
    relative = minimum.value / mean
    negative = np.nonzero(relative < -tolerance)[0]
    if negative.size == 0:
        return None
    worst = negative[np.argmin(relative[negative])]
    amounts = ", ".join(f"{names[i]} {100.0 * relative[i]:+.1f} %" for i in negative)
    share = 100.0 * negative_share(coeffs)
    text = (f"Negative light: irradiance goes below zero ({amounts} of the mean) on surfaces "
            f"facing {direction_words(minimum.direction[worst])}, {share:.1f} % of all directions")
    if relative[worst] >= -SMALL_NEGATIVE:
        return (text + "; a small dip, within what nine terms miss there anyway: smoothing "
                "removes it but blurs the lighting elsewhere")
    return text + "; a smoothing window removes it"
