"""A complete glTF 2.0 ``EXT_lights_image_based`` environment, as Babylon.js reads it.

One .gltf (PNG images embedded) with one light: intensity 1, the irradiance coefficients
(``interop``) and a specular cube mip chain prefiltered from the world image
(``core.specular``): faces in Babylon's lookup axes (x, z, y)_blender, texel (i, j) the WebGL
direction of s_c = 2(i + ½)/s − 1, t_c = 1 − 2(j + ½)/s; level i at GGX α_i = S^(i/(N−1))/S
(Babylon's lod = log2(S α)(N − 1)/log2(S)); RGBD-encoded as Babylon's ``toRGBD``
(rgb = (c/255)^2.2 / (d/255), at most 255). Babylon's conventions: docs/interop.md.
"""

import base64
import json
from math import log2

import numpy as np

from ..core.downsample import block_downsample, whole_factor
from ..core.equirect import check_pixels, texel_directions
from ..core.irradiance import check_coefficients
from ..core.sh import sh_basis
from ..core.specular import (
    SOURCE_TEXELS_PER_TEXEL,
    bilinear_lookup,
    downsample,
    prefilter,
    scatter_average,
)
from ..core.world_map import mapping_rotation
from .interop import BLENDER_TO_BABYLON_LOOKUP, to_gltf_irradiance_coefficients
from .png import png_bytes

EXTENSION = "EXT_lights_image_based"
CUBE_SIZE = 64  # S: the size of level 0
LEVELS = 4  # 64, 32, 16, 8: the last (r = 1) at 8 × 8
MINIMUM_VARIANCE = 0.0005  # Babylon's α = r² + 0.0005
# The cube is built from the image box-downsampled to about this width (4 source texels
# across each 64² level-0 texel; benchmarks/REPORT.md gives the change against full resolution).
CUBE_SOURCE_WIDTH = 1024
MIRROR_SUBSAMPLES = 4  # k × k bilinear lookups per level-0 texel for images coarser than it
FACE_NAMES = ("px", "nx", "py", "ny", "pz", "nz")
RGBD_GAMMA = 2.2
RGBD_MAX = 255.0

# Direction of texel (s_c, t_c) on each face: (major axis, axis of s_c, axis of t_c) as
# coefficient vectors, d = major + s_c · s_axis + t_c · t_axis (WebGL cube-map table).
FACE_AXES = np.array([
    [[1, 0, 0], [0, 0, -1], [0, -1, 0]],   # +X: s_c = −z, t_c = −y
    [[-1, 0, 0], [0, 0, 1], [0, -1, 0]],   # −X: s_c = +z, t_c = −y
    [[0, 1, 0], [1, 0, 0], [0, 0, 1]],     # +Y: s_c = +x, t_c = +z
    [[0, -1, 0], [1, 0, 0], [0, 0, -1]],   # −Y: s_c = +x, t_c = −z
    [[0, 0, 1], [1, 0, 0], [0, -1, 0]],    # +Z: s_c = +x, t_c = −y
    [[0, 0, -1], [-1, 0, 0], [0, -1, 0]],  # −Z: s_c = −x, t_c = −y
], dtype=np.float64)


def level_alphas(size=CUBE_SIZE, levels=LEVELS):
    """α Babylon samples each level at: S^(i/(N−1)) / S, i = 0 … N − 1 (module docstring)."""
    if levels == 1:
        return np.array([1.0 / size])
    return size ** (np.arange(levels) / (levels - 1)) / size


def level_roughness(size=CUBE_SIZE, levels=LEVELS):
    """The material roughness r whose reflections Babylon reads from each level."""
    return np.sqrt(np.maximum(level_alphas(size, levels) - MINIMUM_VARIANCE, 0.0))


def face_lookup_directions(face, size, u=None, v=None):
    """Unit lookup directions (Babylon's cube axes) of face ``face`` (0-5), (size, size, 3).

    ``u``, ``v``: texel coordinates in [0, size) (column, row from the top) instead of the
    texel centres.
    """
    if u is None:
        v, u = np.meshgrid(np.arange(size) + 0.5, np.arange(size) + 0.5, indexing="ij")
    sc = 2.0 * np.asarray(u) / size - 1.0
    tc = 1.0 - 2.0 * np.asarray(v) / size
    major, s_axis, t_axis = FACE_AXES[face]
    d = major + sc[..., None] * s_axis + tc[..., None] * t_axis
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def face_directions(face, size, u=None, v=None):
    """The same texels' directions in Blender world axes (x, y, z)_blender."""
    return face_lookup_directions(face, size, u, v) @ BLENDER_TO_BABYLON_LOOKUP


