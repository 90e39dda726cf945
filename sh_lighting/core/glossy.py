"""The world's glossy reflection as a few prefiltered maps plus a split-sum factor.

Diffuse by SH, glossy by environment maps prefiltered for the roughness (Kautz, Daubert and
Seidel 2004). Split sum (Karis 2013): L_glossy ≈ P_α(d) · (F0 · A(r, n·v) + B(r, n·v)), P_α
the GGX-prefiltered radiance (``specular.prefilter``), A, B the integrated environment BRDF
(``environment_brdf_table``), looked up along the lobe's mean direction d (``lobe_factor``) at
the roughness whose kernel is as spread as the lobe (``effective_roughness``); multiple
scattering as Fdez-Agüera 2019: F0 A + B + (F0 A + B) F_avg (1 − E) / (1 − F_avg (1 − E)),
E = A + B. ``level_maps`` prefilters the world at ``ROUGHNESS_LEVELS``. Details:
docs/modules.md.
"""

import functools

import numpy as np

from .downsample import block_downsample, whole_factor
from .equirect import check_pixels, direction_to_texel, texel_directions
from .specular import bilinear_lookup, downsample, prefilter, scatter_average
from .world_map import mapping_rotation

ROUGHNESS_LEVELS = (0.0, 0.25, 0.5, 0.75, 1.0)
LEVEL_WIDTHS = (256, 128, 64, 32, 32)
# The prefilter sums over the world downsampled to this many times the level's width (1: its
# own texels; on a smooth sky ≤ 0.7 % from a quadrature at every level, tests/core; 2 costs
# 2.3× the time, 4 s at a load of 10 for the 1024 × 512 HDRIs).
SOURCE_FACTOR = 1
# A larger world is first box-averaged (solid-angle weights, one float32 pass: no float64 copy
# of it) to about this width, 4x the widest level: an 8K map is 1 GB as float64.
SOURCE_WIDTH = 1024
# The split sum's table: TABLE_SIZE × TABLE_SIZE (n·v, r) at texel centres, each entry
# summed over TABLE_STEPS × TABLE_STEPS half-vectors placed by GGX's distribution; the lobe's
# mean and spread with TAIL_POWER (``_ggx_samples``): even in ξ they are 0.6° and 0.04 off at
# n·v = 0.05, r = 0.3 (tests/core).
TABLE_SIZE = 16
TABLE_STEPS = 64
TAIL_POWER = 3


def _smith_g1(alpha2, cos):
    """Smith's masking of GGX for one direction at cosine ``cos`` to the normal."""
    return 2.0 * cos / (cos + np.sqrt(alpha2 + (1.0 - alpha2) * cos * cos))


def _ggx_samples(roughness, n_dot_v, steps, power=1):
    """The light directions of GGX's importance samples (normal z, view in the xz plane) for
    scalar perceptual ``roughness`` and each of the cosines ``n_dot_v`` (m,) > 0:
    (l (m, steps, steps, 3), v·h (m, steps, steps), each one's f n·l / pdf(l) / steps², 0
    below the horizon), f the single-scattering GGX BRDF without its Fresnel
    (``environment_brdf``). The half-vectors sit at the midpoints u of a steps × steps grid
    mapped to GGX's cumulative distribution ξ = 1 − (1 − u)^power, φ = 2π u' (weights times
    dξ/du = power (1 − u)^(power − 1)): power 1 spreads them evenly in ξ, a larger power puts
    more of them into the lobe's tail (ξ near 1, θ_h toward 90°), which at grazing view
    reaches far from the mirror direction."""
    mu = np.asarray(n_dot_v, dtype=np.float64).reshape(-1, 1, 1)
    alpha2 = float(roughness) ** 4
    u = (np.arange(steps) + 0.5) / steps
    xi = 1.0 - (1.0 - u) ** power
    tan_h = np.sqrt(alpha2 * xi / (1.0 - xi))[:, None]
    cos_h = 1.0 / np.sqrt(1.0 + tan_h * tan_h)
    sin_h = tan_h * cos_h
    phi = 2.0 * np.pi * u[None, :]
    half = np.stack(np.broadcast_arrays(sin_h * np.cos(phi), sin_h * np.sin(phi), cos_h), -1)
    sin_v = np.sqrt(np.maximum(0.0, 1.0 - mu * mu))
    v_h = half[..., 0] * sin_v + half[..., 2] * mu  # (m, steps, steps)
    light = 2.0 * v_h[..., None] * half
    light[..., 0] -= sin_v
    light[..., 2] -= mu
    n_l = light[..., 2]
    seen = (n_l > 0.0) & (v_h > 0.0)
    n_l = np.where(seen, n_l, 1.0)
    g = _smith_g1(alpha2, n_l) * _smith_g1(alpha2, mu)
    density = (power * (1.0 - u) ** (power - 1))[:, None]
    weight = np.where(seen, g * v_h / (mu * half[..., 2]) * density, 0.0) / (steps * steps)
    return light, v_h, weight


