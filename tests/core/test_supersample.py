"""Refining hot texels of a capture: finding them and averaging a finer render back."""

import numpy as np
import pytest

from sh_lighting.core.projection import project_equirect
from sh_lighting.core.supersample import average_fine_rows, hot_region


def test_smooth_map_has_no_hot_region():
    rng = np.random.default_rng(1)
    assert hot_region(1.0 + rng.random((64, 128, 3))) is None
    assert hot_region(np.zeros((8, 16, 3))) is None


def test_one_hot_texel_and_its_margin():
    pixels = np.ones((64, 128, 4))
    pixels[20, 50, 1] = 1e5
    assert hot_region(pixels) == (19, 22, 49, 3)
    assert hot_region(pixels, margin=0) == (20, 21, 50, 1)


def test_hot_region_wraps_across_the_seam_and_stops_at_the_poles():
    pixels = np.ones((64, 128, 3))
    pixels[0, 127] = pixels[1, 0] = pixels[0, 2] = 1e5
    assert hot_region(pixels) == (0, 3, 126, 6)  # columns 126, 127, 0, 1, 2, 3


def test_replicated_map_averages_back_exactly():
    rng = np.random.default_rng(2)
    coarse = rng.random((16, 32, 4))
    fine = np.repeat(np.repeat(coarse, 4, axis=0), 4, axis=1)
    assert np.allclose(average_fine_rows(fine, 4, 0, 16), coarse, rtol=1e-14, atol=0.0)
    assert np.allclose(average_fine_rows(fine[8:20, 12:24], 4, 2, 16), coarse[2:5, 3:6])


def test_averaging_keeps_each_texels_light_so_l00_is_unchanged():
    """Solid-angle weights: Σ value·dΩ over every coarse texel is kept, hence L00 exactly."""
    rng = np.random.default_rng(3)
    fine = rng.random((64, 128, 3)) * 10.0
    coarse = average_fine_rows(fine, 8, 0, 8)
    assert abs(project_equirect(coarse)[0] / project_equirect(fine)[0] - 1.0).max() < 1e-13


def test_shapes_are_checked():
    with pytest.raises(ValueError, match="multiple"):
        average_fine_rows(np.ones((6, 8, 3)), 4, 0, 4)
    with pytest.raises(ValueError, match="outside"):
        average_fine_rows(np.ones((8, 8, 3)), 4, 3, 4)
