"""Extract Lights: the world image's compact bright sources as Blender Sun lights, SH for the
rest (``core.lights``; generalises Split Sun).

``extract_lights(scene, count, error_target)`` reads the world's equirect Environment Texture
(``world.read_world``: the Background's Strength and the Mapping node's rotation as evaluated
at the current frame, the pixels decoded as Compute from World sees them), takes up to ``count`` sources out, makes one Sun light per source (aimed along the
source's direction in the world, angle from its size, colour and strength from its texels ×
Strength) and stores the coefficients of the world without them, as the current values and as
the Reset values (as Split Sun does: Reset then keeps the lights out of the SH). The lights
are ordinary objects (move, retint, delete them; all undoable), marked by the custom property
``LIGHT_MARKER`` (their index) so that a new extraction updates them in place and deletes the
ones no longer needed, and Compute from World (which stores the whole world's coefficients
again) deletes them (``remove_lights``): a light is never counted twice. The brightest light
is also Split Sun's Sun (``design.SUN_MARKER``, and the provenance names it), so Split Sun
updates that light instead of adding another, and an extraction reuses Split Sun's Sun.

The world itself keeps the sources (the background and, in Apply mode KEEP_BSDF, the glossy
and transmission reflections of the world still show them), so the lights are made invisible
to glossy and transmission rays: in Cycles they then light diffuse closures only, replacing
what was taken out of the SH, and a glossy surface does not reflect a source twice.
"""

from dataclasses import dataclass

import bpy
import numpy as np
from mathutils import Matrix

from ...core import lights as core_lights
from ...core.world_map import map_coefficients, sun_light_rotation, to_world_direction
from .. import scene_data
from ..world import reader as world
from . import edits as design

LIGHT_MARKER = "sh_lighting_light"
LIGHT_NAME = "SH Light"


@dataclass(frozen=True, eq=False)
class LightsInfo:
    """What ``extract_lights`` did: lights (names, brightest first), created / removed (names),
    extraction (the ``core.lights.Extraction``, in the image's axes, before Strength),
    coefficients (9, 3) stored, strength and rotation of the world read."""

    lights: list
    created: list
    removed: list
    extraction: object
    coefficients: np.ndarray

    def report(self):
        """One line for the user."""
        errors = self.extraction.errors
        before, after = 100 * errors[0][0], 100 * errors[-1][0]
        if not self.lights:
            text = "No compact bright source found in the world image"
        else:
            text = f"{len(self.lights)} light(s) extracted: " + ", ".join(self.lights)
        if self.removed:
            text += f" ({len(self.removed)} old one(s) removed)"
        return (f"{text}; mean error vs the world's irradiance {before:.2f} % of its light with "
                f"SH alone, {after:.2f} % with SH + lights")


def extracted_lights(scene):
    """The light objects of ``scene`` an extraction (or Split Sun) made, by index."""
    found = []
    for obj in scene.objects:
        if obj.type != "LIGHT":
            continue
        if LIGHT_MARKER in obj:
            found.append((int(obj[LIGHT_MARKER]), obj.name, obj))
        elif obj.get(design.SUN_MARKER):
            found.append((-1, obj.name, obj))
    return [obj for _, _, obj in sorted(found, key=lambda item: item[:2])]


def remove_lights(scene):
    """Delete the extracted lights of ``scene`` (their light data too if unused); names."""
    names = []
    for obj in extracted_lights(scene):
        names.append(obj.name)
        light = obj.data
        bpy.data.objects.remove(obj)
        if light is not None and light.users == 0:
            bpy.data.lights.remove(light)
    return names


def _light_object(scene, existing, index):
    """(object, created): the extracted light ``index`` if there is one, else a new one."""
    if existing:
        obj = existing.pop(0)
        obj.data.type = "SUN"
        if index == 0:
            obj[design.SUN_MARKER] = True
        elif design.SUN_MARKER in obj:
            del obj[design.SUN_MARKER]
        obj[LIGHT_MARKER] = index
        obj.visible_glossy = obj.visible_transmission = False
        return obj, False
    name = f"{LIGHT_NAME} {index + 1}"
    obj = bpy.data.objects.new(name, bpy.data.lights.new(name, type="SUN"))
    obj[LIGHT_MARKER] = index
    if index == 0:
        obj[design.SUN_MARKER] = True  # Split Sun updates this light, adds no other
    obj.visible_glossy = obj.visible_transmission = False  # the world's image reflects it
    obj.id_properties_ui(LIGHT_MARKER).update(
        description="Made by SH Lighting's Extract Lights, which updates or deletes this light "
        "(Reset and Compute from World delete it)")
    scene.collection.objects.link(obj)
    return obj, True


def extract_lights(scene, count=3, error_target=None):
    """Take up to ``count`` lights out of the world image (module docstring); ``LightsInfo``.

    ``error_target``: stop once the mean error of SH + lights is at most this fraction of the
    world's light. A ValueError (``world.WorldError``, ``design.DesignError``) with nothing
    changed when the world is not an equirect image or an argument is wrong.
    """
    source = world.read_world(scene)
    if isinstance(source, world.ProceduralSource):
        raise design.DesignError(
            f"world '{source.world}' is not an Environment Texture image read directly "
            f"({source.reason}): Extract Lights needs World Output ← Background ← Environment "
            "Texture [← Mapping ← Texture Coordinate]")
    if source.projection != "EQUIRECTANGULAR":
        raise design.DesignError(
            f"Extract Lights needs an equirectangular world image; image "
            f"'{source.image.name}' of world '{source.world}' is a "
            f"{source.projection.replace('_', ' ').lower()}")
    strength = float(source.strength)
    if not strength > 0.0:
        raise design.DesignError(
            f"world '{source.world}' has Strength {strength:g}: no light to extract")
    extraction = core_lights.extract_lights(source.pixels(), count, error_target,
                                             luminance=design.luminance())
    rest = map_coefficients(extraction.rest, strength, source.rotation)
    scene_data.validate(rest)  # fail before anything changes

    existing = extracted_lights(scene)
    names, created = [], []
    for index, light in enumerate(extraction.lights):
        obj, new = _light_object(scene, existing, index)
        data = obj.data
        data.energy = light.strength * strength
        data.color = tuple(float(v) for v in light.colour)
        data.angle = light.angular_diameter
        direction = to_world_direction(light.direction, source.rotation)
        obj.rotation_mode = "XYZ"
        obj.rotation_euler = Matrix(sun_light_rotation(direction).tolist()).to_euler("XYZ")
        names.append(obj.name)
        if new:
            created.append(obj.name)
    removed = []
    for obj in existing:  # lights of an earlier extraction no longer needed
        removed.append(obj.name)
        light = obj.data
        bpy.data.objects.remove(obj)
        if light is not None and light.users == 0:
            bpy.data.lights.remove(light)
    record = {"source": "WORLD", "world": source.world, "method": "IMAGE",
              "image": source.image.name, "lights": names}
    if names:
        record["sun"] = names[0]
    stored = scene_data.store(scene, rest, record)  # also the Reset values
    return LightsInfo(names, created, removed, extraction, stored)