def _brdf_terms(roughness, n_dot_v, steps):
    """(A (m,), B (m,)) of ``environment_brdf`` at each of the cosines ``n_dot_v`` (m,)."""
    _, v_h, weight = _ggx_samples(roughness, n_dot_v, steps)
    schlick = (1.0 - np.clip(v_h, 0.0, 1.0)) ** 5
    return (weight * (1.0 - schlick)).sum(axis=(1, 2)), (weight * schlick).sum(axis=(1, 2))


def _lobe_means(roughness, n_dot_v, steps, power):
    """``lobe_mean`` at each of the cosines ``n_dot_v`` (m,): (m, 3)."""
    light, _, weight = _ggx_samples(roughness, n_dot_v, steps, power)
    return ((weight[..., None] * light).sum(axis=(1, 2))
            / weight.sum(axis=(1, 2))[:, None])


def _lobe_factors(means, n_dot_v):
    """``lobe_factor`` from the lobe ``means`` (m, 3) at the cosines ``n_dot_v`` (m,)."""
    tan_m = -means[:, 0] / means[:, 2]  # the view at +x, R at −x
    mu = np.asarray(n_dot_v, dtype=np.float64)
    sin_r, cos_r = np.sqrt(np.maximum(0.0, 1.0 - mu * mu)), mu
    return tan_m / (sin_r + tan_m * (1.0 - cos_r))


def _effective_roughnesses(means, steps):
    """``effective_roughness`` from the lobe ``means`` (m, 3)."""
    spread = _kernel_spreads(steps)  # falling, 1 → 2/3
    return np.interp(-np.linalg.norm(means, axis=1), -spread, _SPREAD_GRID)


def environment_brdf(roughness, n_dot_v, steps=TABLE_STEPS):
    """(A, B) of the split sum (module docstring) at scalar perceptual ``roughness`` and
    ``n_dot_v`` > 0: ∫ f (1 − F_c) n·l dω and ∫ f F_c n·l dω over the light directions l, with
    f = D G / (4 n·l n·v) the single-scattering GGX BRDF without its Fresnel (α = r², separable
    Smith G), F_c = (1 − v·h)⁵ Schlick's weight. The half-vectors h sit at the midpoints of a
    steps × steps grid of GGX's cumulative distribution (θ_h = atan(α √(ξ/(1 − ξ))), φ = 2π ξ'),
    l = h mirrored v, so each carries f n·l / pdf(l) = G (v·h) / (n·v n·h)."""
    scale, bias = _brdf_terms(roughness, [n_dot_v], steps)
    return float(scale[0]), float(bias[0])


def lobe_mean(roughness, n_dot_v, steps=TABLE_STEPS, power=TAIL_POWER):
    """The mean light direction of the GGX lobe, ∫ l f n·l dω / ∫ f n·l dω (f as in
    ``environment_brdf``, its Fresnel left out; normal z, view in the xz plane) at scalar
    perceptual ``roughness`` and ``n_dot_v`` > 0, as a (3,) vector: its direction is where
    the lobe's light comes from on average (the mirror direction R for a mirror, nearer the
    normal the rougher the surface and the more grazing the view), its length ≤ 1 the mean
    cosine of the lobe to it (1 for a mirror: how concentrated the lobe is). Importance
    samples as ``environment_brdf``'s, more of them in the tail (``TAIL_POWER``)."""
    return _lobe_means(roughness, [n_dot_v], steps, power)[0]


def lobe_factor(roughness, n_dot_v, steps=TABLE_STEPS):
    """t of the direction N + t (R − N) (unnormalized) toward ``lobe_mean``'s direction, at
    scalar ``roughness`` and ``n_dot_v``: in the plane of the normal N and the mirror
    direction R, at θ_R = acos(n·v) and the mean at θ_m from N,
    tan θ_m = t sin θ_R / (1 − t (1 − cos θ_R)), so t = tan θ_m / (sin θ_R + tan θ_m
    (1 − cos θ_R)): 1 for a mirror (θ_m = θ_R), 0 for a lobe centred on the normal. What the
    split sum's table holds for the lookup direction: it depends on the view as well as the
    roughness (Lagarde and de Rousiers' fit, on the roughness alone, is up to 22° off it)."""
    means = _lobe_means(roughness, [n_dot_v], steps, TAIL_POWER)
    return float(_lobe_factors(means, [n_dot_v])[0])


def kernel_mean_cosine(roughness, steps=TABLE_STEPS, power=TAIL_POWER):
    """The mean cosine to R of the prefilter's kernel at perceptual ``roughness`` (α = r²):
    ∫ D_α(h) max(R·ω, 0) (R·ω) dω / ∫ D_α(h) max(R·ω, 0) dω, h halfway between R and ω
    (``core.specular``, Karis's n = v = R). With ω at 2θ_h from R, dω = 4 (R·h) dω_h, it is
    summed over the half-vectors placed by GGX's distribution D (R·h) dω_h as in
    ``_ggx_samples`` (the tail-heavy grid, no φ needed): weights max(cos 2θ_h, 0). 1 for a
    mirror, 2/3 at r = 1 (D constant)."""
    alpha2 = float(roughness) ** 4
    u = (np.arange(steps) + 0.5) / steps
    xi = 1.0 - (1.0 - u) ** power
    cos2_h = (1.0 - xi) / (1.0 - xi + alpha2 * xi)  # cos² θ_h at the cumulative ξ
    cos_l = 2.0 * cos2_h - 1.0
    weight = np.maximum(cos_l, 0.0) * (1.0 - u) ** (power - 1)
    return float((weight * cos_l).sum() / weight.sum())


