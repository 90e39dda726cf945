"""core.pruning: exact peaks of each term, the rule for leaving terms out, grey and clamp tests.

Independent checks: every bound is compared with E evaluated by ``irradiance`` (eq. 13) on a
dense Fibonacci grid of unit normals, which can only under-estimate a maximum.
"""

import math

import numpy as np
import pytest

from sh_lighting.core import pruning
from sh_lighting.core.irradiance import C1, C2, C3, C4, C5, irradiance
from sh_lighting.core.minimum import irradiance_minimum
from sh_lighting.core.sh import spread_normals

# A grid of 40,000 normals: the spacing (~0.018 rad) bounds how far below a true maximum of a
# quadratic of unit-size coefficients the grid's maximum can fall (second order: ~1e-4).
GRID_SLACK = 2e-4


NORMALS = spread_normals(40_000)


def only(index, rgb=(1.0, 1.0, 1.0)):
    c = np.zeros((9, 3))
    c[index] = rgb
    return c


def ambient(value=1.0):
    return only(0, (value, value, value))


def test_term_peaks_are_the_closed_forms():
    assert pruning.TERM_PEAKS == pytest.approx([C4, 2 * C2, 2 * C2, 2 * C2, C1, C1, 2 * C5, C1, C1])
    assert C3 == pytest.approx(3.0 * C5)  # so the L20 peak c3 − c5 is 2 c5


@pytest.mark.parametrize("index", range(9))
def test_each_peak_is_the_maximum_of_the_term_over_the_sphere(index):
    coeffs = only(index, (1.0, -2.5, 0.25))
    peaks = pruning.term_peaks(coeffs)[0]
    assert not np.delete(peaks, index, axis=0).any()
    on_grid = np.abs(irradiance(coeffs, NORMALS)).max(axis=0)
    assert (on_grid <= peaks[index] * (1.0 + 1e-12)).all()
    assert (on_grid >= peaks[index] * (1.0 - GRID_SLACK)).all()


def test_peaks_are_attained_where_the_table_says():
    s = 1.0 / math.sqrt(2.0)
    assert irradiance(only(4), [s, s, 0.0])[0] == pytest.approx(C1)  # 2 c1 xy at x = y
    assert irradiance(only(6), [0.0, 0.0, 1.0])[0] == pytest.approx(C3 - C5)
    assert irradiance(only(6), [1.0, 0.0, 0.0])[0] == pytest.approx(-C5)


def test_pure_ambient_keeps_one_term_and_is_grey_and_positive():
    fit = pruning.fit_terms(ambient(2.0))
    assert fit.kept == (0,) and fit.omitted == tuple(range(1, 9))
    assert fit.bound == 0.0 and fit.bound_absolute == 0.0
    assert pruning.is_grey(ambient(2.0), fit.kept)
    assert not pruning.can_be_negative(ambient(2.0), fit.kept)


def test_ambient_and_directional_has_no_band_two():
    coeffs = ambient(1.0)
    coeffs[2] = (0.4, 0.3, 0.2)  # light from above, coloured
    fit = pruning.fit_terms(coeffs)
    assert fit.kept == (0, 2)
    assert pruning.band_of_terms(fit.kept) == (0, 1)
    assert not pruning.is_grey(coeffs, fit.kept)


def test_zero_tolerance_keeps_every_term_even_zero_ones():
    fit = pruning.fit_terms(ambient(), relative_tolerance=0.0)
    assert fit.kept == pruning.ALL_TERMS and fit.omitted == ()
    # One sample of several with tolerance 0 is enough.
    fit = pruning.fit_terms([ambient(), ambient(2.0)], relative_tolerance=[1e-3, 0.0])
    assert fit.kept == pruning.ALL_TERMS


def test_a_term_at_the_tolerance_is_kept_just_below_it_is_left_out():
    tolerance = 1e-3 * C4  # L00 = 1
    for factor, kept in ((1.0, (0, 2)), (0.999, (0,))):
        coeffs = ambient()
        coeffs[2, 0] = factor * tolerance / (2.0 * C2)
        assert pruning.fit_terms(coeffs).kept == kept


