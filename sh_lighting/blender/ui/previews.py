"""The Design panel's images: one ``bpy.utils.previews`` collection, filled from core's numpy.

``register()`` opens it with the 9 basis images; ``irradiance`` redraws the sphere only when
the coefficients' bytes change, exposed to its own range (brightest pixel white,
``core.preview.fit_exposure``); ``swatch`` is one coefficient's colour square. Preview pixels
run bottom row first with premultiplied alpha, so ``to_preview`` flips and premultiplies.
"""

import bpy
import bpy.utils.previews
import numpy as np

from ...core.polar_plot import polar_image
from ...core.preview import (
    basis_sphere_images,
    fit_exposure,
    irradiance_sphere_image,
    linear_to_srgb,
)

BASIS_SIZE = 64
IRRADIANCE_SIZE = 128
BASIS_NAMES = tuple(f"basis_{k}" for k in range(9))
IRRADIANCE_NAME = "irradiance"
SWATCH_SIZE = 16
PHOTO_SIZE = 160  # the Match Photo dialog's thumbnail: its longer side, px
PHOTO_NAME = "photo"
RING = (1.0, 0.25, 0.1)  # the circle drawn on it
POLAR_SIZE = 128  # a measured luminaire's polar diagram, px

# Blender's previews live in a collection that the add-on must hold from register() to
# unregister() (bpy.utils.previews), so the module keeps that one reference; what the
# collection's images were drawn from (``signature``, ``stops``, ``swatches``, ``photo``) are
# attributes of the collection itself and go with it.
_held = {"collection": None}


def to_preview(preview, rgba):
    """Copy an RGBA float image (H, W, 4), rows top to bottom, into an ``ImagePreview``."""
    height, width = rgba.shape[:2]
    preview.image_size = (width, height)
    premultiplied = np.array(rgba[::-1], dtype=np.float32)
    premultiplied[..., :3] *= premultiplied[..., 3:]
    flat = premultiplied.ravel()
    preview.image_pixels_float.foreach_set(flat)


def from_preview(preview):
    """The pixels of an ``ImagePreview`` as (H, W, 4) float32, rows top to bottom
    (premultiplied alpha, as stored)."""
    width, height = preview.image_size
    flat = np.empty(width * height * 4, dtype=np.float32)
    preview.image_pixels_float.foreach_get(flat)
    return flat.reshape(height, width, 4)[::-1]


def collection():
    """The open previews collection, or a RuntimeError when the add-on is not registered."""
    pcoll = _held["collection"]
    if pcoll is None:
        raise RuntimeError("SH Lighting previews are not available: the add-on is not registered")
    return pcoll


def basis():
    """The 9 ``ImagePreview`` of Y_lm (figure 4), index l(l+1) + m."""
    pcoll = collection()
    return tuple(pcoll[name] for name in BASIS_NAMES)


def signature(coeffs):
    """What the irradiance image depends on, cheap to compare: the float64 bytes."""
    return np.asarray(coeffs, dtype=np.float64).tobytes()


def irradiance(coeffs):
    """(the ``ImagePreview`` of the irradiance sphere of ``coeffs`` ((9, 3) L_lm), its
    exposure in stops).

    A white diffuse sphere as seen from the front (``core.preview.irradiance_sphere_image``)
    at the exposure that shows its brightest pixel white (``fit_exposure``), negative
    irradiance in magenta; recomputed only when the coefficients changed since the last call.
    """
    pcoll = collection()
    preview = pcoll.get(IRRADIANCE_NAME) or pcoll.new(IRRADIANCE_NAME)
    key = signature(coeffs)
    if key != pcoll.signature:
        stops = fit_exposure(coeffs, IRRADIANCE_SIZE)
        image = irradiance_sphere_image(
            coeffs, IRRADIANCE_SIZE, exposure=stops, show_negative=True
        )
        to_preview(preview, image)
        pcoll.signature, pcoll.stops = key, stops
    return preview, pcoll.stops


