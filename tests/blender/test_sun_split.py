"""Sun detection and the sun + SH split on the 8 HDRIs that ship inside bpy.

Errors of the irradiance against brute force (eq. 1), as a fraction of the map's total power:
(a) plain 9-term SH, (b) the detected sun as a Blender Sun light + 9-term SH of the rest,
(c) the EEVEE-style split (sun above World.sun_threshold = 10, order-1 SH for the rest).

Which maps have a sun was decided from the data (detect_sun's defaults: contrast 100 × the
median, radius < 5°, ≥ 2 % of the power). city, sunrise: the sun; interior: the sun through a
window; forest: the sun through the leaves; night: a small orange lamp; sunset: the sun on the
horizon, only 2.3 % of the power. courtyard: no texel stands out enough for its power to
matter (the brightest region holds 0.4 %); studio: its brightest source is a softbox more than
10° across, not a sun.

The split always lowers the worst-case error (the ringing of the strong source is gone). The
mean error can rise a little when the sun holds a modest share of the light, because the SH
errors of the sun and of the rest partly cancel in the plain fit. The maps differ between
Blender versions (printed by this test with -s, mean/max % of power, plain SH9 → sun+SH9):

* Blender 4.2.23: interior's sun holds 12.5 % of the power, mean 0.70 → 0.80, max 2.54 → 2.05
  (the only map whose mean rises; forest 6.4 %: mean 0.81 → 0.60; sunset 2.3 %: 0.52 → 0.35).
* Blender 5.0.1: interior's sun holds 21.5 %, mean 0.69 → 0.47, max 2.20 → 1.58; the mean
  drops on every map with a sun (forest 6.4 %: 0.81 → 0.60; sunset 2.3 %: 0.51 → 0.35).

So the mean is asserted to drop where the sun carries a fifth of the light or more, and on
every map with a sun from Blender 5.0 on.
"""

from math import pi

import bpy
import numpy as np
import pytest
from conftest import HDRI_NAMES
from quadrature import random_directions

from sh_lighting.blender.world.images import load_image_pixels
from sh_lighting.core.projection import project_equirect
from sh_lighting.core.sun import detect_sun, remove_sun, sun_split_error

pytestmark = pytest.mark.blender
NORMALS = random_directions(128, seed=11)
DOMINANT = 0.2  # a sun holding this share of the power or more lowers the mean error too
HAS_SUN = {"city", "forest", "interior", "night", "sunrise", "sunset"}


@pytest.mark.parametrize("name", HDRI_NAMES)
def test_sun_split_on_bundled_hdri(name, hdri_dir, capsys):
    pixels = load_image_pixels(hdri_dir / f"{name}.exr")
    sun = detect_sun(pixels)
    errors = sun_split_error(pixels, NORMALS, sun=sun)
    with capsys.disabled():
        if sun is None:
            found = "no sun"
        else:
            elevation = np.degrees(np.arcsin(sun.direction[2]))
            found = (
                f"sun at elevation {elevation:.1f}°, diameter "
                f"{np.degrees(sun.angular_diameter):.2f}°, strength {sun.strength:.2f} W/m², "
                f"colour {np.round(sun.colour, 2)}, {100 * sun.power_fraction:.1f} % of power"
            )
        print(
            f"\n  {name:10s} {found}\n  {'':10s} error mean/max % of power: "
            f"plain SH9 {100 * errors.plain_mean:.2f}/{100 * errors.plain_max:.2f}, "
            f"sun+SH9 {100 * errors.sun_mean:.2f}/{100 * errors.sun_max:.2f}, "
            f"EEVEE-style {100 * errors.eevee_mean:.2f}/{100 * errors.eevee_max:.2f}"
        )
    assert (sun is not None) == (name in HAS_SUN)
    if sun is None:
        assert (errors.sun_mean, errors.sun_max) == (errors.plain_mean, errors.plain_max)
        return
    assert errors.sun_max < errors.plain_max
    if sun.power_fraction >= DOMINANT or bpy.app.version >= (5, 0, 0):
        assert errors.sun_mean < errors.plain_mean
    assert np.degrees(sun.angular_diameter) < 10.0
    # sun + rest = the map's power, channel by channel: ΔL00 / Y00 = the sun's irradiance
    y00 = 0.5 / np.sqrt(pi)
    taken = (project_equirect(pixels)[0] - project_equirect(remove_sun(pixels, sun))[0]) / y00
    assert np.abs(taken - sun.irradiance).max() < 1e-5 * sun.strength
