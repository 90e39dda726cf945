"""Which terms of eq. 13 a lighting needs, and the exact error of leaving the others out.

The 9-term irradiance (Ramamoorthi and Hanrahan 2001, eq. 13) is a sum of one term per
coefficient, each a coefficient times a fixed polynomial of the unit normal n = (x, y, z):

    term     polynomial       largest |polynomial| on the unit sphere
    L00      c4               c4
    L1-1     2 c2 y           2 c2            (|y| ≤ 1)
    L10      2 c2 z           2 c2
    L11      2 c2 x           2 c2
    L2-2     2 c1 xy          c1              (|xy| ≤ ½, at x = y = 1/√2)
    L2-1     2 c1 yz          c1
    L20      c3 z² − c5       c3 − c5 = 2 c5  (z² ∈ [0, 1]: from −c5 to c3 − c5; c3 = 3 c5)
    L21      2 c1 xz          c1
    L22      c1 (x² − y²)     c1              (|x² − y²| ≤ 1)

so ``TERM_PEAKS[i] · |L_i|`` is exactly the largest contribution term i can make anywhere on the
sphere (per colour channel). A *sample* is one (9, 3) set of raw radiance coefficients L_lm
(Blender axes): the current values, or their values at one keyframed frame.

**Tolerance.** For a sample, ``tolerance = relative × mean irradiance of its brightest
channel`` (the mean of E over the sphere is c4 L00, ``minimum.mean_irradiance``). One number
for all three channels: an error is judged against the brightness of the image, and a channel
that is black (mean 0) must not forbid leaving out terms that are zero in every channel.

**Rule** (``fit_terms``). A set S of terms may be left out when, for every sample,

* each term of S has a largest contribution below the sample's tolerance, and
* the exact maximum over the sphere of |Σ_{i∈S} term_i(n)|, in every channel, is below it.

The second is a quadratic form nᵀMn (eq. 12 with the kept coefficients set to zero); its
maximum and minimum come from ``minimum.py`` (certified bounds, exact to rounding). An error of
exactly zero is always accepted (a term that is zero at a frame where the lighting is black).
A relative tolerance of 0 keeps every term. S is grown greedily, smallest terms first (ranked by
largest peak / tolerance over the samples): a candidate joins S only if S stays valid, so the
final S satisfies the rule by construction; ``bound`` reports its exact error.

Everything here is numpy; the Blender layer only chooses nodes for the terms it is told to keep.
"""

from dataclasses import dataclass

import numpy as np

# TERM_PEAKS: largest |constant × polynomial| of each term over the unit sphere (table above).
from .irradiance import C4, TERM_PEAKS, irradiance
from .minimum import irradiance_maximum, irradiance_minimum
from .sh import COEFFICIENT_NAMES

# The terms of each band (l = 0, 1, 2) by index l(l+1)+m.
BANDS = ((0,), (1, 2, 3), (4, 5, 6, 7, 8))
ALL_TERMS = tuple(range(9))
DEFAULT_RELATIVE_TOLERANCE = 1e-3


@dataclass(frozen=True)
class TermFit:
    """The terms a set of samples needs.

    kept, omitted: sorted term indices (l(l+1)+m), together 0..8.
    bound: max over samples of (exact max over the sphere and channels of |Σ omitted terms|)
        divided by the sample's brightest-channel mean irradiance (0 when nothing is omitted;
        inf if an omitted term is non-zero at a sample whose mean irradiance is ≤ 0, which the
        rule never allows).
    bound_absolute: the same maximum, not divided (irradiance units).
    """

    kept: tuple
    omitted: tuple
    bound: float
    bound_absolute: float

    @property
    def kept_names(self):
        return tuple(COEFFICIENT_NAMES[i] for i in self.kept)

    @property
    def omitted_names(self):
        return tuple(COEFFICIENT_NAMES[i] for i in self.omitted)