def swatch_colour(rgb):
    """The display colour of an RGB coefficient: the triple over its channel of largest
    magnitude (so that channel is 1 and a negative light shows its colour too), clipped to
    [0, 1], sRGB-encoded; mid grey for an all-zero triple."""
    rgb = np.asarray(rgb, dtype=np.float64)
    largest = rgb[np.argmax(np.abs(rgb))]
    if largest == 0.0 or not np.isfinite(rgb).all():
        return np.full(3, 0.5)
    return linear_to_srgb(np.clip(rgb / largest, 0.0, 1.0))


def swatch(index, rgb):
    """The ``ImagePreview`` of coefficient ``index``'s colour (``swatch_colour``), redrawn
    only when that colour changes by a display step."""
    pcoll = collection()
    name = f"swatch_{index}"
    preview = pcoll.get(name) or pcoll.new(name)
    colour = swatch_colour(rgb)
    key = tuple(np.round(colour * 255.0).astype(int))
    if pcoll.swatches.get(index) != key:
        image = np.ones((SWATCH_SIZE, SWATCH_SIZE, 4))
        image[..., :3] = colour
        to_preview(preview, image)
        pcoll.swatches[index] = key
    return preview


def photo_thumbnail(pixels, size=PHOTO_SIZE):
    """(thumbnail RGBA (h, w, 4) sRGB-encoded, scale in thumbnail px per photo px) of linear
    ``pixels`` (H, W, 3+), rows top to bottom: every k-th pixel, k making the longer side at
    most ``size``."""
    height, width = pixels.shape[:2]
    step = max(1, -(-max(height, width) // size))
    small = np.asarray(pixels[::step, ::step, :3], dtype=np.float64)
    thumb = np.ones((*small.shape[:2], 4))
    thumb[..., :3] = linear_to_srgb(np.clip(np.nan_to_num(small), 0.0, 1.0))
    return thumb, 1.0 / step


def draw_ring(thumb, scale, circle, width=1.5):
    """``thumb`` with the circle (cx, cy, r in photo pixels from the top-left corner) drawn
    on it as a ring of colour ``RING``; a copy."""
    out = thumb.copy()
    cx, cy, r = (float(v) * scale for v in circle)
    if r <= 0.0:
        return out
    y, x = np.mgrid[0:out.shape[0], 0:out.shape[1]] + 0.5
    ring = np.abs(np.hypot(x - cx, y - cy) - r) <= 0.5 * width
    out[ring, :3] = RING
    return out


def photo(path, pixels, circle):
    """The ``ImagePreview`` of the photo at ``path`` (its linear ``pixels``, read by the
    caller only when the path is new: pass None for the one shown) with ``circle`` drawn;
    None when no photo was given yet."""
    pcoll = collection()
    preview = pcoll.get(PHOTO_NAME) or pcoll.new(PHOTO_NAME)
    held = pcoll.photo
    if pixels is not None:
        held = pcoll.photo = (path, *photo_thumbnail(pixels), None)
    if held is None or held[0] != path:
        return None
    key = tuple(round(float(v), 2) for v in circle)
    if held[3] != key:
        to_preview(preview, draw_ring(held[1], held[2], circle))
        pcoll.photo = (*held[:3], key)
    return preview


def polar(name, measured, fitted):
    """The ``ImagePreview`` of a luminaire's polar diagram (``core.polar_plot``: the file's
    curves against the fitted lamps'), redrawn only when the curves change."""
    pcoll = collection()
    key = f"polar_{name}"
    preview = pcoll.get(key) or pcoll.new(key)
    signature_ = np.asarray(measured, dtype=np.float64).tobytes() + np.asarray(
        fitted, dtype=np.float64).tobytes()
    if pcoll.polar.get(key) != signature_:
        to_preview(preview, polar_image(measured, fitted, POLAR_SIZE))
        pcoll.polar[key] = signature_
    return preview


def register():
    if _held["collection"] is not None:  # registered twice without unregister: start clean
        unregister()
    pcoll = bpy.utils.previews.new()
    for name, image in zip(BASIS_NAMES, basis_sphere_images(BASIS_SIZE), strict=True):
        to_preview(pcoll.new(name), image)
    pcoll.signature, pcoll.stops, pcoll.swatches, pcoll.photo = None, 0.0, {}, None
    pcoll.polar = {}
    _held["collection"] = pcoll


def unregister():
    pcoll = _held["collection"]
    _held["collection"] = None
    if pcoll is not None:
        bpy.utils.previews.remove(pcoll)
