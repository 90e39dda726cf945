"""The world's glossy reflection as a few prefiltered maps plus a split-sum factor (issue 21).

In EEVEE, Keep BSDF hides the world from EEVEE's own lighting (its one world capture serves
diffuse and glossy alike), so the diffuse light comes from the nine SH terms alone. The glossy
part is given back as Kautz, Daubert and Seidel ("Advanced Environment Mapping in VR
Applications", 2004) do: diffuse by SH, glossy by environment maps prefiltered for the
roughness. With the split-sum approximation (Karis, "Real Shading in Unreal Engine 4", 2013)
a surface of perceptual roughness r, GGX α = r², seen at n·v reflects toward the viewer

    L_glossy ≈ P_α(R) · (F0 · A(r, n·v) + B(r, n·v)),

with R the mirror direction of the view about the normal (looked up toward the lobe's
dominant direction, ``dominant_factor``), P_α the radiance prefiltered with
the GGX lobe (``specular.prefilter``) and A, B the scale and bias of the environment BRDF
integrated over the hemisphere. ``environment_brdf`` integrates A and B numerically;
``environment_brdf_table`` tabulates them for the shader, as Karis does. (His analytic fit for
mobiles, after Lazarov 2013, is 0.1–0.2 too low at r ≤ 0.5 against this integral, measured.)
Cycles' Principled BSDF renders multiple-scattering GGX, which gives back the energy single
scattering loses: the shader adds it as Fdez-Agüera ("A Multiple-Scattering Microfacet Model
for Real-Time Image-based Lighting", 2019) does, with E = A + B, F_avg = F0 + (1 − F0)/21,

    F0 A + B + (F0 A + B) F_avg (1 − E) / (1 − F_avg (1 − E)).

``level_maps`` prefilters the world at the roughness levels ``ROUGHNESS_LEVELS`` into
equirectangular maps in Blender world directions (the world's Mapping rotation and Strength
applied, docs/reference.md §3), sharper levels wider (``LEVEL_WIDTHS``); between two levels
the shader interpolates linearly in r. Level r = 0 (a mirror) is the mean of the world over
each texel. Pure numpy; pixels (H, W, 3 or 4), rows top to bottom.
"""

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
# summed over TABLE_STEPS × TABLE_STEPS half-vectors placed by GGX's distribution.
TABLE_SIZE = 16
TABLE_STEPS = 64


def dominant_factor(roughness):
    """t of the direction N + t (R − N) (unnormalized) where the split sum looks P_α up, at
    perceptual ``roughness`` r (scalar or array), α = r²: t = s (√s + α), s = 1 − α, the
    GGX lobe's dominant direction of Lagarde and de Rousiers ("Moving Frostbite to Physically
    Based Rendering", SIGGRAPH 2014 course notes, "specular dominant direction"). The lobe
    f n·l of a rough surface leans from R toward the normal (its n·l factor and the shadowing
    at grazing angles), so the mirror direction R places the highlight too far toward the
    rim: t = 1 at r = 0 (R), 0 at r = 1 (N). Measured in benchmarks/bench_real_scene's scene
    (sunrise.exr, the sphere of roughness 0.5, the nodes rendered by Cycles): 22.8 % → 20.4 %
    from path tracing of the world's reflections; with α in place of r², 62 %."""
    alpha = np.asarray(roughness, dtype=np.float64) ** 2
    smooth = 1.0 - alpha
    return smooth * (np.sqrt(smooth) + alpha)


def _smith_g1(alpha2, cos):
    """Smith's masking of GGX for one direction at cosine ``cos`` to the normal."""
    return 2.0 * cos / (cos + np.sqrt(alpha2 + (1.0 - alpha2) * cos * cos))


def environment_brdf(roughness, n_dot_v, steps=TABLE_STEPS):
    """(A, B) of the split sum (module docstring) at scalar perceptual ``roughness`` and
    ``n_dot_v`` > 0: ∫ f (1 − F_c) n·l dω and ∫ f F_c n·l dω over the light directions l, with
    f = D G / (4 n·l n·v) the single-scattering GGX BRDF without its Fresnel (α = r², separable
    Smith G), F_c = (1 − v·h)⁵ Schlick's weight. The half-vectors h sit at the midpoints of a
    steps × steps grid of GGX's cumulative distribution (θ_h = atan(α √(ξ/(1 − ξ))), φ = 2π ξ'),
    l = h mirrored v, so each carries f n·l / pdf(l) = G (v·h) / (n·v n·h)."""
    mu = float(n_dot_v)
    alpha2 = float(roughness) ** 4
    xi = (np.arange(steps) + 0.5) / steps
    tan_h = np.sqrt(alpha2 * xi / (1.0 - xi))[:, None]
    cos_h = 1.0 / np.sqrt(1.0 + tan_h * tan_h)
    sin_h = tan_h * cos_h
    phi = 2.0 * np.pi * xi[None, :]
    half = np.stack(np.broadcast_arrays(sin_h * np.cos(phi), sin_h * np.sin(phi), cos_h), -1)
    view = np.array([np.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu])
    v_h = half @ view
    n_l = 2.0 * v_h * half[..., 2] - mu
    seen = (n_l > 0.0) & (v_h > 0.0)
    n_l = np.where(seen, n_l, 1.0)
    g = _smith_g1(alpha2, n_l) * _smith_g1(alpha2, mu)
    weight = np.where(seen, g * v_h / (mu * half[..., 2]), 0.0) / (steps * steps)
    schlick = (1.0 - np.clip(v_h, 0.0, 1.0)) ** 5
    return float((weight * (1.0 - schlick)).sum()), float((weight * schlick).sum())


def environment_brdf_table(size=TABLE_SIZE):
    """(size, size, 2) float32: (A, B) at n·v = (i + ½)/size along the columns i and
    r = (j + ½)/size along the rows j, row 0 first: what an image looked up at (n·v, r)
    interpolates."""
    centres = (np.arange(size) + 0.5) / size
    return np.array([[environment_brdf(r, mu) for mu in centres] for r in centres],
                    dtype=np.float32)


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
