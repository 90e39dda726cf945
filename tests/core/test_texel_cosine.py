"""The exact texel kernel ∫ max(n·ω, 0) dω and the reference irradiance built on it: checked
against identities that hold exactly (the whole sphere gives π for every normal) and against
brute-force subdivision of single texels, and the 9-term error of a constant map is 0."""

import importlib
from math import pi

import numpy as np
import pytest

from sh_lighting.core.projection import project_equirect
from sh_lighting.core.sh import spread_normals
from sh_lighting.core.texel_cosine import clamped_cosine_integral, texel_moments

irradiance_module = importlib.import_module("sh_lighting.core.irradiance")
reference_irradiance = irradiance_module.reference_irradiance
error_estimate = irradiance_module.error_estimate
AXES = np.array([[0, 0, 1], [0, 0, -1], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0],
                 [0.6, 0.8, 0.0], [np.sqrt(0.5), 0.0, np.sqrt(0.5)]], dtype=np.float64)


def normals(count=500, seed=3):
    rng = np.random.default_rng(seed)
    n = rng.normal(size=(count, 3))
    n[: len(AXES)] = AXES
    n[len(AXES): len(AXES) + 50, 2] *= 1e-3  # nearly horizontal normals, r close to 1
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def grid(height, width):
    z = np.cos(np.linspace(0.0, pi, height + 1))
    phi = pi - 2.0 * pi * np.arange(width + 1) / width
    return z, phi


def kernel_of_texel(n, z, phi, i, j):
    count = len(n)
    return clamped_cosine_integral(n, np.full(count, z[i + 1]), np.full(count, z[i]),
                                   np.full(count, phi[j + 1]), np.full(count, phi[j]))


@pytest.mark.parametrize("height, width", [(1, 1), (1, 2), (2, 1), (3, 7), (8, 16), (5, 3)])
def test_the_texels_of_any_map_sum_to_pi_for_every_normal(height, width):
    """∫ over the sphere of max(n·ω, 0) dω = π: exact whatever the texels."""
    n = normals()
    z, phi = grid(height, width)
    total = sum(kernel_of_texel(n, z, phi, i, j) for i in range(height) for j in range(width))
    assert np.abs(total - pi).max() < 1e-13


def brute_force(n, z_lo, z_hi, phi0, phi1, k=800):
    """Midpoint rule in (z, φ), uniform in solid angle: error O(1/k²)."""
    zz = z_lo + (np.arange(k) + 0.5) / k * (z_hi - z_lo)
    pp = phi0 + (np.arange(k) + 0.5) / k * (phi1 - phi0)
    s = np.sqrt(1.0 - zz * zz)[:, None]
    d = n[0] * s * np.cos(pp) + n[1] * s * np.sin(pp) + n[2] * zz[:, None]
    return np.maximum(d, 0.0).mean() * (z_hi - z_lo) * (phi1 - phi0)


def test_single_texels_agree_with_subdivision():
    n = normals(30, seed=5)
    z, phi = grid(4, 6)
    worst = 0.0
    for q, normal in enumerate(n):
        i, j = q % 4, (q * 7) % 6
        exact = kernel_of_texel(normal[None], z, phi, i, j)[0]
        worst = max(worst, abs(exact - brute_force(normal, z[i + 1], z[i], phi[j + 1], phi[j])))
    assert worst < 2e-6  # the subdivision's own error at k = 800 (O(1/k²))


def test_moments_are_the_integral_of_the_direction():
    z, phi = grid(3, 5)
    v = texel_moments(z[2], z[1], phi[3], phi[2])
    for axis, e in enumerate(np.eye(3)):
        assert v[axis] == pytest.approx(brute_force(e, z[2], z[1], phi[3], phi[2]) -
                                        brute_force(-e, z[2], z[1], phi[3], phi[2]), abs=1e-6)


@pytest.mark.parametrize("height, width", [(1, 1), (1, 2), (2, 4), (7, 5), (64, 128)])
def test_a_constant_map_has_exactly_pi_times_its_radiance_and_no_9_term_error(height, width):
    colour = np.array([0.2, 0.5, 1.5])
    pixels = np.broadcast_to(colour, (height, width, 3)).astype(np.float64)
    n = spread_normals(256)
    assert np.abs(reference_irradiance(pixels, n) / (pi * colour) - 1.0).max() < 1e-14
    estimate = error_estimate(pixels, project_equirect(pixels))
    assert estimate["mean"] < 1e-14 and estimate["max"] < 1e-14


