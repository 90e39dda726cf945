"""Files the Blender tests write: lossless float EXRs made with Blender itself.

``Image.save`` on a generated float image tags the file as sRGB display data and changes the
values; ``Image.save_render`` with a scene whose image settings ask for 32-bit RGBA OpenEXR
writes them exactly. A temporary scene carries those settings, so no user scene changes.
"""

import bpy
import numpy as np


def write_exr(path, pixels):
    """Save top-to-bottom float ``pixels`` (H, W, 3 or 4) as a lossless 32-bit RGBA EXR."""
    height, width = pixels.shape[:2]
    rgba = np.ones((height, width, 4), dtype=np.float32)
    rgba[..., : pixels.shape[2]] = pixels[..., :4]
    image = bpy.data.images.new("sh_test_exr", width, height, float_buffer=True, alpha=True)
    image.pixels.foreach_set(np.ascontiguousarray(rgba[::-1]).ravel())  # bottom row first
    scene = bpy.data.scenes.new("sh_test_exr")
    settings = scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "OPEN_EXR", "RGBA", "32"
    settings.exr_codec = "ZIP"  # lossless
    image.save_render(str(path), scene=scene)
    bpy.data.scenes.remove(scene)
    bpy.data.images.remove(image)
    return str(path)


def write_constant_exr(path, rgb, width=16, height=8):
    """A constant-colour EXR of ``width`` × ``height`` texels (alpha 1)."""
    return write_exr(path, np.broadcast_to(np.asarray(rgb, dtype=np.float32), (height, width, 3)))


# Provenance records for tests that store coefficients (``scene_data.store``): values set by a
# script, and values standing for ones computed from the world (they become the Reset values).
SCRIPT = {"source": "SCRIPT"}
WORLD = {"source": "WORLD"}


def write_png(path, values, alpha=None):
    """Top-to-bottom 8-bit ``values`` (H, W, 3) as a PNG (RGBA when ``alpha`` is given)."""
    height, width = values.shape[:2]
    rgba = np.ones((height, width, 4), dtype=np.float32)
    rgba[..., :3] = np.asarray(values) / 255.0
    if alpha is not None:
        rgba[..., 3] = np.asarray(alpha) / 255.0
    image = bpy.data.images.new("tmp", width, height, alpha=alpha is not None)
    image.pixels.foreach_set(np.ascontiguousarray(rgba[::-1]).ravel())
    image.filepath_raw = str(path)
    image.file_format = "PNG"
    image.save()
    bpy.data.images.remove(image)
    return str(path)
