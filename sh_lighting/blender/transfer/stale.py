"""Where a transfer bake lives and whether it still fits: the nine attribute names, the
object's JSON record, the fingerprints compared with it, and deleting a bake.

Stale means: the object's vertex coordinates, corners or placement changed (its own
fingerprint), or any rendered object or collection instancer of the scene was moved, edited,
added, hidden or removed (the scene's fingerprint): shadows and bounce light come from all of
them. Both are CRCs computed in milliseconds for 100k vertices, cheap enough for a panel's
draw. Not seen: material edits of other objects (the bounce light's colour) and edits made
by modifiers or geometry nodes of other objects that keep their mesh's coordinates.
"""

import json
import zlib

import numpy as np

from ..data.scene_data import PROPERTY_NAMES

ATTRIBUTE_NAMES = tuple(name.replace("sh_L", "sh_T", 1) for name in PROPERTY_NAMES)
RECORD = "sh_transfer"
RECORD_VERSION = 1
RENDERED_TYPES = {"MESH", "CURVE", "SURFACE", "META", "FONT", "CURVES", "POINTCLOUD", "VOLUME"}

def geometry_fingerprint(obj):
    """Vertex and corner counts and a CRC of the coordinates, corner vertices and placement."""
    mesh = obj.data
    coordinates = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", coordinates)
    corners = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", corners)
    crc = zlib.crc32(coordinates.tobytes())
    crc = zlib.crc32(corners.tobytes(), crc)
    crc = zlib.crc32(np.array(obj.matrix_world, dtype=np.float32).tobytes(), crc)
    return f"{len(mesh.vertices)}:{len(mesh.loops)}:{crc:08x}"


def scene_fingerprint(scene):
    """A CRC over the scene's rendered objects and instancers: names, placement, mesh
    coordinates (an occluder's material or a geometry-nodes edit keeping them is not seen)."""
    crc = 0
    for obj in sorted(scene.objects, key=lambda o: o.name):
        instancing = obj.instance_type != "NONE"
        if (obj.type not in RENDERED_TYPES and not instancing) or obj.hide_render:
            continue
        crc = zlib.crc32(obj.name.encode(), crc)
        crc = zlib.crc32(np.array(obj.matrix_world, dtype=np.float32).tobytes(), crc)
        if obj.type == "MESH":
            coordinates = np.empty(len(obj.data.vertices) * 3, dtype=np.float32)
            obj.data.vertices.foreach_get("co", coordinates)
            crc = zlib.crc32(coordinates.tobytes(), crc)
    return f"{crc:08x}"


def record(obj):
    """The object's bake record (dict) or None if it was never baked or is unreadable."""
    text = obj.get(RECORD) if obj is not None else None
    if not isinstance(text, str):
        return None
    try:
        value = json.loads(text)
    except ValueError:
        return None
    return value if isinstance(value, dict) else None


def status(scene, obj, scene_print=None):
    """(state, message): ("NONE", …) never baked, ("OK", …) or ("STALE", what changed).

    ``scene_print``: ``scene_fingerprint(scene)`` if already computed (a panel listing many
    objects computes it once).
    """
    info = record(obj)
    if info is None or obj.type != "MESH":
        return "NONE", f"'{obj.name}' has no transfer bake"
    missing = [n for n in ATTRIBUTE_NAMES if obj.data.color_attributes.get(n) is None]
    if missing:
        return "STALE", f"'{obj.name}': the transfer attributes were removed: bake again"
    if info.get("geometry") != geometry_fingerprint(obj):
        return "STALE", f"'{obj.name}' was edited or moved since the bake: bake again"
    if info.get("scene") != (scene_print or scene_fingerprint(scene)):
        return "STALE", (
            f"'{obj.name}': objects of the scene changed since the bake (moved, edited, "
            "added, hidden or removed): bake again"
        )
    return "OK", (f"'{obj.name}': baked, {info.get('samples')} samples, "
                  f"{info.get('seconds')} s")


def remove_transfer(obj):
    """Delete the bake's attributes and record from ``obj``; True if there was one."""
    found = obj.get(RECORD) is not None
    if RECORD in obj:
        del obj[RECORD]
    if obj.type == "MESH":
        for name in ATTRIBUTE_NAMES:
            attribute = obj.data.color_attributes.get(name)
            if attribute is not None:
                obj.data.color_attributes.remove(attribute)
                found = True
    return found
