"""One light out of an HDRI (core/lights.py with k = 1, the old Split Sun): detection of a
compact bright source and the light + SH split, on synthetic equirect maps."""

from dataclasses import FrozenInstanceError
from math import pi

import numpy as np
import pytest
from eevee_style import eevee_style_split
from quadrature import random_directions

from sh_lighting.core.colour import luminance_weights
from sh_lighting.core.equirect import texel_directions, texel_solid_angles
from sh_lighting.core.projection import project_equirect
from sh_lighting.core.sh import sh_basis
from sh_lighting.core.irradiance import irradiance, reference_irradiance, total_power
from sh_lighting.core.lights import (
    CONTRAST_LOW,
    NO_GAIN,
    TOO_DIM,
    TOO_LARGE,
    Light,
    extract_lights,
    light_irradiance,
    relative_errors,
    remove_light,
)

H, W = 128, 256  # texels of 1.4°
SKY = np.array([0.8, 0.9, 1.2])
GROUND = np.array([0.3, 0.25, 0.2])
SUN_RGB = np.array([1.0, 0.9, 0.7])
EXACT = 1e-12
Y709 = luminance_weights()  # the luminance extract_lights uses by default


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def sky_with_disc(direction, radius_deg=2.5, radiance=3000.0, height=H, width=W):
    """A constant sky over a constant ground, plus a disc added to the texels whose centre is
    within ``radius_deg`` of ``direction``. Returns (pixels, disc mask)."""
    dirs = texel_directions(height, width)
    pixels = np.where(dirs[..., 2:] > 0.0, SKY, GROUND)
    disc = dirs @ unit(direction) > np.cos(np.radians(radius_deg))
    pixels = pixels + disc[..., None] * radiance * SUN_RGB
    return pixels, disc


def disc_irradiance(disc, radiance=3000.0, height=H, width=W):
    """Σ_disc (L − sky) dΩ per channel: what the sun must carry."""
    solid = np.broadcast_to(texel_solid_angles(height, width)[:, None], disc.shape)
    return radiance * SUN_RGB * solid[disc].sum()


def one_light(pixels, **options):
    """The one light ``extract_lights`` takes out of ``pixels`` (k = 1: the sun)."""
    extraction = extract_lights(pixels, 1, **options)
    assert len(extraction.lights) == 1, extraction.stop
    return extraction.lights[0]


def disc_moment_irradiance(disc, direction, radiance=3000.0):
    """Σ_disc (L − sky) (ω·s) dΩ per channel: the irradiance facing s of the disc's texels."""
    solid = np.broadcast_to(texel_solid_angles(H, W)[:, None], disc.shape)[disc]
    cosines = texel_directions(H, W)[disc] @ direction
    return radiance * SUN_RGB * (solid * cosines).sum()


def test_sun_in_the_sky_is_found_exactly():
    s = unit([0.5, -0.6, 0.55])
    pixels, disc = sky_with_disc(s)
    sun = one_light(pixels)
    assert isinstance(sun, Light)
    assert np.array_equal(sun.mask, disc)
    assert np.abs(sun.background - SKY).max() < 1e-7  # the ring around the disc is all sky
    expected = disc_irradiance(disc)  # the map lost exactly the disc's excess
    assert np.abs(sun.power - expected).max() < 1e-6 * expected.max()
    facing = disc_moment_irradiance(disc, sun.direction)
    assert np.abs(sun.irradiance - facing).max() < 1e-6 * facing.max()
    assert sun.strength == pytest.approx(facing.max(), rel=1e-6)
    assert np.abs(sun.colour - SUN_RGB).max() < 1e-6  # its max is already 1
    assert np.abs(sun.strength * sun.colour - sun.irradiance).max() < EXACT * sun.strength
    # direction: within the disc, close to its centre (texels are 1.4°: quantisation only)
    assert np.degrees(np.arccos(sun.direction @ s)) < 0.5
    assert np.linalg.norm(sun.direction) == pytest.approx(1.0, abs=1e-15)
    # diameter of the disc with the region's solid angle: about 5° (up to the texel staircase)
    assert np.degrees(sun.angular_diameter) == pytest.approx(5.0, abs=0.3)
    total = (pixels @ Y709 * texel_solid_angles(H, W)[:, None]).sum()
    assert sun.power_fraction == pytest.approx(expected @ Y709 / total, rel=1e-6)
    with pytest.raises(FrozenInstanceError):
        sun.strength = 1.0