# The one non-zero entry of each face's s and t axis (FACE_AXES) and its sign: s_c and t_c of a
# direction are ± one of its coordinates over the major one (``cube_texel_index``).
_S_AXIS, _T_AXIS = (np.argmax(np.abs(FACE_AXES[:, k]), axis=-1) for k in (1, 2))
_S_SIGN, _T_SIGN = (FACE_AXES[np.arange(6), k, axis] for k, axis in ((1, _S_AXIS), (2, _T_AXIS)))


def cube_texel_index(directions, size):
    """Flat index face·s² + row·s + column of the texel holding each Blender direction.

    s_c = (d · s axis) / |major| with an s axis of one ±1 entry is that coordinate of d,
    signed, over |major|: picked, not summed with the zero products (an einsum over a
    gathered (N, 3, 3) array of axes took 0.05-0.15 s of a .gltf export at 8K; the same
    values to the bit, the zeros added nothing).
    """
    d = np.asarray(directions, dtype=np.float64) @ BLENDER_TO_BABYLON_LOOKUP.T
    axis = np.argmax(np.abs(d), axis=-1)
    picked = np.take_along_axis(d, axis[..., None], -1)[..., 0]
    face = 2 * axis + (picked < 0)
    major = np.abs(picked)
    sc = np.take_along_axis(d, _S_AXIS[face][..., None], -1)[..., 0] * _S_SIGN[face] / major
    tc = np.take_along_axis(d, _T_AXIS[face][..., None], -1)[..., 0] * _T_SIGN[face] / major
    col = np.clip(((sc + 1.0) * 0.5 * size).astype(np.int64), 0, size - 1)
    row = np.clip(((1.0 - tc) * 0.5 * size).astype(np.int64), 0, size - 1)
    return (face * size + row) * size + col


