"""Exact minimum/maximum of the 9-term irradiance on the sphere (minimum.py).

Checked against closed forms (constant light, one delta: docs/reference.md §2, the hard case),
against every stationary point found independently from the 6th-degree secular polynomial,
and against dense sampling refined by Riemannian Newton steps.
"""

from math import pi, sqrt

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from quadrature import random_directions

from sh_lighting.core.irradiance import C1, C2, C4, irradiance, irradiance_matrices
from sh_lighting.core import minimum
from sh_lighting.core.minimum import (
    irradiance_maximum,
    irradiance_minimum,
    mean_irradiance,
    minimize_quadratic_on_sphere,
    negative_light_warning,
)
from sh_lighting.core.sh import sh_basis

EXACT = 1e-13  # relative to the coefficients' scale: rounding only
REFINED = 1e-9  # agreement with an independently refined local optimum (brief's bound)
SAMPLES = random_directions(20000, seed=3)


def delta(s, power=1.0):
    """Coefficients of a delta light of total ``power`` in direction ``s``: L_lm = P Y_lm(s)."""
    s = np.asarray(s, float) / np.linalg.norm(s)
    return power * np.repeat(sh_basis(s)[:, None], 3, axis=1)


def refine(a, b, v, steps=30):
    """Riemannian Newton on the sphere for vᵀ a v + 2 bᵀ v, from the unit vector v."""
    for _ in range(steps):
        g = 2.0 * (a @ v + b)
        p = np.eye(3) - np.outer(v, v)
        hess = p @ (2.0 * a) @ p - (v @ g) * p + np.outer(v, v)  # identity on the normal
        step = np.linalg.solve(hess, -(p @ g))
        v = v + p @ step
        v /= np.linalg.norm(v)
    return v


def stationary_minimum(a, b, c):
    """min over all stationary points, from the roots of the secular polynomial (independent).

    Σ β_i² Π_{j≠i}(d_j − λ)² − Π(d_i − λ)² = 0 has degree 6; each real root λ gives
    v = −(A − λI)⁻¹ b (valid where |v| ≈ 1).
    """
    d, q = np.linalg.eigh(a)
    beta = q.T @ b
    P = np.polynomial.Polynomial
    factors = [P([di, -1.0]) ** 2 for di in d]
    poly = -(factors[0] * factors[1] * factors[2])
    for i in range(3):
        others = [factors[j] for j in range(3) if j != i]
        poly = poly + beta[i] ** 2 * others[0] * others[1]
    best = np.inf
    for lam in poly.roots():
        if abs(lam.imag) > 1e-6:
            continue
        v = np.linalg.solve(a - lam.real * np.eye(3), -b)
        v /= np.linalg.norm(v)
        best = min(best, v @ a @ v + 2 * b @ v + c)
    return best


def test_single_delta_minimum_is_minus_19_over_480_at_u_minus_8_over_15():
    for s in ([0, 0, 1], [0.3, -0.5, 0.81], [-1, 2, -0.5]):
        s = np.asarray(s, float) / np.linalg.norm(s)
        lo = irradiance_minimum(delta(s, power=2.0))
        assert np.abs(lo.value - 2.0 * (-19 / 480)).max() < EXACT
        assert np.abs(lo.bound - lo.value).max() < EXACT
        assert np.abs(lo.direction @ s + 8 / 15).max() < 1e-7  # on the cone u = −8/15
        hi = irradiance_maximum(delta(s, power=2.0))
        assert np.abs(hi.value - 2.0 * 1.0625).max() < EXACT
        assert np.abs(hi.direction @ s - 1.0).max() < 1e-12


def test_constant_lighting_min_equals_max_equals_pi_c():
    c = np.array([0.5, 1.0, 2.0])
    coeffs = np.zeros((9, 3))
    coeffs[0] = 2.0 * sqrt(pi) * c
    lo, hi = irradiance_minimum(coeffs), irradiance_maximum(coeffs)
    assert np.abs(lo.value - pi * c).max() < EXACT and np.abs(hi.value - pi * c).max() < EXACT
    assert np.allclose(np.linalg.norm(lo.direction, axis=1), 1.0)
    assert np.abs(mean_irradiance(coeffs) - pi * c).max() < EXACT