def test_the_sum_of_left_out_terms_is_bounded_too():
    # L10 and L20 each peak at 60 % of the tolerance, both at n = +z: alone each may go,
    # together they reach 120 %. The first in the ranking (a tie: lower index) goes.
    coeffs = ambient()
    tolerance = 1e-3 * C4
    for index in (2, 6):
        coeffs[index] = 0.6 * tolerance / pruning.TERM_PEAKS[index]
    fit = pruning.fit_terms(coeffs)
    assert fit.kept == (0, 6)
    error = np.abs(irradiance(coeffs, NORMALS) - irradiance(_kept_only(coeffs, fit.kept), NORMALS))
    assert error.max() < tolerance
    # The reported bound is the exact maximum (the grid gets within its resolution of it).
    assert fit.bound_absolute == pytest.approx(error.max(), rel=GRID_SLACK)
    assert fit.bound == pytest.approx(fit.bound_absolute / C4)
    assert not pruning.omission_holds(coeffs, (1, 2, 3, 4, 5, 6, 7, 8))
    assert pruning.omission_holds(coeffs, fit.omitted)


def test_exact_bound_beats_the_triangle_inequality():
    # 2 c2 (a x + a y) peaks at 2 c2 a √2, not 2 c2 · 2a: 0.6 + 0.6 = 1.2 tolerances by the
    # triangle inequality, 0.85 exactly, so both go.
    tolerance = 1e-3 * C4
    coeffs = ambient()
    coeffs[1] = coeffs[3] = 0.6 * tolerance / (2.0 * C2)
    fit = pruning.fit_terms(coeffs)
    assert fit.kept == (0,)
    assert fit.bound_absolute == pytest.approx(0.6 * math.sqrt(2.0) * tolerance, rel=1e-9)


def test_an_animated_term_that_grows_is_kept():
    frames = np.repeat(ambient()[None], 50, axis=0)
    frames[:, 2, :] = np.linspace(0.0, 0.8, 50)[:, None]  # L10 from 0 to large
    assert pruning.fit_terms(frames[:1]).kept == (0,)
    fit = pruning.fit_terms(frames)
    assert fit.kept == (0, 2) and pruning.is_grey(frames, fit.kept)


def test_tolerance_follows_each_samples_brightness():
    # The same tiny L10 is negligible under a bright ambient, not under a dim one.
    bright, dim = ambient(10.0), ambient(0.1)
    bright[2] = dim[2] = 1e-3
    assert pruning.fit_terms(bright).kept == (0,)
    assert pruning.fit_terms(dim).kept == (0, 2)
    assert pruning.fit_terms([bright, dim]).kept == (0, 2)
    # Each sample with its own relative tolerance.
    assert pruning.fit_terms([bright, dim], [1e-3, 0.1]).kept == (0,)


def test_black_frames_leave_zero_terms_out_but_not_lit_ones():
    black = np.zeros((9, 3))
    assert pruning.fit_terms([black, ambient()]).kept == (0,)
    odd = np.zeros((9, 3))
    odd[2] = 0.5  # no mean light at all, but L10: the tolerance is 0, so it stays
    assert pruning.fit_terms([odd, ambient()]).kept == (0, 2)


def test_a_black_channel_does_not_keep_terms_that_are_zero():
    red = np.zeros((9, 3))
    red[0, 0], red[2, 0] = 1.0, 0.3
    fit = pruning.fit_terms(red)
    assert fit.kept == (0, 2) and not pruning.is_grey(red, fit.kept)


