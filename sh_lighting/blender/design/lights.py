"""Extract Lights: the world image's compact bright sources as Blender Sun lights, SH for the
rest (``core.lights``).

``extract_lights`` reads the world's equirect image as Compute from World does, makes one Sun
per source (aimed along it, angle from its size, colour and strength from its texels ×
Strength) in a collection "SH Lights (<image>)", and stores the rest as the current and Reset
values. The add-on's lights are those the scene's ``REGISTRY`` pointers name (a Shift+D copy
is not): a new extraction updates them, Compute from World deletes them. They are invisible to
glossy and transmission rays (the world still shows the sources there). Details:
docs/modules.md.
"""

import time
from dataclasses import dataclass
from math import ceil, degrees

import bpy
import numpy as np
from mathutils import Matrix, Vector

from ...core import lights as core_lights
from ...core.equirect import zero_nonfinite
from ...core.world_map import map_coefficients, sun_light_rotation, to_world_direction
from ..data import scene_data
from ..world import reader
from . import edits

REGISTRY = "sh_lighting_lights"  # scene property: {"lights": [Object], "collection": Collection}
LEGACY_MARKERS = ("sh_lighting_light", "sh_lighting_sun")  # object properties before it
LIGHT_NAME = "SH Light"
COLLECTION_NAME = "SH Lights ({})"
DISTANCE = 5.0  # metres from the 3D cursor toward the source: where each new light is placed
# Extract Lights' default error target (mean error of SH + lights, fraction of the world's
# light): measured on Blender's 8 HDRIs, it stops sunrise.exr after its sun (2.2 % -> 0.40 %,
# a second light 0.34 %); tests/blender/design/test_extract_default.py has the counts.
ERROR_TARGET = 0.005
SIZE_LIMIT = 2.0 * float(core_lights.MAX_RADIUS)  # radians across: larger sources stay in SH
FLOAT32_MAX = float(np.finfo(np.float32).max)


@dataclass(frozen=True, eq=False)
class LightsInfo:
    """What ``extract_lights`` did: lights (names, brightest first), created / removed (names),
    extraction (the ``core.lights.Extraction``, in the image's axes, before Strength),
    coefficients (9, 3) stored; image (name), collection (name or ""), seconds taken."""

    lights: list
    created: list
    removed: list
    extraction: object
    coefficients: np.ndarray
    image: str
    collection: str
    seconds: float

    def report(self):
        """One line for the user: the image, what was made, the 9-term error before and
        after, the time, why no more lights were taken and what would take more."""
        extraction = self.extraction
        before, after = 100 * extraction.errors[0][0], 100 * extraction.errors[-1][0]
        text = f"Extract Lights from '{self.image}' ({self.seconds:.2f} s): "
        if self.lights:
            text += (f"{len(self.lights)} light(s) in '{self.collection}' "
                     f"({', '.join(self.lights)})")
            if self.removed:
                text += f", {len(self.removed)} old one(s) removed"
            text += (f"; mean error vs the world's irradiance {before:.2f} % of its light "
                     f"with SH alone, {after:.2f} % with SH + lights")
        else:
            if self.removed:
                text += f"{len(self.removed)} old light(s) removed, "
            text += (f"no light extracted, the world stays in the SH (mean error "
                     f"{before:.2f} % of its light)")
        if extraction.stop_kind != core_lights.COUNT:
            text += f"; no more: {extraction.stop}"
        largest = degrees(2.0 * core_lights.LARGEST_RADIUS)
        if extraction.stop_kind == core_lights.TOO_LARGE:
            limit, size = degrees(2.0 * extraction.max_radius), degrees(extraction.stop_size)
            if size and size < largest:
                text += (f" (set Size Limit to {ceil(size)}° or more to extract it as a light, "
                         "or leave it in the SH)")
            elif not size and limit < largest:
                text += (f" (raise Size Limit above {limit:.0f}° to extract it as a light, or "
                         "leave it in the SH)")
        note = getattr(self.coefficients, "note", "")  # a key written over an animated value
        return f"{text}; SH lighting {note}" if note else text