def as_samples(samples):
    """``samples`` as a finite float64 (S, 9, 3) array; one (9, 3) sample is accepted too."""
    s = np.array(samples, dtype=np.float64)
    if s.ndim == 2:
        s = s[None]
    if s.ndim != 3 or s.shape[1:] != (9, 3) or s.shape[0] == 0:
        raise ValueError(f"samples must have shape (S, 9, 3) with S ≥ 1, got {np.shape(samples)}")
    if not np.isfinite(s).all():
        raise ValueError("coefficient samples contain NaN or Inf")
    return s


def _relative(relative_tolerance, count):
    r = np.broadcast_to(np.asarray(relative_tolerance, dtype=np.float64), (count,)).copy()
    if not (np.isfinite(r).all() and (r >= 0.0).all()):
        raise ValueError(f"relative tolerance must be finite and ≥ 0, got {relative_tolerance}")
    return r


def term_peaks(samples):
    """(S, 9, 3): the largest |contribution| of each term over the sphere, exactly."""
    return np.abs(as_samples(samples)) * TERM_PEAKS[:, None]


def mean_scale(samples):
    """(S,): the mean irradiance c4 L00 of each sample's brightest channel, at least 0."""
    return np.maximum(C4 * as_samples(samples)[:, 0, :].max(axis=1), 0.0)


def tolerances(samples, relative_tolerance):
    """(S,) absolute tolerance of each sample: relative × ``mean_scale``."""
    s = as_samples(samples)
    return _relative(relative_tolerance, len(s)) * mean_scale(s)


def sum_max_abs(coeffs):
    """(3,) exact max over unit normals of |E(n)| of one (9, 3) sample, per channel.

    Certified: the maximum's upper bound and the minimum's lower bound of ``minimum.py``.
    """
    c = np.asarray(coeffs, dtype=np.float64)
    if not c.any():
        return np.zeros(3)
    return np.maximum(irradiance_maximum(c).bound, -irradiance_minimum(c).bound)


def omitted_max_abs(samples, omitted):
    """(S, 3) exact max over the sphere of |Σ_{i ∈ omitted} term_i(n)|, per sample and channel."""
    s = as_samples(samples)
    only = np.zeros_like(s)
    idx = list(omitted)
    only[:, idx] = s[:, idx]
    return np.array([sum_max_abs(sample) for sample in only])


def _within(error, tol):
    """Elementwise: an error is accepted below the tolerance, or when it is exactly zero."""
    return (error < tol) | (error == 0.0)


def omission_holds(samples, omitted, relative_tolerance=DEFAULT_RELATIVE_TOLERANCE):
    """True when leaving out the terms ``omitted`` obeys the rule at every sample.

    Cheap first: each term's peak, then the triangle inequality (sum of peaks); the exact
    maximum only for samples where the triangle bound is not already below the tolerance.
    """
    s = as_samples(samples)
    omitted = sorted(set(omitted))
    if not omitted:
        return True
    rel = _relative(relative_tolerance, len(s))
    if (rel == 0.0).any():
        return False
    tol = rel * mean_scale(s)
    peaks = term_peaks(s)[:, omitted]  # (S, k, 3)
    if not _within(peaks, tol[:, None, None]).all():
        return False
    return _set_within(s, omitted, peaks.sum(axis=1), tol)


def _set_within(s, omitted, triangle, tol):
    """Σ of the omitted terms within tolerance at every sample (triangle bound, then exact)."""
    unsure = ~_within(triangle, tol[:, None]).all(axis=1)
    for index in np.nonzero(unsure)[0]:
        exact = omitted_max_abs(s[index : index + 1], omitted)[0]
        if not _within(exact, tol[index]).all():
            return False
    return True


