"""The sRGB decoding used for 8-bit sRGB world images."""

import numpy as np

from sh_lighting.core.colour import srgb_to_linear


def encode(linear):
    """The sRGB encoding (IEC 61966-2-1), written independently as the inverse."""
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1 / 2.4) - 0.055)


def test_known_values():
    assert srgb_to_linear(0.0) == 0.0
    assert abs(srgb_to_linear(1.0) - 1.0) < 1e-15
    assert abs(srgb_to_linear(0.5) - 0.21404114048223255) < 1e-15
    assert abs(srgb_to_linear(128 / 255) - 0.21586050011389926) < 1e-15
    assert abs(srgb_to_linear(0.04045) - 0.04045 / 12.92) < 1e-15


def test_inverse_of_the_encoding_on_every_byte():
    linear = srgb_to_linear(np.arange(256) / 255.0)
    assert np.abs(encode(linear) - np.arange(256) / 255.0).max() < 1e-12
    assert (np.diff(linear) > 0).all()


def test_continuous_at_the_knee_and_odd():
    below, above = srgb_to_linear(np.array([0.04045 - 1e-12, 0.04045 + 1e-12]))
    assert abs(above - below) < 1e-8  # the standard's two pieces meet only to ~2e-9
    v = np.linspace(-2.0, 2.0, 41)
    assert np.array_equal(srgb_to_linear(-v), -srgb_to_linear(v))
    assert srgb_to_linear(np.ones((2, 3, 3), dtype=np.float32)).dtype == np.float64
