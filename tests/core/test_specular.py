"""The prefiltered specular cube and its encoding (core.specular, core.gltf_environment, core.png).

What Babylon.js makes of the exported cube (orientation, levels, decoding) is checked by
running Babylon in node (tests/interop); these are the core's own properties.
"""

import struct
import zlib
from math import pi

import numpy as np
import pytest

from sh_lighting.formats import gltf as env
from sh_lighting.core.equirect import direction_to_texel, texel_directions, texel_solid_angles
from sh_lighting.formats.png import png_bytes
from sh_lighting.core.specular import (
    bilinear_lookup,
    downsample,
    ggx_distribution,
    prefilter,
    scatter_average,
)


def sky(height=32, width=64):
    """A smooth positive map: 1 + 0.5 z + 0.3 x (radiance), rows top to bottom."""
    d = texel_directions(height, width)
    return np.repeat((1.0 + 0.5 * d[..., 2] + 0.3 * d[..., 0])[..., None], 3, axis=-1)


def test_ggx_lobe_integrates_to_one_over_the_hemisphere():
    # ∫ D(h) (n·h) dω_h = 1: in θ_h, ∫ D cos θ sin θ dθ dφ
    theta = (np.arange(200_000) + 0.5) * (pi / 2 / 200_000)
    for alpha in (0.05, 0.3, 1.0):
        d = ggx_distribution(alpha, np.cos(theta) ** 2)
        integral = 2 * pi * np.sum(d * np.cos(theta) * np.sin(theta)) * (pi / 2 / 200_000)
        assert integral == pytest.approx(1.0, rel=1e-3)


def test_downsample_keeps_the_solid_angle_weighted_mean():
    pixels = np.random.default_rng(0).random((64, 128, 3))
    small = downsample(pixels, 16, 32)
    weights = texel_solid_angles(64, 128)[:, None, None]
    big_mean = (pixels * weights).sum(axis=(0, 1)) / (weights.sum() * 128)
    small_w = texel_solid_angles(16, 32)[:, None, None]
    # each coarse texel is the mean of its fine texels; the means agree to the row weights
    assert np.allclose((small * small_w).sum(axis=(0, 1)) / (small_w.sum() * 32), big_mean,
                       rtol=2e-3)
    assert np.allclose(downsample(np.ones((64, 128, 3)), 16, 32), 1.0)


def test_prefilter_of_a_constant_is_the_constant_and_blurs_a_smooth_map_little():
    directions = env.face_directions(0, 4).reshape(-1, 3)
    constant = np.full((32, 64, 3), 2.5)
    assert np.allclose(prefilter(constant, directions, 0.5, 64), 2.5)
    smooth = sky()
    sharp = prefilter(smooth, directions, 0.05, 64)
    truth = 1.0 + 0.5 * directions[:, 2] + 0.3 * directions[:, 0]
    assert np.abs(sharp[:, 0] - truth).max() < 0.02


def test_prefilter_widens_with_alpha():
    pixels = np.zeros((64, 128, 3))
    row, col = direction_to_texel(np.array([1.0, 0.0, 0.0]), 64, 128)
    pixels[row, col] = 1000.0
    toward = np.array([[1.0, 0.0, 0.0]])
    aside = np.array([[np.cos(0.3), np.sin(0.3), 0.0]])
    ratios = [prefilter(pixels, aside, a, 128)[0, 0] / prefilter(pixels, toward, a, 128)[0, 0]
              for a in (0.1, 0.3, 1.0)]
    assert ratios[0] < ratios[1] < ratios[2] < 1.0


def test_scatter_average_loses_no_light():
    pixels = np.random.default_rng(1).random((256, 512, 3))
    size = 16
    faces = scatter_average(pixels, lambda d: env.cube_texel_index(d, size), 6 * size * size)
    assert np.allclose(scatter_average(np.ones((256, 512, 3)),
                                       lambda d: env.cube_texel_index(d, size),
                                       6 * size * size), 1.0)
    assert faces.min() >= 0.0 and faces.max() <= 1.0


def test_bilinear_lookup_hits_texel_centres_and_wraps():
    pixels = np.random.default_rng(2).random((8, 16, 3))
    centres = texel_directions(8, 16)
    assert np.allclose(bilinear_lookup(pixels, centres[2:6]), pixels[2:6])
    seam = bilinear_lookup(pixels, np.array([-1.0, 1e-9, 0.0]) / 1.0)  # u = 0 ≡ 1: the seam
    assert np.allclose(seam, 0.5 * (pixels[3, 0] + pixels[3, -1]) * 0.5
                       + 0.5 * (pixels[4, 0] + pixels[4, -1]) * 0.5)


def test_cube_texel_index_inverts_the_face_directions():
    for size in (1, 2, 8):
        for face in range(6):
            directions = env.face_directions(face, size).reshape(-1, 3)
            index = env.cube_texel_index(directions, size)
            assert (index == np.arange(face * size * size, (face + 1) * size * size)).all()


def test_faces_are_the_webgl_faces_in_babylon_lookup_axes():
    # +X face centre looks along lookup +x = Blender +x; +Y along lookup +y = Blender +z;
    # +Z along lookup +z = Blender +y (lookup = (x, z, y)_blender)
    centres = [env.face_directions(f, 1)[0, 0] for f in range(6)]
    assert np.allclose(centres, [[1, 0, 0], [-1, 0, 0], [0, 0, 1], [0, 0, -1], [0, 1, 0],
                                 [0, -1, 0]])
    # the PNG's top row is t = 1: on +X, lookup −y (Blender −z) is at the top
    top, bottom = env.face_directions(0, 8)[0, 4], env.face_directions(0, 8)[-1, 4]
    assert top[2] < 0 < bottom[2]


