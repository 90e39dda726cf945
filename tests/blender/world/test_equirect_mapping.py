"""Pin the core's equirectangular texel <-> direction mapping against Cycles itself.

The world's image encodes each texel's own (row, column) in (R, G); Cycles renders it with a
panoramic or perspective camera (1 sample, Closest, filter 0.01 px), so each output pixel holds
the index of the texel its ray hit, which must equal ``equirect.direction_to_texel`` of the ray
for every pixel not within 2 % of a texel boundary. What Cycles was seen to do (the panoramic
camera's frame, the one ray along +Z that misses the top row): docs/modules.md.
"""

import math

import numpy as np
import pytest

import bpy
from blender_scenes import environment_world
from mathutils import Vector

from sh_lighting.blender.world.images import load_image_pixels
from sh_lighting.core import equirect

pytestmark = pytest.mark.blender

MARGIN = 0.02  # of a texel: rays closer than this to a texel boundary are not compared


def build_coded_world(height, width):
    """World whose equirect texel (i, j) (row i from the top) has colour (i, j, 0.5)."""
    image = bpy.data.images.new("coded", width, height, float_buffer=True, alpha=True)
    pixels = np.empty((height, width, 4), dtype=np.float32)
    pixels[..., 0] = np.arange(height)[:, None]
    pixels[..., 1] = np.arange(width)[None, :]
    pixels[..., 2] = 0.5
    pixels[..., 3] = 1.0
    image.pixels.foreach_set(pixels[::-1].ravel())  # Blender stores the bottom row first
    image.pack()

    scene = bpy.context.scene
    environment_world(scene, image, interpolation="Closest", name="coded")
    return scene


def setup_render(scene, width, height):
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False
    scene.cycles.filter_width = 0.01
    scene.render.dither_intensity = 0.0
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.render.resolution_x = width
    scene.render.resolution_y = height
    scene.render.resolution_percentage = 100
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_mode = "RGBA"
    settings.color_depth = "32"


def add_camera(scene, rotation):
    data = bpy.data.cameras.new("camera")
    camera = bpy.data.objects.new("camera", data)
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location = (0.0, 0.0, 0.0)
    camera.rotation_euler = rotation
    return camera


def make_panoramic(camera):
    camera.data.type = "PANO"
    if hasattr(camera.data, "panorama_type"):  # 4.3+
        camera.data.panorama_type = "EQUIRECTANGULAR"
    else:  # 4.2: the panorama settings live on the Cycles camera properties
        camera.data.cycles.panorama_type = "EQUIRECTANGULAR"


def render(scene, path):
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return load_image_pixels(path)


def camera_rotation(camera):
    bpy.context.view_layer.update()
    return np.array(camera.matrix_world.to_3x3(), dtype=np.float64)


def texel_coordinates(directions, height, width):
    """Continuous texel coordinates (row from the top, column) of unit directions."""
    u, v = equirect.direction_to_uv(directions)
    return (1.0 - v) * height, u * width


def compare(shown, directions, height, width):
    """Assert each pixel away from texel boundaries shows the texel the core predicts.

    Returns the boolean mask of compared pixels.
    """
    rows_f, cols_f = texel_coordinates(directions, height, width)

    def clear(f):
        frac = f - np.floor(f)
        return (frac > MARGIN) & (frac < 1.0 - MARGIN)

    # A ray exactly along a pole is degenerate (see the module docstring): not compared.
    horizontal = np.hypot(directions[..., 0], directions[..., 1])
    compared = clear(rows_f) & clear(cols_f) & (horizontal > 1e-5)
    rows, cols = equirect.direction_to_texel(directions, height, width)
    shown_rows = shown[..., 0]
    shown_cols = shown[..., 1]
    # The encoded values are small integers, stored exactly in a float EXR.
    assert np.array_equal(shown_rows, np.round(shown_rows))
    assert np.all(shown[..., 2] == 0.5)
    bad_rows = compared & (shown_rows != rows)
    assert not bad_rows.any(), (
        f"{bad_rows.sum()} pixels show another row than the core predicts, first at "
        f"{np.argwhere(bad_rows)[:5].tolist()}"
    )
    bad_cols = compared & (shown_cols != cols)
    assert not bad_cols.any(), (
        f"{bad_cols.sum()} pixels show another column than the core predicts, first at "
        f"{np.argwhere(bad_cols)[:5].tolist()}"
    )
    return compared


