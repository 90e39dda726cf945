"""The lightings and normals every client is checked with, and the deviation measure.

* ``texel``: one bright texel (coloured, so the channels differ) at the generic direction
  (0.58, −0.61, 0.53) in Blender axes, so that every axis and sign is tested;
* ``forest`` and ``sunset``: two HDRIs shipped inside bpy (a sky with sun; a low sun);
* ``signed``: arbitrary coefficients, negative parts included (three.js and Filament only take
  coefficients; its glTF specular cube is made from its 9-term radiance).

Deviation: the largest |client − E(n)/π| over the normals and channels, as a fraction of the
largest |E(n)/π| (the peak).
"""

from functools import lru_cache
from math import pi

import numpy as np

from sh_lighting.core import irradiance
from sh_lighting.core.equirect import direction_to_texel, texel_directions
from sh_lighting.core.frames import BLENDER_TO_Y_UP
from sh_lighting.core.projection import project_equirect
from sh_lighting.core.sh import spread_normals

NAMES = ("texel", "forest", "sunset", "signed")
WITH_IMAGE = ("texel", "forest", "sunset")
TEXEL_DIRECTION = np.array([0.58, -0.61, 0.53]) / np.linalg.norm([0.58, -0.61, 0.53])
TEXEL_MAP_SIZE = (128, 256)
NORMALS = spread_normals(512)  # Blender axes
GLTF_NORMALS = NORMALS @ BLENDER_TO_Y_UP.T
TOLERANCE = 1e-5  # of the peak


def texel_map():
    pixels = np.zeros(TEXEL_MAP_SIZE + (3,))
    row, col = direction_to_texel(TEXEL_DIRECTION, *TEXEL_MAP_SIZE)
    pixels[row, col] = (100.0, 80.0, 60.0)
    return pixels, texel_directions(*TEXEL_MAP_SIZE)[row, col]


@lru_cache(maxsize=None)
def lighting(name):
    """(coefficients (9, 3), equirect pixels or None) of a named lighting."""
    if name == "texel":
        pixels = texel_map()[0]
    elif name == "signed":
        return np.random.default_rng(13).normal(size=(9, 3)), None
    else:
        from conftest import bundled_hdri_dir
        from sh_lighting.blender.world.images import load_image_pixels

        pixels = load_image_pixels(bundled_hdri_dir() / f"{name}.exr")[..., :3]
    return project_equirect(pixels), pixels


def expected(coeffs, normals=NORMALS):
    """What a white Lambertian surface shows: E(n)/π, (N, 3)."""
    return irradiance(coeffs, normals) / pi


def deviation(client, coeffs, normals=NORMALS):
    ours = expected(coeffs, normals)
    return float(np.abs(np.asarray(client) - ours).max() / np.abs(ours).max())
