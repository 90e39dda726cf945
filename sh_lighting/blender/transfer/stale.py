"""Where a transfer bake lives and whether it still fits: the nine attribute names, the
object's JSON record, the fingerprints compared with it, and deleting a bake.

Stale means: what the bake saw changed. The object's own fingerprint: its mesh's coordinates
and corners, and its evaluated geometry (shape keys, animation) and placement; the scene's:
every object the view layer renders (an object or collection disabled in renders, a
collection excluded, holdout or indirect only, ray visibility, instancers), each with its
evaluated placement and geometry and its modifiers' settings (render and viewport can
differ). Lamps, cameras and the world do not count (the transfer is the response to the world
Y_lm alone). Evaluated from the depsgraph, updated first, so a script's edit is seen at once.
CRCs, milliseconds for 100k vertices. Not seen: other objects' material edits (the bounce
light's colour).
"""

import json
import zlib

import bpy
import numpy as np

from ..data.scene_data import PROPERTY_NAMES

ATTRIBUTE_NAMES = tuple(name.replace("sh_L", "sh_T", 1) for name in PROPERTY_NAMES)
RECORD = "sh_transfer"
# A per-texel bake (``texels``): the atlas UV map on the mesh, nine images in the file.
UV_NAME = "sh_transfer_uv"
IMAGE_NAMES = tuple(f"SH Transfer {name[3:]}" for name in ATTRIBUTE_NAMES)  # SH Transfer T00
IMAGE_MARKER = "sh_lighting_transfer_image"
# The lamps' bounce B (EEVEE only: its lamps light directly but bounce nothing): the
# irradiance the scene's lamps give after at least one bounce, per corner or per texel.
BOUNCE_ATTRIBUTE = "sh_TB"
BOUNCE_IMAGE = "SH Transfer TB"
BOUNCE_MARKER = len(IMAGE_NAMES)  # its IMAGE_MARKER value
SCRATCH_NAME = "sh_transfer_bake"  # the attribute Cycles bakes into, removed after each bake
RECORD_VERSION = 2
RENDERED_TYPES = {"MESH", "CURVE", "SURFACE", "META", "FONT", "CURVES", "POINTCLOUD", "VOLUME"}
# Object settings that change what Cycles' bake sees of an object (ray visibility and kind).
RAY_SETTINGS = ("visible_diffuse", "visible_glossy", "visible_transmission",
                "visible_volume_scatter", "visible_shadow", "is_holdout", "is_shadow_catcher")
_INSTANCE_DEPTH = 4  # collection instances inside instances, followed this deep


def view_layer_of(scene):
    """The view layer a bake in ``scene`` renders: the context's, else the scene's first."""
    context_layer = getattr(bpy.context, "view_layer", None)
    if bpy.context.scene == scene and context_layer is not None:
        return context_layer
    return scene.view_layers[0]


def evaluated_depsgraph(scene):
    """``scene``'s depsgraph, evaluated now (a script's edits since the last update seen)."""
    view_layer = view_layer_of(scene)
    if view_layer == getattr(bpy.context, "view_layer", None):
        return bpy.context.evaluated_depsgraph_get()
    view_layer.update()
    return view_layer.depsgraph


def rendered_objects(view_layer):
    """{object: its layer collection's (holdout, indirect only)} for every object the view
    layer renders: not disabled in renders, in a collection neither excluded nor disabled."""
    found = {}

    def walk(layer_collection):
        collection = layer_collection.collection
        if layer_collection.exclude or collection.hide_render:
            return
        flags = (layer_collection.holdout, layer_collection.indirect_only)
        for obj in collection.objects:
            if not obj.hide_render:
                found.setdefault(obj, flags)
        for child in layer_collection.children:
            walk(child)

    walk(view_layer.layer_collection)
    return found


def _evaluated(obj, depsgraph):
    try:
        return obj.evaluated_get(depsgraph)
    except (RuntimeError, ReferenceError):  # not in this depsgraph (e.g. disabled in viewports)
        return obj


