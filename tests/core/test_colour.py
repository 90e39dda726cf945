"""core.colour: the sRGB curve, the working spaces' matrices and luminance, byte decoding."""

import numpy as np
import pytest

from sh_lighting.core import colour
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


# -- working spaces: published matrices (independent of the primaries-based derivation) -----

# ITU-R BT.2087-0 (Rec.709 -> Rec.2020, 4 decimals) and the ACES documentation's linear
# Rec.709 -> ACEScg matrix with Bradford adaptation (4 decimals).
BT2087 = [[0.6274, 0.3293, 0.0433], [0.0691, 0.9195, 0.0114], [0.0164, 0.0880, 0.8956]]
REC709_TO_ACESCG = [[0.6131, 0.3395, 0.0474], [0.0702, 0.9164, 0.0134],
                    [0.0206, 0.1096, 0.8698]]


def test_conversion_matrices_match_published_ones():
    m = colour.conversion_matrix("Linear Rec.709", "Linear Rec.2020")
    assert np.abs(m - BT2087).max() < 1e-4
    m = colour.conversion_matrix("Linear Rec.709", "ACEScg")
    assert np.abs(m - REC709_TO_ACESCG).max() < 1e-4


def test_luminance_weights():
    assert np.abs(colour.luminance_weights() - [0.2126, 0.7152, 0.0722]).max() < 5e-5
    for space in colour.WORKING_SPACES:
        assert abs(colour.luminance_weights(space).sum() - 1.0) < 1e-12


def test_conversions_keep_white_and_invert():
    rng = np.random.default_rng(0)
    coeffs = rng.normal(size=(9, 3))
    for space in colour.WORKING_SPACES:
        there = colour.convert_coefficients(coeffs, "Linear Rec.709", space)
        back = colour.convert_coefficients(there, space, "Linear Rec.709")
        assert np.abs(back - coeffs).max() < 1e-12
        white = colour.convert_coefficients(np.ones(3), "Linear Rec.709", space)
        assert np.abs(white - 1.0).max() < 1e-12
    same = colour.convert_coefficients(coeffs, "ACEScg", "ACEScg")
    assert np.array_equal(same, coeffs) and same is not coeffs
    with pytest.raises(ValueError, match="unknown working colour space"):
        colour.convert_coefficients(coeffs, "Rec.709", "ACEScg")
    with pytest.raises(ValueError, match=r"\(\.\.\., 3\)"):
        colour.convert_coefficients(np.ones((9, 4)), "ACEScg", "Linear Rec.709")


def test_byte_decoding_is_the_curve_then_the_primaries_matrix():
    codes = np.random.default_rng(1).integers(0, 256, (4, 5, 3)).astype(np.uint8)
    curve, matrix = colour.byte_decoding("sRGB", "Linear Rec.709")
    assert matrix is None and curve.dtype == np.float32 and curve.shape == (256,)
    decoded = colour.decode_bytes(codes, curve, matrix)
    assert decoded.dtype == np.float32
    assert np.abs(decoded - srgb_to_linear(codes / 255.0)).max() < 1e-7
    acescg = colour.decode_bytes(codes, *colour.byte_decoding("sRGB", "ACEScg"))
    expected = srgb_to_linear(codes / 255.0) @ np.array(REC709_TO_ACESCG).T
    assert acescg.dtype == np.float32 and np.abs(acescg - expected).max() < 1e-4
    linear = colour.decode_bytes(codes, *colour.byte_decoding("ACEScg", "ACEScg"))
    assert np.abs(linear - codes / 255.0).max() < 1e-7
    with pytest.raises(ValueError, match="not decoded here"):
        colour.byte_decoding("Display P3", "ACEScg")