def effective_roughness(roughness, n_dot_v, steps=TABLE_STEPS):
    """The perceptual roughness whose prefilter kernel (``kernel_mean_cosine``) is as spread
    as the GGX lobe at scalar ``roughness`` and ``n_dot_v`` (its mean cosine to its own mean
    direction, ``lobe_mean``'s length): the maps are looked up at it, so that the split sum's
    lobe is not narrower than the BRDF's, which it is at grazing view (the lobe stretched
    away from the mirror direction) and, without the n·l the kernel carries, near it too. A
    moment match, as a von Mises-Fisher lobe is fitted by its mean resultant length (Fisher,
    "Dispersion on a sphere", 1953). Clamped to [0, 1], the maps' range (the lobe of r ≥ 0.8
    is wider than the kernel of r = 1)."""
    means = _lobe_means(roughness, [n_dot_v], steps, TAIL_POWER)
    return float(_effective_roughnesses(means, steps)[0])


_SPREAD_GRID = np.linspace(0.0, 1.0, 257)


@functools.lru_cache(maxsize=4)
def _kernel_spreads(steps):
    """``kernel_mean_cosine`` at the roughnesses ``_SPREAD_GRID``."""
    return np.array([kernel_mean_cosine(r, steps) for r in _SPREAD_GRID])


def environment_brdf_table(size=TABLE_SIZE):
    """(size, size, 4) float32: (A, B, t, r_eff) at n·v = (i + ½)/size along the columns i
    and r = (j + ½)/size along the rows j, row 0 first: what an image looked up at (n·v, r)
    holds. A, B: ``environment_brdf``; t: ``lobe_factor``, toward where the maps are looked
    up; r_eff: ``effective_roughness``, the maps' roughness looked up. A new array each call
    (the sums done once per size)."""
    return _table(size).copy()


@functools.lru_cache(maxsize=2)
def _table(size):
    centres = (np.arange(size) + 0.5) / size
    table = np.empty((size, size, 4), dtype=np.float32)
    for row, r in zip(table, centres):
        row[:, 0], row[:, 1] = _brdf_terms(r, centres, TABLE_STEPS)
        means = _lobe_means(r, centres, TABLE_STEPS, TAIL_POWER)
        row[:, 2] = _lobe_factors(means, centres)
        row[:, 3] = _effective_roughnesses(means, TABLE_STEPS)
    return table


def _mirror(pixels, height, width, to_world):
    """The world's mean over each (height, width) texel: the image's texels scattered into
    the texel holding their world direction when fine enough, else bilinear lookups; so are
    the texels no image texel centre falls in (near the poles of a rotated map, smaller than
    the image's texels there)."""
    directions = texel_directions(height, width) @ to_world
    if pixels.shape[0] < 2 * height:
        return bilinear_lookup(pixels, directions)

    def index(world_directions):
        row, col = direction_to_texel(world_directions @ to_world.T, height, width)
        return row * width + col

    level = scatter_average(pixels, index, height * width).reshape(height, width, 3)
    empty = ~level.any(axis=-1)
    level[empty] = bilinear_lookup(pixels, directions[empty])
    return level


def level_maps(pixels, strength=1.0, euler=None, levels=ROUGHNESS_LEVELS, widths=LEVEL_WIDTHS):
    """[(W/2, W, 3) float32 map of P_α, α = r², for each level r of ``levels``] of the world
    showing equirect ``pixels`` at ``strength`` through a Mapping node of XYZ Euler ``euler``
    (None: none). Map texel (row, column) holds the radiance reflected toward its world
    direction, so a shader looks it up at the reflection vector as the world itself is."""
    image = check_pixels(pixels)
    factor = whole_factor(image.shape[0], image.shape[1], SOURCE_WIDTH)
    if factor > 1:
        image = block_downsample(image, factor)[0]
    else:
        image = np.asarray(image, dtype=np.float64)[..., :3]
    to_world = mapping_rotation(euler)  # image direction = to_world.T @ world direction
    maps = []
    for r, width in zip(levels, widths):
        height = max(1, width // 2)
        if r <= 0.0:
            level = _mirror(image, height, width, to_world)
        else:
            source = downsample(image, SOURCE_FACTOR * height, SOURCE_FACTOR * width)
            directions = texel_directions(height, width) @ to_world
            level = prefilter(source, directions, r * r, SOURCE_FACTOR * width)
        maps.append((float(strength) * level).astype(np.float32))
    return maps