def _crc_coordinates(mesh, crc):
    coordinates = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", coordinates)
    return zlib.crc32(coordinates.tobytes(), crc)


def _settings(struct):
    """The RNA settings of ``struct`` (a modifier) as text: values, IDs by name."""
    values = []
    for prop in struct.bl_rna.properties:
        if prop.identifier == "rna_type" or prop.type == "COLLECTION":
            continue
        try:
            value = getattr(struct, prop.identifier)
        except (AttributeError, RuntimeError):
            continue
        if prop.type == "POINTER":
            value = getattr(value, "name_full", None)
        elif getattr(prop, "is_array", False):
            value = tuple(value)
        values.append((prop.identifier, value))
    if isinstance(struct, bpy.types.NodesModifier):  # its inputs are ID properties
        values.extend((key, str(struct[key])) for key in struct.keys())
    return repr(values)


def _object_crc(obj, depsgraph, crc, depth=0):
    """``crc`` updated with what a bake sees of ``obj``: name, ray settings, evaluated
    placement and geometry, the mesh's own coordinates (an edit not yet evaluated), modifiers,
    and the objects of the collection it instances."""
    evaluated = _evaluated(obj, depsgraph)
    crc = zlib.crc32(obj.name_full.encode(), crc)
    crc = zlib.crc32(repr([getattr(obj, key, None) for key in RAY_SETTINGS]).encode(), crc)
    crc = zlib.crc32(np.array(evaluated.matrix_world, dtype=np.float32).tobytes(), crc)
    for modifier in obj.modifiers:
        crc = zlib.crc32(_settings(modifier).encode(), crc)
    if obj.type == "MESH":
        crc = _crc_coordinates(obj.data, crc)
        if evaluated is not obj and isinstance(evaluated.data, bpy.types.Mesh):
            crc = _crc_coordinates(evaluated.data, crc)
    elif obj.type in RENDERED_TYPES:
        crc = zlib.crc32(np.array(evaluated.bound_box, dtype=np.float32).tobytes(), crc)
    collection = obj.instance_collection if obj.instance_type == "COLLECTION" else None
    if collection is not None and depth < _INSTANCE_DEPTH:
        crc = zlib.crc32(collection.name_full.encode(), crc)
        for inner in sorted(collection.all_objects, key=lambda o: o.name_full):
            if not inner.hide_render:
                crc = _object_crc(inner, depsgraph, crc, depth + 1)
    return crc


def geometry_fingerprint(obj, depsgraph=None):
    """Vertex and corner counts and a CRC of the corners and of what ``_object_crc`` sees."""
    depsgraph = depsgraph or evaluated_depsgraph(bpy.context.scene)
    mesh = obj.data
    corners = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", corners)
    crc = _object_crc(obj, depsgraph, zlib.crc32(corners.tobytes()))
    return f"{len(mesh.vertices)}:{len(mesh.loops)}:{crc:08x}"


def scene_fingerprint(scene, depsgraph=None):
    """A CRC over what a bake in ``scene`` sees of the objects its view layer renders
    (``_object_crc`` of each, with the holdout and indirect-only flags of its collection)."""
    depsgraph = depsgraph or evaluated_depsgraph(scene)
    crc = 0
    objects = rendered_objects(view_layer_of(scene))
    for obj in sorted(objects, key=lambda o: o.name_full):
        if obj.type not in RENDERED_TYPES and obj.instance_type == "NONE":
            continue
        crc = zlib.crc32(repr(objects[obj]).encode(), crc)
        crc = _object_crc(obj, depsgraph, crc)
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


