"""The world's prefiltered glossy maps and the split-sum fit (core.glossy), each against an
independent numerical integration."""

from math import pi

import numpy as np
import pytest

from sh_lighting.core.equirect import texel_directions
from sh_lighting.core.glossy import (
    LEVEL_WIDTHS,
    ROUGHNESS_LEVELS,
    dominant_factor,
    environment_brdf,
    environment_brdf_table,
    level_maps,
)
from sh_lighting.core.rotation import euler_xyz_matrix

from .quadrature import sphere_rule

SUN = np.array([0.6, -0.3, 0.5]) / np.linalg.norm([0.6, -0.3, 0.5])


def image_radiance(d):
    """A smooth sky with a soft bright spot (image directions d, (..., 3) → (...,))."""
    return 1.0 + 0.5 * d[..., 2] + 0.3 * d[..., 0] + 20.0 * np.exp(12.0 * (d @ SUN - 1.0))


def prefiltered(world, directions, alpha, rule):
    """P_α by Gauss-Legendre × trapezoid quadrature of the GGX lobe (core.specular's
    definition, written out again): Σ L D max(R·ω, 0) w / Σ D max(R·ω, 0) w."""
    omega, weights = rule
    c = directions @ omega.T  # (n, N)
    lobe = np.maximum(c, 0.0) / ((alpha * alpha - 1.0) * (1.0 + c) / 2.0 + 1.0) ** 2 * weights
    return (lobe @ world(omega)) / lobe.sum(axis=1)


