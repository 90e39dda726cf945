"""The world map as Blender shows it, and the Sun light's orientation (world_map.py)."""

import numpy as np
import pytest
from quadrature import random_directions

from sh_lighting.core.equirect import texel_directions
from sh_lighting.core.irradiance import irradiance, reference_irradiance
from sh_lighting.core.projection import project_equirect
from sh_lighting.core.rotation import euler_xyz_matrix, rotate_coefficients
from sh_lighting.core.sh import spread_normals
from sh_lighting.core.world_map import (
    average_down,
    equirect_irradiance,
    map_coefficients,
    map_irradiance,
    mapping_rotation,
    sun_light_rotation,
    to_world_direction,
    world_error,
)

EXACT = 1e-12
EULER = (0.4, -1.1, 2.3)
STRENGTH = 1.7
# A 128×256 map holds each texel's value as a constant: the projection of a smooth radiance
# sampled at texel centres is off by O(texel²) (measured ~4e-5 relative here).
SAMPLING = 5e-4
# equirect_irradiance adds the brute force's terms in another order: float64 rounding.
REORDERED = 1e-13


def smooth_radiance(d):
    """A positive radiance with bands 0 to 2 and no symmetry: (..., 3)."""
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    r = 2.0 + 0.7 * x - 0.3 * y + 0.5 * z + 0.4 * x * z
    g = 1.5 + 0.2 * x + 0.6 * y * z - 0.3 * (x * x - y * y)
    b = 1.0 - 0.4 * z + 0.3 * x * y + 0.2 * z * z
    return np.stack([r, g, b], axis=-1)


def test_mapping_rotation_is_the_transpose_of_the_lookup_rotation():
    assert np.array_equal(mapping_rotation(None), np.eye(3))
    r = mapping_rotation(EULER)
    assert np.abs(r - euler_xyz_matrix(EULER).T).max() < EXACT
    assert np.abs(r @ r.T - np.eye(3)).max() < EXACT
    assert np.linalg.det(r) == pytest.approx(1.0, abs=EXACT)


def test_a_feature_of_the_image_appears_where_the_lookup_reads_it():
    omega = random_directions(20, seed=3)
    world = to_world_direction(omega, EULER)
    # Blender shows at world direction d the image at R d (R the Mapping node's rotation)
    assert np.abs(world @ euler_xyz_matrix(EULER).T - omega).max() < EXACT
    assert np.abs(to_world_direction(omega, None) - omega).max() == 0.0


def world_pixels(height, width, euler, strength):
    """The world sampled directly: texel d holds strength · L_image(R d)."""
    d = texel_directions(height, width)
    return strength * smooth_radiance(d @ euler_xyz_matrix(euler).T)


def test_map_coefficients_equal_the_world_sampled_directly():
    image = smooth_radiance(texel_directions(128, 256))
    got = map_coefficients(image, STRENGTH, EULER)
    direct = project_equirect(world_pixels(128, 256, EULER, STRENGTH))
    assert np.abs(got - direct).max() < SAMPLING * np.abs(direct).max()
    # and exactly the image's coefficients, scaled and rotated by Rᵀ
    expected = rotate_coefficients(project_equirect(image) * STRENGTH, euler_xyz_matrix(EULER).T)
    assert np.abs(got - expected).max() < EXACT * np.abs(expected).max()
    assert np.abs(map_coefficients(image) - project_equirect(image)).max() == 0.0


def test_map_irradiance_is_the_worlds_brute_force_irradiance():
    image = smooth_radiance(texel_directions(128, 256))
    normals = random_directions(50, seed=5)
    got = map_irradiance(image, normals, STRENGTH, EULER)
    direct = reference_irradiance(world_pixels(128, 256, EULER, STRENGTH), normals)
    assert np.abs(got - direct).max() < SAMPLING * np.abs(direct).max()
    # radiance of bands ≤ 2 only: the 9-term irradiance of the same world is the same
    nine = irradiance(map_coefficients(image, STRENGTH, EULER), normals)
    assert np.abs(got - nine).max() < SAMPLING * np.abs(direct).max()
    plain = map_irradiance(image, normals)
    expected = reference_irradiance(image, normals)
    assert np.abs(plain - expected).max() < REORDERED * np.abs(expected).max()


AXES = [(0, 0, 1), (0, 0, -1), (1, 0, 0), (0, -1, 0), (1e-13, 0.0, 1.0), (0.6, 0.8, 0.0)]


@pytest.mark.parametrize(("height", "width"), [(32, 64), (33, 64), (7, 10), (1, 4)])
def test_equirect_irradiance_equals_the_brute_force_sum(height, width):
    rng = np.random.default_rng(height)
    pixels = rng.normal(1.0, 1.5, (height, width, 4))  # signed, as real HDRIs can be
    pixels[rng.integers(height), rng.integers(width), :3] = 500.0  # a sun
    axes = np.array(AXES, dtype=float)
    normals = np.concatenate([random_directions(200, seed=1), spread_normals(50),
                              axes / np.linalg.norm(axes, axis=1, keepdims=True)])
    expected = reference_irradiance(pixels, normals)
    got = equirect_irradiance(pixels, normals)
    assert got.shape == (len(normals), 3)
    assert np.abs(got - expected).max() < REORDERED * np.abs(expected).max()
    grid = normals[:12].reshape(3, 4, 3)  # any leading shape
    assert equirect_irradiance(pixels, grid).shape == (3, 4, 3)