def status(scene, obj, scene_print=None, depsgraph=None):
    """(state, message): ("NONE", …) never baked, ("OK", …) or ("STALE", what changed).

    ``scene_print``: ``scene_fingerprint(scene)`` and ``depsgraph``: ``scene``'s evaluated
    depsgraph, if already at hand (a panel listing many objects computes them once).
    """
    info = record(obj)
    if info is None or obj.type != "MESH":
        return "NONE", f"'{obj.name}' has no transfer bake"
    missing = missing_parts(obj, info)
    if missing:
        return "STALE", f"'{obj.name}': {missing}: bake again"
    if info.get("version") != RECORD_VERSION:
        return "STALE", f"'{obj.name}' was baked by an older version of the add-on: bake again"
    depsgraph = depsgraph or evaluated_depsgraph(scene)
    if info.get("geometry") != geometry_fingerprint(obj, depsgraph):
        return "STALE", f"'{obj.name}' was edited or moved since the bake: bake again"
    if info.get("scene") != (scene_print or scene_fingerprint(scene, depsgraph)):
        return "STALE", (
            f"'{obj.name}': objects of the scene changed since the bake (moved, edited, "
            "added, hidden or removed): bake again"
        )
    return "OK", (f"'{obj.name}': baked, {info.get('samples')} samples, "
                  f"{info.get('seconds')} s")


def atlas_images():
    """The atlas's nine images in index order (the add-on's: local, marked), or None if one
    is missing."""
    found = [bpy.data.images.get(name) for name in IMAGE_NAMES]
    if any(i is None or i.library is not None or i.get(IMAGE_MARKER) != index
           for index, i in enumerate(found)):
        return None
    return found


def bounce_image():
    """The atlas's bounce image (the add-on's: local, marked) or None."""
    image = bpy.data.images.get(BOUNCE_IMAGE)
    if image is None or image.library is not None or image.get(IMAGE_MARKER) != BOUNCE_MARKER:
        return None
    return image


def missing_parts(obj, info):
    """What of ``obj``'s bake (record ``info``) is gone: a phrase, or None."""
    if info.get("store") == "TEXELS":
        if obj.data.uv_layers.get(UV_NAME) is None:
            return "the transfer's UV map was removed"
        if atlas_images() is None:
            return "the transfer's images were removed"
        return None
    if any(obj.data.color_attributes.get(n) is None for n in ATTRIBUTE_NAMES):
        return "the transfer attributes were removed"
    return None


def has_transfer(obj):
    """True if ``obj`` holds anything of a bake: its record or one of the attributes."""
    if obj.get(RECORD) is not None:
        return True
    return obj.type == "MESH" and (obj.data.uv_layers.get(UV_NAME) is not None or any(
        obj.data.color_attributes.get(n) is not None
        for n in ATTRIBUTE_NAMES + (BOUNCE_ATTRIBUTE, SCRATCH_NAME)))


def remove_transfer(obj):
    """Delete the bake's attributes (the scratch one of an interrupted bake too), atlas UV map
    and record from ``obj``, and the atlas images once no object of the file is baked per
    texel; True if there was any."""
    found = obj.get(RECORD) is not None
    if RECORD in obj:
        del obj[RECORD]
    if obj.type == "MESH":
        for name in ATTRIBUTE_NAMES + (BOUNCE_ATTRIBUTE, SCRATCH_NAME):
            attribute = obj.data.color_attributes.get(name)
            if attribute is not None:
                obj.data.color_attributes.remove(attribute)
                found = True
        layer = obj.data.uv_layers.get(UV_NAME)
        if layer is not None:
            obj.data.uv_layers.remove(layer)
            found = True
        if found:
            obj.data.update()
    drop_unused_atlas()
    return found


def drop_unused_atlas():
    """Delete the atlas images (the add-on's: by name and marker) once no object of the file
    is baked per texel."""
    if any((record(o) or {}).get("store") == "TEXELS" for o in bpy.data.objects):
        return
    for index, name in enumerate(IMAGE_NAMES + (BOUNCE_IMAGE,)):
        image = bpy.data.images.get(name)
        if image is not None and image.library is None and image.get(IMAGE_MARKER) == index:
            bpy.data.images.remove(image)