def test_reference_of_a_random_map_is_the_sum_of_exact_texel_kernels():
    """Texels wholly above the horizon take n · V, the others the exact kernel: the same as
    the kernel summed over every texel (which is slow but has no shortcut)."""
    rng = np.random.default_rng(7)
    height, width = 6, 10
    pixels = rng.random((height, width, 3))
    n = normals(40, seed=11)
    z, phi = grid(height, width)
    expected = sum(kernel_of_texel(n, z, phi, i, j)[:, None] * pixels[i, j]
                   for i in range(height) for j in range(width))
    assert np.abs(reference_irradiance(pixels, n) - expected).max() < 1e-13
    assert np.allclose(reference_irradiance(pixels, 2.5 * n), 2.5 * expected, rtol=1e-13)


def test_near_horizon_lists_exactly_the_pairs_a_scan_would_find():
    height, width = 33, 17
    z, phi = grid(height, width)
    moments = texel_moments(z[1:, None], z[:-1, None], phi[None, 1:], phi[None, :-1])
    theta = np.linspace(0.0, pi, height + 1)
    edge = irradiance_module._horizon_margin(theta, width, moments[:, 0])
    n = normals(200, seed=13)
    linear = n @ moments.reshape(-1, 3).T
    scan = set(zip(*np.nonzero(np.abs(linear) <= np.repeat(edge, width)[None, :])))
    bounds = irradiance_module._arc_bounds(n, moments[:, 0], edge)
    k, i, j = irradiance_module._near_horizon(bounds, width)
    listed = list(zip(k, i * width + j))
    assert len(listed) == len(set(listed)) and set(listed) == scan
    # and the arcs wholly above the horizon are the rest of the texels with n · V > 0
    first, count = irradiance_module._above_arcs(bounds, width)
    above = {(kk, ii * width + (first[kk, ii] + c) % width)
             for kk in range(len(n)) for ii in range(height) for c in range(count[kk, ii])}
    assert above == set(zip(*np.nonzero(linear > np.repeat(edge, width)[None, :])))


def test_the_texels_the_horizon_misses_are_found_from_their_boundary(monkeypatch):
    """reference_irradiance gives the exact kernel only the texels near the horizon whose
    boundary n·ω changes sign (_boundary_range): the range holds every sampled n·ω of the
    texel, and E is the all-kernel one to rounding."""
    rng = np.random.default_rng(7)
    height, width, count = 24, 48, 400
    n = rng.normal(size=(count, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    row, col = rng.integers(0, height, count), rng.integers(0, width, count)
    theta = np.linspace(0.0, pi, height + 1)
    phi = pi - (2.0 * pi / width) * np.arange(width + 1)
    z_lo, z_hi = np.cos(theta[row + 1]), np.cos(theta[row])
    lo, hi = irradiance_module._boundary_range(
        n, z_lo, z_hi, np.sin(theta[row + 1]), np.sin(theta[row]), np.cos(phi[col + 1]),
        np.sin(phi[col + 1]), np.cos(phi[col]), np.sin(phi[col]))
    s = np.linspace(0.0, 1.0, 41)
    t = theta[row, None, None] + (theta[row + 1] - theta[row])[:, None, None] * s[None, :, None]
    p = phi[col + 1, None, None] + (phi[col] - phi[col + 1])[:, None, None] * s[None, None, :]
    dots = (n[:, 0, None, None] * np.sin(t) * np.cos(p) + n[:, 1, None, None] * np.sin(t)
            * np.sin(p) + n[:, 2, None, None] * np.cos(t))
    assert (lo <= dots.min(axis=(1, 2)) + 1e-12).all() and (hi >= dots.max(axis=(1, 2)) - 1e-12).all()
    assert (lo > 0).sum() > 50 and (hi < 0).sum() > 50 and ((lo < 0) & (hi > 0)).sum() > 3
    pixels = np.random.default_rng(8).random((height, width, 3))
    normals = spread_normals(60)
    quick = reference_irradiance(pixels, normals)
    monkeypatch.setattr(irradiance_module, "SIGN_MARGIN", np.inf)  # every one to the kernel
    np.testing.assert_allclose(quick, reference_irradiance(pixels, normals), rtol=1e-13)
