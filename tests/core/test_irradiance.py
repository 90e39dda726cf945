"""Irradiance: eq. 13, the matrix form (eq. 12), and the brute-force ground truth (eq. 1)."""

from math import pi, sqrt

import numpy as np
import pytest
from quadrature import random_directions

from sh_lighting.core.equirect import texel_directions
from sh_lighting.core.irradiance import (
    C1,
    C2,
    C3,
    C4,
    C5,
    irradiance,
    irradiance_coefficients,
    irradiance_matrices,
    reference_irradiance,
)
from sh_lighting.core.projection import project_equirect
from sh_lighting.core.sh import sh_basis

EXACT = 1e-12


def e9_single_source(u):
    """docs/reference.md §2: 9-term irradiance of a unit-power delta at cosine u."""
    return 0.25 + u / 2.0 + (15.0 * u * u - 5.0) / 32.0


def test_eq13_constants_match_the_paper_to_its_printed_digits():
    printed = [0.429043, 0.511664, 0.743125, 0.886227, 0.247708]
    for exact, rounded in zip([C1, C2, C3, C4, C5], printed):
        assert exact == pytest.approx(rounded, rel=1e-5)


def test_constant_radiance_gives_pi_c():
    c = np.array([0.5, 1.0, 2.0])
    coeffs = np.zeros((9, 3))
    coeffs[0] = 2.0 * sqrt(pi) * c
    n = random_directions(200)
    assert np.abs(irradiance(coeffs, n) - pi * c).max() < EXACT
    pixels = np.broadcast_to(c, (128, 256, 3))
    assert np.abs(irradiance(project_equirect(pixels), n) - pi * c).max() < EXACT
    # brute force, each texel integrated exactly: π c to rounding
    assert np.abs(reference_irradiance(pixels, n[:50]) / (pi * c) - 1.0).max() < 1e-13


def test_single_delta_matches_closed_form_e9():
    """A unit-power delta in direction s has L_lm = Y_lm(s); E9 depends only on u = n·s."""
    s = np.array([0.3, -0.5, 0.81])
    s /= np.linalg.norm(s)
    coeffs = np.repeat(sh_basis(s)[:, None], 3, axis=1)
    n = np.concatenate([random_directions(300), s[None], -s[None]])
    u = n @ s
    e = irradiance(coeffs, n)[:, 0]
    assert np.abs(e - e9_single_source(u)).max() < EXACT
    assert e[-2] == pytest.approx(1.0625, abs=EXACT) and e[-1] == pytest.approx(0.0625, abs=EXACT)
    assert e9_single_source(0.0) == pytest.approx(3 / 32)
    assert e9_single_source(-8 / 15) == pytest.approx(-0.0396, abs=5e-5)  # the minimum
    assert e.min() >= e9_single_source(-8 / 15) - EXACT


def test_small_bright_patch_matches_e9_within_its_size():
    """All light in a 2×2-texel patch: E9 of the map ≈ closed form, brute force ≈ max(u, 0)."""
    h, w = 256, 512
    pixels = np.zeros((h, w, 3))
    pixels[100:102, 300:302] = 1.0
    dirs = texel_directions(h, w)[100:102, 300:302].reshape(-1, 3)
    s = dirs.mean(axis=0)
    s /= np.linalg.norm(s)
    coeffs = project_equirect(pixels)
    power = coeffs[0, 0] / (2.0 * sqrt(pi)) * 4.0 * pi  # ∫ L dω = L00 · 2√π
    n = random_directions(400, seed=2)
    u = n @ s
    patch_size = np.arccos(np.clip(dirs @ s, -1, 1)).max()  # angular radius, ~0.006 rad
    assert np.abs(irradiance(coeffs, n)[:, 0] / power - e9_single_source(u)).max() < 4 * patch_size
    brute = reference_irradiance(pixels, n)[:, 0] / power
    assert np.abs(brute - np.maximum(u, 0.0)).max() < 4 * patch_size


def test_matrix_form_equals_eq13():
    rng = np.random.default_rng(1)
    coeffs = rng.normal(size=(9, 3))
    n = random_directions(500)
    n4 = np.concatenate([n, np.ones((500, 1))], axis=1)
    quad = np.einsum("ni,cij,nj->nc", n4, irradiance_matrices(coeffs), n4)
    assert np.abs(quad - irradiance(coeffs, n)).max() < EXACT
    m = irradiance_matrices(coeffs)
    assert np.array_equal(m, np.transpose(m, (0, 2, 1)))  # symmetric (eq. 12)


