"""sh_lighting.blender.world.images: Blender images -> (H, W, 4) float32 arrays, rows top to bottom."""

import os
import struct
import zlib

import bpy
import numpy as np
import pytest
from blender_files import write_exr

from sh_lighting.blender.world.images import image_pixels, load_image_pixels

pytestmark = pytest.mark.blender

H, W = 3, 5


def known_rgba():
    """Distinct values per texel (rows top to bottom), including values above 1 and alpha < 1."""
    rows = np.arange(H, dtype=np.float32)[:, None]
    cols = np.arange(W, dtype=np.float32)[None, :]
    pixels = np.empty((H, W, 4), dtype=np.float32)
    pixels[..., 0] = 10.0 * rows + cols  # 0..24
    pixels[..., 1] = 0.25 + cols / 8.0
    pixels[..., 2] = 1000.0 * (rows + 1.0)  # sun-like radiance
    pixels[..., 3] = 1.0
    pixels[0, 0, 3] = 0.5
    return pixels


def png_bytes(rgb_rows):
    """A minimal 8-bit RGB PNG (rows top to bottom, as PNG stores them), written by hand."""
    height, width = len(rgb_rows), len(rgb_rows[0])
    raw = b"".join(b"\x00" + bytes(v for px in row for v in px) for row in rgb_rows)

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw))
            + chunk(b"IEND", b""))


def image_names():
    return {image.name for image in bpy.data.images}


def test_exr_round_trip_top_to_bottom(tmp_path):
    expected = known_rgba()
    path = write_exr(tmp_path / "known.exr", expected)
    before = image_names()

    pixels = load_image_pixels(path)

    assert pixels.shape == (H, W, 4)
    assert pixels.dtype == np.float32
    # Float EXR values come back unchanged (linear, no colour management), row 0 on top.
    np.testing.assert_array_equal(pixels, expected)
    assert pixels[0, 3, 0] == 3.0 and pixels[2, 0, 0] == 20.0
    assert image_names() == before  # the datablock was removed again


def test_image_pixels_of_datablock_is_flipped_view(tmp_path):
    expected = known_rgba()
    image = bpy.data.images.load(write_exr(tmp_path / "known.exr", expected))

    pixels = image_pixels(image)

    np.testing.assert_array_equal(pixels, expected)
    # Blender's own order is bottom row first: the first value of image.pixels is the
    # bottom-left texel, i.e. our last row.
    assert image.pixels[0] == expected[H - 1, 0, 0] == 20.0
    # A view of one buffer, flipped; no copy was made.
    assert pixels.strides[0] < 0
    assert pixels.base is not None and pixels.base.size == H * W * 4


def test_linear_pixels_of_a_float_image_is_the_readback_itself(tmp_path):
    """No second copy of a float image (at 8192x4096 it cost as long as the readback)."""
    from sh_lighting.blender.world.images import linear_pixels

    expected = known_rgba()
    image = bpy.data.images.load(write_exr(tmp_path / "known.exr", expected))
    pixels = linear_pixels(image)
    np.testing.assert_array_equal(pixels, expected)
    assert pixels.strides[0] < 0 and pixels.base.size == H * W * 4
    bpy.data.images.remove(image)


def test_generated_float_image(tmp_path):
    expected = known_rgba()
    image = bpy.data.images.new("generated", W, H, float_buffer=True, alpha=True)
    image.pixels.foreach_set(expected[::-1].ravel())
    np.testing.assert_array_equal(image_pixels(image), expected)


def test_8bit_srgb_png_reads_bytes_over_255_not_linearised(tmp_path):
    # Top row: bytes 0, 51, 128, 255 in red; bottom row: 200 in green.
    top = [(0, 7, 9), (51, 7, 9), (128, 7, 9), (255, 7, 9)]
    bottom = [(1, 200, 3)] * 4
    path = tmp_path / "bytes.png"
    path.write_bytes(png_bytes([top, bottom]))

    image = bpy.data.images.load(str(path))
    assert image.colorspace_settings.name == "sRGB"
    assert not image.is_float
    pixels = image_pixels(image)

    assert pixels.shape == (2, 4, 4)
    expected_top = np.array(top, dtype=np.float32) / 255.0
    np.testing.assert_allclose(pixels[0, :, :3], expected_top, atol=1e-6)
    np.testing.assert_allclose(pixels[1, :, 1], 200.0 / 255.0, atol=1e-6)
    np.testing.assert_allclose(pixels[..., 3], 1.0)
    # The sRGB decode of byte 128 would be 0.2158; Blender's Image.pixels gives 0.50196.
    assert abs(pixels[0, 2, 0] - 128.0 / 255.0) < 1e-6
    # Declaring the image linear does not change what Image.pixels returns either.
    image.colorspace_settings.name = "Non-Color"
    np.testing.assert_allclose(image_pixels(image)[0, :, :3], expected_top, atol=1e-6)


def test_missing_file_raises_value_error_with_path(tmp_path):
    path = tmp_path / "nowhere" / "sky.exr"
    before = image_names()
    with pytest.raises(ValueError, match="does not exist") as info:
        load_image_pixels(path)
    assert str(path) in str(info.value)
    assert image_names() == before


def test_unreadable_file_raises_value_error_and_leaves_nothing(tmp_path):
    path = tmp_path / "garbage.exr"
    path.write_bytes(b"this is not an image")
    before = image_names()
    with pytest.raises(ValueError, match="could not read") as info:
        load_image_pixels(path)
    assert str(path) in str(info.value)
    assert image_names() == before


def test_datablock_whose_file_vanished(tmp_path):
    path = write_exr(tmp_path / "gone.exr", known_rgba())
    image = bpy.data.images.load(path)
    os.remove(path)  # removed before Blender read the pixels (images load lazily)
    with pytest.raises(ValueError) as info:
        image_pixels(image)
    message = str(info.value)
    assert "gone.exr" in message and "does not exist" in message
    assert "pack" in message  # tells the user a way out


def test_render_result_is_refused_with_advice():
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 1
    scene.render.resolution_x = scene.render.resolution_y = 4
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    bpy.ops.render.render()
    result = bpy.data.images["Render Result"]
    assert result.type == "RENDER_RESULT"
    with pytest.raises(ValueError, match="save it") as info:
        image_pixels(result)
    assert "Render Result" in str(info.value)


def test_8bit_decoding_in_row_blocks_is_the_whole_image_decoding(tmp_path, monkeypatch):
    """linear_pixels decodes 8-bit images DECODE_ROWS at a time (no full-size temporaries):
    blocks that split the rows unevenly give the same values, top row first."""
    from sh_lighting.blender.world import images
    from sh_lighting.core.colour import srgb_to_linear

    rows = [[((17 * r + 3 * c) % 256, (5 * r) % 256, 255 - c) for c in range(6)]
            for r in range(7)]
    path = tmp_path / "rows.png"
    path.write_bytes(png_bytes(rows))
    image = bpy.data.images.load(str(path))
    monkeypatch.setattr(images, "DECODE_ROWS", 3)
    blocked = images.linear_pixels(image)
    monkeypatch.setattr(images, "DECODE_ROWS", 1 << 20)
    whole = images.linear_pixels(image)
    bpy.data.images.remove(image)
    np.testing.assert_array_equal(blocked, whole)
    assert blocked[6, 0, 0] == pytest.approx(srgb_to_linear((17 * 6 % 256) / 255.0), abs=2e-3)