def test_levels_follow_babylons_lod_for_roughness():
    alphas = env.level_alphas(64, 4)
    assert np.allclose(alphas, [1 / 64, 4 / 64, 16 / 64, 1.0])
    # Babylon: lod = log2(S α) (N − 1) / log2(S) must give the level's index
    assert np.allclose(np.log2(64 * alphas) * 3 / 6, [0, 1, 2, 3])
    assert np.allclose(env.level_roughness(64, 4) ** 2 + 0.0005, alphas)


def test_rgbd_round_trip_and_range():
    values = np.array([[1e-3, 2e-3, 5e-4], [0.5, 0.25, 0.1], [3.0, 1.0, 0.0], [200.0, 20.0, 2.0],
                       [1000.0, 1.0, 1.0], [-1.0, 0.0, 0.0]])
    decoded = env.rgbd_decode(env.rgbd_encode(values))
    peak = values.max(axis=1)
    error = np.abs(decoded - values).max(axis=1)
    # from 1 to 255 d scales the texel to the top of the 8-bit range: ~0.4 % steps; below 1
    # d is at its largest (1) and the 8-bit gamma steps grow toward black
    bright = (peak >= 1) & (peak <= 255)
    assert np.all(error[bright] <= 0.006 * peak[bright])
    dim = (peak > 0) & (peak < 1)
    assert np.all(error[dim] <= 0.03 * peak[dim])
    assert decoded[4, 0] == pytest.approx(255.0)  # clipped at RGBD's range
    assert (decoded[5] == 0).all()  # negative radiance written as 0


def test_png_bytes_is_a_valid_png():
    data = np.random.default_rng(3).integers(0, 256, size=(5, 7, 4), dtype=np.uint8)
    png = png_bytes(data)
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    length, kind = struct.unpack(">I4s", png[8:16])
    assert kind == b"IHDR" and struct.unpack(">IIBB", png[16:26]) == (7, 5, 8, 6)
    pos, idat = 8, b""
    while pos < len(png):
        length, kind = struct.unpack(">I4s", png[pos:pos + 8])
        body = png[pos + 4:pos + 8 + length]
        assert struct.unpack(">I", png[pos + 8 + length:pos + 12 + length])[0] == zlib.crc32(body)
        if kind == b"IDAT":
            idat += png[pos + 8:pos + 8 + length]
        pos += 12 + length
    rows = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(5, 1 + 7 * 4)
    assert (rows[:, 0] == 0).all() and (rows[:, 1:].reshape(5, 7, 4) == data).all()
    with pytest.raises(ValueError, match="uint8"):
        png_bytes(data.astype(np.float32))


def test_gltf_document_structure():
    coeffs = np.random.default_rng(4).normal(size=(9, 3))
    document = env.gltf_document(coeffs, sky(), name="sky", extras={"source": "sky.exr"})
    (light,) = document["extensions"]["EXT_lights_image_based"]["lights"]
    assert document["extensionsUsed"] == ["EXT_lights_image_based"]
    assert document["scenes"][0]["extensions"]["EXT_lights_image_based"] == {"light": 0}
    assert light["specularImageSize"] == 64 and light["intensity"] == 1.0
    assert light["specularImages"] == [list(range(6 * i, 6 * i + 6)) for i in range(4)]
    assert len(document["images"]) == 24
    assert all(i["uri"].startswith("data:image/png;base64,") for i in document["images"])
    assert light["extras"] == {"source": "sky.exr"}
    with pytest.raises(ValueError, match="power-of-two size"):
        env.specular_cube(sky(), size=48)
    with pytest.raises(ValueError, match="levels"):
        env.specular_cube(sky(), size=8, levels=5)


@pytest.mark.parametrize("shape", [(1, 1), (8, 1), (1, 8), (2, 2)])
def test_every_level_of_a_tiny_constant_map_is_the_constant(shape):
    # With one texel column every texel centre faces +X, so directions facing
    # away saw no texel in their hemisphere: 0/0 -> NaN -> black on about half the cube.
    pixels = np.full((*shape, 3), 0.7)
    with np.errstate(all="raise"):  # a 0/0 is an error here, not a RuntimeWarning
        chain = env.specular_cube(pixels, size=8, levels=4)
    for level, faces in enumerate(chain):
        assert np.abs(faces - 0.7).max() < 1e-6, (shape, level, faces.min(), faces.max())


def test_a_cube_from_the_downsampled_image_matches_the_full_resolution_one():
    """specular_cube box-downsamples wide images (CUBE_SOURCE_WIDTH) first: on a smooth map
    with noise and a bright patch, the mirror level moves by well under 1 % on average and
    the GGX levels (built from a 4·s-wide source either way) by float32 rounding."""
    rng = np.random.default_rng(1)
    pixels = (sky(256, 512) * (1.0 + 0.1 * rng.random((256, 512, 1)))).astype(np.float32)
    pixels[80:90, 100:117] = 30.0
    full = env.specular_cube(pixels, size=16, levels=3, source_width=None)
    # the same 16 image columns per level-0 texel as CUBE_SOURCE_WIDTH gives a 64² cube
    small = env.specular_cube(pixels, size=16, levels=3, source_width=256)
    for level, (a, b) in enumerate(zip(small, full)):
        change = np.abs(a - b) / b
        if level == 0:
            # texels on the patch's edges change most: 12 % of the level's peak measured
            assert 1e-4 < change.mean() < 0.01 and (np.abs(a - b) / b.max()).max() < 0.15
        else:
            assert change.max() < 1e-4
