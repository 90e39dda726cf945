"""The pure helpers of `python -m benchmarks.report` (irradiance-map lookup, mips, stats)."""

from math import pi, sqrt

import numpy as np
import pytest

from benchmarks.report_helpers import (
    build_irradiance_map,
    downsample2,
    error_stats,
    fibonacci_normals,
    irradiance_map_shape,
    lookup_bilinear,
    power_law_samples,
    samples_to_reach,
    synthetic_map,
)
from sh_lighting.core import project_equirect, texel_directions, uv_to_direction
from sh_lighting.core.equirect import texel_solid_angles


def test_fibonacci_normals_are_unit_and_balanced():
    n = fibonacci_normals(1000)
    assert n.shape == (1000, 3)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0)
    assert np.abs(n.mean(axis=0)).max() < 2e-3


def test_map_shapes_match_the_stated_sizes():
    assert [irradiance_map_shape(s * s) for s in (16, 32, 64)] == [(11, 22), (23, 46), (45, 90)]


def test_lookup_hits_texel_centres_and_wraps_longitude():
    rng = np.random.default_rng(1)
    emap = rng.random((5, 8, 3))
    centres = texel_directions(5, 8).reshape(-1, 3)
    assert np.allclose(lookup_bilinear(emap, centres), emap.reshape(-1, 3))
    # halfway between the last and the first column (u = 0 seam) of row 2
    d = uv_to_direction(np.array([0.0]), np.array([1.0 - 2.5 / 5]))
    assert np.allclose(lookup_bilinear(emap, d)[0], 0.5 * (emap[2, 7] + emap[2, 0]))
    # above the first row's centre (near the pole): clamped to row 0
    d = uv_to_direction(np.array([0.5 / 8]), np.array([0.99]))
    assert np.allclose(lookup_bilinear(emap, d)[0], emap[0, 0])


def test_lookup_is_exact_for_a_map_linear_in_v():
    emap = np.repeat(np.linspace(0.0, 1.0, 6)[:, None, None], 12, axis=1) * np.ones(3)
    u, v = np.array([0.13, 0.77]), np.array([0.4, 0.61])  # inside the row-centre range
    got = lookup_bilinear(emap, uv_to_direction(u, v))
    expected = ((1.0 - v) * 6 - 0.5) / 5
    assert np.allclose(got, expected[:, None])


def test_irradiance_map_of_constant_sky_is_pi():
    emap = build_irradiance_map(np.ones((64, 128, 3)), 3, 6)
    assert np.allclose(emap, pi, rtol=1e-3)  # texel-centre cosines: not exact


@pytest.mark.parametrize("weighting", ["texel", "solid_angle"])
def test_downsample2_averages_blocks(weighting):
    rng = np.random.default_rng(2)
    pixels = rng.random((8, 16, 4)).astype(np.float32)
    level = downsample2(pixels, weighting)
    assert level.shape == (4, 8, 3) and level.dtype == np.float64
    block = pixels[2:4, 6:8, :3].astype(np.float64)
    if weighting == "texel":
        assert np.allclose(level[1, 3], block.mean(axis=(0, 1)))
    else:
        omega = texel_solid_angles(8, 16)
        total = (omega[2:4, None, None] * block).sum(axis=(0, 1))
        assert np.allclose(level[1, 3], total / (2.0 * omega[2:4].sum()))
        # ∫ L dω, hence L00, is kept exactly by the solid-angle weighting
        assert np.allclose(project_equirect(level)[0], project_equirect(pixels)[0])


def test_error_stats_fractions_and_relative_floor():
    ref = np.array([[1.0, 2.0, 4.0], [0.001, 2.0, 4.0]])
    est = ref + np.array([[0.1, 0.0, 0.0], [0.1, 0.0, 0.0]])
    stats = error_stats(est, ref, np.array([10.0, 10.0, 10.0]))
    assert stats["max"] == pytest.approx(0.01)
    assert stats["mean"] == pytest.approx(0.2 / 6 / 10)
    assert stats["rel_max"] == pytest.approx(0.1)  # the 0.001 value is below the 1 % floor
    assert stats["rel_excluded"] == pytest.approx(1 / 6)


@pytest.mark.parametrize("name", ["sun", "points", "step", "constant"])
def test_synthetic_maps_keep_their_power_at_any_resolution(name):
    small, large = (project_equirect(synthetic_map(name, h, 2 * h))[0] for h in (128, 256))
    assert np.allclose(small, large, rtol=0.02)
    if name == "constant":
        assert np.allclose(small, 2.0 * sqrt(pi))


def test_samples_to_reach_and_power_law():
    samples, errors = [1, 4, 16, 64], [0.8, 0.4, 0.2, 0.1]
    assert samples_to_reach(samples, errors, 0.25) == 16
    assert samples_to_reach(samples, errors, 0.01) is None
    needed, slope = power_law_samples(samples, errors, 0.05)
    assert slope == pytest.approx(0.5) and needed == pytest.approx(256.0)
