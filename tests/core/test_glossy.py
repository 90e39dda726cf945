"""The world's prefiltered glossy maps and the split-sum fit (core.glossy), each against an
independent numerical integration."""

from math import pi

import numpy as np
import pytest

from sh_lighting.core.equirect import texel_directions
from sh_lighting.core.glossy import (
    LEVEL_WIDTHS,
    ROUGHNESS_LEVELS,
    effective_roughness,
    environment_brdf,
    environment_brdf_table,
    kernel_mean_cosine,
    level_maps,
    lobe_factor,
    lobe_mean,
)
from sh_lighting.core.rotation import euler_xyz_matrix

from quadrature import sphere_rule

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
    assert table.shape == (4, 4, 4)
    # row j: r = (j + ½)/4, column i: n·v = (i + ½)/4
    assert tuple(table[2, 1]) == pytest.approx(
        (*environment_brdf(0.625, 0.375), lobe_factor(0.625, 0.375),
         effective_roughness(0.625, 0.375)), abs=1e-6)
    mu = 0.3
    assert environment_brdf(0.0, mu) == pytest.approx((1 - (1 - mu) ** 5, (1 - mu) ** 5))


def lobe_mean_direction(roughness, n_dot_v, f0=None, steps=600):
    """The mean light direction of the single-scattering GGX lobe f n·l over the hemisphere
    (midpoint rule; normal z, view in the xz plane), unnormalized (its length the lobe's mean
    cosine to it), with Schlick's Fresnel at ``f0`` (None: none), and the view."""
    light, v, vh, t, f = ggx_hemisphere(roughness, n_dot_v, steps)
    fresnel = 1.0 if f0 is None else f0 + (1 - f0) * (1 - np.clip(vh, 0, 1)) ** 5
    weight = f * fresnel * np.sin(t)  # f n·l dω
    return (weight[..., None] * light).sum(axis=(0, 1)) / weight.sum(), v


def dominant_factor(roughness):
    """Lagarde and de Rousiers' view-independent fit of the lookup direction ("Moving
    Frostbite to Physically Based Rendering", 2014, "specular dominant direction"):
    t = s (√s + α), s = 1 − α, α = r², which the shader used before the table's t; here only
    the comparison the table's t is measured against."""
    alpha = roughness ** 2
    return (1.0 - alpha) * (np.sqrt(1.0 - alpha) + alpha)


def _degrees(a, b):
    return float(np.degrees(np.arccos(np.clip(a @ b / np.linalg.norm(a) / np.linalg.norm(b),
                                              -1, 1))))


@pytest.mark.parametrize("roughness", [0.3, 0.5, 0.7, 1.0])
@pytest.mark.parametrize("n_dot_v", [0.95, 0.5, 0.2, 0.05])
def test_lobe_mean_matches_a_uniform_quadrature(roughness, n_dot_v):
    """core.glossy.lobe_mean (GGX importance samples, TABLE_STEPS², the tail-heavy grid)
    against the midpoint rule over the hemisphere: the direction within 0.05°, the length
    within 0.001 (with the samples even in ξ, up to 0.7° and 0.037 apart at n·v 0.05; the
    midpoint rule's 600 × 1200 cells do not resolve r ≤ 0.2 there)."""
    got = lobe_mean(roughness, n_dot_v)
    expected, _ = lobe_mean_direction(roughness, n_dot_v)
    print(f"r {roughness}, n·v {n_dot_v}: {_degrees(got, expected):.3f}° apart, length "
          f"{np.linalg.norm(got):.4f} vs {np.linalg.norm(expected):.4f}")
    assert _degrees(got, expected) < 0.05
    assert np.linalg.norm(got) == pytest.approx(np.linalg.norm(expected), abs=0.001)


