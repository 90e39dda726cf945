"""The one coefficient check (core.coefficients): what scripts, presets and the core may pass."""

import numpy as np
import pytest

from sh_lighting.core.coefficients import FLOAT32_MAX, check_coefficients
from sh_lighting.core.irradiance import irradiance
from sh_lighting.formats.presets import PresetError

GOOD = np.arange(27, dtype=np.float64).reshape(9, 3) / 8.0  # exact in float32 too


def rows_with(i, j, value):
    rows = GOOD.tolist()
    rows[i][j] = value
    return rows


@pytest.mark.parametrize(
    "coeffs, message",
    [
        ("123", r"coefficients are a string, not a list of rows: pass one \[r, g, b\] row"),
        ({"L00": [1, 1, 1]}, r"coefficients are a dict, not a list of rows"),
        (None, r"coefficients are None \(null\), not a list of rows"),
        (3.0, r"coefficients are float, not a list of rows"),
        ([["1", "2", "3"]] * 9, r"coefficient L00 channel R is a string \('1'\), not a number"),
        (rows_with(2, 1, True), r"coefficient L10 channel G is a boolean \(True\), not a number"),
        (rows_with(4, 2, 1 + 2j), r"coefficient L2-2 channel B is a complex number"),
        (rows_with(0, 0, None), r"coefficient L00 channel R is None \(null\), not a number"),
        (GOOD.tolist()[:8] + [[1.0, 2.0]], r"coefficient L22 has 2 values, not 3"),
        (GOOD.tolist()[:3] + ["abc"] + GOOD.tolist()[4:], r"coefficient L11 is a string"),
        (GOOD.tolist()[:8], r"needs 9 RGB coefficients \(shape \(9, 3\)\), got shape \(8, 3\)"),
        (np.zeros((9, 4)), r"got shape \(9, 4\)"),
        (np.ones((9, 3), dtype=bool), r"L00 channel R is a boolean"),
        (np.ones((9, 3), dtype=complex), r"L00 channel R is a complex number"),
        (np.full((9, 3), "1"), r"L00 channel R is a string"),
        (rows_with(3, 0, float("nan")), r"L11 channel R is nan: NaN and infinite"),
        (rows_with(3, 2, -float("inf")), r"L11 channel B is -inf"),
        (rows_with(8, 2, 1e39), r"L22 channel B is 1e\+39, beyond the float32 range"),
        (rows_with(8, 2, 10**400), r"L22 channel B is inf"),  # an int too large for a float
        (np.full((9, 3), -1e39), r"L00 channel R is -1e\+39, beyond the float32 range"),
    ],
)
def test_refusals_name_the_value_and_raise_value_error(coeffs, message):
    with pytest.raises(ValueError, match=message):
        check_coefficients(coeffs)


def test_the_error_class_is_the_callers():
    with pytest.raises(PresetError, match="beyond the float32"):
        check_coefficients(np.full((9, 3), 1e39), error=PresetError)


def test_accepted_inputs_give_a_float64_copy():
    class Vector:  # what mathutils.Vector offers: a length and iteration, no list type
        def __init__(self, values):
            self.values = list(values)

        def __len__(self):
            return 3

        def __iter__(self):
            return iter(self.values)

    for coeffs in (GOOD, GOOD.tolist(), tuple(map(tuple, GOOD)), [Vector(r) for r in GOOD],
                   GOOD.astype(np.float32).astype(np.float64), np.array(GOOD, dtype=object),
                   [[np.float32(v) for v in row] for row in GOOD]):
        c = check_coefficients(coeffs)
        assert c.dtype == np.float64 and c.shape == (9, 3)
        assert np.array_equal(c, GOOD)
        assert c is not coeffs
    ints = check_coefficients([[1, 2, 3]] * 9)
    assert ints.dtype == np.float64 and ints[0, 2] == 3.0


def test_float32_range_is_the_limit_exactly():
    """Every magnitude float32 holds is kept (its largest value and just above it, which
    still rounds to it); from float32 max + half an ulp on, the value would be infinite."""
    near = np.nextafter(FLOAT32_MAX + 2.0**103, 0.0)
    assert np.isfinite(np.float32(near))
    for value in (FLOAT32_MAX, -FLOAT32_MAX, near):
        assert check_coefficients(rows_with(0, 0, value))[0, 0] == value
    with pytest.raises(ValueError, match="beyond the float32 range"):
        check_coefficients(rows_with(0, 0, FLOAT32_MAX + 2.0**103))


def test_any_order_for_the_core():
    assert irradiance(np.ones((16, 3)), [0.0, 0.0, 1.0]).shape == (3,)
    with pytest.raises(ValueError, match=r"5 SH coefficients is not \(order \+ 1\)²"):
        irradiance(np.ones((5, 3)), [0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="L3-1 channel R is a string"):
        irradiance(rows_with(0, 0, 0.0) + [[0, 0, 0]] * 2 + [["x", 0, 0]] + [[0, 0, 0]] * 4,
                   [0.0, 0.0, 1.0])