def specular_cube(pixels, size=CUBE_SIZE, levels=LEVELS, strength=1.0, euler=None,
                  source_width=CUBE_SOURCE_WIDTH, colour=None):
    """The prefiltered mip chain: a list of ``levels`` arrays (6, s, s, 3) of linear radiance,
    faces in glTF order, rows as in the PNG (top first).

    ``pixels``: the equirect image shown by the world at ``strength`` through a Mapping node
    of XYZ Euler ``euler`` (``world_map``; None: no Mapping node). Images wider than
    ``source_width`` are first box-downsampled to about that width by a whole factor
    (``core.downsample``: solid-angle weighted, power kept); None keeps the full resolution.
    ``colour``: a 3×3 matrix taking the image's RGB to the cube's (a colour-space
    conversion), applied to the downsampled source: the same as converting every texel first
    (both are linear), at a fraction of the cost.
    """
    pixels = _cube_source(check_pixels(pixels), source_width) * float(strength)
    if colour is not None:
        pixels = pixels @ np.asarray(colour, dtype=np.float64).T
    to_world = mapping_rotation(euler)  # world direction = to_world @ image direction
    if size < 2 or size & (size - 1) or not 1 <= levels <= int(log2(size)) + 1:
        raise ValueError(
            f"a specular cube needs a power-of-two size ≥ 2 and 1 … log2(size) + 1 levels, "
            f"got size {size} with {levels} levels"
        )
    # the source of the GGX levels, downsampled once for the largest of them (level 1)
    width = SOURCE_TEXELS_PER_TEXEL * size // 2
    source = downsample(pixels, width // 2, width)
    chain = []
    for level, alpha in enumerate(level_alphas(size, levels)):
        s = size >> level
        if level == 0:
            faces = _mirror_level(pixels, s, to_world)
        else:
            directions = np.stack([face_directions(f, s) for f in range(6)])
            faces = prefilter(source, directions @ to_world, alpha, SOURCE_TEXELS_PER_TEXEL * s)
        chain.append(np.asarray(faces, dtype=np.float64))
    return chain


def _cube_source(pixels, source_width):
    """The image's RGB as float64, box-downsampled to about ``source_width`` wide if wider."""
    height, width = pixels.shape[:2]
    factor = whole_factor(height, width, source_width) if source_width else 1
    if factor == 1:
        return np.asarray(pixels, dtype=np.float64)[..., :3]
    return block_downsample(pixels, factor)[0]


def _mirror_level(pixels, s, to_world):
    """Level 0 (α = 1/S): each cube texel's mean of the image (``core.specular``)."""
    if pixels.shape[0] >= 4 * s:  # image texels at most half a cube texel: average them
        return scatter_average(
            pixels, lambda d: cube_texel_index(d @ to_world.T, s), 6 * s * s
        ).reshape(6, s, s, 3)
    offsets = (np.arange(MIRROR_SUBSAMPLES) + 0.5) / MIRROR_SUBSAMPLES
    v = np.arange(s)[:, None, None, None] + offsets[None, None, :, None]
    u = np.arange(s)[None, :, None, None] + offsets[None, None, None, :]
    u, v = np.broadcast_arrays(u, v)
    faces = [
        bilinear_lookup(pixels, face_directions(face, s, u, v) @ to_world).mean(axis=(2, 3))
        for face in range(6)
    ]
    return np.stack(faces)


def rgbd_encode(radiance):
    """(..., 3) linear radiance → (..., 4) uint8 RGBD as Babylon's ``toRGBD`` writes it."""
    c = np.clip(np.nan_to_num(np.asarray(radiance, dtype=np.float64), nan=0.0), 0.0, RGBD_MAX)
    peak = np.maximum(c.max(axis=-1, keepdims=True), 1e-7)
    d = np.clip(np.floor(RGBD_MAX / peak), 1.0, 255.0)
    rgb = np.clip(c * d / 255.0, 0.0, 1.0) ** (1.0 / RGBD_GAMMA)
    return np.concatenate([np.round(rgb * 255.0), d], axis=-1).astype(np.uint8)


def rgbd_decode(rgbd):
    """(..., 4) uint8 RGBD → (..., 3) linear radiance, as Babylon's ``fromRGBD`` reads it."""
    a = np.asarray(rgbd, dtype=np.float64) / 255.0
    return a[..., :3] ** RGBD_GAMMA / a[..., 3:4]


def radiance_image(coeffs, height=64, width=128):
    """An equirect image (H, W, 3) of the 9-term radiance Σ L_lm Y_lm, negative parts 0:
    the specular source when there is no world image (edited or loaded coefficients)."""
    c, _order = check_coefficients(coeffs)
    return np.maximum(sh_basis(texel_directions(height, width)) @ c, 0.0)


def _data_uri(png):
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def gltf_document(coeffs, pixels=None, strength=1.0, euler=None, name="", extras=None,
                  size=CUBE_SIZE, levels=LEVELS, colour=None):
    """The glTF JSON object (dict) of the environment of ``coeffs`` and its world image.

    ``pixels``: the equirect world image (H, W, 3 or 4), rows top to bottom, shown at
    ``strength`` through ``euler`` (``specular_cube``, with ``colour`` the matrix from the
    image's RGB to the coefficients'); None: the specular cube is made from
    ``radiance_image(coeffs)`` (then ``strength``, ``euler`` and ``colour`` are not used).
    """
    if pixels is None:
        pixels, strength, euler, colour = radiance_image(coeffs), 1.0, None, None
    chain = specular_cube(pixels, size, levels, strength, euler, colour=colour)
    irradiance = to_gltf_irradiance_coefficients(coeffs)
    images, indices = [], []
    for level, faces in enumerate(chain):
        row = []
        for face, texels in zip(FACE_NAMES, faces):
            row.append(len(images))
            images.append({
                "name": f"specular_{level}_{face}",
                "uri": _data_uri(png_bytes(rgbd_encode(texels))),
            })
        indices.append(row)
    light = {
        "name": name or "environment",
        "intensity": 1.0,
        "rotation": [0.0, 0.0, 0.0, 1.0],
        "irradianceCoefficients": irradiance,
        "specularImageSize": size,
        "specularImages": indices,
    }
    if extras:
        light["extras"] = dict(extras)
    return {
        "asset": {"version": "2.0", "generator": "sh_lighting"},
        "extensionsUsed": [EXTENSION],
        "extensions": {EXTENSION: {"lights": [light]}},
        "scene": 0,
        "scenes": [{"name": name or "environment", "extensions": {EXTENSION: {"light": 0}}}],
        "images": images,
    }


def gltf_text(coeffs, pixels=None, strength=1.0, euler=None, name="", extras=None,
              size=CUBE_SIZE, levels=LEVELS, colour=None):
    """:func:`gltf_document` as the text of a .gltf file."""
    document = gltf_document(coeffs, pixels, strength, euler, name, extras, size, levels,
                             colour)
    return json.dumps(document, indent=1, ensure_ascii=False, allow_nan=False) + "\n"
