"""The polar diagram: curves where the intensity puts them, the fit's apart from the file's."""

import numpy as np
import pytest

from sh_lighting.core.polar_plot import COLOURS, GAMMA, polar_curves, polar_image


def _pixel(image, gamma_deg, r, right=True):
    size = image.shape[0]
    g = np.radians(gamma_deg)
    x = 0.5 * size + (1 if right else -1) * 0.46 * size * r * np.sin(g)
    y = 0.5 * size + 0.46 * size * r * np.cos(g)
    return image[int(y), int(x), :3]


def test_curves_sample_the_planes():
    curves = polar_curves(lambda d: 10.0 + 5.0 * d[..., 0] + 2.0 * d[..., 1])
    assert curves.shape == (2, 2, GAMMA.size)
    assert curves[0, 0, 90] == pytest.approx(15.0)  # C0 at γ 90°: +X
    assert curves[0, 1, 90] == pytest.approx(5.0)  # C180: −X
    assert curves[1, 0, 90] == pytest.approx(12.0) and curves[1, 1, 90] == pytest.approx(8.0)
    assert curves[0, 0, 0] == pytest.approx(10.0)  # the nadir in every plane


def test_measured_and_fitted_drawn_where_they_are():
    """A downlight I = cos γ (a circle through the centre) against a fit at 60 %."""
    measured = polar_curves(lambda d: np.clip(-d[..., 2], 0.0, None))
    image = polar_image(measured, 0.6 * measured, size=128)
    assert image.shape == (128, 128, 4) and (image[..., 3] == 1).all()
    for gamma in (0.0, 30.0, 60.0):
        r = np.cos(np.radians(gamma))
        on_file = _pixel(image, gamma, r)
        assert np.allclose(on_file, COLOURS[1]) or np.allclose(on_file, COLOURS[0])
        on_fit = _pixel(image, gamma, 0.6 * r, right=False)
        assert on_fit.min() > 0.55  # light: the fit's thin line
    assert not np.allclose(_pixel(image, 150.0, 0.5), COLOURS[0])  # nothing upward


@pytest.mark.parametrize("bad", [np.zeros((2, 2, 5)), np.full((2, 2, GAMMA.size), np.nan)])
def test_bad_curves_refused(bad):
    with pytest.raises(ValueError, match="polar curves"):
        polar_image(bad, bad)
