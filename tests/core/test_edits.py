"""Exact lighting edits (edits.py), checked against projecting edited equirect maps."""

import numpy as np
import pytest
from quadrature import random_directions

from sh_lighting.core.edits import (
    LUMINANCE,
    band_gains,
    describe_coefficients,
    exposure,
    flip_vertical,
    rotate,
    saturation,
    vertical_parity,
    yaw_pitch_roll_matrix,
)
from sh_lighting.core.equirect import texel_directions
from sh_lighting.core.irradiance import C2, irradiance
from sh_lighting.core.projection import project_equirect
from sh_lighting.core.sh import sh_basis

EXACT = 1e-12
H, W = 24, 48


def delta(s, rgb=(1.0, 1.0, 1.0)):
    s = np.asarray(s, float) / np.linalg.norm(s)
    return sh_basis(s)[:, None] * np.asarray(rgb)[None, :]


def make_map():
    """An asymmetric coloured map: a warm lobe up-front-right, a blue lobe low at −Y, noise."""
    dirs = texel_directions(H, W)
    rng = np.random.default_rng(4)
    lobe1 = np.exp(6.0 * (dirs @ np.array([0.5, -0.3, 0.81]) - 1.0))[..., None] * [4, 2, 1]
    lobe2 = np.exp(3.0 * (dirs @ np.array([0.1, -0.9, -0.42]) - 1.0))[..., None] * [0, 1, 3]
    return 0.1 + lobe1 + lobe2 + rng.uniform(0.0, 0.2, (H, W, 3))


PIXELS = make_map()
COEFFS = project_equirect(PIXELS)


def test_rotation_convention_moves_lights_as_documented():
    r = yaw_pitch_roll_matrix(np.pi / 2, 0, 0)
    assert np.abs(r @ [1, 0, 0] - [0, 1, 0]).max() < 1e-15
    r = yaw_pitch_roll_matrix(0, np.pi / 2, 0)
    assert np.abs(r @ [0, 1, 0] - [0, 0, 1]).max() < 1e-15
    r = yaw_pitch_roll_matrix(0, 0, np.pi / 2)
    assert np.abs(r @ [0, 0, 1] - [1, 0, 0]).max() < 1e-15
    yaw, pitch, roll = 0.3, -1.1, 2.0
    r = yaw_pitch_roll_matrix(yaw, pitch, roll)
    assert np.abs(r @ r.T - np.eye(3)).max() < 1e-15 and np.linalg.det(r) == pytest.approx(1)
    s = np.array([0.2, 0.7, -0.4])
    s /= np.linalg.norm(s)
    moved = rotate(delta(s), yaw, pitch, roll)
    assert np.abs(moved - delta(r @ s)).max() < EXACT


def test_rotation_composes_roll_then_pitch_then_yaw():
    step = rotate(rotate(rotate(COEFFS, roll=0.7), pitch=-0.4), yaw=1.9)
    assert np.abs(rotate(COEFFS, 1.9, -0.4, 0.7) - step).max() < EXACT
    assert np.abs(rotate(rotate(COEFFS, yaw=0.5), yaw=0.8) - rotate(COEFFS, yaw=1.3)).max() < EXACT
    back = rotate(rotate(rotate(COEFFS, 1.0, 0.5, -0.2), yaw=-1.0), pitch=-0.5)
    assert np.abs(rotate(back, roll=0.2) - COEFFS).max() < EXACT
    # rotation keeps each band's energy Σ_m L_lm² (docs/reference.md §4)
    turned = rotate(COEFFS, 0.4, 1.2, -2.2)
    for band in (slice(0, 1), slice(1, 4), slice(4, 9)):
        assert np.abs((turned[band] ** 2).sum(0) - (COEFFS[band] ** 2).sum(0)).max() < EXACT


@pytest.mark.parametrize("k", [1, 5, 12, -7])
def test_yaw_equals_projecting_the_column_rolled_map(k):
    """Yaw by 2πk/W turns φ by k texels; columns run toward decreasing φ, so roll by −k."""
    rolled = np.roll(PIXELS, -k, axis=1)
    assert np.abs(rotate(COEFFS, yaw=2 * np.pi * k / W) - project_equirect(rolled)).max() < EXACT


