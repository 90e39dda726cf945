"""The Design panel's images: one ``bpy.utils.previews`` collection, filled from core's numpy.

``register()`` opens the collection and fills the 9 basis images (they never change);
``unregister()`` removes it. The irradiance sphere is refreshed on demand: ``irradiance``
compares a cheap signature of the coefficients (their bytes and the exposure) with the one it
last drew and recomputes only when it differs, so drawing the panel costs nothing while the
lighting stays the same and one small image (``bench_preview``: a few ms) after an edit.

``ImagePreview`` pixels run bottom row first and are stored as bytes (values quantised to
1/255); core's images run top row first, so ``to_preview`` flips them. Headless, Blender gives
every preview ``icon_id`` 0 (there are no UI icons), but the pixels are kept.
"""

import bpy
import bpy.utils.previews
import numpy as np

from ..core.preview import basis_sphere_images, irradiance_sphere_image

BASIS_SIZE = 64
IRRADIANCE_SIZE = 128
BASIS_NAMES = tuple(f"basis_{k}" for k in range(9))
IRRADIANCE_NAME = "irradiance"

# The collection and the signature of the irradiance image it holds; None when unregistered.
_state = {"collection": None, "signature": None}


def to_preview(preview, rgba):
    """Copy an RGBA float image (H, W, 4), rows top to bottom, into an ``ImagePreview``."""
    height, width = rgba.shape[:2]
    preview.image_size = (width, height)
    flat = np.ascontiguousarray(rgba[::-1], dtype=np.float32).ravel()
    preview.image_pixels_float.foreach_set(flat)


def from_preview(preview):
    """The pixels of an ``ImagePreview`` as (H, W, 4) float32, rows top to bottom."""
    width, height = preview.image_size
    flat = np.empty(width * height * 4, dtype=np.float32)
    preview.image_pixels_float.foreach_get(flat)
    return flat.reshape(height, width, 4)[::-1]


def collection():
    """The open previews collection, or a RuntimeError when the add-on is not registered."""
    pcoll = _state["collection"]
    if pcoll is None:
        raise RuntimeError("SH Lighting previews are not available: the add-on is not registered")
    return pcoll


def basis():
    """The 9 ``ImagePreview`` of Y_lm (figure 4), index l(l+1) + m."""
    pcoll = collection()
    return tuple(pcoll[name] for name in BASIS_NAMES)


def signature(coeffs, exposure):
    """What the irradiance image depends on, cheap to compare: the float64 bytes, exposure."""
    return np.asarray(coeffs, dtype=np.float64).tobytes(), float(exposure)


def irradiance(coeffs, exposure=0.0):
    """The ``ImagePreview`` of the irradiance sphere of ``coeffs`` ((9, 3) L_lm).

    A white diffuse sphere as seen from the front (``core.preview.irradiance_sphere_image``)
    at ``exposure`` stops, negative irradiance in magenta; recomputed only when the
    coefficients or the exposure changed since the last call.
    """
    pcoll = collection()
    preview = pcoll.get(IRRADIANCE_NAME) or pcoll.new(IRRADIANCE_NAME)
    key = signature(coeffs, exposure)
    if key != _state["signature"]:
        image = irradiance_sphere_image(
            coeffs, IRRADIANCE_SIZE, exposure=exposure, show_negative=True
        )
        to_preview(preview, image)
        _state["signature"] = key
    return preview


def register():
    if _state["collection"] is not None:  # registered twice without unregister: start clean
        unregister()
    pcoll = bpy.utils.previews.new()
    for name, image in zip(BASIS_NAMES, basis_sphere_images(BASIS_SIZE), strict=True):
        to_preview(pcoll.new(name), image)
    _state["collection"] = pcoll
    _state["signature"] = None


def unregister():
    pcoll = _state["collection"]
    _state["collection"] = None
    _state["signature"] = None
    if pcoll is not None:
        bpy.utils.previews.remove(pcoll)