@pytest.mark.parametrize("roughness", [0.05, 0.1, 0.3, 0.5, 0.7, 1.0])
def test_kernel_mean_cosine_matches_a_quadrature_in_the_cosine(roughness):
    """The prefilter kernel's mean cosine: against the midpoint rule in c = R·ω, where the
    kernel is max(c, 0) / (A + B c)², A = (α² + 1)/2, B = (α² − 1)/2 (core.specular); within
    2e-3 (the grid's cells near ξ = 1 at r = 1, where D is flat)."""
    a2 = roughness ** 4
    c = (np.arange(2_000_000) + 0.5) / 2_000_000
    kernel = c / ((a2 + 1) / 2 + (a2 - 1) / 2 * c) ** 2
    expected = (kernel * c).sum() / kernel.sum()
    print(f"r {roughness}: {kernel_mean_cosine(roughness):.5f} vs {expected:.5f}")
    assert kernel_mean_cosine(roughness) == pytest.approx(expected, abs=2e-3)


@pytest.mark.parametrize("roughness, n_dot_v", [(0.3, 0.9), (0.3, 0.2), (0.5, 0.9), (0.5, 0.5),
                                                (0.5, 0.2), (0.7, 0.5), (0.7, 0.1)])
def test_effective_roughness_spreads_the_kernel_as_the_lobe(roughness, n_dot_v):
    """effective_roughness's kernel is as spread as the lobe of the uniform quadrature (mean
    cosines within 0.002), wider than the material's own roughness, the more so at grazing
    view; clamped to 1 where the lobe is wider than any kernel; 0 for a mirror."""
    expected, _ = lobe_mean_direction(roughness, n_dot_v)
    r_eff = effective_roughness(roughness, n_dot_v)
    print(f"r {roughness}, n·v {n_dot_v}: r_eff {r_eff:.3f}")
    assert kernel_mean_cosine(r_eff) == pytest.approx(np.linalg.norm(expected), abs=0.002)
    assert r_eff > roughness
    if n_dot_v < 0.5:
        assert r_eff > effective_roughness(roughness, 0.9)
    assert effective_roughness(0.9, 0.5) == 1.0
    assert effective_roughness(0.0, 0.5) == pytest.approx(0.0, abs=1e-6)


@pytest.mark.parametrize("roughness", [0.3, 0.5, 0.7])
@pytest.mark.parametrize("n_dot_v", [0.9, 0.5, 0.2])
def test_lookup_direction_is_the_lobes_mean(roughness, n_dot_v):
    """The split sum looks the maps up at N + t (R − N), t the table's (lobe_factor,
    interpolated by the shader between its texel centres): within 1° (0.7° measured) of the
    mean direction of the lobe the bench's metal reflects (F0 = 0.8, Fresnel left out of the
    table); the view-independent dominant_factor (Lagarde and de Rousiers) is up to 22° off,
    R up to 51°. t = 1 for a mirror."""
    mean, v = lobe_mean_direction(roughness, n_dot_v, f0=0.8)
    normal = np.array([0.0, 0.0, 1.0])
    mirror = 2 * n_dot_v * normal - v
    table = environment_brdf_table()
    size = table.shape[0]
    # bilinear between the texel centres, as the shader's lookup (clamped to the outer ones)
    x = np.clip(n_dot_v * size - 0.5, 0, size - 1)
    y = np.clip(roughness * size - 0.5, 0, size - 1)
    i, j = min(int(x), size - 2), min(int(y), size - 2)
    fx, fy = x - i, y - j
    t = ((1 - fy) * ((1 - fx) * table[j, i, 2] + fx * table[j, i + 1, 2])
         + fy * ((1 - fx) * table[j + 1, i, 2] + fx * table[j + 1, i + 1, 2]))
    looked = normal + t * (mirror - normal)
    fitted = normal + dominant_factor(roughness) * (mirror - normal)
    print(f"r {roughness}, n·v {n_dot_v}: from the lobe's mean, mirror {_degrees(mirror, mean):.1f}°, "
          f"dominant_factor {_degrees(fitted, mean):.1f}°, table {_degrees(looked, mean):.2f}°")
    assert _degrees(looked, mean) < 1.0
    assert lobe_factor(0.0, 0.3) == pytest.approx(1.0)
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