def _registry(scene):
    value = scene.get(REGISTRY)
    return value if hasattr(value, "to_dict") else None


def _ours(scene, obj):
    """Whether ``obj`` is a light of ``scene`` the add-on may change: in the scene, local."""
    return (isinstance(obj, bpy.types.Object) and obj.type == "LIGHT" and obj.library is None
            and scene.objects.get(obj.name) == obj)


def _legacy(scene):
    """Lights a file saved before ``REGISTRY`` marked, whose names the provenance records."""
    names = set()
    for record in (scene_data.computed_provenance(scene), scene_data.provenance(scene)):
        names.update(str(n) for n in record.get("lights", ()))
        if record.get("sun"):
            names.add(str(record["sun"]))
    found = []
    for obj in scene.objects:
        marks = [obj.get(m) for m in LEGACY_MARKERS]
        if obj.name in names and any(m is not None for m in marks) and _ours(scene, obj):
            index = marks[0] if isinstance(marks[0], int) else -1
            found.append((index, obj.name, obj))
    return [obj for _, _, obj in sorted(found, key=lambda item: item[:2])]


def extracted_lights(scene):
    """The light objects of ``scene`` an extraction made (brightest first), that it may change."""
    registry = _registry(scene)
    if registry is None:
        return _legacy(scene)
    made = [obj for obj in registry.get("lights", ()) if _ours(scene, obj)]
    return list(dict.fromkeys(made))


def _collection(scene):
    """The collection of the extracted lights if it is still the add-on's and in the scene."""
    registry = _registry(scene)
    found = registry.get("collection") if registry is not None else None
    if not isinstance(found, bpy.types.Collection) or found.library is not None:
        return None
    return found if found in scene.collection.children_recursive else None


def _delete(obj):
    light = obj.data
    bpy.data.objects.remove(obj)
    if light is not None and light.users == 0:
        bpy.data.lights.remove(light)


def _record(scene, made, collection):
    scene[REGISTRY] = {"lights": list(made), "collection": collection}
    if not made and collection is None:
        del scene[REGISTRY]


def remove_lights(scene):
    """Delete the extracted lights of ``scene`` (their light data too if unused) and their
    collection if it is left empty; the names of the lights deleted."""
    names = []
    for obj in extracted_lights(scene):
        names.append(obj.name)
        _delete(obj)
    collection = _collection(scene)
    if collection is not None and not collection.objects and not collection.children:
        bpy.data.collections.remove(collection)
    if _registry(scene) is not None:
        del scene[REGISTRY]
    return names


def _new_light(scene, collection, index, direction):
    name = f"{LIGHT_NAME} {index + 1}"
    obj = bpy.data.objects.new(name, bpy.data.lights.new(name, type="SUN"))
    obj.location = scene.cursor.location + DISTANCE * Vector(direction)
    collection.objects.link(obj)
    return obj


def _own_collection(scene, image):
    """The add-on's collection for lights from ``image``, made (in the scene) if needed."""
    name = COLLECTION_NAME.format(image)
    collection = _collection(scene)
    if collection is None:
        collection = bpy.data.collections.new(name)
        scene.collection.children.link(collection)
    elif collection.name != name:
        collection.name = name
    return collection


def _check_lights(extraction, strength):
    """A DesignError, before anything changes, when a light's strength is beyond float32."""
    for index, light in enumerate(extraction.lights, 1):
        energy = light.strength * strength
        if not energy <= FLOAT32_MAX:
            raise edits.DesignError(
                f"light {index} would have strength {energy:.3g} W/m², beyond what Blender "
                f"stores (float32, {FLOAT32_MAX:.3g}): lower the world's Strength or the "
                "image's values")


def _half(size_limit):
    """The size limit's radius for the core, or the value as it is for the core to refuse."""
    return 0.5 * size_limit if core_lights.real_number(size_limit) else size_limit