def test_taking_the_light_out_restores_the_sky_and_conserves_power():
    pixels, disc = sky_with_disc([0.5, -0.6, 0.55])
    rgba = np.concatenate([pixels, np.full((H, W, 1), 0.5)], axis=-1).astype(np.float32)
    before = rgba.copy()
    extraction = extract_lights(rgba, 1)
    [sun] = extraction.lights
    rest = remove_light(rgba, sun)
    clean, _ = sky_with_disc([0.5, -0.6, 0.55], radiance=0.0)
    assert rest.dtype == np.float32 and np.all(rest[..., 3] == 0.5)
    assert np.array_equal(rest[..., :3], clean.astype(np.float32))
    assert np.array_equal(extraction.rest, rest)
    # sun + rest carry exactly the map's power: L00 / Y00 = ∫ L dω
    l00 = project_equirect(rgba)[0] - project_equirect(rest)[0]
    assert np.abs(l00 / sh_basis(np.array([0, 0, 1.0]))[0] - sun.power).max() < 1e-4
    assert np.array_equal(rgba, before)  # input left untouched


@pytest.mark.parametrize(
    "direction",
    [[0.03, 0.02, 1.0], [-1.0, 0.0, 0.3], [1.0, -1.0, -0.2]],
    ids=["across the pole", "across the u = 0 seam", "below the horizon"],
)
def test_connectivity_wraps_around(direction):
    pixels, disc = sky_with_disc(direction, radius_deg=3.0)
    sun = one_light(pixels)
    assert np.array_equal(sun.mask, disc)
    background = SKY if direction[2] > 0.1 else GROUND
    expected = disc_irradiance(disc)
    if direction[2] < 0:  # under the horizon the ring is ground, which the disc sits on
        assert np.abs(sun.background - background).max() < 1e-7
    assert np.abs(sun.power - expected).max() < 1e-6 * expected.max()
    assert np.degrees(np.arccos(sun.direction @ unit(direction))) < 0.5


def test_one_light_beats_plain_sh_and_the_eevee_style_split():
    pixels, _ = sky_with_disc([0.5, -0.6, 0.55])
    normals = random_directions(120, seed=2)
    extraction = extract_lights(pixels, 1, normals=normals)
    (plain_mean, plain_max), (sun_mean, sun_max) = extraction.errors
    # the 9 terms ring around the strong disc; sun + SH9 is left with only the horizon step
    assert sun_mean < plain_mean / 5 and sun_max < plain_max / 5
    assert plain_mean > 0.01 and sun_mean < 0.005
    # the EEVEE-style split keeps only l ≤ 1 for the rest: between the two here
    rgb, direction, coeffs = eevee_style_split(pixels)
    eevee = irradiance(coeffs, normals) + np.maximum(normals @ direction, 0.0)[:, None] * rgb
    reference = reference_irradiance(pixels, normals)
    eevee_mean, _ = relative_errors(eevee, reference, total_power(project_equirect(pixels)))
    assert sun_mean < eevee_mean < plain_mean


def test_no_light_in_a_smooth_map():
    rng = np.random.default_rng(7)
    field = sh_basis(texel_directions(H, W), 3) @ rng.normal(size=16)
    pixels = np.exp(field)[..., None] * [1.0, 0.9, 0.8]  # smooth, positive
    assert 5 < pixels.max() / np.median(pixels) < 20  # contrast below the 20 × needed
    extraction = extract_lights(pixels, 1)
    assert extraction.lights == [] and extraction.stop_kind == CONTRAST_LOW
    assert "less than 20 ×" in extraction.stop
    whole = project_equirect(pixels.astype(np.float32))  # the extraction works in float32
    assert np.array_equal(extraction.coefficients, whole)
    # with a lower contrast the broad bright lobe is a candidate, too large to be a light
    assert extract_lights(pixels, 1, contrast=5.0).stop_kind == TOO_LARGE


