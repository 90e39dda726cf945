"""Mirror-ball mapping (Cycles' convention) and projection of mirror-ball images."""

from math import pi, sqrt

import numpy as np
import pytest

from sh_lighting.core.mirror_ball import (
    direction_to_mirror_ball,
    mirror_ball_to_direction,
    mirror_ball_weights,
    project_mirror_ball,
)
from sh_lighting.core.rotation import euler_xyz_matrix, rotate_coefficients
from sh_lighting.core.sh import sh_basis

LIGHT = np.array(
    [[3.0, 2.0, 1.0], [0.5, 0.0, 0.0], [0.0, 0.7, 0.0], [0.0, 0.0, 0.9], [0.2, 0.0, 0.0],
     [0.0, -0.3, 0.0], [0.1, 0.1, 0.1], [0.1, 0.1, 0.4], [-0.2, 0.0, 0.2]]
)


def ball_of(function, size):
    """A size² mirror-ball image (rows top to bottom) of radiance ``function(directions)``."""
    centres = (np.arange(size) + 0.5) / size
    u, v = np.meshgrid(centres, 1.0 - centres)
    d = mirror_ball_to_direction(u, v)
    inside = np.isfinite(d[..., 0])
    pixels = np.zeros((size, size, 3))
    pixels[inside] = function(d[inside])
    return pixels


def rel_err(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


def test_centre_shows_minus_y_and_rim_shows_plus_y():
    assert np.allclose(mirror_ball_to_direction(0.5, 0.5), [0.0, -1.0, 0.0])
    for u, v in [(1.0, 0.5), (0.0, 0.5), (0.5, 1.0), (0.5, 0.0)]:
        assert np.allclose(mirror_ball_to_direction(u, v), [0.0, 1.0, 0.0], atol=1e-12)
    # Half-way out to the right (normal at 30°): a ray turned by 60°, towards +x.
    d = mirror_ball_to_direction(0.75, 0.5)
    assert np.allclose(d, [sqrt(3.0) / 2.0, -0.5, 0.0])
    assert np.allclose(mirror_ball_to_direction(0.5, 0.75), [0.0, -0.5, sqrt(3.0) / 2.0])
    assert np.isnan(mirror_ball_to_direction(0.95, 0.95)).all()


def test_directions_are_unit_and_round_trip():
    rng = np.random.default_rng(1)
    u, v = rng.random((2, 1000))
    keep = (2 * u - 1) ** 2 + (2 * v - 1) ** 2 < 0.999
    d = mirror_ball_to_direction(u[keep], v[keep])
    assert np.allclose(np.linalg.norm(d, axis=-1), 1.0)
    back_u, back_v = direction_to_mirror_ball(d)
    assert np.allclose(back_u, u[keep], atol=1e-9) and np.allclose(back_v, v[keep], atol=1e-9)


@pytest.mark.parametrize("size", [64, 256, 1024])
def test_constant_ball_gives_l00_only(size):
    """The map is equal-area (dΩ = 4 dA): a constant ball integrates to 4π; measured errors
    2e-5 (64), 3e-5 (256), 1.3e-6 (1024) on L00 and 3e-3, 2e-4, 2e-5 on the rest."""
    coeffs = project_mirror_ball(np.ones((size, size, 3)))
    assert abs(coeffs[0, 0] / (2.0 * sqrt(pi)) - 1.0) < 1e-4
    assert np.abs(coeffs[1:]).max() < {64: 5e-3, 256: 5e-4, 1024: 5e-5}[size]


def test_weights_of_texels_outside_the_disk_are_zero():
    w = mirror_ball_weights(32, 32)
    assert (w[0, 0] == 0).all() and (w[-1, -1] == 0).all()
    assert np.allclose(w.sum(axis=(0, 1))[0], 4.0 * pi * 0.5 * sqrt(1.0 / pi), rtol=1e-3)


@pytest.mark.parametrize("size", [128, 512])
def test_known_lighting_is_recovered(size):
    """A ball sampled from Σ L_lm Y_lm at texel centres gives back L_lm, to first order in the
    texel size: the image itself misplaces light near the rim, where one texel spans a wide
    range of directions (measured 6.9e-3 at 128, 2.5e-3 at 512, 5.9e-4 at 2048)."""
    coeffs = project_mirror_ball(ball_of(lambda d: sh_basis(d) @ LIGHT, size))
    assert rel_err(coeffs, LIGHT) < {128: 1e-2, 512: 4e-3}[size]


def test_rotated_lighting_gives_rotated_coefficients():
    r = euler_xyz_matrix((0.4, -1.0, 2.2))
    coeffs = project_mirror_ball(ball_of(lambda d: sh_basis(d @ r) @ LIGHT, 512))
    assert rel_err(coeffs, rotate_coefficients(LIGHT, r)) < 4e-3  # measured 1.2e-3


def test_non_square_ball_and_rgba():
    """A 2:1 image is an ellipse filling the frame: the same disk, stretched."""
    pixels = np.ones((128, 256, 4))
    pixels[..., 3] = 0.0
    coeffs = project_mirror_ball(pixels)
    assert abs(coeffs[0, 0] / (2.0 * sqrt(pi)) - 1.0) < 1e-3


def test_nonfinite_texels():
    pixels = np.ones((32, 32, 3))
    pixels[0, 0] = np.nan  # outside the disk: never read
    assert np.isfinite(project_mirror_ball(pixels)).all()
    pixels[16, 16] = np.inf
    with pytest.raises(ValueError, match="non-finite"):
        project_mirror_ball(pixels)
    zeroed = project_mirror_ball(pixels, nonfinite="zero")
    pixels[16, 16] = 0.0
    assert np.array_equal(zeroed, project_mirror_ball(pixels))
    with pytest.raises(ValueError, match="nonfinite"):
        project_mirror_ball(pixels, nonfinite="ignore")


def test_an_equirect_world_made_into_a_mirror_ball_keeps_its_lighting():
    from sh_lighting.core.equirect import texel_directions
    from sh_lighting.core.mirror_ball import mirror_ball_image
    from sh_lighting.core.projection import project_equirect

    world = sh_basis(texel_directions(128, 256)) @ LIGHT
    image = mirror_ball_image(world, 256)
    assert image.shape == (256, 256, 3) and not image[0, 0].any()  # a corner: no ball
    # The centre shows −Y, straight back at the camera.
    assert np.allclose(image[128, 128], sh_basis(np.array([0.0, -1.0, 0.0])) @ LIGHT, rtol=0.05)
    # Nearest texels of a 256×128 map: measured 0.50 % of the largest coefficient.
    assert rel_err(project_mirror_ball(image), project_equirect(world)) < 0.008