def test_hard_case_b_orthogonal_to_lowest_eigenvector():
    """L22 = 1: A = diag(c1, −c1, 0), lowest eigenvector y; b = (c2 L11, 0, 0) ⟂ y.

    With y² = 1 − x², E = 2 c1 x² + 2 β x − c1 + c, minimum at x = −β / 2c1 (|x| < 1):
    E_min = c − c1 − β² / (2 c1), at two normals (±y).
    """
    for l11 in (0.0, 0.3, -1.2):
        coeffs = np.zeros((9, 3))
        coeffs[0], coeffs[8], coeffs[3] = 3.0, 1.0, l11
        beta, c = C2 * l11, C4 * 3.0
        assert abs(beta) < 2 * C1  # the hard case proper
        lo = irradiance_minimum(coeffs)
        assert np.abs(lo.value - (c - C1 - beta**2 / (2 * C1))).max() < EXACT
        assert np.abs(lo.direction[:, 0] + beta / (2 * C1)).max() < 1e-12
        assert np.abs(lo.direction[:, 2]).max() < 1e-12
        assert np.abs(lo.bound - lo.value).max() < EXACT
        # a nudge off the hard case (b gains a tiny y part) moves the minimum continuously
        coeffs[1] = 1e-9
        assert np.abs(irradiance_minimum(coeffs).value - lo.value).max() < 1e-8
    # past the hard case: |β| > 2 c1 puts the minimiser at x = −sign β, y = 0
    coeffs[1], coeffs[3] = 0.0, 2.5
    assert 2.5 * C2 > 2 * C1
    lo = irradiance_minimum(coeffs)
    assert np.abs(lo.value - (C4 * 3.0 + C1 - 2 * C2 * 2.5)).max() < EXACT
    assert np.abs(lo.direction - [-1.0, 0.0, 0.0]).max() < 1e-7


@pytest.mark.parametrize("tiny", [0.0, 3e-16, 3e-13, 1e-10, 1e-7])
def test_near_hard_case_keeps_full_accuracy(tiny):
    """b almost ⟂ the lowest eigenvector: λ sits within ~|β₁| of d₁, where the plain formula
    v = −(A − λI)⁻¹ b loses half its digits. The minimum is continuous in β₁: with β₁ = 0 it is
    d₁ + c − Σ_{i>1} β_i²/(d_i − d₁) (the hard case, here |v_rest| < 1).
    """
    d = np.array([-1.07020571, 0.20816646, 0.33877229])
    beta = np.array([tiny, 0.161528191, 0.329104010])
    rotation = np.linalg.qr(np.random.default_rng(1).normal(size=(3, 3)))[0]
    a, b = rotation @ np.diag(d) @ rotation.T, rotation @ beta
    value, v, bound, _ = minimize_quadratic_on_sphere(a, b, 0.5)
    hard = d[0] + 0.5 - np.sum(beta[1:] ** 2 / (d[1:] - d[0]))
    assert abs(value - bound) < EXACT
    assert abs(value - hard) < EXACT + 2 * tiny  # E moves by at most ~2|β₁| with β₁
    assert abs(np.linalg.norm(v) - 1.0) < 1e-15


def test_b_zero_gives_lowest_eigenvalue():
    a = np.array([[2.0, 0.5, 0.0], [0.5, -1.0, 0.3], [0.0, 0.3, 0.7]])
    value, v, bound, lam = minimize_quadratic_on_sphere(a, np.zeros(3), 0.25)
    assert value == pytest.approx(np.linalg.eigvalsh(a)[0] + 0.25, abs=EXACT)
    assert bound == pytest.approx(value, abs=EXACT)
    assert np.linalg.norm(a @ v - lam * v) < 1e-12


def test_repeated_lowest_eigenvalue():
    a = np.diag([-1.0, -1.0, 3.0])
    sampled = lambda b: ((SAMPLES @ a) * SAMPLES).sum(1) + 2 * (SAMPLES @ b)  # noqa: E731
    # b partly in the double eigenspace: the ordinary case
    b = np.array([0.2, -0.1, 0.5])
    value, v, bound, _ = minimize_quadratic_on_sphere(a, b, 0.0)
    assert value == pytest.approx(stationary_minimum(a, b, 0.0), abs=1e-12)
    assert value <= sampled(b).min() and abs(value - bound) < EXACT
    # b ⟂ the double eigenspace: the hard case, a whole circle of minimisers with z = −b3/4
    b = np.array([0.0, 0.0, 0.5])
    value, v, bound, lam = minimize_quadratic_on_sphere(a, b, 0.0)
    z = -0.5 / 4.0
    assert lam == -1.0 and v[2] == pytest.approx(z, abs=1e-15)
    assert value == pytest.approx(-(1 - z * z) + 3 * z * z + 2 * 0.5 * z, abs=EXACT)
    assert value <= sampled(b).min() and abs(value - bound) < EXACT


