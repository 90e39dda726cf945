"""Compute from World, done once per state of the world: a cache of ``world_coefficients``.

Compute from World reuses its last result when the world has not changed. The result lives
in ``_CACHE``, a module-level dict (never in the .blend: it is transient state) keyed by the
world's ``as_pointer()``, holding (signature, coefficients, WorldInfo). A hit needs the whole
signature to be equal, so a pointer reused by another world after undo or deletion cannot
give a wrong answer; the key only bounds the dict to one entry per world (and ``CACHE_SIZE``
in all). A ``load_post`` handler (``register_cache``) empties it when a file is loaded.

The signature is a digest of everything ``world_coefficients`` reads:
* the capture width, whether the world uses nodes (its colour if not), the file's working
  colour space;
* every node of its tree and, recursively, of the node groups it uses: type, name, mute,
  every setting (a generic walk of the node's RNA properties, into structs such as colour
  ramps, curves and image users), every unlinked input's value, every link (muted, valid);
  an Object it references contributes its world matrix, a Text its contents;
* each image: name, source, file path, colour space, alpha mode, generated settings, whether
  its pixels are loaded (``Image.reload`` unloads them, so a reload invalidates), the size and
  modification time of its file on disk, a hash of its packed bytes when packed, and a hash
  of its pixels when it is generated or edited in memory (``is_dirty``), where no file
  describes them;
* the scene's current frame when the world is animated or uses a sequence or movie.
Errors are never cached. The capture path (procedural worlds) is taken only by
``world_coefficients`` itself, so a hit never renders.
"""

import hashlib
import numbers
import os
import time
from dataclasses import replace

import bpy
import numpy as np

from . import compat, preferences, properties, world

CACHE_SIZE = 16
_CACHE = {}
_SKIPPED_PROPERTIES = frozenset(
    {
        "rna_type", "location", "location_absolute", "width", "height", "dimensions", "name",
        "label", "inputs", "outputs", "internal_links", "parent", "warning_propagation",
        "use_custom_color", "color", "color_tag", "select", "hide", "width_hidden",
    }
)
_MAX_DEPTH = 4


def cached_world_coefficients(scene, capture_width=256):
    """``world_coefficients``, reusing the last result while ``world_signature`` is unchanged.

    Returns (a copy of) the (9, 3) coefficients and a ``WorldInfo`` (``cached`` True on a hit).
    """
    start = time.perf_counter()
    world_id = scene.world if scene is not None else None
    if world_id is None:
        return world.world_coefficients(scene, capture_width=capture_width)
    key = world_id.as_pointer()
    entry = _CACHE.get(key)
    images = []
    signature = world_signature(scene, capture_width, images)
    if entry is not None and entry[0] == signature:
        info = replace(entry[2], cached=True, elapsed=time.perf_counter() - start)
        return entry[1].copy(), info
    loaded = [image.has_data for image in images]
    coeffs, info = world.world_coefficients(scene, capture_width=capture_width)
    if [image.has_data for image in images] != loaded:
        # Computing loaded an image: sign again, as the next look-up will see it.
        signature = world_signature(scene, capture_width)
    _CACHE.pop(key, None)
    while len(_CACHE) >= CACHE_SIZE:
        _CACHE.pop(next(iter(_CACHE)))
    _CACHE[key] = (signature, np.array(coeffs, copy=True), info)
    return coeffs, info


def compute_and_store(scene, capture_width=None):
    """Compute from World: ``cached_world_coefficients`` stored on ``scene`` as its
    coefficients and its Reset values.

    ``capture_width`` None: the scene's override, else the add-on preferences', else 256.
    Returns the stored (9, 3) float64 copy and the ``WorldInfo``; a ValueError (``WorldError``
    or invalid coefficients) leaves the scene unchanged.
    """
    if capture_width is None:
        capture_width = properties.capture_width_for(
            getattr(scene, "sh_lighting", None), preferences.addon_preferences()
        )
    coeffs, info = cached_world_coefficients(scene, capture_width=_whole(capture_width))
    return properties.store_coefficients(scene, coeffs, computed=True), info


def _whole(capture_width):
    """``capture_width`` as an int, or a ValueError saying what to pass."""
    if isinstance(capture_width, bool) or not isinstance(capture_width, numbers.Integral):
        raise ValueError(
            f"capture_width is {capture_width!r}: give a whole number of pixels, such as 256"
        )
    return int(capture_width)


def clear_cache():
    """Forget every cached world result."""
    _CACHE.clear()


@bpy.app.handlers.persistent
def _clear_cache_on_load(*_args):
    clear_cache()


def register_cache():
    """Empty the cache whenever a .blend file is loaded (idempotent)."""
    if _clear_cache_on_load not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(_clear_cache_on_load)


def unregister_cache():
    while _clear_cache_on_load in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_clear_cache_on_load)
    clear_cache()


