"""Band windows and the minimal non-negative window (windowing.py)."""

from math import pi, sqrt

import numpy as np
import pytest
from quadrature import random_directions

from sh_lighting.core.equirect import texel_directions
from sh_lighting.core.irradiance import irradiance, reference_irradiance
from sh_lighting.core.minimum import irradiance_minimum
from sh_lighting.core.projection import project_equirect
from sh_lighting.core.sh import sh_basis
from sh_lighting.core.windowing import (
    apply_window,
    hanning_window,
    lanczos_window,
    minimal_nonnegative_window,
    nonnegative_family,
    window_cost,
)

EXACT = 1e-14
CERTIFIED = 1e-12  # min E ≥ −1e-12 × mean irradiance after the minimal window
WEAKER = 1e-9  # this much less smoothing must leave E negative somewhere


def delta(s, power=1.0):
    s = np.asarray(s, float) / np.linalg.norm(s)
    return power * np.repeat(sh_basis(s)[:, None], 3, axis=1)


def physical_lighting(seed):
    """A strong delta light, two weaker ones (random positive RGB powers) and a dim sky."""
    rng = np.random.default_rng(seed)
    coeffs = np.zeros((9, 3))
    coeffs[0] = 2.0 * sqrt(pi) * rng.uniform(0.0, 0.01, 3)
    for k, s in enumerate(random_directions(3, seed=seed + 100)):
        power = rng.uniform(1.0, 2.0, 3) if k == 0 else rng.uniform(0.0, 0.2, 3)
        coeffs += power * np.repeat(sh_basis(s)[:, None], 3, axis=1)
    return coeffs


def lowest(coeffs):
    return irradiance_minimum(coeffs).value.min()


def test_window_values_in_closed_form():
    assert np.abs(hanning_window(3) - [1.0, 0.75, 0.25]).max() < EXACT
    assert np.abs(hanning_window(2) - [1.0, 0.5, 0.0]).max() < EXACT
    third = 3 * sqrt(3) / (2 * pi)  # sinc(1/3)
    assert np.abs(lanczos_window(3) - [1.0, third, third / 2]).max() < EXACT
    assert np.all(hanning_window(np.inf) == 1.0) and np.all(lanczos_window(np.inf) == 1.0)
    assert np.all(hanning_window(1.0) == [1.0, 0.0, 0.0])
    with pytest.raises(ValueError):
        hanning_window(0.0)


@pytest.mark.parametrize("make", [hanning_window, lanczos_window])
@pytest.mark.parametrize("width", [0.5, 1.0, 1.7, 2.0, 3.0, 4.5, 10.0, 1e6])
def test_windows_keep_l0_are_at_most_one_and_decrease(make, width):
    w = make(width, max_order=6)
    assert w[0] == 1.0
    assert np.all(w <= 1.0) and np.all(w >= 0.0)
    assert np.all(np.diff(w) <= 0.0)


def test_family_endpoints_and_l0():
    assert np.all(nonnegative_family(0.0) == 1.0)
    assert np.all(nonnegative_family(1.0) == hanning_window(2))
    assert np.all(nonnegative_family(2.0) == [1.0, 0.0, 0.0])
    for t in np.linspace(0, 2, 17):
        w = nonnegative_family(t)
        assert w[0] == 1.0 and np.all(w <= 1.0) and np.all(w >= 0.0)


def test_apply_window_scales_each_band():
    coeffs = np.arange(27.0).reshape(9, 3)
    out = apply_window(coeffs, [1.0, 0.5, 0.25])
    assert np.all(out[0] == coeffs[0])
    assert np.all(out[1:4] == 0.5 * coeffs[1:4]) and np.all(out[4:] == 0.25 * coeffs[4:])


def test_minimal_window_for_one_light_in_closed_form():
    """One delta: E_t(u) = 1/4 + (2−t)u/8 + (1−t)(15u² − 5)/32 touches 0 when s = 1 − t solves
    91 s² − 88 s + 16 = 0 (its larger root): t* = 1 − (44 + 4√30)/91 = 0.27573.
    """
    result = minimal_nonnegative_window(delta([0.2, -0.4, 0.7]))
    assert result.parameter == pytest.approx(1.0 - (44 + 4 * sqrt(30)) / 91, abs=1e-12)
    assert np.all(result.minimum >= -CERTIFIED * 0.25)
    assert np.abs(result.window - nonnegative_family(result.parameter)).max() == 0.0


@pytest.mark.parametrize("seed", range(4))
def test_minimal_window_makes_physical_lighting_nonnegative_and_is_minimal(seed):
    coeffs = physical_lighting(seed)
    assert lowest(coeffs) < 0.0  # strong lights: the plain 9 terms ring below zero
    result = minimal_nonnegative_window(coeffs)
    mean = 0.886227 * coeffs[0]
    assert 0.0 < result.parameter <= 1.0  # the first segment suffices for physical light
    assert np.all(result.minimum >= -CERTIFIED * mean)
    weaker = apply_window(coeffs, nonnegative_family(result.parameter - WEAKER))
    assert lowest(weaker) < 0.0
    # concavity makes the feasible set an interval: no smaller t on a grid works either
    for t in np.linspace(0.0, result.parameter - WEAKER, 12):
        assert lowest(apply_window(coeffs, nonnegative_family(t))) < 0.0
    # dense sampling agrees: nothing below zero beyond rounding
    e = irradiance(result.coefficients, random_directions(5000, seed=seed))
    assert np.all(e >= -CERTIFIED * mean)