@pytest.mark.parametrize("seed", range(6))
def test_random_coefficients_against_sampling_refinement_and_secular_polynomial(seed):
    rng = np.random.default_rng(seed)
    coeffs = rng.normal(size=(9, 3)) * rng.uniform(0.01, 10.0)
    scale = np.abs(coeffs).max()
    lo, hi = irradiance_minimum(coeffs), irradiance_maximum(coeffs)
    samples = irradiance(coeffs, SAMPLES)
    assert np.all(lo.value <= samples.min(axis=0) + EXACT * scale)
    assert np.all(hi.value >= samples.max(axis=0) - EXACT * scale)
    assert np.abs(lo.value - lo.bound).max() < EXACT * scale
    assert np.abs(hi.value - hi.bound).max() < EXACT * scale
    m = irradiance_matrices(coeffs)
    for ch in range(3):
        a, b, c = m[ch, :3, :3], m[ch, :3, 3], m[ch, 3, 3]
        best = refine(a, b, SAMPLES[np.argmin(samples[:, ch])])
        refined = best @ a @ best + 2 * b @ best + c
        assert lo.value[ch] <= refined + EXACT * scale
        assert abs(lo.value[ch] - refined) < REFINED * scale
        assert abs(lo.value[ch] - stationary_minimum(a, b, c)) < 1e-9 * scale
        # the returned direction is a unit vector where E takes the returned value
        n = lo.direction[ch]
        assert abs(np.linalg.norm(n) - 1.0) < 1e-14
        assert abs(irradiance(coeffs, n)[ch] - lo.value[ch]) < EXACT * scale


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(-5, 5, allow_nan=False, allow_infinity=False), min_size=9, max_size=9),
    st.sampled_from([0, 1, 2, 3, 4, 5, 6, 7, 8]),
)
def test_certificate_holds_for_arbitrary_coefficients(values, zeroed):
    coeffs = np.zeros((9, 3))
    coeffs[:, 0] = values
    coeffs[zeroed, 0] = 0.0  # exercise degenerate (hard-case-prone) inputs
    coeffs[:, 1] = np.round(values, 1)  # repeated eigenvalues, b ⟂ eigenvectors
    scale = max(1.0, np.abs(coeffs).max())
    lo = irradiance_minimum(coeffs)
    assert np.abs(lo.value - lo.bound).max() < 1e-12 * scale
    assert np.all(lo.value <= irradiance(coeffs, SAMPLES[:2000]).min(axis=0) + 1e-12 * scale)


def test_negative_light_warning_names_channels_amount_and_direction():
    coeffs = np.zeros((9, 3))
    coeffs[:, 0] = delta([0, 0, 1])[:, 0]  # R: one light straight above
    coeffs[0, 1:] = 1.0  # G, B: constant
    message = negative_light_warning(coeffs)
    # R: minimum −19/480 against a mean of 1/4: −15.8 %; G and B are fine
    assert message is not None and "R -15.8 %" in message
    assert "G" not in message.split("(")[1].split(")")[0]
    assert "below" in message
    constant = np.zeros((9, 3))
    constant[0] = 1.0
    assert negative_light_warning(constant) is None


def test_negative_light_warning_on_nonpositive_mean():
    coeffs = np.zeros((9, 3))
    coeffs[0] = [-1.0, 1.0, 1.0]
    assert "R" in negative_light_warning(coeffs)


def test_negative_light_is_said_in_proportion():
    """How deep and over how much of the sphere: a lone light dips −15.8 % of the mean (not
    small); the same light over an ambient that leaves a −3 % dip is small, and the warning
    says so and over what share of directions (counted against a dense lattice)."""
    lone = delta([0, 0, 1])
    assert not minimum.negative_light_is_small(lone)
    lone_share = minimum.negative_share(lone)
    # E < 0 where 15x² + 16x + 3 < 0, x = cos θ in (−0.8239, −0.2427): a band of area share
    # (0.8239 − 0.2427)/2 = 0.2906
    assert lone_share == pytest.approx(0.2906, abs=0.002)
    assert "29.1 % of all directions" in negative_light_warning(lone)
    assert "smoothing window removes it" in negative_light_warning(lone)
    # ambient a: E_min = −19/480 + a, mean 1/4 + a; −3 % of the mean
    a = (19 / 480 - 0.03 * 0.25) / 1.03
    dipped = lone.copy()
    dipped[0] += a / (pi * 0.5 / sqrt(pi))  # L00 → E += π · L00 · Y00 = L00 √π / 2
    relative = minimum.irradiance_minimum(dipped).value / minimum.mean_irradiance(dipped)
    assert relative == pytest.approx(-0.03, abs=1e-9)
    assert minimum.negative_light_is_small(dipped)
    message = negative_light_warning(dipped)
    assert "-3.0 %" in message and "a small dip" in message
    assert 0.0 < minimum.negative_share(dipped) < lone_share
    constant = np.zeros((9, 3))
    constant[0] = 1.0
    assert not minimum.negative_light_is_small(constant) and minimum.negative_share(constant) == 0