def test_pruning_never_exceeds_the_tolerance_on_random_lighting():
    rng = np.random.default_rng(7)
    for _ in range(40):
        samples = rng.normal(size=(3, 9, 3)) * 10.0 ** rng.uniform(-5, -1, size=(1, 9, 1))
        samples[:, 0] = rng.uniform(0.5, 2.0, size=(3, 3))
        relative = 10.0 ** rng.uniform(-4, -1)
        fit = pruning.fit_terms(samples, relative)
        for sample in samples:
            tolerance = relative * C4 * sample[0].max()
            error = np.abs(
                irradiance(sample, NORMALS) - irradiance(_kept_only(sample, fit.kept), NORMALS)
            )
            assert error.max() < tolerance
            assert error.max() <= fit.bound_absolute * (1.0 + 1e-9)
        exact = pruning.omitted_max_abs(samples, fit.omitted).max(axis=1)
        scale = pruning.mean_scale(samples)
        assert fit.bound_absolute == pytest.approx(exact.max(), rel=1e-12, abs=0.0)
        assert fit.bound == pytest.approx((exact / scale).max(), rel=1e-12, abs=0.0)


def test_grey_means_exactly_equal_channels_of_the_kept_terms():
    coeffs = ambient()
    coeffs[2] = 0.5
    assert pruning.is_grey(coeffs, (0, 2))
    coeffs[3] = (0.1, 0.2, 0.3)
    assert not pruning.is_grey(coeffs, (0, 2, 3))
    assert pruning.is_grey(coeffs, (0, 2))  # L11 not kept: does not count
    coeffs[2, 1] = np.nextafter(0.5, 1.0)
    assert not pruning.is_grey(coeffs, (0, 2))


def test_negative_irradiance_behind_a_single_light():
    # A delta light along +z: E9(u) = 1/4 + u/2 + (15u² − 5)/32 (REFERENCE §2), min < 0.
    y00 = 0.5 / math.sqrt(math.pi)
    y1, y20 = math.sqrt(3 / (4 * math.pi)), 0.25 * math.sqrt(5 / math.pi)
    delta = np.zeros((9, 3))
    delta[0], delta[2], delta[6] = y00, y1, 2 * y20
    assert pruning.can_be_negative(delta, pruning.ALL_TERMS)
    assert pruning.can_be_negative(delta, (0, 2))  # 1/4 + u/2: −1/4 at u = −1
    assert not pruning.can_be_negative(delta, (0, 6))  # 1/4 + (15u² − 5)/32 ≥ 3/32


def test_negative_decided_exactly_when_the_cheap_bounds_cannot():
    # c4 L00 + 2 c2 (a x + a y): the peaks say it may reach c4 − 4 c2 a < 0, the exact minimum
    # c4 − 2√2 c2 a is positive.
    a = C4 / (2.0 * C2) / 1.6
    coeffs = ambient()
    coeffs[1] = coeffs[3] = a
    assert C4 - 4 * C2 * a < 0 < C4 - 2 * math.sqrt(2) * C2 * a
    assert not pruning.can_be_negative(coeffs, pruning.ALL_TERMS)
    coeffs[1] = coeffs[3] = 1.01 * C4 / (2 * math.sqrt(2) * C2)
    assert pruning.can_be_negative(coeffs, pruning.ALL_TERMS)


def test_can_be_negative_agrees_with_the_exact_minimum():
    rng = np.random.default_rng(11)
    for _ in range(150):
        coeffs = rng.normal(size=(9, 3)) * 0.4
        coeffs[0] = rng.uniform(0.3, 1.5, size=3)
        kept = tuple(sorted(rng.choice(9, size=rng.integers(1, 10), replace=False)))
        expected = bool((irradiance_minimum(_kept_only(coeffs, kept)).value < 0).any())
        assert pruning.can_be_negative(coeffs, kept) == expected


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="shape"):
        pruning.fit_terms(np.zeros((8, 3)))
    bad = ambient()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        pruning.fit_terms(bad)
    with pytest.raises(ValueError, match="tolerance"):
        pruning.fit_terms(ambient(), -1e-3)


def _kept_only(coeffs, kept):
    out = np.zeros_like(np.asarray(coeffs, dtype=np.float64))
    out[list(kept)] = np.asarray(coeffs)[list(kept)]
    return out