def test_level_maps_match_a_quadrature_of_the_rotated_world():
    pixels = np.repeat(image_radiance(texel_directions(512, 1024))[..., None], 3, axis=-1)
    euler, strength = (0.3, -0.2, 1.1), 1.7
    rotation = euler_xyz_matrix(np.array(euler))
    maps = level_maps(pixels, strength, euler)
    rule = sphere_rule(400, 800)
    rng = np.random.default_rng(3)
    for r, width, level in zip(ROUGHNESS_LEVELS, LEVEL_WIDTHS, maps):
        assert level.shape == (width // 2, width, 3)
        if r == 0.0:
            continue  # a mirror: the world's mean per texel, checked below by its total
        rows = rng.integers(0, width // 2, 40)
        cols = rng.integers(0, width, 40)
        d = texel_directions(width // 2, width)[rows, cols]
        # the world shows the image looked up at R d (docs/reference.md §3), times Strength
        expected = prefiltered(lambda w: strength * image_radiance(w @ rotation.T), d, r * r,
                               rule)
        got = level[rows, cols, 0]
        print(f"r = {r}: largest relative error {np.max(np.abs(got / expected - 1)):.4f}")
        assert got == pytest.approx(expected, rel=0.02)
    # the mirror level: the same light as the world (its solid-angle weighted mean)
    mirror = maps[0][..., 0].astype(np.float64)
    h, w = mirror.shape
    solid = np.cos(np.arange(h) * pi / h) - np.cos((np.arange(h) + 1) * pi / h)
    mean = (mirror * solid[:, None]).sum() / (solid.sum() * w)
    omega, weights = rule
    truth = strength * (image_radiance(omega) * weights).sum() / weights.sum()
    assert mean == pytest.approx(truth, rel=2e-3)


def ggx_hemisphere(roughness, n_dot_v, steps):
    """The midpoint grid over the light hemisphere (normal z, view in the xz plane): light
    directions (steps, 2·steps, 3), the view v, v·h, θ, and the single-scattering GGX D G / (4 n·v)
    (α = r², separable Smith G) at each."""
    alpha2 = roughness ** 4
    v = np.array([np.sqrt(1 - n_dot_v ** 2), 0.0, n_dot_v])
    theta = (np.arange(steps) + 0.5) * (pi / 2 / steps)
    phi = (np.arange(2 * steps) + 0.5) * (2 * pi / (2 * steps))
    t, p = np.meshgrid(theta, phi, indexing="ij")
    light = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    half = light + v
    half /= np.linalg.norm(half, axis=-1, keepdims=True)
    nh, vh, nl = half[..., 2], half @ v, light[..., 2]
    d = alpha2 / (pi * (nh * nh * (alpha2 - 1) + 1) ** 2)

    def g1(c):
        return 2 * c / (c + np.sqrt(alpha2 + (1 - alpha2) * c * c))

    return light, v, vh, t, d * g1(nl) * g1(n_dot_v) / (4 * n_dot_v)


def split_sum(roughness, n_dot_v, steps=600):
    """(A, B) integrated numerically: ∫ D G /(4 n·v) (1 − F_c or F_c) over the light
    hemisphere, F_c = (1 − v·h)⁵, GGX α = r², separable Smith G (midpoint rule)."""
    light, v, vh, t, f = ggx_hemisphere(roughness, n_dot_v, steps)
    # f times n·l dω = n·l sin θ dθ dφ
    measure = np.sin(t) * (pi / 2 / steps) * (2 * pi / (2 * steps))
    fresnel = (1 - np.clip(vh, 0, 1)) ** 5
    return float((f * (1 - fresnel) * measure).sum()), float((f * fresnel * measure).sum())


@pytest.mark.parametrize("roughness, n_dot_v", [(0.25, 0.9), (0.5, 0.9), (0.5, 0.4),
                                                (0.8, 0.7), (1.0, 0.5), (0.5, 0.1)])
def test_environment_brdf_matches_a_uniform_quadrature(roughness, n_dot_v):
    a, b = environment_brdf(roughness, n_dot_v)
    a_ref, b_ref = split_sum(roughness, n_dot_v)
    print(f"r {roughness}, n·v {n_dot_v}: {a:.4f} {b:.4f}, uniform grid {a_ref:.4f} {b_ref:.4f}")
    assert a == pytest.approx(a_ref, abs=0.01) and b == pytest.approx(b_ref, abs=0.005)


def test_environment_brdf_table_layout_and_mirror_limit():
    table = environment_brdf_table(4)
    assert table.shape == (4, 4, 2)
    # row j: r = (j + ½)/4, column i: n·v = (i + ½)/4
    assert tuple(table[2, 1]) == pytest.approx(environment_brdf(0.625, 0.375), abs=1e-6)
    mu = 0.3
    assert environment_brdf(0.0, mu) == pytest.approx((1 - (1 - mu) ** 5, (1 - mu) ** 5))


def lobe_mean_direction(roughness, n_dot_v, steps=600):
    """The mean light direction of the single-scattering GGX lobe f n·l (with Schlick's
    Fresnel at F0 = 0.8, the bench's metal) over the hemisphere (midpoint rule; normal z,
    view in the xz plane), normalized."""
    light, v, vh, t, f = ggx_hemisphere(roughness, n_dot_v, steps)
    fresnel = 0.8 + 0.2 * (1 - np.clip(vh, 0, 1)) ** 5
    weight = f * fresnel * np.sin(t)  # f n·l dω
    mean = (weight[..., None] * light).sum(axis=(0, 1))
    return mean / np.linalg.norm(mean), v


@pytest.mark.parametrize("roughness", [0.3, 0.5, 0.7])
@pytest.mark.parametrize("n_dot_v", [0.9, 0.5, 0.2])
def test_dominant_direction_is_nearer_the_lobe_than_the_mirror(roughness, n_dot_v):
    """The split sum looks the maps up at N + t (R − N) (dominant_factor): nearer the GGX
    lobe's mean direction than the mirror direction R, by at least a quarter of R's angle
    from it, or within 1° of it (near-normal view of a smooth surface, where R is within
    0.4°); t = 1 for a mirror, 0 at roughness 1."""
    mean, v = lobe_mean_direction(roughness, n_dot_v)
    normal = np.array([0.0, 0.0, 1.0])
    mirror = 2 * n_dot_v * normal - v
    lean = normal + dominant_factor(roughness) * (mirror - normal)
    lean /= np.linalg.norm(lean)

    def angle(a):
        return float(np.degrees(np.arccos(np.clip(a @ mean, -1, 1))))

    print(f"r {roughness}, n·v {n_dot_v}: mirror {angle(mirror):.1f}°, "
          f"dominant {angle(lean):.1f}° from the lobe's mean")
    assert angle(lean) < max(0.75 * angle(mirror), 1.0)
    assert dominant_factor(0.0) == 1.0 and dominant_factor(1.0) == 0.0


def test_mirror_level_of_a_large_rotated_world_has_no_holes():
    """A world wider than SOURCE_WIDTH is box-averaged to it first (no float64 copy of the
    whole map); the mirror level's texels that no source texel centre falls in (near the poles
    of the rotated map) are looked up instead of left black (50 were, before). Each texel
    within 3 % of the world at its centre (a texel's mean of a smooth sky), 6 % in the four
    rows nearest each pole, whose texels are narrower than the source's (5 % before too)."""
    pixels = np.repeat(image_radiance(texel_directions(1024, 2048))[..., None], 3,
                       axis=-1).astype(np.float32)
    euler = (0.3, -0.2, 1.1)
    rotation = euler_xyz_matrix(np.array(euler))
    mirror = level_maps(pixels, 1.0, euler)[0][..., 0]
    height, width = mirror.shape
    truth = image_radiance(texel_directions(height, width) @ rotation.T)
    print(f"mirror level: {np.count_nonzero(mirror == 0)} black texels, largest relative "
          f"error {np.max(np.abs(mirror / truth - 1)):.4f}")
    assert np.count_nonzero(mirror == 0) == 0
    assert mirror[4:-4] == pytest.approx(truth[4:-4], rel=0.03)
    assert mirror == pytest.approx(truth, rel=0.06)