# Pano frame (forward, left, up) in the camera's local axes: forward = -Z, left = -X, up = +Y.
PANO_TO_LOCAL = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])


def panorama_directions(width, height, rotation):
    y, x = np.mgrid[0:height, 0:width]
    pano = equirect.uv_to_direction((x + 0.5) / width, 1.0 - (y + 0.5) / height)
    return pano @ (rotation @ PANO_TO_LOCAL).T


TEX_H, TEX_W = 32, 64
PANO_W, PANO_H = 150, 75  # not a multiple of the texture: pixel centres fall all over texels


def test_panorama_facing_x_is_the_environment_image(tmp_path):
    scene = build_coded_world(TEX_H, TEX_W)
    setup_render(scene, PANO_W, PANO_H)
    camera = add_camera(scene, (math.pi / 2, 0.0, -math.pi / 2))
    make_panoramic(camera)
    rotation = camera_rotation(camera)
    # This rotation makes the panorama's frame the world frame.
    np.testing.assert_allclose(rotation @ PANO_TO_LOCAL, np.eye(3), atol=1e-6)

    shown = render(scene, tmp_path / "pano_x.exr")
    assert shown.shape == (PANO_H, PANO_W, 4)
    directions = panorama_directions(PANO_W, PANO_H, rotation)
    compared = compare(shown, directions, TEX_H, TEX_W)
    assert compared.mean() > 0.9

    # In words: the render is the texture resampled, top row = zenith, centre column = +X.
    y, x = np.mgrid[0:PANO_H, 0:PANO_W]
    rows_f = (y + 0.5) * TEX_H / PANO_H
    cols_f = (x + 0.5) * TEX_W / PANO_W
    inside = compared & (np.abs(rows_f - np.round(rows_f)) > MARGIN)
    inside &= np.abs(cols_f - np.round(cols_f)) > MARGIN
    assert np.array_equal(shown[..., 0][inside], np.floor(rows_f)[inside])
    assert np.array_equal(shown[..., 1][inside], np.floor(cols_f)[inside])


def test_tilted_panorama_matches_core_for_every_pixel(tmp_path):
    scene = build_coded_world(TEX_H, TEX_W)
    setup_render(scene, PANO_W, PANO_H)
    camera = add_camera(scene, (1.1, 0.3, 2.0))
    make_panoramic(camera)
    rotation = camera_rotation(camera)

    shown = render(scene, tmp_path / "pano_tilted.exr")
    directions = panorama_directions(PANO_W, PANO_H, rotation)
    compared = compare(shown, directions, TEX_H, TEX_W)
    assert compared.mean() > 0.9
    # The tilt matters: the untilted mapping would disagree with most of this render.
    untilted = panorama_directions(PANO_W, PANO_H, np.linalg.inv(PANO_TO_LOCAL))
    rows, cols = equirect.direction_to_texel(untilted, TEX_H, TEX_W)
    assert np.mean((shown[..., 0] == rows) & (shown[..., 1] == cols)) < 0.2


# Odd sizes put the +X and +Y axes and the equator inside texels, not on their edges.
PERSP_TEX_H, PERSP_TEX_W = 23, 45
PERSP_SIZE = 41  # odd, so the centre pixel's ray is the camera's aim
PERSP_ANGLE = math.radians(20.0)