def extract_lights(scene, count=3, error_target=None, size_limit=SIZE_LIMIT, nonfinite="raise"):
    """Take up to ``count`` lights out of the world image (module docstring); ``LightsInfo``.

    ``error_target``: stop once the mean error of SH + lights is at most this fraction of the
    world's light. ``size_limit``: radians across; larger sources stay in the SH (up to
    ``2 core.lights.LARGEST_RADIUS``). A ValueError (``reader.WorldError``,
    ``edits.DesignError``) with nothing changed when the world is not an equirect image, an
    argument is wrong or a light would not fit Blender's float32 values. ``nonfinite``
    "zero": NaN/Inf texels of the world image count as black (as Compute from World's).
    """
    if nonfinite not in ("raise", "zero"):
        raise ValueError(f'nonfinite must be "raise" or "zero", got {nonfinite!r}')
    started = time.perf_counter()
    source = reader.read_world(scene)
    if isinstance(source, reader.ProceduralSource):
        raise edits.DesignError(
            f"world '{source.world}' is not an Environment Texture image read directly "
            f"({source.reason}): Extract Lights needs World Output ← Background ← Environment "
            "Texture [← Mapping ← Texture Coordinate]")
    if source.projection != "EQUIRECTANGULAR":
        raise edits.DesignError(
            f"Extract Lights needs an equirectangular world image; image "
            f"'{source.image.name}' of world '{source.world}' is a "
            f"{source.projection.replace('_', ' ').lower()}")
    strength = float(source.strength)
    if not strength > 0.0:
        raise edits.DesignError(
            f"world '{source.world}' has Strength {strength:g}: no light to extract")
    pixels = source.pixels()
    if nonfinite == "zero":
        pixels = zero_nonfinite(pixels)
    extraction = core_lights.extract_lights(pixels, count, error_target,
                                             max_radius=_half(size_limit),
                                             luminance=edits.luminance())
    rest = map_coefficients(extraction.rest, strength, source.rotation)
    scene_data.validate(rest)  # fail before anything changes
    _check_lights(extraction, strength)

    existing = extracted_lights(scene)
    collection = _own_collection(scene, source.image.name) if extraction.lights else None
    made, created = [], []
    for index, light in enumerate(extraction.lights):
        direction = to_world_direction(light.direction, source.rotation)
        if existing:
            obj = existing.pop(0)
            if obj.data.users > 1:  # shared with an artist's linked duplicate (Alt+D): not ours
                obj.data = obj.data.copy()
            obj.data.type = "SUN"
        else:
            obj = _new_light(scene, collection, index, direction)
            created.append(obj.name)
        for marker in LEGACY_MARKERS:  # adopted from an old file: the registry says it now
            if marker in obj:
                del obj[marker]
        obj.visible_glossy = obj.visible_transmission = False  # the world's image reflects it
        data = obj.data
        data.energy = light.strength * strength
        data.color = tuple(float(v) for v in light.colour)
        data.angle = light.angular_diameter
        obj.rotation_mode = "XYZ"
        obj.rotation_euler = Matrix(sun_light_rotation(direction).tolist()).to_euler("XYZ")
        made.append(obj)
    removed = []
    for obj in existing:  # lights of an earlier extraction no longer needed
        removed.append(obj.name)
        _delete(obj)
    if collection is None:
        collection = _collection(scene)
        if collection is not None and not collection.objects and not collection.children:
            bpy.data.collections.remove(collection)  # ours, and nothing left in it
            collection = None
    _record(scene, made, collection)
    names = [obj.name for obj in made]
    record = {"source": "WORLD", "world": source.world, "method": "IMAGE",
              "image": source.image.name, "lights": names,
              "size_limit": float(size_limit)}  # what Edit World needs to find them again
    if error_target is not None:
        record["error_target"] = float(error_target)
    if names:
        record["sun"] = names[0]
    stored = scene_data.store(scene, rest, record)  # also the Reset values
    return LightsInfo(names, created, removed, extraction, stored, source.image.name,
                      collection.name if made else "", time.perf_counter() - started)
