"""Read Blender images into numpy arrays laid out the way ``sh_lighting.core`` wants them.

(H, W, C) float arrays, rows top to bottom (``Image.pixels`` runs bottom first). Float images
hold scene-linear values already; 8-bit ones hold byte / 255, undecoded. ``linear_pixels`` is
the one decoding every path uses: 8-bit texels are decoded from the image's colour space to
the working space as Cycles does (``core.colour.byte_decoding``: byte 128 of an sRGB PNG is
0.2159 in a Rec.709 file); what Blender renders otherwise than modelled (other colour spaces,
alpha < 1) raises ``DecodeError`` and the reader captures the world instead. Details:
docs/modules.md.
"""

import os

import bpy
import numpy as np

from ...core.colour import BYTE_SPACES, byte_decoding, decode_bytes
from ...formats import exr
from ..data.compat import working_space


# Rows of an 8-bit image decoded at a time (at 8192×4096 the whole-image temporaries were
# 1.5 GB traced; benchmarks/REPORT.md, "Sizes").
DECODE_ROWS = 64


class DecodeError(ValueError):
    """Blender renders the image's texels otherwise than ``linear_pixels`` can reproduce."""


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


def undecodable_reason(image):
    """Why ``linear_pixels`` cannot decode ``image`` whatever its texels, or "" if it can
    (``core.colour.BYTE_SPACES`` lists the 8-bit colour spaces it decodes).

    Looks at the image's settings only (no pixels are read).
    """
    if image.is_float:
        return ""
    settings = image.colorspace_settings
    if settings.is_data or settings.name in BYTE_SPACES:
        return ""
    return (
        f"8-bit image '{image.name}' is in colour space {settings.name}, which is not "
        f"decoded directly (only {', '.join(BYTE_SPACES)} and Non-Color are)"
    )


def linear_pixels(image, keep_transparent=False):
    """The radiance Blender renders from ``image``: float32 (H, W, 4), rows top to bottom.

    Float images give ``image_pixels``' flipped view as it is (no second copy of the image:
    at 8192×4096 the copy cost as long as the readback itself and 512 MB more at its peak).

    RGB is scene linear in the file's working space (see the module docstring); alpha is
    the image's. Raises DecodeError (a ValueError) when Blender renders the texels otherwise
    (``undecodable_reason``, or 8-bit texels with alpha < 1 in Straight or Premultiplied
    alpha mode), and ValueError when the image has no pixel data (``image_pixels``).
    ``keep_transparent``: such texels are decoded as stored (straight colour, its alpha
    beside it) instead, for a caller that leaves them out itself (a photo's cut-out).
    """
    pixels = image_pixels(image)
    reason = undecodable_reason(image)
    if reason:
        raise DecodeError(reason)
    # Float images and alpha modes that ignore alpha show the stored colour (measured against
    # Cycles on 4.2 and 5.0); 8-bit texels with alpha < 1 are shown premultiplied.
    if (
        not keep_transparent and not image.is_float
        and image.alpha_mode in ("STRAIGHT", "PREMUL") and (pixels[..., 3] < 1.0).any()
    ):
        raise DecodeError(
            f"8-bit image '{image.name}' has transparent texels, which Blender shows "
            "premultiplied by their alpha: save it without alpha (RGB) to have it read "
            "directly, or set its Alpha mode to None or Channel Packed to ignore the alpha"
        )
    settings = image.colorspace_settings
    if image.is_float or settings.is_data:
        return pixels
    decoding = byte_decoding(settings.name, working_space())
    decoded = np.empty(pixels.shape, dtype=np.float32)
    for r0 in range(0, pixels.shape[0], DECODE_ROWS):  # row blocks: no full-size temporaries
        block = pixels[r0 : r0 + DECODE_ROWS]
        codes = (block[..., :3] * 255.0 + 0.5).astype(np.uint8)  # exact: pixels are byte / 255
        decoded[r0 : r0 + DECODE_ROWS, :, :3] = decode_bytes(codes, *decoding)
    decoded[..., 3] = pixels[..., 3]
    return decoded


def load_image_pixels(path):
    """The radiance Blender renders from the image file at ``path`` (:func:`linear_pixels`),
    leaving nothing in bpy.data.

    Raises ValueError naming the path when the file is missing or is not a readable image,
    DecodeError when Blender renders it otherwise than it can be decoded here.
    """
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ValueError(f"image file '{path}' does not exist: check the path")
    if exr.is_exr(path):
        exr.check_exr(path)  # a truncated EXR crashes Blender's reader (SIGSEGV)
    try:
        image = bpy.data.images.load(path, check_existing=False)
    except RuntimeError as error:
        raise ValueError(f"Blender could not open image file '{path}': {error}") from None
    try:
        return linear_pixels(image)
    finally:
        bpy.data.images.remove(image)