def test_half_turns_equal_projecting_flipped_maps():
    # pitch π: (x, y, z) → (x, −y, −z): rows reversed, φ → −φ (columns reversed)
    flipped = PIXELS[::-1, ::-1]
    assert np.abs(rotate(COEFFS, pitch=np.pi) - project_equirect(flipped)).max() < EXACT
    # roll π: (x, y, z) → (−x, y, −z): rows reversed, φ → π − φ
    mirrored = np.roll(PIXELS[::-1, ::-1], W // 2, axis=1)
    assert np.abs(rotate(COEFFS, roll=np.pi) - project_equirect(mirrored)).max() < EXACT


def test_flip_vertical_equals_projecting_the_upside_down_map():
    flipped = flip_vertical(COEFFS)
    assert np.abs(flipped - project_equirect(PIXELS[::-1])).max() < EXACT
    assert np.all(flip_vertical(flipped) == COEFFS)
    assert list(np.nonzero(vertical_parity(2) < 0)[0]) == [2, 5, 7]  # L10, L2-1, L21
    # the parity comes from the basis: Y_lm(x, y, −z) = (−1)^(l+m) Y_lm(x, y, z), any order
    d = random_directions(50)
    mirror = d * [1, 1, -1]
    assert np.abs(sh_basis(mirror, 4) - sh_basis(d, 4) * vertical_parity(4)).max() < EXACT
    # lit from above becomes lit from below
    up = delta([0.3, 0.0, 0.9])
    assert np.abs(flip_vertical(up) - delta([0.3, 0.0, -0.9])).max() < EXACT


def test_exposure_is_exact_powers_of_two():
    assert np.all(exposure(COEFFS, 1) == 2 * COEFFS)
    assert np.all(exposure(COEFFS, -3) == COEFFS / 8)
    assert np.abs(exposure(exposure(COEFFS, 0.7), -0.7) - COEFFS).max() < EXACT
    e = irradiance(COEFFS, random_directions(20))
    assert np.abs(irradiance(exposure(COEFFS, 2), random_directions(20)) - 4 * e).max() < EXACT


def test_saturation():
    grey = saturation(COEFFS, 0.0)
    assert np.abs(grey - (COEFFS @ LUMINANCE)[:, None]).max() < EXACT
    assert np.all(saturation(COEFFS, 1.0) == COEFFS)
    for amount in (0.0, 0.4, 2.5):
        out = saturation(COEFFS, amount)
        assert np.abs(out @ LUMINANCE - COEFFS @ LUMINANCE).max() < EXACT  # luminance kept
        # the chroma (difference from grey) scales by exactly `amount`
        chroma = COEFFS - (COEFFS @ LUMINANCE)[:, None]
        assert np.abs(out - (COEFFS @ LUMINANCE)[:, None] - amount * chroma).max() < EXACT
    only = saturation(COEFFS, 0.0, bands=(1, 2))
    assert np.all(only[0] == COEFFS[0])
    assert np.abs(only[1:] - grey[1:]).max() < EXACT
    # a pure grey coefficient set is a fixed point
    assert np.abs(saturation(grey, 3.0) - grey).max() < EXACT


def test_band_gains():
    out = band_gains(COEFFS, ambient=2.0, directional=0.5, quadratic=0.0)
    assert np.all(out[0] == 2 * COEFFS[0])
    assert np.all(out[1:4] == 0.5 * COEFFS[1:4])
    assert np.all(out[4:] == 0.0)
    assert np.all(band_gains(COEFFS) == COEFFS)
    # directional gain on a single top light: E changes only in its z term (eq. 13)
    up = delta([0, 0, 1])
    n = random_directions(30)
    diff = irradiance(band_gains(up, directional=3.0), n) - irradiance(up, n)
    assert np.abs(diff[:, 0] - 2 * C2 * 2 * up[2, 0] * n[:, 2]).max() < EXACT


def saturate_pixels(pixels, amount):
    """Saturation done on the map itself: grey = luminance, chroma scaled by ``amount``."""
    grey = (pixels @ LUMINANCE)[..., None]
    return grey + amount * (pixels - grey)


def test_composed_edits_equal_projecting_the_edited_map():
    """Each chain of edits against the map edited texel by texel, then projected: a band-wise
    slip in any edit (a wrong band, a sign, a gain on the wrong term) breaks the equality,
    which checking that two orders of the same edits agree would not catch."""
    k = 5
    yaw = 2 * np.pi * k / W
    a = saturation(exposure(rotate(COEFFS, yaw=yaw), 1.5), 0.3)
    edited = saturate_pixels(2 ** 1.5 * np.roll(PIXELS, -k, axis=1), 0.3)
    assert np.abs(a - project_equirect(edited)).max() < EXACT
    c = flip_vertical(rotate(COEFFS, yaw=yaw))
    assert np.abs(c - project_equirect(np.roll(PIXELS, -k, axis=1)[::-1])).max() < EXACT
    # a turn that is not a texel shift: single lights, moved by the matrix, then mirrored in z
    s = np.array([0.2, 0.7, -0.4])
    r = yaw_pitch_roll_matrix(0.0, 0.3, 0.0)
    mirrored = (r @ (s / np.linalg.norm(s))) * [1, 1, -1]
    assert np.abs(flip_vertical(rotate(delta(s), pitch=0.3)) - delta(mirrored)).max() < EXACT


def test_descriptions_of_known_lightings():
    above = describe_coefficients(delta([0, 0, 1]))
    assert len(above) == 9
    assert above[2].startswith("L10 +0.489") and "lit from above" in above[2]
    assert "±200 %" in above[2]  # 2c2 Y1² / (c4 Y00) = (1/2) / (1/4)
    assert "no" in above[1] and "no" in above[3]
    assert "lit from below" in describe_coefficients(flip_vertical(delta([0, 0, 1])))[2]
    side = describe_coefficients(delta([-1, 0, 0], rgb=(0.2, 1.0, 0.1)))
    assert "lit from −X" in side[3] and "±X than ±Y" in side[8]
    assert "horizon" in side[6]
    constant = np.zeros((9, 3))
    constant[0] = 1.0
    text = describe_coefficients(constant)
    assert text[0].startswith("L00 +1: overall light")
    assert all(line.split(": ")[1].startswith("no ") for line in text[1:])
    weak = constant.copy()
    weak[2] = 0.05  # 2 c2 0.05 / c4 = 5.8 % of the mean
    assert "slightly lit from above (±6 %" in describe_coefficients(weak)[2]
    dark = -constant
    assert "not physical" in describe_coefficients(dark)[0]