def world_signature(scene, capture_width, images=None):
    """A digest of everything ``world_coefficients(scene, capture_width)`` depends on.

    The images it covers are appended to the list ``images`` when one is given.
    """
    world_id = scene.world
    parts = [int(capture_width), world_id.name_full, compat.uses_nodes(world_id),
             compat.working_space()]
    animated = world_id.animation_data is not None
    tree = world_id.node_tree if compat.uses_nodes(world_id) else None
    if tree is None:
        parts.append(tuple(world_id.color))
    else:
        found = [] if images is None else images
        parts.append(_tree_signature(tree, set(), found))
        animated = animated or _tree_animated(tree, set())
        parts.extend(_image_signature(image) for image in found)
        animated = animated or any(i.source in ("SEQUENCE", "MOVIE") for i in found)
    if animated:
        parts.append(("frame", scene.frame_current, scene.frame_subframe))
    return hashlib.blake2b(repr(parts).encode(), digest_size=20).hexdigest()


def _tree_animated(tree, seen):
    if tree.as_pointer() in seen:
        return False
    seen.add(tree.as_pointer())
    if tree.animation_data is not None:
        return True
    return any(
        _tree_animated(node.node_tree, seen)
        for node in tree.nodes
        if getattr(node, "node_tree", None) is not None
    )


def _value(value):
    if isinstance(value, (set, frozenset)):
        return tuple(sorted(value))
    if hasattr(value, "__len__") and not isinstance(value, str):
        try:
            return tuple(_value(v) for v in value)
        except TypeError:
            return repr(value)
    if isinstance(value, float):
        return float(value).hex()
    return value


def _tree_signature(tree, seen, images):
    if tree.as_pointer() in seen:
        return ("tree", tree.name_full)
    seen.add(tree.as_pointer())
    nodes = []
    for node in sorted(tree.nodes, key=lambda n: n.name):
        sockets = [
            (s.identifier, s.is_linked, _value(getattr(s, "default_value", None)))
            for s in node.inputs
        ]
        settings = _struct_signature(node, 0, seen, images)
        nodes.append((node.name, node.bl_idname, node.mute, settings, sockets))
    links = sorted(
        (
            link.from_node.name,
            link.from_socket.identifier,
            link.to_node.name,
            link.to_socket.identifier,
            link.is_muted,
            link.is_valid,
        )
        for link in tree.links
    )
    return (tree.bl_idname, nodes, links)


def _struct_signature(struct, depth, seen, images):
    """The settings of an RNA struct (a node, a colour ramp, ...), see the cache notes."""
    parts = []
    for prop in struct.bl_rna.properties:
        key = prop.identifier
        if key in _SKIPPED_PROPERTIES or key.startswith(("bl_", "show_")):
            continue
        try:
            value = getattr(struct, key)
        except (AttributeError, RuntimeError, TypeError):
            continue
        if prop.type == "POINTER":
            parts.append((key, _pointer_signature(value, depth, seen, images)))
        elif prop.type == "COLLECTION":
            if depth < _MAX_DEPTH:
                items = [_struct_signature(item, depth + 1, seen, images) for item in value]
                parts.append((key, items))
        else:
            parts.append((key, _value(value)))
    return parts


def _pointer_signature(value, depth, seen, images):
    if value is None:
        return None
    if isinstance(value, bpy.types.Image):
        if all(value != image for image in images):
            images.append(value)
        return ("image", value.name_full)
    if isinstance(value, bpy.types.NodeTree):
        return _tree_signature(value, seen, images)
    if isinstance(value, bpy.types.Object):
        return ("object", value.name_full, _value([tuple(row) for row in value.matrix_world]))
    if isinstance(value, bpy.types.Text):
        return ("text", value.name_full, value.as_string())
    if isinstance(value, bpy.types.ID):
        return ("id", type(value).__name__, value.name_full)
    if depth < _MAX_DEPTH:
        return _struct_signature(value, depth + 1, seen, images)
    return None


def _image_signature(image):
    parts = [
        image.name_full,
        image.source,
        image.type,
        image.filepath,
        image.colorspace_settings.name,
        image.alpha_mode,
        image.is_dirty,
        image.has_data,
        image.generated_type,
        image.generated_width,
        image.generated_height,
        image.use_generated_float,
        _value(image.generated_color),
    ]
    path = bpy.path.abspath(image.filepath, library=image.library) if image.filepath else ""
    try:
        stat = os.stat(path) if path else None
        parts.append((stat.st_size, stat.st_mtime_ns) if stat else None)
    except OSError:
        parts.append("no file")
    if image.packed_file is not None:
        data = image.packed_file.data
        parts.append(("packed", len(data), hashlib.blake2b(data, digest_size=20).hexdigest()))
    if image.has_data and (image.is_dirty or image.source == "GENERATED"):
        width, height = image.size
        pixels = np.empty(width * height * image.channels, dtype=np.float32)
        image.pixels.foreach_get(pixels)
        parts.append(("pixels", width, height, hashlib.blake2b(pixels, digest_size=20).hexdigest()))
    return tuple(parts)
