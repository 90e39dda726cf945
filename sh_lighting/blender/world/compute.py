"""Compute from World: the world's coefficients stored on the scene, with where they came from.

No cache: Compute is an explicit button press, reading a world image costs milliseconds
(7-12 ms for the 1024×512 HDRIs bundled with Blender, 0.1-0.2 s at 4096×2048) and a capture
of a procedural world about 3 s at the default width (benchmarks/REPORT.md, "the world
cache"); the cache
that reused results while the world was unchanged cost more than a fresh compute on a packed
image (it hashed every byte) and ~260 lines of signatures.
"""

import numbers
import os
from dataclasses import dataclass, field

import bpy
import numpy as np

from ..data import preferences, settings, scene_data
from . import reader


def world_provenance(info):
    """The provenance ``store`` records for a ``reader.WorldInfo``: source "WORLD", the world,
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


# Normals at which the Compute button measures the 9-term error against the world: 64 brute-
# force passes over the pixels, box-averaged to about 512 wide (irradiance.error_estimate).
# Measured on the 2-core machine at a load average of 11: the whole click on Blender's
# forest.exr (1024×512) 1.7 s, error 0.76 % mean (768 normals: 0.79 %); 256 normals took 3.8 s.
REPORT_ERROR_NORMALS = 64


def compute_and_store(scene, capture_width=None, error_normals=0, nonfinite="raise",
                      keep_radiance=False):
    """The world's coefficients (``reader.world_coefficients``) stored on ``scene``
    (``scene_data.store``, source "WORLD": they are also the Reset values).

    ``capture_width`` None: the scene's override, else the add-on preferences', else 256 (an
    odd width rounded up). ``error_normals`` > 0: the ``WorldInfo`` also holds the 9-term error
    against the world at that many normals; ``keep_radiance``: it holds the map that was read.
    Returns the stored (9, 3) float64 copy and the ``WorldInfo``; a ValueError
    (``WorldError`` or invalid coefficients) leaves the scene unchanged.
    """
    if capture_width is None:
        capture_width = settings.capture_width_for(
            getattr(scene, "sh_lighting", None), preferences.addon_preferences()
        )
    coeffs, info = reader.world_coefficients(scene, capture_width=_whole(capture_width),
                                             error_normals=error_normals, nonfinite=nonfinite,
                                             keep_radiance=keep_radiance)
    return scene_data.store(scene, coeffs, world_provenance(info)), info


def report(info, elapsed):
    """The Compute button's one-line report of a ``WorldInfo``: what was read (the image and
    world by name, or the capture's size), the 9-term error against the world as a fraction
    of its light, and ``elapsed``, the seconds the whole button press took."""
    if info.source == "image":
        origin = f"image '{info.image}' of world '{info.world}'"
    else:
        width = info.capture_width or 0
        origin = f"a {width}×{width // 2} Cycles capture of world '{info.world}'"
    if info.error is not None:
        mean, largest = info.error
        error = (f"9-term error {100 * mean:.2f} % mean, {100 * largest:.2f} % max of the "
                 f"light ({info.error_normals} normals)")
    elif info.projection == "MIRROR_BALL":
        error = "9-term error not measured for a mirror-ball image"
    else:
        error = "9-term error not measured: a colour channel has no light"
    return f"Computed from {origin}: {error}, in {elapsed:.2f} s"


def _whole(capture_width):
    """``capture_width`` as an int, or a ValueError saying what to pass."""
    if isinstance(capture_width, bool) or not isinstance(capture_width, numbers.Integral):
        raise ValueError(
            f"capture_width is {capture_width!r}: give a whole number of pixels, such as 256"
        )
    return int(capture_width)


# -- do the stored values come from the world as it is now? -----------------------------------


@dataclass(frozen=True)
class WorldMatch:
    """What ``world_match`` found.

    record: the provenance of the Reset values when the scene's coefficients are exactly
    those ({} otherwise: edited, loaded or never computed); source: the world's
    ``ImageSource`` as it reads now when it is the image, world, Strength, Mapping rotation
    and working space ``record`` names (else None); reason: why ``source`` is None ("" when
    it is not); stale: True when the values are the ones computed from a world image but the
    world now reads differently (an export pairing them with the world would mix two).
    """

    record: dict = field(default_factory=dict)
    source: object = None
    reason: str = ""
    stale: bool = False


def world_match(scene):
    """Whether ``scene``'s coefficients are exactly what Compute from World stored from its
    world as the world reads now (``reader.read_world``: image, file, projection, Strength and
    Mapping rotation as evaluated at the current frame, working space): the one check for
    the glTF export's specular cube, the exported metadata and the windows' error against
    the world. Nothing is re-projected. Returns a ``WorldMatch``.
    """
    computed = scene_data.get_computed(scene)
    if computed is None or not scene_data.has_coefficients(scene):
        return WorldMatch(reason="nothing was computed from the world")
    if not np.array_equal(computed, scene_data.get_coefficients(scene)):
        return WorldMatch(reason="the coefficients were edited, loaded or split since "
                          "Compute from World")
    record = scene_data.computed_provenance(scene)
    if record.get("method") != "IMAGE":
        return WorldMatch(record, reason="they were computed from a capture, not an image")
    try:
        source = reader.read_world(scene)
    except reader.WorldError as why:
        return WorldMatch(record, reason=f"the world cannot be read now: {why}", stale=True)
    if not isinstance(source, reader.ImageSource):
        return WorldMatch(record, reason=f"world '{source.world}' is no longer an image "
                          f"({source.reason})", stale=True)
    changed = _changes(record, source)
    if changed:
        return WorldMatch(record, reason="the world changed since Compute from World: "
                          + "; ".join(changed), stale=True)
    return WorldMatch(record, source)


def _changes(record, source):
    """What differs between provenance ``record`` and the ``ImageSource`` read now."""
    rotation = [float(v) for v in (source.rotation or (0.0, 0.0, 0.0))]
    now = {"world": source.world, "image": source.image.name,
           "projection": source.projection, "working_space": source.working_space,
           "strength": float(source.strength), "rotation": rotation}
    if "path" in record:
        image = source.image
        now["path"] = os.path.normpath(bpy.path.abspath(image.filepath, library=image.library))
    changed = []
    for key, value in now.items():
        then = record.get(key)
        then = list(then) if key == "rotation" and then is not None else then
        if key in record and then != value:
            changed.append(f"{key.replace('_', ' ')} {value!r} now, {then!r} then")
    return changed
