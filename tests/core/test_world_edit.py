"""core.world_edit: the clamped edited world, measured on a map."""

import numpy as np

from sh_lighting.core.projection import project_equirect
from sh_lighting.core.world_edit import clamped_edit

EULER = (0.3, -0.2, 1.1)


def _map():
    rng = np.random.default_rng(3)
    return (0.5 + rng.random((32, 64, 3))).astype(np.float32)


def test_unclamped_edit_projects_to_the_designed_terms():
    pixels = _map()
    from sh_lighting.core.world_map import map_coefficients

    own = map_coefficients(pixels, 1.5, EULER)
    delta = np.zeros((9, 3))
    delta[2] = 0.2
    delta[3] = (-0.1, 0.0, 0.1)
    result = clamped_edit(pixels, 1.5, EULER, delta, True, own + delta)
    assert result.share == 0.0 and result.texels == 0.0
    assert result.difference < 1e-3  # the discrete projection of Y_lm, nothing else


def test_clamp_is_measured():
    pixels = _map()
    own = project_equirect(pixels)
    delta = np.zeros((9, 3))
    delta[2] = -4.0 * own[0]  # far darker below than the map
    result = clamped_edit(pixels, 1.0, None, delta, True, own + delta)
    assert 0.1 < result.texels < 0.6
    assert result.share > 0.01 and result.difference > 0.05
    replaced = clamped_edit(pixels, 1.0, None, own, False, own)  # k = 0: the nine terms alone
    assert replaced.share == 0.0 and replaced.difference < 1e-3
