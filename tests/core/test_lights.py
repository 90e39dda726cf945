"""core.lights: the extracted lights plus the SH of the rest equal the world's irradiance."""

import numpy as np
import pytest

from sh_lighting.core import lights as core_lights
from sh_lighting.core.equirect import texel_directions, texel_solid_angles
from sh_lighting.core.irradiance import irradiance, relative_error, total_power
from sh_lighting.core.projection import project_equirect
from sh_lighting.core.sh import spread_normals
from eevee_style import eevee_style_split
from sh_lighting.core.world_map import equirect_irradiance

HEIGHT, WIDTH = 128, 256
SKY = np.array([0.3, 0.4, 0.5])


def disc_world(suns, sky=SKY):
    """Constant sky plus uniform discs: [(direction, radius in degrees, RGB radiance)]."""
    pixels = np.ones((HEIGHT, WIDTH, 3)) * sky
    directions = texel_directions(HEIGHT, WIDTH)
    for direction, radius, radiance in suns:
        d = np.asarray(direction, float) / np.linalg.norm(direction)
        inside = directions @ d > np.cos(np.radians(radius))
        pixels[inside] = radiance
    return pixels.astype(np.float32)


TWO_SUNS = [((1.0, 0.0, 1.0), 3.0, (3000.0, 2800.0, 2500.0)),
            ((-1.0, 0.2, 0.8), 2.0, (2000.0, 2100.0, 2200.0))]


def test_two_opposite_suns_become_two_lights_where_eevee_merges_them():
    pixels = disc_world(TWO_SUNS)
    result = core_lights.extract_lights(pixels, count=4)
    assert len(result.lights) == 2
    normals = spread_normals(512)
    truth = equirect_irradiance(pixels, normals)
    power = total_power(project_equirect(pixels))
    for light, (direction, _, radiance) in zip(result.lights, TWO_SUNS):
        d = np.asarray(direction) / np.linalg.norm(direction)
        assert np.degrees(np.arccos(light.direction @ d)) < 0.2
        assert light.colour.max() == 1.0
    # EEVEE's threshold split: one sun between the two, far from both
    _, eevee_direction, eevee_coeffs = eevee_style_split(pixels)
    for direction, _, _ in TWO_SUNS:
        d = np.asarray(direction) / np.linalg.norm(direction)
        assert np.degrees(np.arccos(eevee_direction @ d)) > 15.0
    eevee_rgb, _, _ = eevee_style_split(pixels)
    eevee = relative_error(irradiance(eevee_coeffs, normals)
                           + np.maximum(normals @ eevee_direction, 0)[:, None] * eevee_rgb,
                           truth, power)
    ours = result.errors[-1]
    plain = result.errors[0]
    print(f"\ntwo suns, mean / max error (% of the light): plain SH {100 * plain[0]:.2f} / "
          f"{100 * plain[1]:.2f}, SH + 2 lights {100 * ours[0]:.3f} / {100 * ours[1]:.3f}, "
          f"EEVEE-style split {100 * eevee[0]:.2f} / {100 * eevee[1]:.2f}")
    assert ours[0] < 0.1 * plain[0] and ours[0] < 0.1 * eevee[0]


def test_rest_plus_lights_is_the_world_irradiance_by_brute_force():
    pixels = disc_world(TWO_SUNS)
    result = core_lights.extract_lights(pixels, count=2)
    # normals that see each source whole: the light's cosine law is then exact
    normals = spread_normals(2000)
    clear = np.ones(len(normals), bool)
    for light in result.lights:
        clear &= normals @ light.direction > np.sin(light.angular_diameter)
    truth = equirect_irradiance(pixels, normals[clear])
    rebuilt = (equirect_irradiance(result.rest, normals[clear])
               + core_lights.light_irradiance(result.lights, normals[clear]))
    worst = np.abs(rebuilt - truth).max() / truth.max()
    print(f"\nrest + lights vs the world, brute force, {clear.sum()} normals: max {worst:.2e}")
    assert worst < 1e-4
    # power: the map lost exactly what the lights carry
    solid = texel_solid_angles(HEIGHT, WIDTH)[:, None, None]
    lost = ((pixels - result.rest) * solid).sum(axis=(0, 1))
    carried = sum(light.power for light in result.lights)
    np.testing.assert_allclose(lost, carried, rtol=1e-6)


def test_count_zero_target_and_bad_arguments():
    pixels = disc_world(TWO_SUNS)
    none = core_lights.extract_lights(pixels, count=0)
    assert none.lights == [] and len(none.errors) == 1
    np.testing.assert_allclose(none.coefficients, project_equirect(pixels))
    one = core_lights.extract_lights(pixels, count=8, error_target=0.9 * none.errors[0][0])
    assert len(one.lights) == 1 and one.errors[-1][0] <= 0.9 * none.errors[0][0]
    for bad in (-1, 9, 1.5, "3", "x", None, float("nan"), True):
        with pytest.raises(ValueError, match="whole number from 0 to 8"):
            core_lights.extract_lights(pixels, count=bad)
    for bad in (0.0, "x", float("nan"), [0.1]):
        with pytest.raises(ValueError, match="error target must be a fraction above 0"):
            core_lights.extract_lights(pixels, error_target=bad)
    for bad in ("x", None, float("inf"), 0.0):
        with pytest.raises(ValueError, match="size limit must be above 0° and at most 120°"):
            core_lights.extract_lights(pixels, max_radius=bad)


def test_uniform_sky_has_no_light():
    result = core_lights.extract_lights(disc_world([]), count=3)
    assert result.lights == []