def test_eq13_equals_the_general_sum():
    rng = np.random.default_rng(2)
    coeffs = np.zeros((25, 3))
    coeffs[:9] = rng.normal(size=(9, 3))
    n = random_directions(500)
    general = sh_basis(n, 2) @ irradiance_coefficients(coeffs[:9])
    assert np.abs(irradiance(coeffs[:9], n) - general).max() < EXACT
    assert np.abs(irradiance(coeffs, n) - general).max() < EXACT  # l=3 is zero, l=4 is empty


def test_irradiance_coefficients_scale_bands():
    coeffs = np.ones((9, 3))
    e = irradiance_coefficients(coeffs)[:, 0]
    assert np.allclose(e, [pi] + [2 * pi / 3] * 3 + [pi / 4] * 5, rtol=0, atol=1e-15)


def test_reference_is_vectorised_over_any_normal_shape():
    pixels = np.random.default_rng(3).random((16, 32, 4)).astype(np.float32)
    n = random_directions(12).reshape(3, 4, 3)
    out = reference_irradiance(pixels, n)
    assert out.shape == (3, 4, 3)
    assert np.allclose(out.reshape(-1, 3), reference_irradiance(pixels, n.reshape(-1, 3)), 1e-14)


@pytest.mark.parametrize(
    "coeffs, message",
    [(np.zeros((8, 3)), "order"), (np.zeros((9, 2)), "shape"), (np.full((9, 3), np.nan), "NaN")],
)
def test_bad_coefficients(coeffs, message):
    with pytest.raises(ValueError, match=message):
        irradiance(coeffs, np.array([0.0, 0.0, 1.0]))


def test_reference_refuses_non_finite_pixels():
    pixels = np.ones((4, 8, 3))
    pixels[1, 2, 1] = np.inf
    with pytest.raises(ValueError, match="row 1, column 2"):
        reference_irradiance(pixels, np.array([0.0, 0.0, 1.0]))


def test_universal_error_bounds_on_random_non_negative_maps():
    """|E9 - E| ≤ (3/32) P and E9 ≥ -0.0396 P for any non-negative lighting (docs/reference.md §2).

    Each map has one texel holding most of the light, so the error comes near the bounds
    (a point source attains them; the reference integrates the sun's 2.8° texel exactly, an
    area light, which stays a little further from them)."""
    rng = np.random.default_rng(9)
    n = random_directions(300, seed=4)
    worst = 0.0
    for trial in range(5):
        pixels = rng.random((64, 128, 3)) ** 8  # spiky, non-negative
        pixels[rng.integers(8, 56), rng.integers(128)] += 8e3  # a sun
        coeffs = project_equirect(pixels)
        power = coeffs[0] * 2.0 * sqrt(pi)
        err = np.abs(irradiance(coeffs, n) - reference_irradiance(pixels, n)) / power
        assert err.max() <= 3 / 32
        assert (irradiance(coeffs, n) / power).min() >= -0.0396
        worst = max(worst, err.max())
    assert worst > 0.08  # near the bound (measured 7.9–8.2 % of P), not far below it


def test_error_estimate_of_a_map_the_nine_terms_cannot_hold():
    """A constant map: E is exact with L00 alone (estimate ~0); one bright texel (a delta):
    the 9-term error reaches the universal bound 3/32 of the power only at its horizon, and
    is large compared with the constant map's. A black channel gives None."""
    from sh_lighting.core.irradiance import error_estimate

    constant = np.full((32, 64, 3), 0.5)
    flat = error_estimate(constant, project_equirect(constant), 512)
    assert flat["max"] < 1e-3
    delta = constant * 1e-3
    delta[5, 20] = 1e3
    spiky = error_estimate(delta, project_equirect(delta), 512)
    assert 0.05 < spiky["max"] <= 3 / 32 + 0.01 and spiky["mean"] < spiky["max"]
    black = constant.copy()
    black[..., 2] = 0.0
    assert error_estimate(black, project_equirect(black)) is None
