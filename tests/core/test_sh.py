"""Real SH basis (eq. 3) and the clamped-cosine transfer Â_l (eq. 8)."""

from math import pi, sqrt

import numpy as np
import pytest
from quadrature import random_directions, sphere_rule

from sh_lighting.core.sh import (
    COEFFICIENT_NAMES,
    lambert_band_factors,
    num_coefficients,
    order_of,
    sh_basis,
    sh_basis_recurrence,
    sh_index,
)

EXACT = 1e-13  # rounding only: both sides are the same polynomial


def test_paper_table_constants_at_axes():
    """The paper prints the constants to 6 digits (eq. 3)."""
    x, y, z = np.eye(3)
    diag = np.array([1.0, 1.0, 0.0]) / sqrt(2.0)
    assert sh_basis(x)[0] == pytest.approx(0.282095, abs=1e-6)
    assert sh_basis(y)[1] == pytest.approx(0.488603, abs=1e-6)
    assert sh_basis(z)[2] == pytest.approx(0.488603, abs=1e-6)
    assert sh_basis(x)[3] == pytest.approx(0.488603, abs=1e-6)
    assert sh_basis(diag)[4] == pytest.approx(1.092548 * 0.5, abs=1e-6)
    assert sh_basis(z)[6] == pytest.approx(0.315392 * 2.0, abs=1e-6)
    assert sh_basis(x)[8] == pytest.approx(0.546274, abs=1e-6)


@pytest.mark.parametrize("order", [0, 1, 2, 3, 4, 6])
def test_closed_forms_match_recurrence(order):
    d = random_directions(500)
    d = np.concatenate([d, np.eye(3), -np.eye(3)])  # poles and axes included
    assert np.abs(sh_basis(d, order) - sh_basis_recurrence(d, order)).max() < EXACT


@pytest.mark.parametrize("order", [2, 4])
def test_orthonormal_on_the_sphere(order):
    dirs, weights = sphere_rule()
    y = sh_basis(dirs, order)
    gram = (y * weights[:, None]).T @ y
    assert np.abs(gram - np.eye(num_coefficients(order))).max() < EXACT


def test_index_and_names():
    assert [sh_index(l, m) for l in range(3) for m in range(-l, l + 1)] == list(range(9))
    assert COEFFICIENT_NAMES[sh_index(1, 0)] == "L10"
    assert order_of(25) == 4
    with pytest.raises(ValueError, match="order"):
        order_of(8)


def test_lambert_band_factors_exact_values():
    expected = [pi, 2 * pi / 3, pi / 4, 0.0, -pi / 24, 0.0, pi / 64]
    assert np.abs(lambert_band_factors(6) - expected).max() < 1e-15


def test_lambert_band_factors_against_integration():
    """Â_l = 2π ∫_0^1 u P_l(u) du (the clamped cosine's Legendre coefficient), by quadrature."""
    u, w = np.polynomial.legendre.leggauss(40)
    u, w = 0.5 * (u + 1.0), 0.5 * w
    for l, a in enumerate(lambert_band_factors(8)):
        p_l = np.polynomial.legendre.Legendre.basis(l)(u)
        assert a == pytest.approx(2 * pi * np.sum(w * u * p_l), abs=EXACT)


def test_bad_directions_and_orders():
    with pytest.raises(ValueError, match=r"\(\.\.\., 3\)"):
        sh_basis(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="max_order"):
        sh_basis(np.zeros(3), -1)


def test_coefficient_table_names_and_words_each_row():
    from sh_lighting.core.sh import COEFFICIENT_PHRASES, coefficient_table

    coeffs = np.arange(27.0).reshape(9, 3) - 13.0
    lines = coefficient_table(coeffs)
    assert len(lines) == 10 and lines[0].split() == ["R", "G", "B", "what", "it", "does"]
    assert lines[3].split()[:4] == ["L10", "-7.00000", "-6.00000", "-5.00000"]
    assert lines[3].endswith("light from above vs below") and len(COEFFICIENT_PHRASES) == 9
