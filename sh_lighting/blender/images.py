"""Read Blender images into numpy arrays laid out the way ``sh_lighting.core`` wants them.

The core takes ``(H, W, C)`` float arrays with rows **top to bottom**; Blender's
``Image.pixels`` run bottom row first, so the arrays returned here are flipped views.

What ``Image.pixels`` holds (observed on Blender 5.0.1, see tests/blender/test_images.py):

* float images (OpenEXR, Radiance HDR, generated float images): the stored float values,
  unchanged; for an EXR these are linear, scene-referred radiance;
* 8-bit images such as an sRGB PNG: the stored bytes divided by 255, **not** linearised: a
  byte of 128 reads as 0.50196, whatever the image's colour space is set to (sRGB or linear).
  Such values must be converted from the image's colour space before they are used as
  radiance; nothing here converts them.

No math here: this module only moves pixels between Blender and numpy.
"""

import os

import bpy
import numpy as np


def has_pixel_data(image):
    """Whether ``image`` has pixels to read (loading them from its file if not done yet)."""
    # Reading ``size`` makes Blender load the image buffer if it has not done so yet; only then
    # does ``has_data`` tell whether loading worked.
    width, height = image.size
    return image.has_data and width > 0 and height > 0


def missing_data_message(image):
    """Why ``image`` has no pixels, and what the user can do about it."""
    name = image.name
    if image.type in {"RENDER_RESULT", "COMPOSITING"}:
        return (
            f"image '{name}' is a {image.type.replace('_', ' ').lower()}, whose pixels Blender "
            "does not expose: save it to an image file (Image > Save As) and use that file"
        )
    if image.packed_file is not None:
        return (
            f"image '{name}' is packed in the .blend file but its data could not be decoded: "
            "unpack it or replace it with a readable image file"
        )
    if image.source in {"FILE", "SEQUENCE", "MOVIE", "TILED"}:
        path = bpy.path.abspath(image.filepath, library=image.library)
        path = os.path.normpath(path) if path else path
        if not path:
            return (
                f"image '{name}' has no file path and no pixel data: open or pack an image "
                "file for it"
            )
        if not os.path.isfile(path):
            return (
                f"image '{name}' has no pixel data because its file '{path}' does not exist: "
                "fix the path (Image Editor > Image > Replace) or pack the image into the "
                ".blend file"
            )
        return (
            f"image '{name}' has no pixel data: Blender could not read its file '{path}' as an "
            "image; check that the file is a valid image (EXR, HDR, PNG, ...) and reload it"
        )
    return f"image '{name}' (source {image.source}) has no pixel data: give it an image to show"


def image_pixels(image):
    """The pixels of a Blender ``image`` as a float32 ``(H, W, 4)`` array, rows top to bottom.

    The array is a flipped view (``[::-1]``) of one freshly allocated buffer filled with
    ``image.pixels.foreach_get``; it is independent of the image afterwards. Float images give
    their stored (linear) values; 8-bit images give byte / 255 in the image's own colour space
    (an sRGB PNG is *not* linearised). Images with fewer than 4 channels are widened to RGBA
    (grey copied to RGB, alpha 1).

    Raises ValueError explaining what to do when the image has no pixel data (file missing or
    unreadable, render result, empty image).
    """
    if not has_pixel_data(image):
        raise ValueError(missing_data_message(image))
    width, height = image.size
    channels = image.channels
    flat = np.empty(width * height * channels, dtype=np.float32)
    image.pixels.foreach_get(flat)
    pixels = flat.reshape(height, width, channels)[::-1]
    if channels == 4:
        return pixels
    rgba = np.ones((height, width, 4), dtype=np.float32)
    if channels >= 3:
        rgba[..., :3] = pixels[..., :3]
    else:
        rgba[..., :3] = pixels[..., :1]
        if channels == 2:
            rgba[..., 3] = pixels[..., 1]
    return rgba


def load_image_pixels(path):
    """Read the image file at ``path`` like :func:`image_pixels`, leaving nothing in bpy.data.

    Raises ValueError naming the path when the file is missing or is not a readable image.
    """
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ValueError(f"image file '{path}' does not exist: check the path")
    try:
        image = bpy.data.images.load(path, check_existing=False)
    except RuntimeError as error:
        raise ValueError(f"Blender could not open image file '{path}': {error}") from None
    try:
        return image_pixels(image)
    finally:
        bpy.data.images.remove(image)
