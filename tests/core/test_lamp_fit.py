"""The lamp fit: exact on distributions native lamps make, honest errors on others."""

import numpy as np
import pytest

from sh_lighting.core.lamp_fit import (
    Lamp,
    fit_lamps,
    lamp_intensity,
    plane_illuminance_error,
    sphere_samples,
    spot_mask,
    wall_illuminance_error,
)


def test_spot_mask_matches_blender_formula():
    """Inside the inner cone 1, outside the cone 0, smoothstep between (Cycles' formula)."""
    half, blend = np.radians(30.0), 0.5
    angles = np.radians([0.0, 10.0, 29.9, 30.1])
    dirs = np.stack([np.sin(angles), 0 * angles, -np.cos(angles)], axis=-1)
    mask = spot_mask(dirs, (0, 0, -1.0), half, blend)
    x = (np.cos(angles) - np.cos(half)) / ((1 - np.cos(half)) * blend)
    x = np.clip(x, 0, 1)
    assert mask == pytest.approx(x * x * (3 - 2 * x))
    assert mask[0] == 1.0 and mask[-1] == 0.0


def test_isotropic_is_one_point_light():
    fit = fit_lamps(lambda d: np.full(d.shape[:-1], 250.0))
    assert len(fit.lamps) == 1 and fit.lamps[0].kind == "POINT"
    assert fit.lamps[0].candela == pytest.approx(250.0) and fit.intensity_error < 1e-6


def test_two_native_spots_are_found_again():
    truth = (Lamp("SPOT", (0.0, 0.0, -1.0), np.radians(30.0), 0.4, 1000.0),
             Lamp("SPOT", (0.0, 0.0, -1.0), np.radians(66.0), 1.0, 200.0))
    fit = fit_lamps(lambda d: lamp_intensity(truth, d))
    assert len(fit.lamps) <= 3 and fit.intensity_error < 0.01
    dirs, weights = sphere_samples(90, 180)
    flux = np.sum(weights * lamp_intensity(truth, dirs))
    assert np.sum(weights * lamp_intensity(fit.lamps, dirs)) == pytest.approx(flux, rel=0.01)


def test_dark_gives_no_lamps_and_bad_input_is_refused():
    assert fit_lamps(lambda d: np.zeros(d.shape[:-1])).lamps == ()
    with pytest.raises(ValueError, match="non-negative"):
        fit_lamps(lambda d: np.full(d.shape[:-1], -1.0))
    with pytest.raises(ValueError, match="max_lamps"):
        fit_lamps(lambda d: np.ones(d.shape[:-1]), max_lamps=0)


def test_more_lamps_never_worse_and_cap_holds():
    """A beam plus a sideways lobe: the error falls with the lamp budget, never above 8."""
    def beam(d):
        side = np.array([np.sin(0.8), 0.0, -np.cos(0.8)])
        return 800 * np.exp(-((d[..., 2] + 1) * 30)) + 300 * np.clip(d @ side, 0, 1) ** 8
    one = fit_lamps(beam, max_lamps=1, error_target=0.0)
    eight = fit_lamps(beam, max_lamps=8, error_target=0.0)
    assert len(one.lamps) == 1 and 2 <= len(eight.lamps) <= 8
    assert eight.intensity_error < 0.5 * one.intensity_error


def test_plane_error_zero_for_itself_and_positive_otherwise():
    lamps = (Lamp("SPOT", (0.0, 0.0, -1.0), np.radians(40.0), 0.5, 100.0),)
    assert plane_illuminance_error(lambda d: lamp_intensity(lamps, d), lamps) == 0.0
    assert plane_illuminance_error(lambda d: 1.1 * lamp_intensity(lamps, d), lamps) == \
        pytest.approx(0.1 / 1.1)


def test_wall_error_is_the_worst_wall():
    """A spot tilted toward +X lights the +X wall most; a fit missing a side lamp toward −X
    shows that wall's whole error, not the mean; a dark wall counts for nothing."""
    tilted = (Lamp("SPOT", (0.6, 0.0, -0.8), np.radians(50.0), 0.5, 100.0),)
    side = (Lamp("SPOT", (-0.8, 0.0, -0.6), np.radians(20.0), 0.3, 30.0),)
    exact = tilted + side
    assert wall_illuminance_error(lambda d: lamp_intensity(exact, d), exact, 2.0) == 0.0
    missing = wall_illuminance_error(lambda d: lamp_intensity(exact, d), tilted, 2.0)
    assert missing > 0.5  # the −X wall's light is mostly the side lamp's
    down = (Lamp("SPOT", (0.0, 0.0, -1.0), np.radians(10.0), 0.1, 100.0),)
    assert wall_illuminance_error(lambda d: lamp_intensity(down, d), down, 2.0) == 0.0


def test_elliptical_spot_mask_stretches_the_cone():
    """Scale (2, 1) widens the cone along the spot's X only: tan of the edge doubles."""
    half = np.radians(20.0)
    axis, x_axis = (0.0, 0.0, -1.0), (1.0, 0.0, 0.0)
    edge_x = np.arctan(2 * np.tan(half))
    along_x = np.array([[np.sin(a), 0.0, -np.cos(a)] for a in (edge_x - 0.01, edge_x + 0.01)])
    along_y = np.array([[0.0, np.sin(a), -np.cos(a)] for a in (half - 0.01, half + 0.01)])
    mask_x = spot_mask(along_x, axis, half, 0.01, x_axis, (2.0, 1.0))
    mask_y = spot_mask(along_y, axis, half, 0.01, x_axis, (2.0, 1.0))
    assert mask_x[0] == 1.0 and mask_x[1] == 0.0 and mask_y[0] == 1.0 and mask_y[1] == 0.0