def test_no_light_when_the_bright_area_is_large():
    pixels, _ = sky_with_disc([0.3, 0.8, 0.5], radius_deg=32.0, radiance=300.0)
    extraction = extract_lights(pixels, 1)  # a window, not a sun: wider than MAX_RADIUS
    assert extraction.lights == [] and extraction.stop_kind == TOO_LARGE
    assert "wider than the size limit of 60°" in extraction.stop
    # within a wider limit it is a candidate, but a 64° disc lit as a Sun would not lower the
    # error: it stays in the SH
    assert extract_lights(pixels, 1, max_radius=np.radians(35.0)).stop_kind == NO_GAIN
    # a 24° window: a light by default (it was left in the SH by the 24° of before)
    window, _ = sky_with_disc([0.3, 0.8, 0.5], radius_deg=12.0, radiance=300.0)
    assert one_light(window).power_fraction > 0.8
    assert extract_lights(window, 1, max_radius=np.radians(12.0)).stop_kind == TOO_LARGE
    with pytest.raises(ValueError, match="size limit must be above 0° and at most 120°"):
        extract_lights(pixels, 1, max_radius=np.radians(61.0))


def test_no_light_when_the_source_is_weak():
    pixels, disc = sky_with_disc([0.3, 0.8, 0.5], radius_deg=1.2, radiance=60.0)
    share = disc_irradiance(disc, 60.0) @ Y709 / (
        pixels @ Y709 * texel_solid_angles(H, W)[:, None]
    ).sum()
    assert 0.002 < share < 0.01
    extraction = extract_lights(pixels, 1)
    assert extraction.lights == [] and extraction.stop_kind == TOO_DIM
    assert f"carries {100 * share:.2g} % of the light, less than 1 %" in extraction.stop
    sun = one_light(pixels, min_power_fraction=0.001)
    assert sun.power_fraction == pytest.approx(share, rel=1e-6)


def test_sun_as_a_directional_light():
    pixels, _ = sky_with_disc([0.0, 0.0, 1.0], radius_deg=1.0)
    sun = one_light(pixels)
    n = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.6, -0.8], [0.6, 0.0, 0.8]])
    e = light_irradiance([sun], n)
    assert np.abs(e[0] - sun.irradiance).max() < 1e-6 * sun.strength  # direction's rounding
    assert np.abs(e[1:3]).max() < 1e-6 * sun.strength  # perpendicular: zero up to rounding
    assert np.abs(e[3] - 0.8 * sun.irradiance).max() < 1e-3 * sun.strength


def test_eevee_style_split_clamps_and_conserves_power():
    s = unit([0.5, -0.6, 0.55])
    pixels, disc = sky_with_disc(s)
    rgb, direction, coeffs = eevee_style_split(pixels, threshold=10.0)
    assert coeffs.shape == (4, 3)
    # the sun takes what lies above 10 in each disc texel's largest channel, hue kept:
    # L (1 − 10 / max L)
    solid = texel_solid_angles(H, W)[:, None]
    inside = pixels[disc]
    expected = (inside * (1.0 - 10.0 / inside.max(axis=-1, keepdims=True))
                * np.broadcast_to(solid, disc.shape)[disc][:, None]).sum(axis=0)
    assert np.abs(rgb - expected).max() < EXACT * expected.max()
    assert np.degrees(np.arccos(direction @ s)) < 0.5
    # sun + clamped map = the map's power
    y00 = sh_basis(np.array([0.0, 0.0, 1.0]))[0]
    total = project_equirect(pixels)[0] / y00
    assert np.abs(coeffs[0] / y00 + rgb - total).max() < 1e-9 * total.max()
    # nothing above the threshold: no sun, plain order-1 SH
    rgb, direction, coeffs = eevee_style_split(pixels, threshold=1e6)
    assert direction is None and np.all(rgb == 0.0)
    assert np.abs(coeffs - project_equirect(pixels, max_order=1)).max() < EXACT


def test_total_power_of_the_synthetic_sky():
    """Guards the helpers above: sky and ground halves have power 2π × their radiance."""
    pixels, _ = sky_with_disc([0, 0, 1], radiance=0.0)
    power = project_equirect(pixels)[0] / sh_basis(np.array([0.0, 0.0, 1.0]))[0]
    assert np.abs(power - 2 * pi * (SKY + GROUND)).max() < 1e-9