def test_a_world_without_blue_and_a_black_world_extract():
    """A channel with no light has no relative error: it is left out, not refused."""
    pixels = disc_world(TWO_SUNS)
    pixels[..., 2] = 0.0  # no blue anywhere
    result = core_lights.extract_lights(pixels, count=2)
    assert len(result.lights) == 2
    for light in result.lights:
        assert light.colour[2] == 0.0 and light.colour.max() == 1.0
    # the errors are those of the red and green channels alone
    normals = spread_normals(512)
    truth = equirect_irradiance(pixels, normals)
    power = total_power(project_equirect(pixels))[:2]
    rebuilt = irradiance(result.coefficients, normals) + core_lights.light_irradiance(
        result.lights, normals)
    assert result.errors[-1] == pytest.approx(relative_error(rebuilt[:, :2], truth[:, :2], power))
    assert result.errors[-1][0] < 0.1 * result.errors[0][0]
    black = core_lights.extract_lights(np.zeros((HEIGHT, WIDTH, 3), np.float32), count=2)
    assert black.lights == [] and black.errors == [(0.0, 0.0)]
    assert black.stop_kind == core_lights.DARK and black.stop == "the image has no light"


def _dilated_by_rolls(region, touches_top, touches_bottom):
    """The 8-neighbour dilation of a whole band by shifted copies (the slow reference)."""
    out = region.copy()
    out[1:] |= region[:-1]
    out[:-1] |= region[1:]
    rows = out.copy()
    out |= np.roll(rows, 1, axis=1) | np.roll(rows, -1, axis=1)
    half = region.shape[1] // 2
    if touches_top:
        out[0] |= np.roll(region[0], half)
    if touches_bottom:
        out[-1] |= np.roll(region[-1], half)
    return out


@pytest.mark.parametrize("width", [24, 25])
def test_the_component_grown_from_its_newest_texels_is_that_of_whole_band_dilations(width):
    """_connected grows only from the texels found last; it must give the component that
    repeated dilations of the whole band give, across the longitude seam and the poles."""
    rng = np.random.default_rng(7)
    for trial in range(40):
        mask = rng.random((9, width)) < 0.45
        top, bottom = bool(trial % 2), bool(trial % 3 == 0)
        seed = (int(rng.integers(9)), int(rng.integers(width)))
        mask[seed] = True
        expected = np.zeros_like(mask)
        expected[seed] = True
        while True:
            grown = _dilated_by_rolls(expected, top, bottom) & mask
            if np.array_equal(grown, expected):
                break
            expected = grown
        assert np.array_equal(core_lights._connected(mask, seed, top, bottom), expected)
        assert np.array_equal(core_lights._dilate(expected, top, bottom),
                              _dilated_by_rolls(expected, top, bottom))


def test_the_luminance_updated_in_row_blocks_is_a_whole_new_one():
    rng = np.random.default_rng(3)
    pixels = rng.random((600, 40, 4), dtype=np.float32)
    weights = np.array([0.2126, 0.7152, 0.0722])
    lum = core_lights._luminance(pixels, weights)
    pixels[300:310, 5:9, :3] = 0.5
    core_lights._luminance(pixels, weights, lum, slice(300, 310))
    assert np.array_equal(lum, core_lights._luminance(pixels, weights))


def test_a_light_that_does_not_help_leaves_the_rest_as_the_map():
    """Lights are tried on the rest without a copy of it: one refused (a halo, NO_GAIN) or
    none found must leave the rest equal to the input; the rest's coefficients, updated by
    the change at the lights' texels, are its projection to rounding (1e-13 of the largest)."""
    pixels = disc_world(TWO_SUNS)
    # at a normal perpendicular to the first sun the second one does not lower the error
    side = np.array([[1.0, 0.0, -1.0]]) / np.sqrt(2.0)
    for count, normals, kind in ((0, None, "COUNT"), (1, None, "COUNT"), (4, None, "CONTRAST"),
                                 (4, side, "NO_GAIN")):
        result = core_lights.extract_lights(pixels, count=count, normals=normals)
        assert result.stop_kind == kind and len(result.lights) == min(count, 2 - (kind == "NO_GAIN"))
        rest = pixels.copy()
        for light in result.lights:
            rest = core_lights.remove_light(rest, light)
        assert np.array_equal(result.rest, rest)
        projected = project_equirect(rest)
        np.testing.assert_allclose(result.coefficients, projected, rtol=0,
                                   atol=1e-13 * np.abs(projected).max())
        if not result.lights:
            assert np.array_equal(result.coefficients, projected)


def test_what_the_caller_made_gives_the_same_extraction_without_the_copy():
    """The map's own coefficients and the estimate's downsample passed in, and no rest kept
    (the command line's ``hdri_lights``): the same lights, errors and coefficients."""
    from sh_lighting.core.irradiance import bounded_error_estimate

    pixels = disc_world(TWO_SUNS)[::-1]  # a flipped view, as Blender's readback
    coeffs = project_equirect(pixels)
    made = bounded_error_estimate(pixels, coeffs, 64, reference_width=128)["downsample"]
    assert made is not None and made[0].shape == (64, 128, 3)
    plain = core_lights.extract_lights(pixels, count=4)
    lean = core_lights.extract_lights(pixels, count=4, coefficients=coeffs, keep_rest=False,
                                      downsample=made)
    assert lean.rest is None and plain.rest is not None and len(lean.lights) == 2
    assert lean.errors == plain.errors and lean.stop == plain.stop
    assert np.array_equal(lean.coefficients, plain.coefficients)
    for a, b in zip(lean.lights, plain.lights):
        assert np.array_equal(a.mask, b.mask) and np.array_equal(a.irradiance, b.irradiance)
