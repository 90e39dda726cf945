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
    equirect_irradiance,
    map_coefficients,
    map_irradiance,
    mapping_rotation,
    sun_light_rotation,
    to_world_direction,
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
