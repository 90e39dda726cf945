"""Whole-factor box downsampling and its bound on the change of eq. 1's irradiance."""

import numpy as np
import pytest

from sh_lighting.core.downsample import block_downsample, whole_factor
from sh_lighting.core.equirect import texel_solid_angles
from sh_lighting.core.irradiance import bounded_error_estimate, reference_irradiance
from sh_lighting.core.projection import project_equirect
from sh_lighting.core.sh import spread_normals


def sky(height, width, seed=0):
    """A rough map: noise times a smooth gradient, one bright 2x2 spot, RGBA float32."""
    rng = np.random.default_rng(seed)
    px = rng.random((height, width, 4), dtype=np.float32) * np.linspace(0.2, 2.0, width,
                                                                      dtype=np.float32)[:, None]
    px[height // 3 : height // 3 + 2, width // 5 : width // 5 + 2, :3] = 500.0
    return px


def test_whole_factor_divides_and_reaches_the_target():
    assert whole_factor(4096, 8192, 512) == 16
    assert whole_factor(4000, 8000, 512) == 16  # 500 wide
    assert whole_factor(512, 1024, 1024) == 1
    assert whole_factor(1000, 2000, 512) == 4  # 500 wide
    assert whole_factor(3, 7, 2) == 1  # no common divisor: kept as it is


def test_the_power_is_kept_and_a_blockwise_constant_map_is_unchanged():
    px = sky(64, 128)
    small, bound = block_downsample(px, 4, with_bound=True)
    assert small.shape == (16, 32, 3) and bound.shape == (3,) and (bound > 0).all()
    power = (px[..., :3] * texel_solid_angles(64, 128)[:, None, None]).sum(axis=(0, 1))
    small_power = (small * texel_solid_angles(16, 32)[:, None, None]).sum(axis=(0, 1))
    np.testing.assert_allclose(small_power, power, rtol=1e-6)
    blocky = np.repeat(np.repeat(small, 4, axis=0), 4, axis=1).astype(np.float32)
    again, zero = block_downsample(blocky, 4, with_bound=True)
    np.testing.assert_allclose(again, small, rtol=1e-6)
    assert zero.max() < 1e-6 * bound.min()


@pytest.mark.parametrize("flip", [False, True])
def test_the_irradiance_changes_by_no_more_than_the_bound(flip):
    px = sky(96, 192, seed=3)
    px = px[::-1] if flip else px  # Blender's readback is a flipped view
    n = spread_normals(64)
    exact = reference_irradiance(px, n)
    bounds = []
    for factor in (2, 4, 8):
        small, bound = block_downsample(px, factor, with_bound=True)
        change = np.abs(reference_irradiance(small, n) - exact).max(axis=0)
        assert (change <= bound).all() and change.max() > 0.0
        bounds.append(bound.max())
    assert bounds[0] < bounds[1] < bounds[2]  # larger blocks: larger diameters and spreads


def test_the_estimate_of_a_wide_map_is_within_its_bound_of_the_full_resolution_one():
    px = sky(128, 256, seed=5)
    coeffs = project_equirect(px)
    full = bounded_error_estimate(px, coeffs, 128, reference_width=None)
    small = bounded_error_estimate(px, coeffs, 128, reference_width=64)
    assert full["bound"] == 0.0 and full["reference_size"] == (128, 256)
    assert small["reference_size"] == (32, 64) and 0.0 < small["bound"] < 0.2
    assert abs(small["mean"] - full["mean"]) <= small["bound"]
    assert abs(small["max"] - full["max"]) <= small["bound"]


@pytest.mark.parametrize("factor", [2, 3, 8])
def test_the_bound_is_the_sum_of_the_module_docstring_in_float64(factor):
    """block_downsample sums Σ_B d_B Σ_t Ω_t |L_t − L̄_B| in float32 row blocks (a product of
    the row weights by the deviations); the same sum written out in float64 agrees."""
    px = sky(48, 96, seed=11)[::-1]
    small, bound = block_downsample(px, factor, with_bound=True)
    k, (h, w) = factor, px.shape[:2]
    solid = texel_solid_angles(h, w)
    edges = np.linspace(0.0, np.pi, h // k + 1)
    widest = np.maximum(np.sin(edges[:-1]), np.sin(edges[1:]))
    widest = np.where((edges[:-1] <= 0.5 * np.pi) & (edges[1:] >= 0.5 * np.pi), 1.0, widest)
    diameter = np.minimum(np.pi, np.pi / (h // k) + widest * min(2.0 * np.pi * k / w, np.pi))
    blocks = px[..., :3].astype(np.float64).reshape(h // k, k, w // k, k, 3)
    omega = solid.reshape(h // k, k)[:, :, None, None, None]
    mean = (blocks * omega).sum(axis=(1, 3)) / (solid.reshape(h // k, k).sum(axis=1) * k)[:, None, None]
    np.testing.assert_allclose(small, mean, rtol=1e-6)
    spread = (omega * np.abs(blocks - mean[:, None, :, None])).sum(axis=(1, 2, 3))
    np.testing.assert_allclose(bound, (diameter[:, None] * spread).sum(axis=0), rtol=1e-5)


@pytest.mark.parametrize("threads", [1, 3])
def test_the_threads_change_neither_the_map_nor_its_reference(monkeypatch, threads):
    """block_downsample shares block rows and reference_irradiance normals between threads:
    the map and bound are the same bit for bit, E the same to rounding."""
    import importlib

    from sh_lighting.core import downsample, projection

    irradiance = importlib.import_module("sh_lighting.core.irradiance")  # not the function
    px = sky(96, 192, seed=2)
    n = spread_normals(100)
    monkeypatch.setattr(downsample, "THREADED_TEXELS", 1 << 40)
    monkeypatch.setattr(irradiance, "THREADED_PAIRS", 1 << 40)
    small, bound = block_downsample(px, 3, with_bound=True)
    exact = reference_irradiance(small, n)
    monkeypatch.setattr(downsample, "THREADED_TEXELS", 1)
    monkeypatch.setattr(irradiance, "THREADED_PAIRS", 1)
    monkeypatch.setattr(irradiance, "NORMALS_PER_THREAD", 8)
    monkeypatch.setattr(projection, "MAX_THREADS", threads)
    monkeypatch.setattr(projection.os, "sched_getaffinity", lambda _pid: range(threads))
    again, same_bound = block_downsample(px, 3, with_bound=True)
    assert np.array_equal(again, small) and np.array_equal(same_bound, bound)
    np.testing.assert_allclose(reference_irradiance(small, n), exact, rtol=1e-14)
