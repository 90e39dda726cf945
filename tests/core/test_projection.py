"""project_equirect: exact for the piecewise-constant image (eq. 10)."""

from math import pi, sqrt
import tracemalloc

import numpy as np
import pytest
from quadrature import texel_integral

from sh_lighting.core import projection
from sh_lighting.core.projection import project_equirect
from sh_lighting.core.rotation import rotate_coefficients
from sh_lighting.core.sh import sh_basis

ROUNDING = 1e-12  # relative to the largest coefficient: exact up to float64 rounding


def rel_err(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


@pytest.mark.parametrize("shape", [(1, 2), (2, 4), (3, 5), (4, 8), (7, 3), (64, 128), (512, 1024)])
@pytest.mark.parametrize("order", [2, 4])
def test_constant_map_gives_only_l00(shape, order):
    c = np.array([0.25, 1.0, 3.5])
    coeffs = project_equirect(np.broadcast_to(c, shape + (3,)), order)
    assert np.abs(coeffs[0] / (2.0 * sqrt(pi) * c) - 1.0).max() < ROUNDING
    assert np.abs(coeffs[1:]).max() < ROUNDING * coeffs[0].max()


@pytest.mark.parametrize("shape", [(2, 4), (5, 9), (32, 64)])
def test_equals_independent_texel_quadrature(shape):
    rng = np.random.default_rng(3)
    pixels = rng.random(shape + (3,)) - 0.2
    expected = texel_integral(pixels, lambda d: sh_basis(d, 4))
    assert rel_err(project_equirect(pixels, 4), expected) < ROUNDING


@pytest.mark.parametrize("factor", [(2, 2), (3, 1), (1, 5)])
def test_upsampling_by_replication_changes_nothing(factor):
    rng = np.random.default_rng(4)
    pixels = rng.random((16, 32, 4)).astype(np.float32)
    big = np.repeat(np.repeat(pixels, factor[0], axis=0), factor[1], axis=1)
    assert rel_err(project_equirect(big, 4), project_equirect(pixels, 4)) < ROUNDING


@pytest.mark.parametrize("dtype", [np.float16, np.float32, np.float64])
def test_accumulates_in_float64_for_every_dtype(dtype):
    """Low-precision input gives the float64 result of its own values, not a low-precision sum."""
    rng = np.random.default_rng(5)
    pixels = (rng.random((256, 512, 4)) * 100).astype(dtype)
    result = project_equirect(pixels)
    assert result.dtype == np.float64
    assert rel_err(result, project_equirect(pixels.astype(np.float64))) < ROUNDING


def test_alpha_is_ignored_and_negative_texels_are_kept():
    rng = np.random.default_rng(6)
    rgb = rng.normal(size=(8, 16, 3))
    rgba = np.concatenate([rgb, rng.random((8, 16, 1))], axis=-1)
    assert rel_err(project_equirect(rgba), project_equirect(rgb)) < ROUNDING
    # negative texels are data: projection is linear in them
    assert rel_err(project_equirect(-rgb), -project_equirect(rgb)) < ROUNDING


@pytest.mark.parametrize("shift", [1, 5, 13])
def test_rolling_columns_rotates_about_z(shift):
    """Rolling k columns is the lighting rotated by α = -2πk/W about z (φ = π - 2πu)."""
    rng = np.random.default_rng(7)
    pixels = rng.random((12, 24, 3))
    before = project_equirect(pixels)
    after = project_equirect(np.roll(pixels, shift, axis=1))
    for l in range(3):
        band = slice(l * l, (l + 1) ** 2)
        energy = (before[band] ** 2).sum(axis=0)
        assert np.abs((after[band] ** 2).sum(axis=0) - energy).max() < ROUNDING * energy.max()
    alpha = -2.0 * pi * shift / 24
    rz = np.array([[np.cos(alpha), -np.sin(alpha), 0], [np.sin(alpha), np.cos(alpha), 0], [0, 0, 1]])
    moment = before[[3, 1, 2]]  # (L11, L1-1, L10) is the (x, y, z) moment
    assert rel_err(after[[3, 1, 2]], rz @ moment) < ROUNDING
    assert rel_err(after, rotate_coefficients(before, rz)) < ROUNDING


def test_pixel_centre_sampling_would_not_be_exact():
    """Guard: the exact row weights differ from 'Y at the centre × solid angle' on a coarse map."""
    from sh_lighting.core.equirect import texel_directions, texel_solid_angles

    pixels = np.random.default_rng(8).random((4, 8, 3))
    naive = np.einsum(
        "hwk,hwc,h->kc", sh_basis(texel_directions(4, 8)), pixels, texel_solid_angles(4, 8)
    )
    assert rel_err(naive, project_equirect(pixels)) > 1e-3


@pytest.mark.parametrize(
    "pixels, message",
    [
        (np.zeros((4, 8)), "shape"),
        (np.zeros((4, 8, 2)), "shape"),
        (np.zeros((0, 8, 3)), "zero size"),
        (np.zeros((4, 8, 3), dtype=np.uint8), "float"),
        (np.zeros((4, 8, 3), dtype=np.int32), "float"),
    ],
)
def test_bad_input_is_a_clear_value_error(pixels, message):
    with pytest.raises(ValueError, match=message):
        project_equirect(pixels)


def test_non_finite_texels_are_reported_or_zeroed():
    pixels = np.ones((8, 16, 4), dtype=np.float32)
    pixels[2, 3, 0] = np.nan
    pixels[5, 7, 2] = np.inf
    pixels[6, 1, 3] = np.nan  # alpha: ignored
    with pytest.raises(ValueError, match=r"2 non-finite .*row 2, column 3.*row 5, column 7"):
        project_equirect(pixels)
    cleaned = pixels.copy()
    cleaned[~np.isfinite(cleaned)] = 0.0
    assert np.array_equal(project_equirect(pixels, nonfinite="zero"), project_equirect(cleaned))


@pytest.mark.slow
def test_memory_stays_bounded_on_a_16k_map():
    """16384×8192 float32 RGBA (2 GiB of input) needs far less than 1 GB beyond the input."""
    pixels = np.empty((8192, 16384, 4), dtype=np.float32)
    pixels[...] = 0.5
    tracemalloc.start()
    try:
        coeffs = project_equirect(pixels)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 1 << 30, f"peak extra memory {peak / 2**20:.0f} MiB"
    # By design one float64 block of rows per thread (measured 50 MiB on 2 cores).
    block = projection.ROWS_PER_BLOCK * 3 * 16384 * 8
    assert peak < projection.thread_count(8192) * block + (16 << 20)
    assert coeffs[0] == pytest.approx(2.0 * sqrt(pi) * 0.5, rel=1e-12)
    assert np.abs(coeffs[1:]).max() < ROUNDING


@pytest.mark.parametrize("height", [1, 2, 3, 17, 256, 4096])
@pytest.mark.parametrize("order", [2, 4, 6])
def test_row_weights_equal_the_closed_form_antiderivative(height, order):
    """Gauss-Legendre rows against the exact Fourier antiderivative (accurate away from poles)."""
    from sh_lighting.core.projection import row_weights, row_weights_closed_form

    fast, exact = row_weights(height, order), row_weights_closed_form(height, order)
    assert np.abs(fast - exact).max() < 1e-14 * np.abs(exact).max()


@pytest.mark.parametrize("threads", [1, 3, 8])
@pytest.mark.parametrize("shape", [(517, 4096), (300, 8192), (257, 96)])
def test_result_does_not_depend_on_how_rows_are_shared(monkeypatch, threads, shape):
    """Bands of rows per thread, rows per product and the ragged last block change nothing."""
    rng = np.random.default_rng(sum(shape))
    pixels = rng.random((*shape, 4), dtype=np.float32) * 10.0
    baseline = project_equirect(pixels, max_order=4)
    monkeypatch.setattr(projection, "MAX_THREADS", threads)
    monkeypatch.setattr(projection.os, "sched_getaffinity", lambda _pid: range(threads))
    assert rel_err(project_equirect(pixels, max_order=4), baseline) < ROUNDING


def test_the_projection_of_a_few_texels_is_that_of_the_map_holding_them():
    """project_texels: the exact texel integrals of a map zero but at N texels (repeats add),
    the same as project_equirect of that map to rounding (lights.extract_lights' update)."""
    from sh_lighting.core.projection import project_texels

    rng = np.random.default_rng(4)
    height, width = 48, 96
    rows, columns = rng.integers(0, height, 80), rng.integers(0, width, 80)
    rows[:3], columns[:3] = 0, width - 1  # the pole row and the last column, three times
    values = rng.normal(size=(80, 3)) * 50.0
    dense = np.zeros((height, width, 3))
    np.add.at(dense, (rows, columns), values)
    for order in (2, 4):
        full = project_equirect(dense, max_order=order)
        few = project_texels(values, rows, columns, height, width, max_order=order)
        np.testing.assert_allclose(few, full, rtol=0, atol=1e-13 * np.abs(full).max())