def test_equirect_irradiance_of_a_constant_sky_is_pi_c():
    got = equirect_irradiance(np.full((64, 128, 3), 0.7), random_directions(30, seed=2))
    # the texel centres' n·ω only approximate the cosine: O(texel²)
    assert np.abs(got - np.pi * 0.7).max() < 1e-3


def test_equirect_irradiance_rejects_bad_input():
    with pytest.raises(ValueError, match="non-finite"):
        equirect_irradiance(np.full((4, 8, 3), np.nan), [[0.0, 0.0, 1.0]])
    with pytest.raises(ValueError, match="normals"):
        equirect_irradiance(np.ones((4, 8, 3)), [[0.0, 1.0]])


def test_spread_normals_are_unit_uniform_and_fixed():
    n = spread_normals(256)
    assert n.shape == (256, 3)
    assert np.abs(np.linalg.norm(n, axis=1) - 1.0).max() < EXACT
    assert np.array_equal(n, spread_normals(256))
    assert np.abs(n[:, 2] - (1.0 - 2.0 * (np.arange(256) + 0.5) / 256)).max() < EXACT
    # equal-area points: the first and second moments are those of the uniform sphere
    assert np.abs(n.mean(axis=0)).max() < 0.01
    assert np.abs(n.T @ n / 256 - np.eye(3) / 3.0).max() < 0.01
    with pytest.raises(ValueError, match="whole number"):
        spread_normals(0)


@pytest.mark.parametrize(
    "direction",
    [(0.3, -0.5, 0.8), (-0.9, 0.1, -0.2), (0.0, 0.0, 1.0), (0.0, 0.0, -1.0), (1e-12, 0.0, 1.0)],
)
def test_sun_light_rotation_points_minus_z_away_from_the_sun(direction):
    s = np.asarray(direction) / np.linalg.norm(direction)
    r = sun_light_rotation(direction)
    assert np.abs(r @ r.T - np.eye(3)).max() < EXACT
    assert np.linalg.det(r) == pytest.approx(1.0, abs=EXACT)
    assert np.abs(r @ [0.0, 0.0, -1.0] + s).max() < EXACT  # the light shines along −s
    if np.hypot(s[0], s[1]) > 1e-6:
        assert abs(r[2, 0]) < EXACT  # its X axis is horizontal: no roll
    else:  # (nearly) straight up or down: X is (nearly) +X
        assert np.abs(r[:, 0] - [1.0, 0.0, 0.0]).max() < 1e-9


def test_sun_light_rotation_rejects_a_zero_direction():
    with pytest.raises(ValueError, match="non-zero"):
        sun_light_rotation((0.0, 0.0, 0.0))


# -- the 9-term error against the world (the Compute button's report) --------------------------


def one_hot(height=64, width=128, row=20, column=77, value=500.0):
    pixels = np.zeros((height, width, 3))
    pixels[row, column] = value
    return pixels


def test_average_down_keeps_the_integral_and_leaves_small_maps_alone():
    rng = np.random.default_rng(5)
    pixels = rng.random((64, 128, 3)) * 10.0 ** rng.uniform(-3, 3, (64, 128, 3))
    assert average_down(pixels, 128) is pixels
    coarse = average_down(pixels, 32)
    assert coarse.shape == (16, 32, 3)
    # L00 is the integral: unchanged to rounding; higher bands move by where light sits
    # inside a 4×4 block
    fine_l, coarse_l = project_equirect(pixels), project_equirect(coarse)
    np.testing.assert_allclose(coarse_l[0], fine_l[0], rtol=1e-13)
    assert np.abs(coarse_l - fine_l).max() < 0.05 * np.abs(fine_l).max()
    assert average_down(pixels[:63], 32) is not None  # odd height: no block size divides it
    assert average_down(pixels[:63], 32).shape == (63, 128, 3)


def test_world_error_of_a_near_delta_is_the_known_one_through_the_mapping():
    """docs/reference.md §2: a directional source's 9-term error is 0.0307 P on average and
    3/32 P at most; the world seen through a Mapping rotation and a Strength has the same
    relative error, and the rotation must be the world's (the unrotated truth is far off)."""
    pixels = one_hot()
    normals = spread_normals(256)
    coeffs = map_coefficients(pixels, STRENGTH, EULER)
    mean, largest = world_error(pixels, coeffs, normals, STRENGTH, EULER)
    assert 0.028 < mean < 0.033 and 0.085 < largest <= 3 / 32 + 1e-9
    wrong_mean, _ = world_error(pixels, coeffs, normals, STRENGTH, None)
    assert wrong_mean > 3 * mean


def test_world_error_of_a_map_averaged_down_by_two_moves_little():
    """A 512-wide near-delta (0.7° texels) measured at 256 wide: the hardest case for
    averaging, all the light in one texel; measured 0.17 % (mean) and 1.5 % (max) of the
    error itself."""
    pixels = one_hot(256, 512, 79, 307)
    normals = spread_normals(256)
    coeffs = map_coefficients(pixels, STRENGTH, EULER)
    fine = world_error(pixels, coeffs, normals, STRENGTH, EULER)
    coarse = world_error(pixels, coeffs, normals, STRENGTH, EULER, max_width=256)
    assert abs(coarse[0] - fine[0]) < 0.01 * fine[0]
    assert abs(coarse[1] - fine[1]) < 0.03 * fine[1]


def test_world_error_is_none_without_light_in_a_channel():
    pixels = one_hot()
    pixels[..., 2] = 0.0
    assert world_error(pixels, project_equirect(pixels), spread_normals(16)) is None
