"""Band windows for the lighting coefficients: taming the ringing of the 9-term irradiance.

L'_lm = w_l L_lm (E'_lm = w_l Â_l L_lm, eq. 7), w_0 = 1, 0 ≤ w_l ≤ 1. Hanning:
w_l = (1 + cos(π l / width)) / 2 (width 3: (1, 3/4, 1/4); width 2: (1, 1/2, 0), non-negative
for non-negative light); Lanczos: w_l = sinc(l / width). ``minimal_nonnegative_window``: the
least t ∈ [0, 2] in w(t) = (1 − t)(1, 1, 1) + t (1, ½, 0) (t ≤ 1), then toward (1, 0, 0),
with E_t(n) ≥ 0 for every normal, found by bisection with the exact minimum (``minimum``):
min_n E_t is concave in t, so {t : E_t ≥ 0} is an interval. Details: docs/modules.md.
"""

from dataclasses import dataclass
from math import pi, sqrt

import numpy as np

from .irradiance import check_coefficients, error_over_power, irradiance, total_power
from .minimum import irradiance_minimum
from .sh import band_of_each_coefficient

BISECTION_TOLERANCE = 1e-13  # on t: well below anything visible, ~45 exact minimisations
GOLDEN = (sqrt(5.0) - 1.0) / 2.0
HANNING_NONNEGATIVE = np.array([1.0, 0.5, 0.0])  # hanning_window(2): the cardioid
AMBIENT_ONLY = np.array([1.0, 0.0, 0.0])


def _check_width(width):
    if not width > 0:
        raise ValueError(f"a window width must be > 0 (or inf for no window), got {width!r}")


def hanning_window(width, max_order=2):
    """w_l = (1 + cos(π l / width)) / 2 for l < width, else 0; l = 0..max_order. inf: all 1."""
    _check_width(width)
    x = np.arange(max_order + 1) / width
    return np.where(x < 1.0, 0.5 * (1.0 + np.cos(pi * x)), 0.0)


def lanczos_window(width, max_order=2):
    """w_l = sinc(l / width) = sin(π l / width) / (π l / width) for l < width, else 0."""
    _check_width(width)
    x = np.arange(max_order + 1) / width
    return np.where(x < 1.0, np.sinc(x), 0.0)


def apply_window(coeffs, window):
    """L'_lm = w_l L_lm for a window of one factor per band (len ≥ order + 1)."""
    c, order = check_coefficients(coeffs)
    w = np.asarray(window, dtype=np.float64)
    if w.ndim != 1 or w.size < order + 1:
        raise ValueError(f"the window needs one factor per band l = 0..{order}, got {w.shape}")
    return c * w[band_of_each_coefficient(order)][:, None]


def nonnegative_family(t):
    """The window w(t) of the family in the module docstring, t ∈ [0, 2]."""
    if not 0.0 <= t <= 2.0:
        raise ValueError(f"the family parameter t must be in [0, 2], got {t!r}")
    if t <= 1.0:
        return (1.0 - t) * np.ones(3) + t * HANNING_NONNEGATIVE
    return (2.0 - t) * HANNING_NONNEGATIVE + (t - 1.0) * AMBIENT_ONLY


@dataclass(frozen=True)
class MinimalWindow:
    """The least smoothing of the family that makes E(n) ≥ 0 everywhere.

    parameter: t ∈ [0, 2] (0: no window). window: (3,) w_0, w_1, w_2. coefficients: (9, 3)
    the windowed L_lm. minimum: (3,) the exact minimum of the windowed E(n) per channel.
    """

    parameter: float
    window: np.ndarray
    coefficients: np.ndarray
    minimum: np.ndarray


def _lowest(coeffs, t):
    """min over channels and normals of E for w(t): the certified lower bound, concave in t."""
    return float(irradiance_minimum(apply_window(coeffs, nonnegative_family(t))).bound.min())


def _smallest_feasible(coeffs, lo, hi):
    """Smallest t in (lo, hi] with _lowest ≥ 0, given _lowest(lo) < 0 ≤ _lowest(hi)."""
    while hi - lo > BISECTION_TOLERANCE:
        mid = 0.5 * (lo + hi)
        if _lowest(coeffs, mid) >= 0.0:
            hi = mid
        else:
            lo = mid
    return hi


def _concave_argmax(coeffs, lo, hi):
    """Golden-section search for the maximiser of the concave _lowest on [lo, hi]."""
    a, b = lo, hi
    x1, x2 = b - GOLDEN * (b - a), a + GOLDEN * (b - a)
    f1, f2 = _lowest(coeffs, x1), _lowest(coeffs, x2)
    while b - a > 1e-9:
        if f1 >= 0.0:
            return x1
        if f2 >= 0.0:
            return x2
        if f1 < f2:
            a, x1, f1 = x1, x2, f2
            x2 = a + GOLDEN * (b - a)
            f2 = _lowest(coeffs, x2)
        else:
            b, x2, f2 = x2, x1, f1
            x1 = b - GOLDEN * (b - a)
            f1 = _lowest(coeffs, x1)
    return None


def minimal_nonnegative_window(coeffs):
    """The smallest t of the family (module docstring) with E(n) ≥ 0 for all n and channels.

    ``coeffs``: (9, 3) L_lm. Returns a ``MinimalWindow``; t = 0 (no change) when E ≥ 0
    already. Raises ValueError when some channel has L00 ≤ 0: no window can help then.
    """
    c, order = check_coefficients(coeffs)
    if order != 2:
        raise ValueError(f"the minimal window needs the 9 coefficients of order 2, got {order}")
    if np.any(c[0] <= 0.0):
        raise ValueError(
            "a channel has L00 ≤ 0 (mean irradiance ≤ 0): no smoothing makes it non-negative"
        )
    if _lowest(c, 0.0) >= 0.0:
        t = 0.0
    elif _lowest(c, 1.0) >= 0.0:
        t = _smallest_feasible(c, 0.0, 1.0)
    else:
        # the first segment's feasible interval, if any, lies strictly inside it
        peak = _concave_argmax(c, 0.0, 1.0)
        t = _smallest_feasible(c, 0.0, peak) if peak is not None else None
        if t is None:
            t = _smallest_feasible(c, 1.0, 2.0)
    window = nonnegative_family(t)
    windowed = apply_window(c, window)
    return MinimalWindow(t, window, windowed, irradiance_minimum(windowed).value)


@dataclass(frozen=True)
class WindowCost:
    """Errors of the 9-term irradiance against a reference, plain and windowed.

    Each entry is (3,) per channel, as a fraction of the channel's total power
    P = ∫ L dω = 2√π L00 (the paper's measure, docs/reference.md §2): mean and max of |E − E_ref|
    over the given normals.
    """

    plain_mean: np.ndarray
    plain_max: np.ndarray
    windowed_mean: np.ndarray
    windowed_max: np.ndarray


def window_cost(coeffs, window, normals, reference):
    """How much a window costs in accuracy: errors of plain and windowed E(n) vs ``reference``.

    ``reference``: (N, 3) the brute-force irradiance (``reference_irradiance``, eq. 1) at the
    unit ``normals`` (N, 3) of the map the coefficients were projected from.
    """
    c, _ = check_coefficients(coeffs)
    ref = np.asarray(reference, dtype=np.float64)
    power = total_power(c)
    plain = error_over_power(irradiance(c, normals), ref, power)
    windowed = error_over_power(irradiance(apply_window(c, window), normals), ref, power)
    return WindowCost(plain.mean(axis=0), plain.max(axis=0), windowed.mean(axis=0),
                      windowed.max(axis=0))