def test_no_op_when_already_nonnegative():
    coeffs = np.zeros((9, 3))
    coeffs[0] = [1.0, 2.0, 3.0]
    coeffs[2] = 0.3  # a gentle top light: E = c4 L00 + 2 c2 0.3 z > 0
    result = minimal_nonnegative_window(coeffs)
    assert result.parameter == 0.0 and np.all(result.window == 1.0)
    assert np.all(result.coefficients == coeffs)


def test_nonphysical_coefficients_use_the_second_segment():
    coeffs = np.zeros((9, 3))
    coeffs[0], coeffs[2] = 1.0, 3.0  # L10 ≫ L00: even Hanning width 2 leaves E < 0 below
    assert lowest(apply_window(coeffs, hanning_window(2))) < 0.0
    result = minimal_nonnegative_window(coeffs)
    assert 1.0 < result.parameter < 2.0
    assert np.all(result.minimum >= -CERTIFIED)
    assert lowest(apply_window(coeffs, nonnegative_family(result.parameter - WEAKER))) < 0.0
    # closed form: E = c4 + (2 − t) c2 3 z ≥ 0 ⇔ (2 − t) ≤ c4 / (3 c2)
    assert result.parameter == pytest.approx(2.0 - 0.886227 / (3 * 0.511664), abs=1e-5)


def test_feasible_interval_strictly_inside_the_first_segment():
    """Non-physical coefficients where E ≥ 0 for some t in (0, 1) but not at t = 0 or 1."""
    coeffs = np.zeros((9, 3))
    coeffs[:] = np.array([0.91, 0.673, -1.452, 0.003, -0.765, -1.043, 3.105, -1.154, -0.43])[
        :, None
    ]
    assert lowest(coeffs) < 0 and lowest(apply_window(coeffs, nonnegative_family(1.0))) < 0
    result = minimal_nonnegative_window(coeffs)
    assert 0.0 < result.parameter < 1.0
    assert np.all(result.minimum >= -CERTIFIED)
    assert lowest(apply_window(coeffs, nonnegative_family(result.parameter - WEAKER))) < 0.0


def test_nonpositive_l00_is_refused():
    coeffs = np.zeros((9, 3))
    coeffs[0] = [1.0, 0.0, 1.0]
    with pytest.raises(ValueError, match="L00"):
        minimal_nonnegative_window(coeffs)


def test_window_cost_for_one_light_matches_the_known_errors():
    """One unit-power delta: exact E = max(u, 0); the plain 9 terms err by 3/32 at the horizon
    and by 0.0307 on average (docs/reference.md §2); an identity window costs nothing.
    """
    s = np.array([0.0, 0.0, 1.0])
    normals = np.concatenate([random_directions(40000, seed=5), [[1.0, 0.0, 0.0]]])
    reference = np.repeat(np.maximum(normals @ s, 0.0)[:, None], 3, axis=1)
    coeffs = delta(s)
    cost = window_cost(coeffs, hanning_window(3), normals, reference)
    power = 2.0 * sqrt(pi) * coeffs[0, 0]  # = 1
    assert power == pytest.approx(1.0)
    assert np.abs(cost.plain_max - 3 / 32).max() < EXACT
    assert np.abs(cost.plain_mean - 0.0307).max() < 0.0005  # Monte Carlo over 40,000 normals
    # Hanning width 3 at the horizon: E = 1/4 − 5/128 = 0.2109 vs 0: worse, and reported so
    assert np.all(cost.windowed_max >= 0.25 - 5 / 128 - EXACT)
    same = window_cost(coeffs, np.ones(3), normals, reference)
    assert np.all(same.windowed_mean == same.plain_mean)


def test_window_cost_on_a_map_against_brute_force():
    height, width = 32, 64
    dirs = texel_directions(height, width)
    pixels = 0.2 + np.exp(8.0 * (dirs @ np.array([0.6, 0.0, 0.8]) - 1.0))[..., None] * [
        3.0,
        2.0,
        1.0,
    ]
    coeffs = project_equirect(pixels)
    normals = random_directions(300, seed=9)
    reference = reference_irradiance(pixels, normals)
    cost = window_cost(coeffs, lanczos_window(3), normals, reference)
    power = 2.0 * sqrt(pi) * coeffs[0]
    expected = np.abs(irradiance(coeffs, normals) - reference) / power
    assert np.abs(cost.plain_mean - expected.mean(axis=0)).max() < EXACT
    assert np.abs(cost.plain_max - expected.max(axis=0)).max() < EXACT
    windowed = np.abs(irradiance(apply_window(coeffs, lanczos_window(3)), normals) - reference)
    assert np.abs(cost.windowed_max - (windowed / power).max(axis=0)).max() < EXACT
    # this smooth light is well captured by 9 terms; the window can only blur it further
    assert np.all(cost.plain_mean < 0.01) and np.all(cost.windowed_mean > cost.plain_mean)
