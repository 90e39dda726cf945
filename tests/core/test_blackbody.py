"""The blackbody colour: Blender's piecewise fit, continuous, white near D65, hostile input."""

import numpy as np
import pytest

from sh_lighting.core.blackbody import ABOVE, BELOW, KNOTS, blackbody_rgb


def test_continuous_at_the_knots_and_the_ends():
    for knot in KNOTS:
        jump = np.abs(blackbody_rgb(knot) - blackbody_rgb(knot - 1e-6)).max()
        assert jump < 2e-3, knot  # the fit's pieces meet to its own error
    assert blackbody_rgb(12000.0) == pytest.approx(ABOVE)
    assert blackbody_rgb(11999.999) == pytest.approx(ABOVE, abs=2e-3)
    assert blackbody_rgb(500.0) == pytest.approx(np.maximum(BELOW, 0.0))


def test_warm_to_cold_and_white_near_6500():
    kelvin = np.linspace(1000.0, 12000.0, 200)
    rgb = blackbody_rgb(kelvin)
    assert rgb.shape == (200, 3) and (rgb >= 0).all()
    ratio = rgb[:, 2] / np.maximum(rgb[:, 0], 1e-9)
    assert (np.diff(ratio) >= 0).all()  # bluer as it gets hotter
    assert blackbody_rgb(6500.0) == pytest.approx([1.0, 1.0, 1.0], abs=0.05)
    assert blackbody_rgb(2700.0)[0] > 1.5 * blackbody_rgb(2700.0)[2] + 1.0  # incandescent


@pytest.mark.parametrize("bad", [float("nan"), float("inf")])
def test_not_finite_is_one_clear_error(bad):
    with pytest.raises(ValueError, match="finite number of kelvin"):
        blackbody_rgb(bad)