def perspective_directions(size, angle, rotation):
    y, x = np.mgrid[0:size, 0:size]
    half = math.tan(angle / 2.0)
    local = np.stack(
        [
            ((x + 0.5) / size - 0.5) * 2.0 * half,
            (0.5 - (y + 0.5) / size) * 2.0 * half,
            -np.ones(x.shape),
        ],
        axis=-1,
    )
    world = local @ rotation.T
    return world / np.linalg.norm(world, axis=-1, keepdims=True)


AIMS = {
    "+X": (1.0, 0.0, 0.0),
    "+Y": (0.0, 1.0, 0.0),
    "+Z": (0.0, 0.0, 1.0),
    "-X": (-1.0, 0.0, 0.0),
    "oblique": (0.3, -0.5, 0.4),
}


@pytest.mark.parametrize("name", list(AIMS))
def test_perspective_shots(tmp_path, name):
    scene = build_coded_world(PERSP_TEX_H, PERSP_TEX_W)
    setup_render(scene, PERSP_SIZE, PERSP_SIZE)
    aim_wanted = Vector(AIMS[name]).normalized()
    camera = add_camera(scene, aim_wanted.to_track_quat("-Z", "Y").to_euler())
    camera.data.type = "PERSP"
    camera.data.lens_unit = "FOV"
    camera.data.sensor_fit = "AUTO"
    camera.data.angle = PERSP_ANGLE
    rotation = camera_rotation(camera)
    aim = -rotation[:, 2]  # a Blender camera looks down its local -Z
    np.testing.assert_allclose(aim, np.array(aim_wanted), atol=1e-6)

    shown = render(scene, tmp_path / f"persp_{name}.exr")
    assert shown.shape == (PERSP_SIZE, PERSP_SIZE, 4)
    centre = PERSP_SIZE // 2
    row, col = equirect.direction_to_texel(aim, PERSP_TEX_H, PERSP_TEX_W)
    shown_row, shown_col = shown[centre, centre, 0], shown[centre, centre, 1]
    if name == "+Z":
        # The centre ray is exactly the zenith, which Cycles does not resolve (module
        # docstring); the 8 pixels around it, 0.5 degrees off the pole, show the top row.
        assert row == 0
        around = shown[centre - 1 : centre + 2, centre - 1 : centre + 2, 0].ravel()
        assert np.all(np.delete(around, 4) == 0)
    elif name == "-X":
        # -X lies on the seam u = 0 (column 0 and column W - 1 meet there).
        assert row == (PERSP_TEX_H - 1) // 2
        assert shown_row == row
        assert shown_col in (0, PERSP_TEX_W - 1)
    else:
        assert (shown_row, shown_col) == (row, col)

    directions = perspective_directions(PERSP_SIZE, PERSP_ANGLE, rotation)
    np.testing.assert_allclose(directions[centre, centre], aim, atol=1e-6)
    compared = compare(shown, directions, PERSP_TEX_H, PERSP_TEX_W)
    assert compared.mean() > 0.8
    # The shot spans several texels, so the comparison is not one texel repeated.
    assert len({(r, c) for r, c in shown[..., :2].reshape(-1, 2)[compared.ravel()].tolist()}) >= 4


def test_expected_centre_texels_for_axes():
    """What the core predicts for the axis shots above, spelled out (the Cycles tests pin it)."""
    h, w = PERSP_TEX_H, PERSP_TEX_W
    for direction, expected in [
        ((1.0, 0.0, 0.0), (11, 22)),  # image centre
        ((0.0, 1.0, 0.0), (11, 11)),  # u = 0.25: a quarter of the width from the left
        ((0.0, -1.0, 0.0), (11, 33)),  # u = 0.75
        ((0.0, 0.0, 1.0), (0, 22)),
        ((0.0, 0.0, -1.0), (22, 22)),
    ]:
        row, col = equirect.direction_to_texel(np.array(direction), h, w)
        assert (int(row), int(col)) == expected