def fit_terms(samples, relative_tolerance=DEFAULT_RELATIVE_TOLERANCE):
    """The ``TermFit`` of ``samples`` (S, 9, 3) under the rule of the module docstring.

    ``relative_tolerance``: one value or one per sample (samples of several scenes with their
    own settings). Any sample with a relative tolerance of 0 keeps every term.
    """
    s, rel = _unique(as_samples(samples), relative_tolerance)
    if (rel == 0.0).any():
        return TermFit(ALL_TERMS, (), 0.0, 0.0)
    scale = mean_scale(s)
    tol = rel * scale
    peaks = term_peaks(s)  # (S, 9, 3)
    fits_alone = _within(peaks, tol[:, None, None]).all(axis=(0, 2))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(peaks == 0.0, 0.0, peaks / tol[:, None, None]).max(axis=(0, 2))
    omitted = []
    for term in sorted(np.nonzero(fits_alone)[0], key=lambda i: (ratio[i], i)):
        trial = sorted(omitted + [int(term)])
        if _set_within(s, trial, peaks[:, trial].sum(axis=1), tol):
            omitted = trial
    kept = tuple(i for i in ALL_TERMS if i not in omitted)
    relative, absolute = _worst_error(s, omitted, peaks, scale)
    return TermFit(kept, tuple(omitted), relative, absolute)


def _unique(s, relative_tolerance):
    """Samples with their relative tolerances, duplicates (same values and tolerance) dropped."""
    rel = _relative(relative_tolerance, len(s))
    rows = np.concatenate([s.reshape(len(s), 27), rel[:, None]], axis=1)
    rows = np.unique(rows, axis=0)
    return rows[:, :27].reshape(-1, 9, 3), rows[:, 27]


def _worst_error(s, omitted, peaks, scale):
    """(max relative, max absolute) exact error of leaving out ``omitted`` over the samples.

    Branch and bound: samples in decreasing order of their triangle bound, stopping once that
    bound cannot beat the worst exact value found so far (for both measures).
    """
    if not omitted:
        return 0.0, 0.0
    triangle = peaks[:, omitted].sum(axis=1).max(axis=1)  # (S,)
    with np.errstate(divide="ignore", invalid="ignore"):
        triangle_rel = np.where(triangle == 0.0, 0.0, triangle / scale)
    worst_rel = worst_abs = 0.0
    order = np.lexsort((-triangle, -triangle_rel))
    for index in order:
        if triangle_rel[index] <= worst_rel and triangle[index] <= worst_abs:
            continue
        exact = float(omitted_max_abs(s[index : index + 1], omitted)[0].max())
        worst_abs = max(worst_abs, exact)
        if exact > 0.0:
            worst_rel = max(worst_rel, exact / scale[index] if scale[index] > 0 else np.inf)
    return worst_rel, worst_abs


def is_grey(samples, kept):
    """True when R = G = B exactly for every kept term in every sample (scalar math suffices)."""
    s = as_samples(samples)[:, list(kept)]
    return bool((s[..., 0] == s[..., 1]).all() and (s[..., 0] == s[..., 2]).all())


def can_be_negative(samples, kept):
    """True when the irradiance of the kept terms is below 0 for some normal, channel, sample.

    Decided by the exact minimum (``minimum.irradiance_minimum``, its attained value: a negative
    one is certainly reached); cheap bounds first: the constant part minus the other peaks
    (≥ 0: never negative), then E at the 26 directions of a cube's faces, edges and corners
    (< 0 somewhere: negative).
    """
    s = as_samples(samples)
    only = np.zeros_like(s)
    idx = list(kept)
    only[:, idx] = s[:, idx]
    peaks = term_peaks(only)
    # E ≥ c4 L00 − Σ_{i ≥ 1} peak_i  (the L20 peak covers its −c5 part too).
    lower = C4 * only[:, 0] - peaks[:, 1:].sum(axis=1)
    unsure = np.nonzero((lower < 0.0).any(axis=1))[0]
    if unsure.size == 0:
        return False
    probes = _probe_directions()
    for index in unsure:
        if (irradiance(only[index], probes) < 0.0).any():
            return True
    for index in unsure:
        if (irradiance_minimum(only[index]).value < 0.0).any():
            return True
    return False


def _probe_directions():
    grid = np.array(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1])).reshape(3, -1).T
    grid = grid[np.abs(grid).sum(axis=1) > 0].astype(np.float64)
    return grid / np.linalg.norm(grid, axis=1, keepdims=True)


def band_of_terms(terms):
    """The bands (0, 1, 2) that have at least one of ``terms``."""
    return tuple(band for band, members in enumerate(BANDS) if set(members) & set(terms))
