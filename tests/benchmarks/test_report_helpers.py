"""The pure helpers of `python -m benchmarks.report` (irradiance-map lookup, mips, stats)."""

from math import floor, pi, sqrt

import numpy as np
import pytest

from benchmarks import report_helpers
from benchmarks.report_helpers import (
    SUN,
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
def test_downsample2_averages_blocks(weighting, monkeypatch):
    # 3 rows per block = 6 input rows: blocks of rows 0–5 and a partial one of rows 6–7
    monkeypatch.setattr(report_helpers, "ROWS_PER_BLOCK", 3)
    rng = np.random.default_rng(2)
    pixels = rng.random((8, 16, 4)).astype(np.float32)
    level = downsample2(pixels, weighting)
    assert level.shape == (4, 8, 3) and level.dtype == np.float64
    block = pixels[2:4, 6:8, :3].astype(np.float64)
    omega = texel_solid_angles(8, 16)
    if weighting == "texel":
        assert np.allclose(level[1, 3], block.mean(axis=(0, 1)))
    else:
        total = (omega[2:4, None, None] * block).sum(axis=(0, 1))
        assert np.allclose(level[1, 3], total / (2.0 * omega[2:4].sum()))
        # ∫ L dω, hence L00, is kept exactly by the solid-angle weighting
        assert np.allclose(project_equirect(level)[0], project_equirect(pixels)[0])
    # every output texel, in every block, against a direct computation
    rgb = pixels[..., :3].astype(np.float64)
    weights = np.ones(8) if weighting == "texel" else omega
    for i in range(4):
        w = weights[2 * i : 2 * i + 2]
        for j in range(8):
            texels = rgb[2 * i : 2 * i + 2, 2 * j : 2 * j + 2]
            expected = (w[:, None, None] * texels).sum(axis=(0, 1)) / (2.0 * w.sum())
            assert np.allclose(level[i, j], expected), (i, j)


def test_error_stats_fractions_and_relative_floor():
    ref = np.array([[1.0, 2.0, 4.0], [0.001, 2.0, 4.0]])
    est = ref + np.array([[0.1, 0.0, 0.0], [0.1, 0.0, 0.0]])
    stats = error_stats(est, ref, np.array([10.0, 10.0, 10.0]))
    assert stats["max"] == pytest.approx(0.01)
    assert stats["mean"] == pytest.approx(0.2 / 6 / 10)
    assert stats["rel_max"] == pytest.approx(0.1)  # the 0.001 value is below the 1 % floor
    assert stats["rel_excluded"] == pytest.approx(1 / 6)
    # |ΔE|/P sorted: 0, 0, 0, 0, 0.01, 0.01 → 95th percentile at rank 4.75 → 0.01
    assert stats["p95"] == pytest.approx(0.01)
    # kept relative errors: 0.1 (1.0 + 0.1), and 0 for the four values of channels 1 and 2
    assert stats["rel_mean"] == pytest.approx(0.1 / 5)
    assert stats["rel_p95"] == pytest.approx(0.8 * 0.1)  # rank 0.95·4 = 3.8: 0 + 0.8·(0.1 − 0)
    assert stats["min"] == pytest.approx(0.101 / 10)  # lowest E/P: 0.001 + 0.1 in channel 0


def _percentile(values, q):
    """The linearly interpolated q-th percentile (numpy's default), written out."""
    ordered = sorted(values)
    rank = q / 100 * (len(ordered) - 1)
    low = floor(rank)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (rank - low) * (ordered[high] - ordered[low])


def test_error_stats_against_an_independent_computation():
    rng = np.random.default_rng(5)
    ref = rng.uniform(0.5, 3.0, (40, 3))
    ref[:4] = [0.001, 0.002, 0.0]  # below 1 % of each channel's maximum: not relative
    est = ref + rng.normal(0.0, 0.2, (40, 3))
    est[7, 1] = -0.3  # the approximation goes negative
    power = np.array([20.0, 25.0, 30.0])
    stats = error_stats(est, ref, power)
    frac = [abs(est[i, c] - ref[i, c]) / power[c] for i in range(40) for c in range(3)]
    rel = [abs(est[i, c] - ref[i, c]) / ref[i, c] for i in range(4, 40) for c in range(3)]
    assert stats["mean"] == pytest.approx(sum(frac) / len(frac))
    assert stats["p95"] == pytest.approx(_percentile(frac, 95))
    assert stats["max"] == pytest.approx(max(frac))
    assert stats["rel_mean"] == pytest.approx(sum(rel) / len(rel))
    assert stats["rel_p95"] == pytest.approx(_percentile(rel, 95))
    assert stats["rel_max"] == pytest.approx(max(rel))
    assert stats["rel_excluded"] == pytest.approx(12 / 120)
    assert stats["min"] == pytest.approx(-0.3 / 25.0)
    assert stats["p95"] < stats["max"] and stats["rel_p95"] < stats["rel_max"]


@pytest.mark.parametrize("name", ["sun", "points", "step", "constant"])
def test_synthetic_maps_keep_their_power_at_any_resolution(name):
    small, large = (project_equirect(synthetic_map(name, h, 2 * h))[0] for h in (128, 256))
    assert np.allclose(small, large, rtol=0.02)
    if name == "constant":
        assert np.allclose(small, 2.0 * sqrt(pi))


def test_sun_map_points_at_the_sun_and_holds_its_share(monkeypatch):
    """600 rows: the row-block loops run 3 times; and again in 5-row blocks, which cut
    through the sun disc, giving the very same map."""
    height, width = 600, 1200
    pixels = synthetic_map("sun", height, width)
    monkeypatch.setattr(report_helpers, "ROWS_PER_BLOCK", 5)
    assert np.array_equal(synthetic_map("sun", height, width), pixels)
    direction, _, sun_power = SUN
    rgb = pixels[..., :3].astype(np.float64)
    omega = texel_solid_angles(height, width)[:, None, None]
    disc = rgb[..., 0] > 1.0  # the sky is at most 0.12 · 1.2
    rows = np.nonzero(disc.any(axis=1))[0]
    assert 1 < len(rows) and rows[0] // 5 != rows[-1] // 5  # the disc spans 5-row blocks
    # the disc holds exactly the sun's power, "~90 %" of the map's (sky: 0.05 … 0.12)
    assert np.allclose((omega * rgb)[disc].sum(axis=0), sun_power, rtol=1e-6)
    coeffs = project_equirect(pixels)
    share = sun_power / (2.0 * sqrt(pi) * coeffs[0])
    assert np.all((share > 0.85) & (share < 0.95)), share
    # l = 1 vector (L11, L1-1, L10) ∝ ∫ L ω dω: the sun's power along its direction plus
    # the sky's ∫ 0.07 max(z, 0) z dω = 0.07 · 2π/3 along +z, per channel
    l1 = coeffs[[3, 1, 2]].T  # (RGB, xyz)
    sky = 0.07 * 2.0 * pi / 3.0 * np.array([0.8, 0.9, 1.2])
    expected = sqrt(3.0 / (4.0 * pi)) * (
        sun_power[:, None] * direction + sky[:, None] * np.array([0.0, 0.0, 1.0])
    )
    assert np.allclose(l1, expected, rtol=0, atol=1e-3 * np.abs(expected).max())
    cosines = l1 @ direction / np.linalg.norm(l1, axis=1)
    assert np.all(cosines > np.cos(np.radians(1.0)))  # within 1° of the sun


def test_samples_to_reach_and_power_law():
    samples, errors = [1, 4, 16, 64], [0.8, 0.4, 0.2, 0.1]
    assert samples_to_reach(samples, errors, 0.25) == 16
    assert samples_to_reach(samples, errors, 0.01) is None
    needed, slope = power_law_samples(samples, errors, 0.05)
    assert slope == pytest.approx(0.5) and needed == pytest.approx(256.0)
