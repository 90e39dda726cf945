"""Compute from World: the world's coefficients stored on the scene, with where they came from.

No cache: Compute is an explicit button press, reading a world image costs milliseconds
(7-12 ms for the 1024×512 HDRIs bundled with Blender, 0.1-0.2 s at 4096×2048) and a capture
of a procedural world about 3 s at the default width (benchmarks/REPORT.md §4); the cache
that reused results while the world was unchanged cost more than a fresh compute on a packed
image (it hashed every byte) and ~260 lines of signatures.
"""

import numbers
import os

import bpy

from .. import preferences, properties, scene_data
from . import reader as world


def world_provenance(info):
    """The provenance ``store`` records for a ``world.WorldInfo``: source "WORLD", the world,
    how it was read, the working colour space of the values and what was read (image, its
    file, projection, Mapping rotation, Strength; or the capture width)."""
    record = {"source": "WORLD", "world": info.world, "method": info.source.upper(),
              "working_space": info.working_space}
    if info.source == "image":
        record["image"] = info.image
        image = bpy.data.images.get(info.image)
        if image is not None and image.filepath:
            path = bpy.path.abspath(image.filepath, library=image.library)
            record["path"] = os.path.normpath(path)
        record["projection"] = info.projection
        record["rotation"] = [float(v) for v in (info.rotation or (0.0, 0.0, 0.0))]
        record["strength"] = float(info.strength)
    else:
        record["capture_width"] = int(info.capture_width)
    return record


def compute_and_store(scene, capture_width=None):
    """Compute from World: ``world.world_coefficients`` stored on ``scene`` (``scene_data.store``,
    source "WORLD": they are also the Reset values).

    ``capture_width`` None: the scene's override, else the add-on preferences', else 256 (an
    odd width rounded up). Returns the stored (9, 3) float64 copy and the ``WorldInfo``; a
    ValueError (``WorldError`` or invalid coefficients) leaves the scene unchanged.
    """
    if capture_width is None:
        capture_width = properties.capture_width_for(
            getattr(scene, "sh_lighting", None), preferences.addon_preferences()
        )
    coeffs, info = world.world_coefficients(scene, capture_width=_whole(capture_width))
    return scene_data.store(scene, coeffs, world_provenance(info)), info


def _whole(capture_width):
    """``capture_width`` as an int, or a ValueError saying what to pass."""
    if isinstance(capture_width, bool) or not isinstance(capture_width, numbers.Integral):
        raise ValueError(
            f"capture_width is {capture_width!r}: give a whole number of pixels, such as 256"
        )
    return int(capture_width)
